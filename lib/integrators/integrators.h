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

#define RB_MAX_LIGHTS 64
#define RB_MAX_SHADOW_LAYERS 48

struct rb_integrator;

struct rb_integrator_desc {
    const struct rb_job *job;     /* borrowed; must outlive the integrator */
    const struct rb_scene *scene; /* borrowed; must outlive the integrator */
    struct rb_gpu *gpu;           /* borrowed */
    const float *env_rgba;        /* equirectangular RGBA, or NULL for the job's uniform color */
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
 * previous frame's vertices; an integrator with temporal caches: its cache count - 1). */
uint32_t rb_integrator_history_frames(const struct rb_integrator *it);

/* Renders one frame (time = frame / rate) and reads it back.
 * The contract of history: the state a frame is rendered from is a function of that frame and
 * the history_frames frames before it, nothing earlier. When the frame before this one was not
 * the last rendered (the first frame of a run or of a chunk, or a jump), the driver first
 * renders the history_frames frames before it as warm-up frames, recording what they leave for
 * later frames and writing nothing; so a chunk of a sequence renders the same bits as the same
 * frames of a whole run, whatever the history length. */
enum rb_status rb_integrator_render(struct rb_integrator *it, int frame,
                                    struct rb_frame_result *out, struct rb_err *err);

void rb_integrator_destroy(struct rb_integrator *it);

#endif
