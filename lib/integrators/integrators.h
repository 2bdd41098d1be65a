/* Integrators: one frame driver (driver.c) runs every GPU integrator. An integrator is an ops
 * table (direct.c; bdpt and hybrid join the same way) with its own resources and the ordered
 * passes of its frame; the driver evaluates the moment, fills the frame slots, records,
 * submits, groups the pass timings and fills the result. `direct` is the baseline every other
 * integrator adds to. The caller writes the result (lib/render). */
#ifndef RB_INTEGRATORS_INTEGRATORS_H
#define RB_INTEGRATORS_INTEGRATORS_H

#include "gpu/gpu.h"
#include "job/job.h"
#include "scene/scene.h"

/* Room for the direct integrator's emitter samples (RB_SCENE_EMITTER_LIGHTS_MAX cubes of 6) beside
 * two point lights' cubes and a few spot or directional lights. */
#define RB_MAX_SHADOW_LAYERS 64

struct rb_integrator;

struct rb_integrator_desc {
    const struct rb_job *job;     /* borrowed; must outlive the integrator */
    const struct rb_scene *scene; /* borrowed; must outlive the integrator */
    struct rb_gpu *gpu;           /* borrowed */
    const float *env_rgba;        /* equirectangular RGBA, or NULL for the job's uniform color;
                                   * borrowed, must outlive the integrator */
    uint32_t env_width_px, env_height_px;
    const struct rb_scene_setup *setup; /* borrowed, or NULL: the integrator decides its own */
    uint32_t history_frames; /* 0: the integrator's own; more: keep (and warm up) this many
                              * earlier frames (tests of the history contract) */
};

/* Creates the integrator the job names, uploading the scene. RB_E_UNSUPPORTED for an
 * integrator that does not exist yet; light lists that do not fit are errors naming the
 * counts. */
enum rb_status rb_integrator_create(const struct rb_integrator_desc *desc,
                                    struct rb_integrator **out, struct rb_err *err);

/* How many earlier frames a frame's state depends on (direct: 1, its motion vectors read the
 * previous frame's vertices; bdpt: its cache count - 1, at least 1). */
uint32_t rb_integrator_history_frames(const struct rb_integrator *it);

/* How many warm-up frames rendering frame would render first (frames frame - n to frame - 1):
 * history_frames when frame does not follow the last frame rendered, else 0. */
uint32_t rb_integrator_warmup_frames(const struct rb_integrator *it, int frame);

/* Renders one frame (time = frame / rate) and reads it back.
 * The contract of history. A frame does depend on earlier ones: bdpt's output reconstructs its
 * indirect light from the temporal caches the frames before it wrote. What it may depend on is
 * bounded: the output of frame f is a function of the job and of frames f - history_frames to f
 * (their moments, and what their passes computed), nothing earlier and nothing about how the
 * run got there. An integrator keeps that promise by holding no state a frame reads that a
 * frame more than history_frames back wrote (bdpt: a cache counts only while it is one of the
 * last l frames', by the frame it records; a frame before the job file's first frame,
 * job->sequence_start, fills none when it is only a warm-up). The driver keeps the rest: when
 * the frame before this one was not the last rendered (the first frame of a run or of a chunk,
 * a jump in a frame list, --resume after a kill), it first renders the history_frames frames
 * before it as warm-up frames (ctx.is_warmup), which record what later frames read and write
 * nothing; so any chunk of a sequence renders the same bits as the same frames of a whole run,
 * beauty, layers and sidecars alike. */
enum rb_status rb_integrator_render(struct rb_integrator *it, int frame,
                                    struct rb_frame_result *out, struct rb_err *err);

void rb_integrator_destroy(struct rb_integrator *it);

#endif
