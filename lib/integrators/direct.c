/* The direct integrator: animate -> gbuffer -> shadow -> direct -> output. Direct light only,
 * the baseline the global-illumination integrators add to (DESIGN.md "direct"). Its history is
 * one frame: the G-buffer's motion vectors read the previous frame's world vertices. */
#include "integrators/integrators_int.h"

#include <stdlib.h>

struct direct {
    struct rb_pass_animate *animate;
    struct rb_pass_gbuffer *gbuffer;
    struct rb_pass_shadow *shadow;
    struct rb_pass_direct *direct;
    struct rb_pass_output *output;
};

static uint32_t history_frames(const struct rb_job *job)
{
    (void)job;
    return 1;
}

static void destroy(struct rb_integrator *it, void *state)
{
    (void)it;
    struct direct *d = state;
    rb_pass_output_destroy(d->output);
    rb_pass_direct_destroy(d->direct);
    rb_pass_shadow_destroy(d->shadow);
    rb_pass_gbuffer_destroy(d->gbuffer);
    rb_pass_animate_destroy(d->animate);
    free(d);
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    const struct rb_scene_setup *s = &it->setup;
    if (s->punctual_count == 0 && !s->has_default_light && (s->has_emitters || s->has_environment))
        rb_log(RB_LOG_WARN,
               "the direct integrator lights surfaces with punctual lights only, and this scene "
               "is lit by %s: they show, but light nothing (bdpt or reference light with them)",
               s->has_emitters && s->has_environment ? "emissive surfaces and the environment"
               : s->has_emitters                     ? "emissive surfaces"
                                                     : "the environment");
    struct direct *d = calloc(1, sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st;
    if ((st = rb_pass_animate_create(it->gpu, &d->animate, err)) ||
        (st = rb_pass_gbuffer_create(it->gpu, &d->gbuffer, err)) ||
        (st = rb_pass_shadow_create(it->gpu, &d->shadow, err)) ||
        (st = rb_pass_direct_create(it->gpu, &d->direct, err)) ||
        (st = rb_pass_output_create(it->gpu, &d->output, err))) {
        destroy(it, d);
        return st;
    }
    *state = d;
    return RB_OK;
}

/* Each pass's declaration lists every frame resource its record function binds, draws with
 * or copies, with how (the shaders' stages and readonly/writeonly qualifiers); the driver
 * derives the barriers between the passes from them. The output pass's non-finite counter is
 * its own: it zeroes it, orders that before its shader and makes it visible to the host. */
static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct direct *d = state;
    struct rb_frame *frame = &it->frame;
    const struct rb_frame_slot *cur = ctx->cur, *prev = ctx->prev;
    const struct rb_gpu_image *gb = frame->gbuffer;

    const struct rb_gpu_access animate[] = {
        {.buffer = &frame->src_vertices, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->morph_deltas, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->instances, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->joints, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->weights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &cur->vertices, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "animate", animate, COUNT(animate));
    rb_pass_animate_record(d->animate, cmd, frame, cur);
    rb_integrator_pass_end(it, cmd);
    if (ctx->is_warmup)
        return; /* a later frame reads this frame's world vertices, nothing else */

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
        {.image = &frame->depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    _Static_assert(RB_GBUFFER_COLOR_COUNT == 6, "every G-buffer attachment is declared");
    rb_integrator_pass_begin(it, cmd, "gbuffer", gbuffer, COUNT(gbuffer));
    rb_pass_gbuffer_record(d->gbuffer, cmd, frame, cur, prev);
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access shadow[] = {
        {.buffer = &cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = &frame->indices, .use = RB_GPU_INDEX_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &frame->shadow_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "shadow", shadow, COUNT(shadow));
    rb_pass_shadow_record(d->shadow, cmd, frame, cur);
    rb_integrator_pass_end(it, cmd);

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
    rb_pass_direct_record(d->direct, cmd, frame);
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access output[] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = frame->beauty, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->direct, .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_ALBEDO], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->readback, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "output", output, COUNT(output));
    rb_pass_output_record(d->output, cmd, frame, NULL);
    rb_integrator_pass_end(it, cmd);
}

static void collect(struct rb_integrator *it, void *state, struct rb_frame_result *out)
{
    (void)it;
    const struct direct *d = state;
    out->nonfinite_count = rb_pass_output_nonfinite_count(d->output);
}

const struct rb_integrator_ops rb_integrator_direct = {
    .name = "direct",
    .history_frames = history_frames,
    .create = create,
    .record = record,
    .collect = collect,
    .destroy = destroy,
};
