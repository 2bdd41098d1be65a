/* The direct integrator: animate -> gbuffer -> shadow -> direct -> output. Direct light only,
 * the baseline the global-illumination integrators add to (DESIGN.md "direct"). */
#include "integrators/integrators_int.h"

#include <stdlib.h>
#include <string.h>

#define MAX_CLIPS 64

struct rb_integrator {
    struct rb_gpu *gpu;
    const struct rb_job *job;
    const struct rb_scene *scene;
    struct rb_scene_setup setup;
    bool has_env_map;
    uint32_t clips[MAX_CLIPS];
    struct rb_anim_selection sel;
    struct rb_moment cur, prev;
    struct rb_frame frame;
    bool has_last;
    int last_frame; /* the frame whose vertices are in its parity's slot */

    struct rb_pass_animate *animate;
    struct rb_pass_gbuffer *gbuffer;
    struct rb_pass_shadow *shadow;
    struct rb_pass_direct *direct;
    struct rb_pass_output *output;

    /* the frame being recorded */
    struct rb_frame_slot *cur_slot, *prev_slot;
    bool need_prev;
};

static void record_animate(struct rb_integrator *it, VkCommandBuffer cmd)
{
    /* The previous frame's vertices are recomputed unless this run just made them; both ways
     * give the same bits, so the output does not depend on how the range was chunked. */
    if (it->need_prev)
        rb_pass_animate_record(it->animate, cmd, &it->frame, it->prev_slot);
    rb_pass_animate_record(it->animate, cmd, &it->frame, it->cur_slot);
}

static void record_gbuffer(struct rb_integrator *it, VkCommandBuffer cmd)
{
    rb_pass_gbuffer_record(it->gbuffer, cmd, &it->frame, it->cur_slot, it->prev_slot);
}

static void record_shadow(struct rb_integrator *it, VkCommandBuffer cmd)
{
    rb_pass_shadow_record(it->shadow, cmd, &it->frame, it->cur_slot);
}

static void record_direct(struct rb_integrator *it, VkCommandBuffer cmd)
{
    rb_pass_direct_record(it->direct, cmd, &it->frame);
}

static void record_output(struct rb_integrator *it, VkCommandBuffer cmd)
{
    rb_pass_output_record(it->output, cmd, &it->frame);
}

/* The frame, in order. Each step is one timed pass, followed by a full barrier. */
static const struct {
    const char *name;
    void (*record)(struct rb_integrator *it, VkCommandBuffer cmd);
} steps[] = {
    {"animate", record_animate}, {"gbuffer", record_gbuffer}, {"shadow", record_shadow},
    {"direct", record_direct},   {"output", record_output},
};

static unsigned slot_of(int frame)
{
    return (unsigned)frame & 1u;
}

enum rb_status rb_integrator_create(const struct rb_integrator_desc *desc,
                                    struct rb_integrator **out, struct rb_err *err)
{
    enum rb_integrator_kind kind = desc->job->integrator.name;
    if (kind != RB_INTEGRATOR_DIRECT && kind != RB_INTEGRATOR_DEFAULT)
        return rb_errf(err, RB_E_UNSUPPORTED, "integrator '%s' is not implemented yet",
                       rb_integrator_name(kind));
    struct rb_integrator *it = calloc(1, sizeof(*it));
    if (!it)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    it->gpu = desc->gpu;
    it->job = desc->job;
    it->scene = desc->scene;
    it->has_env_map = desc->env_rgba != NULL;
    it->cur.setup = &it->setup;
    it->prev.setup = &it->setup;
    uint32_t clip_count = 0;
    enum rb_status st = RB_OK;
    if (desc->setup)
        it->setup = *desc->setup;
    else
        st = rb_scene_setup_init(desc->job, desc->scene, desc->env_rgba, desc->env_width_px,
                                 desc->env_height_px, &it->setup, err);
    if (st == RB_OK)
        st = rb_scene_select_clips(desc->scene, desc->job, it->clips, MAX_CLIPS, &clip_count, err);
    if (st)
        goto fail;
    if (it->setup.punctual_count == 0 && !it->setup.has_default_light &&
        (it->setup.has_emitters || it->setup.has_environment))
        rb_log(RB_LOG_WARN,
               "the direct integrator lights surfaces with punctual lights only, and this scene "
               "is lit by %s: they show, but light nothing (bdpt or reference light with them)",
               it->setup.has_emitters && it->setup.has_environment
                   ? "emissive surfaces and the environment"
               : it->setup.has_emitters ? "emissive surfaces"
                                        : "the environment");
    it->sel = (struct rb_anim_selection){
        .clips = it->clips,
        .clip_count = clip_count,
        .offset_s = desc->job->animation.offset_s,
        .speed = desc->job->animation.speed,
        .loop = desc->job->animation.loop,
    };
    if ((st = rb_scene_pose_create(desc->scene, &it->cur.pose, err)) ||
        (st = rb_scene_pose_create(desc->scene, &it->prev.pose, err)))
        goto fail;
    double t0 = desc->job->frame_start / desc->job->rate_fps;
    if ((st = rb_moment_evaluate(desc->job, desc->scene, &it->sel, t0, &it->cur, err)))
        goto fail;
    if ((st = rb_frame_init(desc->gpu, desc, &it->cur, &it->frame, err)))
        goto fail;
    if ((st = rb_pass_animate_create(desc->gpu, &it->animate, err)) ||
        (st = rb_pass_gbuffer_create(desc->gpu, &it->gbuffer, err)) ||
        (st = rb_pass_shadow_create(desc->gpu, &it->shadow, err)) ||
        (st = rb_pass_direct_create(desc->gpu, &it->direct, err)) ||
        (st = rb_pass_output_create(desc->gpu, &it->output, err)))
        goto fail;
    *out = it;
    return RB_OK;
fail:
    rb_integrator_destroy(it);
    return st;
}

enum rb_status rb_integrator_render(struct rb_integrator *it, int frame_index,
                                    struct rb_frame_result *out, struct rb_err *err)
{
    struct rb_gpu *gpu = it->gpu;
    struct rb_frame *frame = &it->frame;
    double rate = it->job->rate_fps;
    double t = frame_index / rate, t_prev = (frame_index - 1) / rate;
    it->cur_slot = &frame->slots[slot_of(frame_index)];
    it->prev_slot = &frame->slots[slot_of(frame_index - 1)];
    it->need_prev = !(it->has_last && it->last_frame == frame_index - 1);

    enum rb_status st = rb_moment_evaluate(it->job, it->scene, &it->sel, t_prev, &it->prev, err);
    if (st == RB_OK)
        st = rb_moment_evaluate(it->job, it->scene, &it->sel, t, &it->cur, err);
    if (st)
        return st;
    if (it->cur.light_count != frame->light_count)
        return rb_errf(err, RB_E_INVALID, "the number of lights changed from %u to %u",
                       frame->light_count, it->cur.light_count);
    /* Host-visible inputs for both slots and the frame, written before the submit. */
    if (it->need_prev)
        rb_frame_write_slot(frame, it->scene, &it->prev, it->prev_slot);
    rb_frame_write_slot(frame, it->scene, &it->cur, it->cur_slot);
    rb_frame_write_globals(frame, it->job, frame_index, &it->cur, &it->prev, it->has_env_map);
    it->has_last = false; /* until this frame completes */

    if ((st = rb_gpu_begin(gpu, err)))
        return st;
    for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]); i++) {
        rb_gpu_pass_begin(gpu, gpu->cmd, steps[i].name);
        steps[i].record(it, gpu->cmd);
        rb_gpu_barrier(gpu->cmd);
        rb_gpu_pass_end(gpu, gpu->cmd);
    }

    if ((st = rb_gpu_submit_wait(gpu, err)))
        return st;
    it->has_last = true;
    it->last_frame = frame_index;

    double ms[RB_GPU_MAX_PASSES];
    if ((st = rb_gpu_pass_times(gpu, ms, err)))
        return st;
    memset(out, 0, sizeof(*out));
    out->frame = frame_index;
    out->time_s = t;
    out->width_px = frame->width_px;
    out->height_px = frame->height_px;
    out->pixels = frame->readback.mapped;
    out->pass_count = gpu->pass_count;
    for (uint32_t i = 0; i < gpu->pass_count; i++) {
        rb_strlcpy(out->passes[i].name, gpu->pass_names[i], sizeof(out->passes[i].name));
        out->passes[i].gpu_ms = ms[i];
    }
    struct rb_mat4 proj = rb_frame_projection(frame, &it->cur.camera);
    out->world_to_camera = it->cur.camera.world_to_camera;
    out->world_to_ndc = rb_mat4_mul(&proj, &it->cur.camera.world_to_camera);
    out->nonfinite_count = rb_pass_output_nonfinite_count(it->output);
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
    rb_pass_output_destroy(it->output);
    rb_pass_direct_destroy(it->direct);
    rb_pass_shadow_destroy(it->shadow);
    rb_pass_gbuffer_destroy(it->gbuffer);
    rb_pass_animate_destroy(it->animate);
    rb_frame_release(it->gpu, &it->frame);
    rb_scene_pose_destroy(it->prev.pose);
    rb_scene_pose_destroy(it->cur.pose);
    free(it);
}
