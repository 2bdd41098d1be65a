/* Private to lib/integrators: building and updating the frame resources the passes share. */
#ifndef RB_INTEGRATORS_INTEGRATORS_INT_H
#define RB_INTEGRATORS_INTEGRATORS_INT_H

#include "integrators/integrators.h"
#include "passes/passes.h"

/* Everything the CPU knows about one time: the pose, the camera, the lights. */
struct rb_moment {
    const struct rb_scene_setup *setup; /* the job's, borrowed from the integrator */
    struct rb_scene_pose *pose;
    struct rb_camera camera;
    struct rb_world_light lights[RB_MAX_LIGHTS];
    uint32_t light_count;
};

/* Creates every shared resource for the scene at the job's resolution: geometry, materials,
 * textures, shadow maps (sized for light_count lights of the kinds in lights), environment,
 * G-buffer and readback. All images end in VK_IMAGE_LAYOUT_GENERAL. */
enum rb_status rb_frame_init(struct rb_gpu *gpu, const struct rb_integrator_desc *desc,
                             const struct rb_moment *first, struct rb_frame *frame,
                             struct rb_err *err);
void rb_frame_release(struct rb_gpu *gpu, struct rb_frame *frame);

/* Evaluates animation, camera and lights at time_s. */
enum rb_status rb_moment_evaluate(const struct rb_job *job, const struct rb_scene *scene,
                                  const struct rb_anim_selection *sel, double time_s,
                                  struct rb_moment *m, struct rb_err *err);

/* Writes a moment's instances, joint matrices and morph weights into a slot. */
void rb_frame_write_slot(struct rb_frame *frame, const struct rb_scene *scene,
                         const struct rb_moment *m, struct rb_frame_slot *slot);

/* Writes globals, lights and shadow views for the current moment (prev gives motion). */
void rb_frame_write_globals(struct rb_frame *frame, const struct rb_job *job, int frame_index,
                            const struct rb_moment *cur, const struct rb_moment *prev,
                            bool has_env_map);

/* The camera's projection for the frame's aspect ratio. */
struct rb_mat4 rb_frame_projection(const struct rb_frame *frame, const struct rb_camera *cam);

#endif
