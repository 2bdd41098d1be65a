/* The bdpt integrator (seed 000; DESIGN.md "bdpt", BDPT.md): direct's frame, then
 *   rsm -> bounds -> [emitters] -> generate -> [probe -> bounce] -> vpl -> split -> (bundle k ->
 * connect k) for each k -> gather -> filter -> output. Reflective shadow maps of the shadowed
 * punctual lights give the VPLs' surfaces; the emissive triangles give VPLs too, points on them
 * picked by power, which light the camera's points directly (weighed against the bundles that find
 * the emitter) and, through a bundle, one bounce further; each such point probes along a
 * cosine-distributed direction (a 1x1 reflective shadow map) for the surface its light meets first,
 * VPL K_v + i, which gives the emitter's light its bounces as a punctual light's VPL does. Each VPL
 * gets a paraboloid shadow map; each global ray-bundle is an orthographic view into per-pixel
 * linked lists, connected to the sub-image of the interleaved G-buffer it lights before the next
 * one reuses the list. Its history is direct's: one frame, for motion vectors. */
#include "integrators/integrators_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct bdpt {
    struct rb_base base;
    struct rb_pass_view *views;
    struct rb_pass_bdpt *passes;
    struct rb_bdpt_frame b;
    struct rb_gpu_buffer usage; /* struct rb_gpu_list_counter per bundle, host-visible */
};

/* The sampling table's streams (rb_qmc_point2): fixed, so every scene and frame draws the same
 * numbers. */
enum { STREAM_VPL_DIRECTION = 1, STREAM_VPL_LIGHT = 2, STREAM_BUNDLE = 3, STREAM_VPL_BOUNCE = 4 };

static uint32_t history_frames(const struct rb_job *job)
{
    (void)job;
    return 1;
}

static void release(struct rb_gpu *gpu, struct bdpt *d)
{
    struct rb_bdpt_frame *b = &d->b;
    struct rb_gpu_buffer *buffers[] = {
        &b->bounds,      &b->samples,     &b->lights,      &b->vpls,         &b->vpl_views,
        &b->probe_views, &b->vpl_draws,   &b->probe_draws, &b->bundle_views, &b->emitters,
        &b->emit_info,   &b->emitter_cdf, &d->usage};
    for (size_t i = 0; i < COUNT(buffers); i++)
        rb_gpu_buffer_release(gpu, buffers[i]);
    for (int i = 0; i < RB_VIEW_RSM_TARGETS; i++) {
        rb_gpu_image_release(gpu, &b->rsm[i]);
        rb_gpu_image_release(gpu, &b->probe[i]);
    }
    rb_gpu_image_release(gpu, &b->rsm_depth);
    rb_gpu_image_release(gpu, &b->probe_depth);
    rb_gpu_image_release(gpu, &b->vpl_maps);
    rb_gpu_image_release(gpu, &b->vpl_depth);
    rb_view_list_release(gpu, &b->bundle);
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_gpu_image_release(gpu, &b->split[i]);
        rb_gpu_image_release(gpu, &b->accum[i]);
        rb_gpu_image_release(gpu, &b->gathered[i]);
        rb_gpu_image_release(gpu, &b->filtered[i]);
    }
}

static void destroy(struct rb_integrator *it, void *state)
{
    struct bdpt *d = state;
    if (!d)
        return;
    release(it->gpu, d);
    rb_pass_bdpt_destroy(d->passes);
    rb_pass_view_destroy(d->views);
    rb_base_destroy(&d->base);
    free(d);
}

/* The integrator's buffers are storage buffers, filled by the shaders or uploaded. */
#define STORAGE (VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT)
/* Draw commands the shaders edit. */
#define DRAWS (STORAGE | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)

/* The fixed quasi-random table (BDPT.md "Sampling"): VPL i draws its light and its direction
 * from rows i, bundle i its direction from row K_v + i. */
static enum rb_status upload_samples(struct rb_gpu *gpu, struct rb_bdpt_frame *b,
                                     struct rb_err *err)
{
    uint32_t rows = b->vpl_count + b->bundle_count;
    struct rb_gpu_bdpt_sample *s = calloc(rows ? rows : 1, sizeof(*s));
    if (!s)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    for (uint32_t i = 0; i < rows; i++) {
        uint32_t u[2], l[2];
        bool is_vpl = i < b->vpl_count;
        uint32_t index = is_vpl ? i : i - b->vpl_count;
        if (is_vpl) {
            rb_qmc_point2(STREAM_VPL_LIGHT, index, l);
            rb_qmc_point2(STREAM_VPL_DIRECTION, index, u);
            s[i].u[0] = rb_qmc_float(l[0]);
            s[i].u[1] = rb_qmc_float(u[0]);
            s[i].u[2] = rb_qmc_float(u[1]);
            rb_qmc_point2(STREAM_VPL_BOUNCE, index, u);
            s[i].v[0] = rb_qmc_float(u[0]);
            s[i].v[1] = rb_qmc_float(u[1]);
        } else {
            rb_qmc_point2(STREAM_BUNDLE, index, u);
            s[i].u[0] = rb_qmc_float(u[0]);
            s[i].u[1] = rb_qmc_float(u[1]);
        }
    }
    enum rb_status st = rb_gpu_buffer_upload(gpu, &b->samples, s,
                                             (VkDeviceSize)(rows ? rows : 1) * sizeof(*s), err);
    free(s);
    return st;
}

/* The emissive triangles (a material whose emissive factor is above zero), as corners in the
 * frame's world vertex buffer, which holds each instance's vertices in instance order. Their
 * points are VPLs too: generate picks them by power each frame from where the animate pass put
 * them. */
static enum rb_status upload_emitters(struct rb_integrator *it, struct rb_bdpt_frame *b,
                                      struct rb_err *err)
{
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = it->cur.pose;
    uint32_t count = 0, cap = 0, dst = 0;
    struct rb_gpu_bdpt_emitter *list = NULL;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        const float *e = scene->materials[p->material].emissive;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f)
            for (uint32_t j = 0; j + 2 < p->index_count; j += 3) {
                if (count == cap) {
                    cap = cap ? 2 * cap : 64;
                    void *grown = realloc(list, cap * sizeof(*list));
                    if (!grown) {
                        free(list);
                        return rb_errf(err, RB_E_NOMEM, "out of memory for emissive triangles");
                    }
                    list = grown;
                }
                const uint32_t *t = &scene->indices[p->first_index + j];
                list[count++] = (struct rb_gpu_bdpt_emitter){
                    .tri = {dst + t[0], dst + t[1], dst + t[2], p->material}};
            }
        dst += p->vertex_count;
    }
    b->emitter_count = count;
    enum rb_status st = rb_frame_buffer(it->gpu, (VkDeviceSize)(count ? count : 1) * sizeof(*list),
                                        STORAGE, false, "bdpt.emitters", &b->emitters, err);
    if (st == RB_OK)
        st = rb_frame_buffer(it->gpu, (VkDeviceSize)(count ? count : 1) * sizeof(float), STORAGE,
                             false, "bdpt.emitter_cdf", &b->emitter_cdf, err);
    if (st == RB_OK && count)
        st = rb_gpu_buffer_upload(it->gpu, &b->emitters, list, count * sizeof(*list), err);
    free(list);
    return st;
}

static enum rb_status make_resources(struct rb_integrator *it, struct bdpt *d, struct rb_err *err)
{
    struct rb_gpu *gpu = it->gpu;
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    uint32_t kv = b->vpl_count ? b->vpl_count : 1, kb = b->bundle_count ? b->bundle_count : 1;
    enum rb_status st = upload_emitters(it, b, err);
    if (st)
        return st;
    /* With emitters, VPL i's bounce is VPL K_v + i. */
    b->has_bounce = b->emitter_count > 0 && b->vpl_count > 0;
    uint32_t all = b->has_bounce ? 2 * kv : kv;
    if ((st = rb_frame_buffer(gpu, 8 * sizeof(uint32_t), STORAGE, false, "bdpt.bounds", &b->bounds,
                              err)) ||
        (st = rb_frame_buffer(gpu, (VkDeviceSize)(kv + kb) * sizeof(struct rb_gpu_bdpt_sample),
                              STORAGE, false, "bdpt.samples", &b->samples, err)) ||
        (st = rb_frame_buffer(gpu, RB_MAX_LIGHTS * sizeof(struct rb_gpu_bdpt_light), STORAGE, true,
                              "bdpt.lights", &b->lights, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(struct rb_gpu_vpl), STORAGE, false, "bdpt.vpls",
                              &b->vpls, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.vpl_views", &b->vpl_views, err)) ||
        (st = rb_frame_buffer(gpu, kv * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.probe_views", &b->probe_views, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(VkDrawIndexedIndirectCommand), DRAWS, false,
                              "bdpt.vpl_draws", &b->vpl_draws, err)) ||
        (st = rb_frame_buffer(gpu, kv * sizeof(VkDrawIndexedIndirectCommand), DRAWS, false,
                              "bdpt.probe_draws", &b->probe_draws, err)) ||
        (st = rb_view_draws_init(gpu, &it->frame, true, all, &b->vpl_draws, err)) ||
        (st = rb_view_draws_init(gpu, &it->frame, true, kv, &b->probe_draws, err)) ||
        (st = rb_frame_buffer(gpu, kb * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.bundle_views", &b->bundle_views, err)) ||
        (st = rb_frame_buffer(gpu, kb * sizeof(struct rb_gpu_list_counter), STORAGE, true,
                              "bdpt.usage", &d->usage, err)) ||
        (st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_bdpt_emit_info), STORAGE, false,
                              "bdpt.emit_info", &b->emit_info, err)) ||
        (st = upload_samples(gpu, b, err)))
        return st;

    const VkImageUsageFlags target =
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;
    const VkImageUsageFlags storage = VK_IMAGE_USAGE_STORAGE_BIT;
    uint32_t rsm = it->job->integrator.bdpt.rsm_size_px;
    uint32_t rsm_layers = frame->shadow_layer_count ? frame->shadow_layer_count : 1;
    static const char *const rsm_names[RB_VIEW_RSM_TARGETS] = {
        "bdpt.rsm.position", "bdpt.rsm.normal", "bdpt.rsm.flux", "bdpt.rsm.material"};
    static const char *const probe_names[RB_VIEW_RSM_TARGETS] = {
        "bdpt.probe.position", "bdpt.probe.normal", "bdpt.probe.flux", "bdpt.probe.material"};
    for (int i = 0; i < RB_VIEW_RSM_TARGETS && st == RB_OK; i++)
        if ((st = rb_frame_image(gpu, rsm, rsm, rsm_layers, rb_view_rsm_formats[i], target, true,
                                 rsm_names[i], &b->rsm[i], err)) == RB_OK)
            st = rb_frame_image(gpu, 1, 1, kv, rb_view_rsm_formats[i], target, true, probe_names[i],
                                &b->probe[i], err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, 1, 1, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.probe.depth",
                            &b->probe_depth, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, rsm, rsm, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.rsm.depth",
                            &b->rsm_depth, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, b->vpl_size_px, b->vpl_size_px, all, VK_FORMAT_R32_SFLOAT,
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, true,
                            "bdpt.vpl_maps", &b->vpl_maps, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, b->vpl_size_px, b->vpl_size_px, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.vpl_depth",
                            &b->vpl_depth, err);
    uint64_t nodes =
        (uint64_t)it->job->integrator.bdpt.node_buffer_kib * 1024 / sizeof(struct rb_gpu_list_node);
    if (st == RB_OK)
        st = rb_view_list_init(gpu,
                               &(struct rb_view_list_desc){.width_px = b->bundle_size_px,
                                                           .height_px = b->bundle_size_px,
                                                           .capacity_nodes = (uint32_t)nodes,
                                                           .debug_name = "bdpt.bundle"},
                               &b->bundle, err);
    uint32_t sw = b->sub_width_px * b->interleave, sh = b->sub_height_px * b->interleave;
    static const char *const split_names[RB_BDPT_SPLIT_COUNT] = {
        "bdpt.split.position", "bdpt.split.normal", "bdpt.split.fresnel", "bdpt.split.geometric"};
    static const char *const light_names[3][RB_BDPT_LIGHT_COUNT] = {
        {"bdpt.accum.direct_diffuse", "bdpt.accum.direct_specular", "bdpt.accum.indirect_diffuse",
         "bdpt.accum.indirect_specular"},
        {"bdpt.gathered.direct_diffuse", "bdpt.gathered.direct_specular",
         "bdpt.gathered.indirect_diffuse", "bdpt.gathered.indirect_specular"},
        {"bdpt.filtered.direct_diffuse", "bdpt.filtered.direct_specular",
         "bdpt.filtered.indirect_diffuse", "bdpt.filtered.indirect_specular"}};
    const VkFormat f = VK_FORMAT_R32G32B32A32_SFLOAT;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT && st == RB_OK; i++)
        st = rb_frame_image(gpu, sw, sh, 1, f, storage, false, split_names[i], &b->split[i], err);
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT && st == RB_OK; i++)
        if ((st = rb_frame_image(gpu, sw, sh, 1, f, storage, false, light_names[0][i], &b->accum[i],
                                 err)) == RB_OK &&
            (st = rb_frame_image(gpu, frame->width_px, frame->height_px, 1, f, storage, false,
                                 light_names[1][i], &b->gathered[i], err)) == RB_OK)
            st = rb_frame_image(gpu, frame->width_px, frame->height_px, 1, f, storage, false,
                                light_names[2][i], &b->filtered[i], err);
    if (st)
        return st;

    VkCommandBuffer cmd;
    if ((st = rb_gpu_oneshot_begin(gpu, &cmd, err)))
        return st;
    struct rb_gpu_image *general[] = {&b->rsm[0],    &b->rsm[1],      &b->rsm[2],   &b->rsm[3],
                                      &b->rsm_depth, &b->probe[0],    &b->probe[1], &b->probe[2],
                                      &b->probe[3],  &b->probe_depth, &b->vpl_maps, &b->vpl_depth};
    for (size_t i = 0; i < COUNT(general); i++)
        rb_gpu_image_barrier(gpu, cmd, general[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_gpu_image_barrier(gpu, cmd, &b->split[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->accum[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->gathered[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->filtered[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    }
    return rb_gpu_oneshot_end(gpu, cmd, err);
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    const struct rb_job_bdpt *job = &it->job->integrator.bdpt;
    const struct rb_frame *frame = &it->frame;
    struct bdpt *d = calloc(1, sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    struct rb_bdpt_frame *b = &d->b;
    uint32_t n = job->interleave ? job->interleave : 1;
    struct rb_vec3 lo = it->setup.bounds_min, hi = it->setup.bounds_max;
    float diag = rb_v3_length(rb_v3_sub(hi, lo));
    if (!(diag > 0.0f))
        diag = 2.0f;
    *b = (struct rb_bdpt_frame){
        .vpl_count = job->vpls,
        .bundle_count = job->bundles,
        .interleave = n,
        .sub_width_px = (frame->width_px + n - 1) / n,
        .sub_height_px = (frame->height_px + n - 1) / n,
        .vpl_size_px = job->vpl_size_px,
        .bundle_size_px = job->bundle_size_px,
        .filter_radius_px = job->filter_radius_px,
        .filter_depth = job->filter_depth,
        .filter_normal = job->filter_normal,
        .clamp_g = job->clamp / (diag * diag),
        .vpl_bias = job->vpl_bias,
        .strategies = job->strategies ? job->strategies : RB_BDPT_STRATEGIES_MIS,
        .scene_centre = {0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), 0.5f * (lo.z + hi.z)},
        .scene_radius = 0.5f * diag,
    };
    static const struct rb_view_variant variants[] = {
        {RB_VIEW_KIND_PERSPECTIVE, RB_VIEW_OUTPUT_RSM},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_RSM},
        {RB_VIEW_KIND_PARABOLOID, RB_VIEW_OUTPUT_DEPTH},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_LIST},
    };
    enum rb_status st;
    if ((st = rb_base_create(it, &d->base, err)) ||
        (st = rb_pass_view_create(it->gpu,
                                  &(struct rb_pass_view_desc){.variants = variants,
                                                              .variant_count = COUNT(variants),
                                                              .debug_name = "bdpt.view"},
                                  &d->views, err)) ||
        (st = rb_pass_bdpt_create(it->gpu, &d->passes, err)) || (st = make_resources(it, d, err))) {
        destroy(it, d);
        return st;
    }
    *state = d;
    return RB_OK;
}

static float luminance(const float c[3])
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/* Each light's chance of a VPL among the punctual lights, by emitted power (BDPT.md "VPL"),
 * and its sampling densities: a point light's sphere, a spot light's cone, a directional
 * light's beam across its shadow map's square. Lights without a shadow map get no VPLs (the
 * bundles' side lights them). Generate weighs the sum, set in b, against the emitters'. */
static void write_lights(const struct rb_integrator *it, struct rb_bdpt_frame *b,
                         const struct rb_moment *m)
{
    struct rb_gpu_bdpt_light *out = b->lights.mapped;
    const struct rb_gpu_light *gl = it->frame.lights.mapped;
    double power[RB_MAX_LIGHTS], total = 0.0;
    float beam = 2.0f * b->scene_radius; /* write_shadow_views' box: 2 radius across */
    for (uint32_t i = 0; i < m->light_count; i++) {
        const struct rb_world_light *l = &m->lights[i];
        float lum = luminance(l->color), density, cos_outer = 0.0f;
        if (l->type == RB_LIGHT_DIRECTIONAL) {
            density = 1.0f / (beam * beam);
        } else if (l->type == RB_LIGHT_SPOT) {
            cos_outer = cosf(l->outer_cone_rad);
            density = 1.0f / (2.0f * (float)RB_PI * (1.0f - cos_outer));
        } else {
            density = 1.0f / (4.0f * (float)RB_PI);
        }
        power[i] = gl[i].color[3] >= 0.0f && lum > 0.0f ? lum / density : 0.0;
        total += power[i];
        out[i] = (struct rb_gpu_bdpt_light){.choice = {0.0f, 0.0f, density, cos_outer}};
    }
    b->punctual_power = (float)total;
    double cdf = 0.0;
    for (uint32_t i = 0; i < m->light_count && total > 0.0; i++) {
        cdf += power[i];
        out[i].choice[0] = (float)(power[i] / total);
        out[i].choice[1] = cdf >= total ? 1.0f : (float)(cdf / total);
    }
}

static void record_rsm(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                       const struct rb_frame_ctx *ctx)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access uses[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->rsm[0], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm[1], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm[2], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm[3], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "rsm", uses, COUNT(uses));
    const struct rb_gpu_light *lights = frame->lights.mapped;
    for (uint32_t i = 0; i < frame->light_count; i++) {
        int first = (int)lights[i].color[3];
        if (first < 0)
            continue;
        uint32_t kind = (uint32_t)lights[i].position[3];
        struct rb_view_batch batch = {
            .kind =
                kind == RB_KIND_DIRECTIONAL ? RB_VIEW_KIND_ORTHOGRAPHIC : RB_VIEW_KIND_PERSPECTIVE,
            .output = RB_VIEW_OUTPUT_RSM,
            .views = &frame->shadow_views,
            .first_view = (uint32_t)first,
            .first_layer = (uint32_t)first,
            .view_count = kind == RB_KIND_POINT ? 6 : 1,
            .targets = {&b->rsm[0], &b->rsm[1], &b->rsm[2], &b->rsm[3]},
            .depth = &b->rsm_depth,
            .intensity = {lights[i].color[0], lights[i].color[1], lights[i].color[2]},
            .use_simplified = true,
        };
        rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
    }
    rb_integrator_pass_end(it, cmd);
}

/* The emitters' bounces: each emitter VPL's probe (a 1x1 reflective shadow map along its
 * direction: the first surface its light meets), then VPLs K_v + i from them. */
static void record_bounce(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                          const struct rb_frame_ctx *ctx)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access probe[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &b->probe_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = &b->probe_draws, .use = RB_GPU_INDIRECT_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->probe[0], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[1], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[2], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[3], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "probe", probe, COUNT(probe));
    rb_pass_view_record(d->views, cmd, frame, ctx->cur,
                        &(struct rb_view_batch){
                            .kind = RB_VIEW_KIND_PERSPECTIVE,
                            .output = RB_VIEW_OUTPUT_RSM,
                            .views = &b->probe_views,
                            .view_count = b->vpl_count,
                            .targets = {&b->probe[0], &b->probe[1], &b->probe[2], &b->probe[3]},
                            .depth = &b->probe_depth,
                            .use_simplified = true,
                            .draws = &b->probe_draws,
                        });
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access bounce[] = {
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_READ_WRITE},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->probe[0], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->probe[1], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->probe[3], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpl_draws, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "bounce", bounce, COUNT(bounce));
    rb_pass_bdpt_bounce_record(d->passes, cmd, b);
    rb_integrator_pass_end(it, cmd);
}

static void record_bundle(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                          const struct rb_frame_ctx *ctx, uint32_t k)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access uses[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &b->bundle_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->bundle.heads, .use = RB_GPU_FRAGMENT_READ_WRITE},
        {.buffer = &b->bundle.nodes, .use = RB_GPU_FRAGMENT_READ_WRITE},
        {.buffer = &d->usage, .use = RB_GPU_TRANSFER_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "bundle", uses, COUNT(uses));
    struct rb_view_batch batch = {
        .kind = RB_VIEW_KIND_ORTHOGRAPHIC,
        .output = RB_VIEW_OUTPUT_LIST,
        .views = &b->bundle_views,
        .first_view = k,
        .first_layer = 0,
        .view_count = 1,
        .list = &b->bundle,
        .use_simplified = true,
    };
    rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
    /* The pool's counters, kept per bundle for collect (the next batch resets them). */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferCopy region = {.srcOffset = 0,
                           .dstOffset = (VkDeviceSize)k * sizeof(struct rb_gpu_list_counter),
                           .size = sizeof(struct rb_gpu_list_counter)};
    vkCmdCopyBuffer(cmd, b->bundle.counter.buffer, d->usage.buffer, 1, &region);
    rb_integrator_pass_end(it, cmd);
}

static void record_connect(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                           uint32_t k)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    struct rb_gpu_access uses[13 + RB_BDPT_SPLIT_COUNT + RB_BDPT_LIGHT_COUNT] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->vpl_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->bundle_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->bundle.heads, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->bundle.nodes, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->env_map, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->emit_info, .use = RB_GPU_COMPUTE_READ},
    };
    uint32_t count = 13;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        uses[count++] = (struct rb_gpu_access){.image = &b->split[i], .use = RB_GPU_COMPUTE_READ};
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        uses[count++] =
            (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_READ_WRITE};
    rb_integrator_pass_begin(it, cmd, "connect", uses, count);
    rb_pass_bdpt_connect_record(d->passes, cmd, frame, b, k);
    rb_integrator_pass_end(it, cmd);
}

static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct bdpt *d = state;
    struct rb_bdpt_frame *b = &d->b;
    struct rb_frame *frame = &it->frame;
    const struct rb_gpu_image *gb = frame->gbuffer;
    if (!rb_base_record_direct(it, &d->base, cmd, ctx))
        return;
    write_lights(it, b, ctx->moment);
    record_rsm(it, d, cmd, ctx);

    const struct rb_gpu_access bounds[] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->bounds, .use = RB_GPU_COMPUTE_READ_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "bounds", bounds, COUNT(bounds));
    rb_pass_bdpt_bounds_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access generate[] = {
        {.buffer = &b->bounds, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->samples, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[0], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[1], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[3], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->bundle_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->emitters, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->materials, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->emit_info, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->vpl_draws, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_draws, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->emitter_cdf, .use = RB_GPU_COMPUTE_READ},
    };
    if (b->emitter_count) {
        const struct rb_gpu_access emitters[] = {
            {.buffer = &ctx->cur->vertices, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &b->emitters, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &frame->materials, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &b->emitter_cdf, .use = RB_GPU_COMPUTE_WRITE},
        };
        rb_integrator_pass_begin(it, cmd, "emitters", emitters, COUNT(emitters));
        rb_pass_bdpt_emitters_record(d->passes, cmd, frame, ctx->cur, b);
        rb_integrator_pass_end(it, cmd);
    }
    rb_integrator_pass_begin(it, cmd, "generate", generate, COUNT(generate));
    rb_pass_bdpt_generate_record(d->passes, cmd, frame, ctx->cur, b);
    rb_integrator_pass_end(it, cmd);
    if (b->has_bounce)
        record_bounce(it, d, cmd, ctx);

    if (b->vpl_count) {
        const struct rb_gpu_access vpl[] = {
            {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
            {.buffer = &b->vpl_views, .use = RB_GPU_GRAPHICS_READ},
            {.buffer = &b->vpl_draws, .use = RB_GPU_INDIRECT_READ},
            {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
            {.image = &b->vpl_maps, .use = RB_GPU_COLOR_ATTACHMENT},
            {.image = &b->vpl_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
        };
        rb_integrator_pass_begin(it, cmd, "vpl", vpl, COUNT(vpl));
        rb_pass_view_record(d->views, cmd, frame, ctx->cur,
                            &(struct rb_view_batch){
                                .kind = RB_VIEW_KIND_PARABOLOID,
                                .output = RB_VIEW_OUTPUT_DEPTH,
                                .views = &b->vpl_views,
                                .view_count = b->has_bounce ? 2 * b->vpl_count : b->vpl_count,
                                .targets = {&b->vpl_maps},
                                .depth = &b->vpl_depth,
                                .use_simplified = true,
                                .draws = &b->vpl_draws,
                            });
        rb_integrator_pass_end(it, cmd);
    }

    struct rb_gpu_access split[5 + RB_BDPT_SPLIT_COUNT + RB_BDPT_LIGHT_COUNT] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_SPECULAR], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_EMISSION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COMPUTE_READ},
    };
    uint32_t count = 5;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        split[count++] = (struct rb_gpu_access){.image = &b->split[i], .use = RB_GPU_COMPUTE_WRITE};
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        split[count++] = (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_WRITE};
    rb_integrator_pass_begin(it, cmd, "split", split, count);
    rb_pass_bdpt_split_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    uint32_t loops = b->vpl_count > b->bundle_count ? b->vpl_count : b->bundle_count;
    for (uint32_t k = 0; k < loops; k++) {
        if (k < b->bundle_count)
            record_bundle(it, d, cmd, ctx, k);
        record_connect(it, d, cmd, k);
    }
    if (b->bundle_count) /* the counters' copies, for collect */
        rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                              VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                              VK_ACCESS_2_HOST_READ_BIT);

    struct rb_gpu_access gather[2 * RB_BDPT_LIGHT_COUNT];
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        gather[2 * i] = (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_READ};
        gather[2 * i + 1] =
            (struct rb_gpu_access){.image = &b->gathered[i], .use = RB_GPU_COMPUTE_WRITE};
    }
    rb_integrator_pass_begin(it, cmd, "gather", gather, COUNT(gather));
    rb_pass_bdpt_gather_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    struct rb_gpu_access filter[2 + 2 * RB_BDPT_LIGHT_COUNT] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
    };
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        filter[2 + 2 * i] =
            (struct rb_gpu_access){.image = &b->gathered[i], .use = RB_GPU_COMPUTE_READ};
        filter[3 + 2 * i] =
            (struct rb_gpu_access){.image = &b->filtered[i], .use = RB_GPU_COMPUTE_WRITE};
    }
    rb_integrator_pass_begin(it, cmd, "filter", filter, COUNT(filter));
    rb_pass_bdpt_filter_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    rb_base_record_output(it, &d->base, cmd, b->filtered);
}

/* The ray-bundle pool's use, bundle by bundle: the most nodes a bundle asked for, and the
 * fragments dropped because the pool was full (a warning here; the timing sidecar carries
 * the numbers, and --strict makes them fatal). */
static void collect(struct rb_integrator *it, void *state, struct rb_frame_result *out)
{
    const struct bdpt *d = state;
    const struct rb_gpu_list_counter *usage = d->usage.mapped;
    uint32_t most = 0, dropped = 0, overflowed = 0;
    for (uint32_t k = 0; k < d->b.bundle_count; k++) {
        if (usage[k].requested > most)
            most = usage[k].requested;
        dropped += usage[k].dropped;
        overflowed += usage[k].dropped > 0;
    }
    out->nonfinite_count = rb_pass_output_nonfinite_count(d->base.output);
    out->bundle_nodes_max = most;
    out->bundle_nodes_capacity = d->b.bundle.capacity_nodes;
    out->bundle_nodes_dropped = dropped;
    if (dropped)
        rb_log(RB_LOG_WARN,
               "frame %d: the ray-bundle node buffer overflowed: %u of %u bundles dropped %u "
               "fragments; a bundle needed up to %u nodes and the buffer holds %u (%u KiB); "
               "raise integrator.bdpt.node_buffer_kib",
               out->frame, overflowed, d->b.bundle_count, dropped, most, d->b.bundle.capacity_nodes,
               it->job->integrator.bdpt.node_buffer_kib);
}

const struct rb_integrator_ops rb_integrator_bdpt = {
    .name = "bdpt",
    .history_frames = history_frames,
    .create = create,
    .record = record,
    .collect = collect,
    .destroy = destroy,
};

const struct rb_bdpt_frame *rb_integrator_bdpt_frame(const struct rb_integrator *it)
{
    const struct bdpt *d = it->ops == &rb_integrator_bdpt ? it->state : NULL;
    return d ? &d->b : NULL;
}
