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

static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct direct *d = state;
    struct rb_frame *frame = &it->frame;
    rb_integrator_pass_begin(it, cmd, "animate");
    rb_pass_animate_record(d->animate, cmd, frame, ctx->cur);
    rb_integrator_pass_end(it, cmd);
    if (ctx->is_warmup)
        return; /* a later frame reads this frame's world vertices, nothing else */
    rb_integrator_pass_begin(it, cmd, "gbuffer");
    rb_pass_gbuffer_record(d->gbuffer, cmd, frame, ctx->cur, ctx->prev);
    rb_integrator_pass_end(it, cmd);
    rb_integrator_pass_begin(it, cmd, "shadow");
    rb_pass_shadow_record(d->shadow, cmd, frame, ctx->cur);
    rb_integrator_pass_end(it, cmd);
    rb_integrator_pass_begin(it, cmd, "direct");
    rb_pass_direct_record(d->direct, cmd, frame);
    rb_integrator_pass_end(it, cmd);
    rb_integrator_pass_begin(it, cmd, "output");
    rb_pass_output_record(d->output, cmd, frame);
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
