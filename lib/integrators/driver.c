/* The frame driver: what every GPU integrator shares. Creation evaluates the job's setup, the
 * animation clips and the first moment, builds the frame resources (frame.c) with one slot per
 * frame of history plus one, and lets the integrator (its ops table) add its own. Each frame it
 * evaluates the moment and the one before it, writes the frame's slot and globals, records the
 * integrator's passes (timed, each preceded by the barriers derived from what it and the
 * passes before it declared: lib/gpu/barrier.c), makes the readback visible to the host,
 * submits, waits, and groups the pass timings by name. A frame whose predecessor was not the
 * last rendered is preceded by warm-up frames (the history contract in integrators.h). */
#include "integrators/integrators_int.h"

#include <stdlib.h>
#include <string.h>

#define MAX_CLIPS 64

static const struct rb_integrator_ops *ops_for(enum rb_integrator_kind kind)
{
    switch (kind) {
    case RB_INTEGRATOR_DIRECT: return &rb_integrator_direct;
    case RB_INTEGRATOR_BDPT: return &rb_integrator_bdpt;
    case RB_INTEGRATOR_HYBRID: return &rb_integrator_hybrid;
    default: return NULL;
    }
}

enum rb_status rb_integrator_create(const struct rb_integrator_desc *desc,
                                    struct rb_integrator **out, struct rb_err *err)
{
    enum rb_integrator_kind kind = rb_integrator_resolve(desc->job->integrator.name);
    const struct rb_integrator_ops *ops = ops_for(kind);
    if (!ops)
        return rb_errf(err, RB_E_UNSUPPORTED, "integrator '%s' is not implemented yet",
                       rb_integrator_name(kind));
    return rb_integrator_create_with(desc, ops, out, err);
}

enum rb_status rb_integrator_create_with(const struct rb_integrator_desc *desc,
                                         const struct rb_integrator_ops *ops,
                                         struct rb_integrator **out, struct rb_err *err)
{
    struct rb_integrator *it = calloc(1, sizeof(*it));
    if (!it)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    it->ops = ops;
    it->gpu = desc->gpu;
    it->job = desc->job;
    it->scene = desc->scene;
    it->has_env_map = desc->env_rgba != NULL;
    it->env_rgba = desc->env_rgba;
    it->env_width_px = desc->env_width_px;
    it->env_height_px = desc->env_height_px;
    it->cur.setup = &it->setup;
    it->prev.setup = &it->setup;
    it->cur.has_emitter_lights = ops->has_emitter_lights;
    it->prev.has_emitter_lights = ops->has_emitter_lights;
    it->history_frames = ops->history_frames(desc->job);
    if (desc->history_frames > it->history_frames)
        it->history_frames = desc->history_frames;
    uint32_t clip_count = 0;
    enum rb_status st = RB_OK;
    if (desc->setup)
        it->setup = *desc->setup;
    else
        st = rb_scene_setup_init(desc->job, desc->scene, desc->env_rgba, desc->env_width_px,
                                 desc->env_height_px, &it->setup, err);
    if (st == RB_OK && !(it->clips = calloc(MAX_CLIPS, sizeof(*it->clips))))
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
    if (st == RB_OK)
        st = rb_scene_select_clips(desc->scene, desc->job, it->clips, MAX_CLIPS, &clip_count, err);
    if (st)
        goto fail;
    it->sel = (struct rb_anim_selection){
        .clips = it->clips,
        .clip_count = clip_count,
        .offset_s = desc->job->animation.offset_s,
        .speed = desc->job->animation.speed,
        .loop = desc->job->animation.loop,
    };
    if (!ops->has_emitter_lights && rb_frame_has_blended(desc->scene)) {
        it->cur.has_layer_lights = true;
        it->cur.layer_env_count = rb_layer_env_lights(desc->job, desc->env_rgba, desc->env_width_px,
                                                      desc->env_height_px, it->cur.layer_env);
        it->prev.has_layer_lights = true;
        it->prev.layer_env_count = it->cur.layer_env_count;
        memcpy(it->prev.layer_env, it->cur.layer_env, sizeof(it->cur.layer_env));
    }
    if ((st = rb_scene_pose_create(desc->scene, &it->cur.pose, err)) ||
        (st = rb_scene_pose_create(desc->scene, &it->prev.pose, err)) ||
        (st = rb_moment_lights_init(desc->job, desc->scene, &it->cur, err)) ||
        (st = rb_moment_lights_init(desc->job, desc->scene, &it->prev, err)))
        goto fail;
    double t0 = desc->job->frame_start / desc->job->rate_fps;
    if ((st = rb_moment_evaluate(desc->job, desc->scene, &it->sel, t0, &it->cur, err)) ||
        (st = rb_frame_init(desc->gpu, desc, &it->cur,
                            (ops->slot_frames ? ops->slot_frames(desc->job) : it->history_frames) +
                                1,
                            &it->frame, err)) ||
        (st = ops->create(it, &it->state, err)))
        goto fail;
    *out = it;
    return RB_OK;
fail:
    rb_integrator_destroy(it);
    return st;
}

uint32_t rb_integrator_history_frames(const struct rb_integrator *it)
{
    return it->history_frames;
}

void rb_integrator_pass_begin(struct rb_integrator *it, VkCommandBuffer cmd, const char *name,
                              const struct rb_gpu_access *uses, uint32_t use_count)
{
    /* Inside the timed pass: the time a pass waits for the ones before it is its own. */
    rb_gpu_pass_begin(it->gpu, cmd, name);
    rb_gpu_barriers_record(&it->barriers, cmd, uses, use_count);
}

void rb_integrator_pass_end(struct rb_integrator *it, VkCommandBuffer cmd)
{
    rb_gpu_pass_end(it->gpu, cmd);
}

static struct rb_frame_slot *slot_of(struct rb_integrator *it, int frame)
{
    uint32_t n = it->frame.slot_count;
    /* frame mod n for negative frames too (a warm-up before frame 0) */
    return &it->frame.slots[(uint32_t)(((int64_t)frame % n + n) % n)];
}

/* The frame's passes grouped by name, in the order each name first ran. */
static enum rb_status group_passes(struct rb_integrator *it, struct rb_err *err)
{
    const struct rb_gpu *gpu = it->gpu;
    it->group_count = 0;
    for (uint32_t i = 0; i < gpu->pass_count; i++) {
        const struct rb_gpu_pass *p = &gpu->passes[i];
        uint32_t g = 0;
        while (g < it->group_count && strcmp(it->groups[g].name, p->name) != 0)
            g++;
        if (g == it->group_count) {
            if (g == it->group_cap) {
                uint32_t cap = it->group_cap ? 2 * it->group_cap : 16;
                struct rb_pass_time *n = realloc(it->groups, cap * sizeof(*n));
                if (!n)
                    return rb_errf(err, RB_E_NOMEM, "out of memory for pass timings");
                it->groups = n;
                it->group_cap = cap;
            }
            it->groups[g] = (struct rb_pass_time){.count = 0};
            rb_strlcpy(it->groups[g].name, p->name, sizeof(it->groups[g].name));
            it->group_count++;
        }
        it->groups[g].gpu_ms += p->gpu_ms;
        it->groups[g].count++;
    }
    return RB_OK;
}

/* One frame: warm-up frames record what later frames read and are not read back. */
static enum rb_status render_one(struct rb_integrator *it, int frame_index, bool is_warmup,
                                 struct rb_err *err)
{
    struct rb_gpu *gpu = it->gpu;
    struct rb_frame *frame = &it->frame;
    double rate = it->job->rate_fps;
    double t = frame_index / rate, t_prev = (frame_index - 1) / rate;
    enum rb_status st = rb_moment_evaluate(it->job, it->scene, &it->sel, t_prev, &it->prev, err);
    if (st == RB_OK)
        st = rb_moment_evaluate(it->job, it->scene, &it->sel, t, &it->cur, err);
    if (st)
        return st;
    if (it->cur.light_count != frame->light_count)
        return rb_errf(err, RB_E_INVALID, "the number of lights changed from %u to %u",
                       frame->light_count, it->cur.light_count);
    struct rb_frame_ctx ctx = {
        .frame = frame_index,
        .is_warmup = is_warmup,
        .cur = slot_of(it, frame_index),
        .prev = slot_of(it, frame_index - 1),
        .moment = &it->cur,
    };
    /* Host-visible inputs of the frame's slot and globals, written before the submit. */
    rb_frame_write_slot(frame, it->scene, &it->cur, ctx.cur);
    rb_frame_write_globals(frame, it->job, frame_index, &it->cur, &it->prev, it->has_env_map);
    it->has_last = false; /* until this frame completes */
    it->slot = ctx.cur;
    if ((it->ops->prepare && (st = it->ops->prepare(it, it->state, &ctx, err))) ||
        (st = rb_gpu_begin(gpu, err)))
        return st;
    it->ops->record(it, it->state, gpu->cmd, &ctx);
    if (!is_warmup) /* the caller reads the pixels once the fence has signalled */
        rb_gpu_barriers_record(
            &it->barriers, gpu->cmd,
            &(struct rb_gpu_access){.buffer = &frame->readback, .use = RB_GPU_HOST_READ}, 1);
    if ((st = rb_gpu_submit_wait(gpu, err)) || (st = rb_gpu_barriers_check(&it->barriers, err)))
        return st;
    it->has_last = true;
    it->last_frame = frame_index;
    return RB_OK;
}

uint32_t rb_integrator_warmup_frames(const struct rb_integrator *it, int frame)
{
    return it->has_last && it->last_frame == frame - 1 ? 0 : it->history_frames;
}

enum rb_status rb_integrator_render(struct rb_integrator *it, int frame_index,
                                    struct rb_frame_result *out, struct rb_err *err)
{
    enum rb_status st = RB_OK;
    for (uint32_t k = rb_integrator_warmup_frames(it, frame_index); k > 0 && st == RB_OK; k--)
        st = render_one(it, frame_index - (int)k, true, err);
    if (st || (st = render_one(it, frame_index, false, err)))
        return st;
    if ((st = rb_gpu_pass_times(it->gpu, err)) || (st = group_passes(it, err)))
        return st;
    const struct rb_frame *frame = &it->frame;
    *out = (struct rb_frame_result){
        .frame = frame_index,
        .time_s = frame_index / it->job->rate_fps,
        .width_px = frame->width_px,
        .height_px = frame->height_px,
        .pixels = frame->readback.mapped,
        .floats_per_pixel = frame->readback_floats,
        .layer_mask = frame->layer_mask,
        .passes = it->groups,
        .pass_count = it->group_count,
        .world_to_camera = it->cur.camera.world_to_camera,
    };
    struct rb_mat4 proj = rb_frame_projection(frame, &it->cur.camera);
    out->world_to_ndc = rb_mat4_mul(&proj, &it->cur.camera.world_to_camera);
    if (it->ops->collect)
        it->ops->collect(it, it->state, out);
    if (out->nonfinite_count)
        rb_log(RB_LOG_WARN, "frame %d: %u non-finite values (NaN or Inf) in the output",
               frame_index, out->nonfinite_count);
    return RB_OK;
}

void rb_integrator_destroy(struct rb_integrator *it)
{
    if (!it)
        return;
    if (it->gpu && it->gpu->device)
        vkDeviceWaitIdle(it->gpu->device);
    if (it->ops && it->state)
        it->ops->destroy(it, it->state);
    rb_gpu_barriers_release(&it->barriers);
    rb_frame_release(it->gpu, &it->frame);
    rb_scene_pose_destroy(it->prev.pose);
    rb_scene_pose_destroy(it->cur.pose);
    free(it->prev.lights);
    free(it->cur.lights);
    free(it->groups);
    free(it->clips);
    free(it);
}
