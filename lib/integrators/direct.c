/* The direct integrator: animate -> gbuffer -> shadow -> direct -> output. Direct light only,
 * the baseline the global-illumination integrators add to (DESIGN.md "direct"): from the
 * punctual lights and from the emissive surfaces, which light through fixed point samples with
 * shadow maps (has_emitter_lights, rb_scene_emitter_lights), so that an area-lit room is not
 * black. bdpt and hybrid run the same passes without those samples: they sample the emitters in
 * their own ways, and would count the emitters' light twice. Its history is
 * one frame: the G-buffer's motion vectors read the previous frame's world vertices. */
#include "integrators/integrators_int.h"

#include <stdlib.h>

static uint32_t history_frames(const struct rb_job *job)
{
    (void)job;
    return 1;
}

static void destroy(struct rb_integrator *it, void *state)
{
    (void)it;
    struct rb_base *d = state;
    if (d)
        rb_base_destroy(d);
    free(d);
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    const struct rb_scene_setup *s = &it->setup;
    if (s->punctual_count == 0 && !s->has_default_light && s->has_environment)
        rb_log(RB_LOG_WARN,
               "the direct integrator lights surfaces with punctual lights and emissive surfaces "
               "only, and this scene is lit by the environment: it shows, but lights nothing "
               "(bdpt or reference light with it)");
    struct rb_base *d = calloc(1, sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_base_create(it, d, err);
    if (st) {
        free(d);
        return st;
    }
    *state = d;
    return RB_OK;
}

static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct rb_base *d = state;
    if (rb_base_record_direct(it, d, cmd, ctx))
        rb_base_record_output(it, d, cmd, NULL, NULL);
}

static void collect(struct rb_integrator *it, void *state, struct rb_frame_result *out)
{
    (void)it;
    const struct rb_base *d = state;
    out->nonfinite_count = rb_pass_output_nonfinite_count(d->output);
}

const struct rb_integrator_ops rb_integrator_direct = {
    .name = "direct",
    .has_emitter_lights = true,
    .history_frames = history_frames,
    .create = create,
    .record = record,
    .collect = collect,
    .destroy = destroy,
};
