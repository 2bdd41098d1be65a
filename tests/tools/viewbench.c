/* viewbench: what the simplified view mesh saves (make bench; a measurement, never a test).
 * Renders a batch of orthographic views of a job's scene (a job file, or a .gltf/.glb for its
 * quick-look job), as the bdpt integrator's ray-bundles see it, into a depth batch and a
 * linked-list batch, under each triangle budget given (integrator.bdpt.view_triangles; 0: the
 * full mesh), and prints the triangles drawn and each batch's median GPU time over the frames.
 *
 *   viewbench SCENE_OR_JOB [--views N] [--size PX] [--frames N] BUDGET...
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "integrators/integrators_int.h"

#define MAX_FRAMES 64

struct bench {
    struct rb_pass_animate *animate;
    struct rb_pass_view *view;
    struct rb_gpu_buffer views; /* struct rb_gpu_view [view_count] */
    struct rb_gpu_image target, depth;
    struct rb_view_list list;
};

static uint32_t view_count = 21, size_px = 256;

static uint32_t no_history(const struct rb_job *job)
{
    (void)job;
    return 0;
}

static void destroy(struct rb_integrator *it, void *state)
{
    struct bench *b = state;
    rb_view_list_release(it->gpu, &b->list);
    rb_gpu_image_release(it->gpu, &b->depth);
    rb_gpu_image_release(it->gpu, &b->target);
    rb_gpu_buffer_release(it->gpu, &b->views);
    rb_pass_view_destroy(b->view);
    rb_pass_animate_destroy(b->animate);
    free(b);
}

/* view_count directions spread over the sphere (a Fibonacci lattice), each an orthographic view
 * of the job's bounds. */
static void write_views(const struct rb_scene_setup *s, struct rb_gpu_view *out)
{
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    float r = 0.5f * rb_v3_length(rb_v3_sub(s->bounds_max, s->bounds_min));
    r = r > 0.0f ? r * 1.01f : 1.0f;
    for (uint32_t i = 0; i < view_count; i++) {
        float z = 1.0f - (2.0f * (float)i + 1.0f) / (float)view_count;
        float phi = 2.39996323f * (float)i, rho = sqrtf(1.0f - z * z);
        struct rb_vec3 d = rb_v3(rho * cosf(phi), rho * sinf(phi), z);
        struct rb_vec3 up = fabsf(d.y) > 0.9f ? rb_v3(1, 0, 0) : rb_v3(0, 1, 0);
        rb_view_orthographic(&out[i], rb_v3_sub(c, rb_v3_scale(d, r)), d, up, r, r, 2.0f * r);
    }
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    struct bench *b = calloc(1, sizeof(*b));
    if (!b)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    const struct rb_view_variant variants[] = {
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_DEPTH},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_LIST},
    };
    enum rb_status st = rb_pass_animate_create(it->gpu, &b->animate, err);
    if (st == RB_OK)
        st = rb_pass_view_create(
            it->gpu, &(struct rb_pass_view_desc){.variants = variants, .variant_count = 2},
            &b->view, err);
    if (st == RB_OK)
        st = rb_gpu_buffer_init(
            it->gpu,
            &(struct rb_gpu_buffer_desc){.size_bytes = sizeof(struct rb_gpu_view) * view_count,
                                         .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                         .is_host_visible = true,
                                         .debug_name = "views"},
            &b->views, err);
    if (st == RB_OK)
        st = rb_gpu_image_init(
            it->gpu,
            &(struct rb_gpu_image_desc){.width_px = size_px,
                                        .height_px = size_px,
                                        .layer_count = view_count,
                                        .format = VK_FORMAT_R32_SFLOAT,
                                        .usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                                        .is_array = true,
                                        .has_layer_views = true,
                                        .debug_name = "view depth"},
            &b->target, err);
    if (st == RB_OK)
        st = rb_gpu_image_init(
            it->gpu,
            &(struct rb_gpu_image_desc){.width_px = size_px,
                                        .height_px = size_px,
                                        .format = VK_FORMAT_D32_SFLOAT,
                                        .usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                        .debug_name = "view scratch depth"},
            &b->depth, err);
    if (st == RB_OK)
        st = rb_view_list_init(it->gpu,
                               &(struct rb_view_list_desc){.width_px = size_px,
                                                           .height_px = size_px,
                                                           .layer_count = view_count,
                                                           .capacity_nodes = 8u << 20,
                                                           .debug_name = "view list"},
                               &b->list, err);
    VkCommandBuffer cmd;
    if (st == RB_OK && (st = rb_gpu_oneshot_begin(it->gpu, &cmd, err)) == RB_OK) {
        rb_gpu_image_barrier(it->gpu, cmd, &b->target, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(it->gpu, cmd, &b->depth, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        st = rb_gpu_oneshot_end(it->gpu, cmd, err);
    }
    if (st) {
        destroy(it, b);
        return st;
    }
    write_views(&it->setup, b->views.mapped);
    *state = b;
    return RB_OK;
}

static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct bench *b = state;
    struct rb_frame *frame = &it->frame;
    const struct rb_frame_slot *cur = ctx->cur;
    rb_base_record_animate(it, b->animate, cmd, cur);

    const struct rb_gpu_access depth[] = {
        {.buffer = &cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &b->views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.image = &b->target, .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "depth", depth, COUNT(depth));
    rb_pass_view_record(b->view, cmd, frame, cur,
                        &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                                .output = RB_VIEW_OUTPUT_DEPTH,
                                                .views = &b->views,
                                                .view_count = view_count,
                                                .targets = {&b->target},
                                                .depth = &b->depth,
                                                .use_simplified = true});
    rb_integrator_pass_end(it, cmd);

    /* The list batch orders its own clears and counter (view.c). */
    rb_integrator_pass_begin(it, cmd, "list", depth, 3);
    rb_pass_view_record(b->view, cmd, frame, cur,
                        &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                                .output = RB_VIEW_OUTPUT_LIST,
                                                .views = &b->views,
                                                .view_count = view_count,
                                                .list = &b->list,
                                                .use_simplified = true});
    rb_integrator_pass_end(it, cmd);
}

static const struct rb_integrator_ops bench_ops = {
    .name = "viewbench",
    .history_frames = no_history,
    .create = create,
    .record = record,
    .destroy = destroy,
};

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof(*v), cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int bench(struct rb_gpu *gpu, const char *path, const char *budget, int frames)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_job_override o[] = {{"integrator.name", "bdpt", NULL},
                                  {"integrator.bdpt.view_triangles", budget, NULL},
                                  {"resolution", "[16, 16]", NULL}};
    struct rb_job *job = NULL;
    struct rb_scene *scene = NULL;
    struct rb_integrator *it = NULL;
    double depth_ms[MAX_FRAMES], list_ms[MAX_FRAMES];
    int status = 1;
    if (rb_job_load(path, o, COUNT(o), &job, &err) ||
        rb_scene_load(job->scene_path, 0, &scene, &err))
        goto out;
    double start_s = rb_monotonic_s(); /* the frame's buffers, the simplified mesh among them */
    if (rb_integrator_create_with(
            &(struct rb_integrator_desc){.job = job, .scene = scene, .gpu = gpu}, &bench_ops, &it,
            &err))
        goto out;
    double setup_s = rb_monotonic_s() - start_s;
    for (int f = 0; f < frames; f++) {
        struct rb_frame_result r;
        if (rb_integrator_render(it, job->frame_start, &r, &err))
            goto out;
        for (uint32_t p = 0; p < r.pass_count; p++) {
            if (!strcmp(r.passes[p].name, "depth"))
                depth_ms[f] = r.passes[p].gpu_ms;
            if (!strcmp(r.passes[p].name, "list"))
                list_ms[f] = r.passes[p].gpu_ms;
        }
    }
    struct rb_view_list *list = &((struct bench *)it->state)->list;
    struct rb_gpu_list_counter c = rb_view_list_usage(list);
    printf("%s: budget %s: %u of %u triangles, %u views of %u^2: depth %.2f ms, list %.2f ms "
           "(%u fragments); set-up %.2f s\n",
           path, budget, it->frame.view_index_count / 3, it->frame.index_count / 3, view_count,
           size_px, median(depth_ms, frames), median(list_ms, frames), c.requested, setup_s);
    status = 0;
out:
    if (status)
        fprintf(stderr, "viewbench: %s: %s\n", path, err.msg);
    rb_integrator_destroy(it);
    rb_scene_destroy(scene);
    rb_job_destroy(job);
    return status;
}

int main(int argc, char **argv)
{
    int frames = 5, i = 1;
    const char *path = NULL;
    if (argc > 1)
        path = argv[i++];
    for (; i + 1 < argc && !strncmp(argv[i], "--", 2); i += 2) {
        long v = strtol(argv[i + 1], NULL, 10);
        if (!strcmp(argv[i], "--views") && v > 0 && v <= 256)
            view_count = (uint32_t)v;
        else if (!strcmp(argv[i], "--size") && v >= 16 && v <= 4096)
            size_px = (uint32_t)v;
        else if (!strcmp(argv[i], "--frames") && v > 0 && v <= MAX_FRAMES)
            frames = (int)v;
        else
            path = NULL;
    }
    if (!path || i >= argc) {
        fprintf(stderr, "usage: viewbench SCENE_OR_JOB [--views N] [--size PX] [--frames N] "
                        "BUDGET...\n");
        return 2;
    }
    rb_log_set_level(RB_LOG_INFO); /* the simplified mesh's triangles and error */
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = NULL;
    if (rb_gpu_create(&(struct rb_gpu_desc){0}, &gpu, &err)) {
        fprintf(stderr, "viewbench: %s\n", err.msg);
        return 3;
    }
    int status = 0;
    for (; i < argc && status == 0; i++)
        status = bench(gpu, path, argv[i], frames);
    rb_gpu_destroy(gpu);
    return status;
}
