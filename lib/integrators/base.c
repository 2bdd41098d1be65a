/* The passes every rasterizing integrator starts and ends its frame with: animate -> gbuffer
 * -> shadow -> direct, then transparency (only when the scene has blended materials) and
 * output. direct records them alone; bdpt and hybrid record their own passes between direct
 * and transparency (DESIGN.md "Frame driver"). */
#include "integrators/integrators_int.h"

#include <stdlib.h>

/* A blended instance's place in the frame's order: its squared distance from the camera. */
struct rb_transparency_sort {
    float dist2;
    uint32_t draw;
};

/* Farthest first; equal distances in instance order: a total order, so the same bits. */
static int farther_first(const void *a, const void *b)
{
    const struct rb_transparency_sort *x = a, *y = b;
    if (x->dist2 != y->dist2)
        return x->dist2 > y->dist2 ? -1 : 1;
    return x->draw < y->draw ? -1 : x->draw > y->draw;
}

/* The blended instances of the first pose (the instances do not change from frame to frame),
 * their index ranges (as rb_frame_world_indices lays them out) and their primitives' centres. */
static enum rb_status blend_init(struct rb_integrator *it, struct rb_base *b, struct rb_err *err)
{
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = it->cur.pose;
    uint32_t n = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        n += scene->materials[p->material].alpha_mode == RB_ALPHA_BLEND && p->index_count;
    }
    if (n == 0)
        return RB_OK;
    b->blend_draws = calloc(n, sizeof(*b->blend_draws));
    b->blend_order = calloc(n, sizeof(*b->blend_order));
    b->blend_instances = calloc(n, sizeof(*b->blend_instances));
    b->blend_centres = calloc((size_t)n * 3, sizeof(float));
    b->blend_sort = calloc(n, sizeof(*b->blend_sort));
    if (!b->blend_draws || !b->blend_order || !b->blend_instances || !b->blend_centres ||
        !b->blend_sort)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %u blended instances", n);
    uint32_t first = 0, k = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        if (scene->materials[p->material].alpha_mode == RB_ALPHA_BLEND && p->index_count) {
            double c[3] = {0, 0, 0};
            for (uint32_t v = 0; v < p->vertex_count; v++)
                for (int a = 0; a < 3; a++)
                    c[a] += scene->vertices[p->first_vertex + v].position[a];
            for (int a = 0; a < 3; a++)
                b->blend_centres[k * 3 + a] = p->vertex_count ? (float)(c[a] / p->vertex_count) : 0;
            b->blend_draws[k] = (struct rb_transparency_draw){first, p->index_count};
            b->blend_instances[k] = i;
            k++;
        }
        first += p->index_count;
    }
    b->blend_count = n;
    return rb_pass_transparency_create(it->gpu, it->frame.transparency.format, &b->transparency,
                                       err);
}

enum rb_status rb_base_create(struct rb_integrator *it, struct rb_base *b, struct rb_err *err)
{
    *b = (struct rb_base){0};
    enum rb_status st;
    if ((st = rb_pass_animate_create(it->gpu, &b->animate, err)) ||
        (st = rb_pass_gbuffer_create(it->gpu, &b->gbuffer, err)) ||
        (st = rb_pass_shadow_create(it->gpu, &b->shadow, err)) ||
        (st = rb_pass_direct_create(it->gpu, &b->direct, err)) ||
        (st = rb_pass_output_create(it->gpu, &b->output, err)) ||
        (it->frame.transparency.image && (st = blend_init(it, b, err))))
        rb_base_destroy(b);
    return st;
}

void rb_base_destroy(struct rb_base *b)
{
    rb_pass_transparency_destroy(b->transparency);
    free(b->blend_sort);
    free(b->blend_centres);
    free(b->blend_instances);
    free(b->blend_order);
    free(b->blend_draws);
    rb_pass_output_destroy(b->output);
    rb_pass_direct_destroy(b->direct);
    rb_pass_shadow_destroy(b->shadow);
    rb_pass_gbuffer_destroy(b->gbuffer);
    rb_pass_animate_destroy(b->animate);
    *b = (struct rb_base){0};
}

/* Each pass's declaration lists every frame resource its record function binds, draws with
 * or copies, with how (the shaders' stages and readonly/writeonly qualifiers); the driver
 * derives the barriers between the passes from them. */
void rb_base_record_animate(struct rb_integrator *it, struct rb_pass_animate *pass,
                            VkCommandBuffer cmd, const struct rb_frame_slot *cur)
{
    struct rb_frame *frame = &it->frame;
    const struct rb_gpu_access animate[] = {
        {.buffer = &frame->src_vertices, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->morph_deltas, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->instances, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->joints, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->weights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->vertices, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "animate", animate, COUNT(animate));
    rb_pass_animate_record(pass, cmd, frame, cur);
    rb_integrator_pass_end(it, cmd);
}

void rb_base_record_gbuffer(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                            const struct rb_frame_ctx *ctx, const struct rb_gbuffer_target *target)
{
    struct rb_frame *frame = &it->frame;
    const struct rb_frame_slot *cur = ctx->cur, *prev = ctx->prev;
    const struct rb_gpu_image *gb = target ? target->colors : frame->gbuffer;
    const struct rb_gpu_access gbuffer[] = {
        {.buffer = &frame->globals, .use = RB_GPU_GRAPHICS_UNIFORM},
        {.buffer = &cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &prev->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->indices, .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &gb[RB_GB_ALBEDO], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &gb[RB_GB_SPECULAR], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &gb[RB_GB_EMISSION], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = target ? target->depth : &frame->depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    _Static_assert(RB_GBUFFER_COLOR_COUNT == 6, "every G-buffer attachment is declared");
    rb_integrator_pass_begin(it, cmd, target ? "cache_gbuffer" : "gbuffer", gbuffer,
                             COUNT(gbuffer));
    rb_pass_gbuffer_record(b->gbuffer, cmd, frame, cur, prev, target);
    rb_integrator_pass_end(it, cmd);
}

void rb_base_record_shadow(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_frame_ctx *ctx)
{
    struct rb_frame *frame = &it->frame;
    const struct rb_gpu_access shadow[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = &frame->materials, .use = RB_GPU_VERTEX_READ}, /* blended ones are left out */
        {.buffer = &frame->indices, .use = RB_GPU_INDEX_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &frame->shadow_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "shadow", shadow, COUNT(shadow));
    rb_pass_shadow_record(b->shadow, cmd, frame, ctx->cur);
    rb_integrator_pass_end(it, cmd);
}

void rb_base_record_direct_light(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd)
{
    struct rb_frame *frame = &it->frame;
    const struct rb_gpu_image *gb = frame->gbuffer;
    const struct rb_gpu_access direct[] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_ALBEDO], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_SPECULAR], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_EMISSION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->env_map, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->direct, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "direct", direct, COUNT(direct));
    rb_pass_direct_record(b->direct, cmd, frame);
    rb_integrator_pass_end(it, cmd);
}

bool rb_base_record_direct(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_frame_ctx *ctx)
{
    rb_base_record_animate(it, b->animate, cmd, ctx->cur);
    if (ctx->is_warmup)
        return false; /* a later frame reads this frame's world vertices, nothing else */
    rb_base_record_gbuffer(it, b, cmd, ctx, NULL);
    rb_base_record_shadow(it, b, cmd, ctx);
    rb_base_record_direct_light(it, b, cmd);
    return true;
}

/* Seed 003's Transparency: the blended instances sorted back to front by their centres'
 * distance from this frame's camera (per object: the triangles of one object blend in their
 * index order, and objects that interpenetrate or overlap out of that order blend in the wrong
 * order where they do), drawn over the G-buffer's depth. */
static void record_transparency(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd)
{
    struct rb_frame *frame = &it->frame;
    const struct rb_scene_pose *pose = it->cur.pose;
    struct rb_vec3 eye = it->cur.camera.position;
    for (uint32_t k = 0; k < b->blend_count; k++) {
        const float *c = &b->blend_centres[k * 3];
        const struct rb_mat4 *m = &pose->node_world[pose->instances[b->blend_instances[k]].node];
        struct rb_vec3 d = rb_v3_sub(rb_mat4_point(m, rb_v3(c[0], c[1], c[2])), eye);
        b->blend_sort[k] = (struct rb_transparency_sort){rb_v3_dot(d, d), k};
    }
    qsort(b->blend_sort, b->blend_count, sizeof(*b->blend_sort), farther_first);
    for (uint32_t k = 0; k < b->blend_count; k++)
        b->blend_order[k] = b->blend_draws[b->blend_sort[k].draw];
    const struct rb_gpu_access uses[] = {
        {.buffer = &frame->globals, .use = RB_GPU_GRAPHICS_UNIFORM},
        {.buffer = &it->slot->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->indices, .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.buffer = &frame->lights, .use = RB_GPU_FRAGMENT_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->depth, .use = RB_GPU_DEPTH_ATTACHMENT},
        {.image = &frame->transparency, .use = RB_GPU_COLOR_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "transparency", uses, COUNT(uses));
    rb_pass_transparency_record(b->transparency, cmd, frame, it->slot, b->blend_order,
                                b->blend_count);
    rb_integrator_pass_end(it, cmd);
}

/* The output pass's non-finite counter is its own: it zeroes it, orders that before its shader
 * and makes it visible to the host. */
void rb_base_record_output(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_gpu_image *light, const struct rb_gpu_image *stats)
{
    struct rb_frame *frame = &it->frame;
    bool has_transparency = b->blend_count > 0;
    if (has_transparency)
        record_transparency(it, b, cmd);
    const struct rb_gpu_image *gb = frame->gbuffer;
    struct rb_gpu_buffer *target =
        frame->readback_device.buffer ? &frame->readback_device : &frame->readback;
    struct rb_gpu_access output[8 + 1 + RB_BDPT_LIGHT_COUNT + 2] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = frame->beauty, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->direct, .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_ALBEDO], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COMPUTE_READ},
        {.buffer = target, .use = RB_GPU_COMPUTE_WRITE},
        {.image = &gb[RB_GB_SPECULAR], .use = RB_GPU_COMPUTE_READ},
    };
    uint32_t count = 9;
    for (uint32_t i = 0; light && i < RB_BDPT_LIGHT_COUNT; i++)
        output[count++] = (struct rb_gpu_access){.image = &light[i], .use = RB_GPU_COMPUTE_READ};
    if (stats)
        output[count++] = (struct rb_gpu_access){.image = stats, .use = RB_GPU_COMPUTE_READ};
    if (has_transparency)
        output[count++] =
            (struct rb_gpu_access){.image = &frame->transparency, .use = RB_GPU_COMPUTE_READ};
    rb_integrator_pass_begin(it, cmd, "output", output, count);
    rb_pass_output_record(b->output, cmd, frame, target, light, stats, has_transparency);
    rb_integrator_pass_end(it, cmd);
    if (target == &frame->readback)
        return;
    /* A discrete GPU: one copy across the bus by the copy engine, rather than every shader
     * invocation's writes (at 1920x1080 on an H200, the output pass took 47 ms writing the
     * host-visible buffer itself). */
    struct rb_gpu_access copy[2] = {
        {.buffer = target, .use = RB_GPU_TRANSFER_READ},
        {.buffer = &frame->readback, .use = RB_GPU_TRANSFER_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "readback", copy, 2);
    vkCmdCopyBuffer(cmd, target->buffer, frame->readback.buffer, 1,
                    &(VkBufferCopy){.size = frame->readback.size});
    rb_integrator_pass_end(it, cmd);
}
