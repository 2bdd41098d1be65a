/* Integrators: a frame as an ordered list of passes over shared frame resources. `direct` is
 * the baseline every other integrator adds to. The caller writes the result (lib/io). */
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
};

struct rb_pass_timing {
    char name[32];
    double gpu_ms;
};

/* What one frame produced. pixels holds RB_OUT_FLOATS floats per pixel in RB_OUT_* order
 * (shaders/common/shared.h), rows top to bottom; valid until the next render or destroy. */
struct rb_frame_result {
    int frame;
    double time_s;
    uint32_t width_px, height_px;
    const float *pixels;
    struct rb_pass_timing passes[RB_GPU_MAX_PASSES];
    uint32_t pass_count;
    struct rb_mat4 world_to_camera, world_to_ndc; /* column-major; NDC as Vulkan: y down, z 0..1 */
    uint32_t nonfinite_count; /* NaN or infinite floats in pixels (all layers); 0 when clean */
};

/* Creates the integrator the job names, uploading the scene. RB_E_UNSUPPORTED for an
 * integrator that does not exist yet; RB_E_OVERFLOW-free: light lists that do not fit are
 * errors naming the counts. */
enum rb_status rb_integrator_create(const struct rb_integrator_desc *desc,
                                    struct rb_integrator **out, struct rb_err *err);

/* Renders one frame (time = frame / rate) and reads it back. Frames may come in any order; the
 * result of a frame never depends on which frames were rendered before it. A frame with NaN or
 * infinite values is still a result: it is counted in nonfinite_count and logged as a warning. */
enum rb_status rb_integrator_render(struct rb_integrator *it, int frame,
                                    struct rb_frame_result *out, struct rb_err *err);

void rb_integrator_destroy(struct rb_integrator *it);

#endif
