/* Private to lib/integrators: the frame driver's state, the ops table an integrator fills, and
 * building and updating the frame resources the passes share (frame.c). */
#ifndef RB_INTEGRATORS_INTEGRATORS_INT_H
#define RB_INTEGRATORS_INTEGRATORS_INT_H

#include "integrators/integrators.h"
#include "passes/passes.h"

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* The environment's directions that light the blended layers of bdpt and hybrid (one shadow
 * layer each). */
#define RB_LAYER_ENV_LIGHTS 12

/* Everything the CPU knows about one time: the pose, the camera, the lights. */
struct rb_moment {
    const struct rb_scene_setup *setup; /* the job's, borrowed from the integrator */
    struct rb_scene_pose *pose;
    struct rb_camera camera;
    struct rb_world_light *lights; /* light_capacity of them (rb_moment_lights_init) */
    uint32_t light_count, light_capacity;
    bool has_emitter_lights; /* the emitters' point samples follow the lights (the ops' flag) */
    /* Lights for the blended layers alone (the transparency pass), after all the others: the
     * emitters' point samples and layer_env, set when the integrator has no emitter lights of
     * its own and the scene has a blended material (bdpt, hybrid). Its passes leave them out:
     * they sample emitters and the environment their own ways. */
    bool has_layer_lights;
    uint32_t layer_light_count; /* the trailing lights that are layer lights */
    struct rb_world_light layer_env[RB_LAYER_ENV_LIGHTS];
    uint32_t layer_env_count; /* rb_layer_env_lights's */
};

/* What the driver hands an integrator's record function: the frame being recorded. */
struct rb_frame_ctx {
    int frame;
    bool is_warmup;                 /* record only what later frames read; nothing is read back */
    struct rb_frame_slot *cur;      /* this frame's slot: frame mod slot_count */
    struct rb_frame_slot *prev;     /* the previous frame's slot, filled when it was rendered */
    const struct rb_moment *moment; /* this frame's camera, lights and pose */
};

/* An integrator: its resources and the ordered passes of its frame. */
struct rb_integrator_ops {
    const char *name;
    /* Whether the emissive surfaces light through the direct pass as point samples
     * (rb_scene_emitter_lights, after the other lights): direct's only light from them; the
     * global-illumination integrators have their own emitter strategies and leave this unset. */
    bool has_emitter_lights;
    /* Earlier frames a frame's state depends on (the history contract in integrators.h). */
    uint32_t (*history_frames)(const struct rb_job *job);
    /* Optional: the earlier frames whose animation slots (vertices) a frame reads, when fewer
     * than history_frames (hybrid: the previous frame's alone); the driver keeps one slot more. */
    uint32_t (*slot_frames)(const struct rb_job *job);
    /* Creates the integrator's own passes and resources once the driver's frame exists. */
    enum rb_status (*create)(struct rb_integrator *it, void **state, struct rb_err *err);
    /* Optional: the frame's CPU work before it is recorded (hybrid: its BVH), which may fail. */
    enum rb_status (*prepare)(struct rb_integrator *it, void *state, const struct rb_frame_ctx *ctx,
                              struct rb_err *err);
    /* Records the frame: each pass between rb_integrator_pass_begin, which declares every
     * resource the pass reads and writes, and rb_integrator_pass_end. Cannot fail. */
    void (*record)(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx);
    /* After the submit: what record's passes counted (e.g. non-finite output values). */
    void (*collect)(struct rb_integrator *it, void *state, struct rb_frame_result *out);
    void (*destroy)(struct rb_integrator *it, void *state);
};

extern const struct rb_integrator_ops rb_integrator_direct;
extern const struct rb_integrator_ops rb_integrator_bdpt;
extern const struct rb_integrator_ops rb_integrator_hybrid;

/* rb_integrator_create with the given ops instead of the job's integrator's (tests drive the
 * driver with integrators of their own). */
enum rb_status rb_integrator_create_with(const struct rb_integrator_desc *desc,
                                         const struct rb_integrator_ops *ops,
                                         struct rb_integrator **out, struct rb_err *err);

/* The driver (driver.c): what every integrator shares. Integrators read it; the driver writes. */
struct rb_integrator {
    const struct rb_integrator_ops *ops;
    void *state; /* the integrator's own */
    struct rb_gpu *gpu;
    const struct rb_job *job;
    const struct rb_scene *scene;
    struct rb_scene_setup setup;
    bool has_env_map;
    const float *env_rgba; /* desc's, borrowed for the integrator's life (the hybrid's bake) */
    uint32_t env_width_px, env_height_px;
    uint32_t history_frames;
    uint32_t *clips;
    struct rb_anim_selection sel;
    struct rb_moment cur, prev;
    struct rb_frame frame;
    bool has_last;
    int last_frame;              /* the last frame rendered (warm-up or not) */
    struct rb_pass_time *groups; /* the last frame's passes, grouped by name */
    uint32_t group_count, group_cap;
    struct rb_gpu_barriers barriers; /* what the passes did, from one frame to the next */
    /* The slot of the frame being recorded (the transparency pass draws its vertices). */
    const struct rb_frame_slot *slot;
};

/* Opens one timed pass of the frame and records the barriers it needs after the passes before
 * it, this frame's and earlier frames': uses (use_count of them) are every frame resource and
 * every resource of the integrator's own that the pass reads or writes, with how (struct
 * rb_gpu_access: read after write, write after read and write after write get a barrier, two
 * reads none). A resource the pass touches and does not declare is not synchronized (tests
 * run with synchronization validation, which reports it). Commands a pass records inside
 * itself (a fill and the barrier to the shader that adds to it) are the pass's own business. */
void rb_integrator_pass_begin(struct rb_integrator *it, VkCommandBuffer cmd, const char *name,
                              const struct rb_gpu_access *uses, uint32_t use_count);
/* Closes the pass opened last. */
void rb_integrator_pass_end(struct rb_integrator *it, VkCommandBuffer cmd);

/* Creates every shared resource for the scene at the job's resolution: geometry, materials,
 * textures, slot_count animation slots, shadow maps (sized for light_count lights of the kinds
 * in lights), environment, G-buffer and readback. All images end in VK_IMAGE_LAYOUT_GENERAL. */
enum rb_status rb_frame_init(struct rb_gpu *gpu, const struct rb_integrator_desc *desc,
                             const struct rb_moment *first, uint32_t slot_count,
                             struct rb_frame *frame, struct rb_err *err);
void rb_frame_release(struct rb_gpu *gpu, struct rb_frame *frame);

/* Whether a material of the scene is blended (glTF alphaMode BLEND): then the frame has a
 * transparency image and the frame's passes end with the transparency pass. */
bool rb_frame_has_blended(const struct rb_scene *scene);

/* The environment as directional lights for the blended layers (struct rb_moment's
 * layer_env): RB_LAYER_ENV_LIGHTS directions spread evenly over the sphere (a Fibonacci
 * lattice), each carrying the environment's light over its cell, the directions nearer it than
 * any other: the radiance integrated over those solid angles, from the map's texels (rgba,
 * equirectangular, w x h; NULL: the job's uniform colour, L 4 pi / N each). Returns their
 * count: 0 for a black environment. */
uint32_t rb_layer_env_lights(const struct rb_job *job, const float *rgba, uint32_t w, uint32_t h,
                             struct rb_world_light out[RB_LAYER_ENV_LIGHTS]);

/* Evaluates animation, camera and lights at time_s. */
/* Allocates m->lights for every light a moment of the job can have: the job's, the scene's and,
 * with m->has_emitter_lights, the emitters' point samples (their count is fixed by the job).
 * m->pose must exist. */
enum rb_status rb_moment_lights_init(const struct rb_job *job, const struct rb_scene *scene,
                                     struct rb_moment *m, struct rb_err *err);
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

/* The scene's triangles as the frame's index buffer lists them (every instance of pose, in
 * instance order, into the world vertex buffer): malloc'd, *count indices; NULL when out of
 * memory. */
uint32_t *rb_frame_world_indices(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                                 uint64_t *count);

/* The camera's projection for the frame's aspect ratio. */
struct rb_mat4 rb_frame_projection(const struct rb_frame *frame, const struct rb_camera *cam);

/* ---- base.c: the passes a rasterizing integrator's frame starts and ends with ------------- */

struct rb_base {
    struct rb_pass_animate *animate;
    struct rb_pass_gbuffer *gbuffer;
    struct rb_pass_shadow *shadow;
    struct rb_pass_direct *direct;
    struct rb_pass_output *output;
    /* The blended instances, with the scene's blended materials alone (else NULL and 0): the
     * pass, and per instance its range of the frame's indices and the centre its order is
     * sorted by (its primitive's bind-pose vertices' mean, in the node's space). */
    struct rb_pass_transparency *transparency;
    struct rb_transparency_draw *blend_draws; /* blend_count, in instance order */
    uint32_t *blend_instances;                /* blend_count: each draw's instance */
    float *blend_centres;                     /* 3 x blend_count */
    struct rb_transparency_sort *blend_sort;  /* blend_count: scratch, per frame */
    struct rb_transparency_draw *blend_order; /* blend_count: the frame's, back to front */
    uint32_t blend_count;
};

enum rb_status rb_base_create(struct rb_integrator *it, struct rb_base *b, struct rb_err *err);
void rb_base_destroy(struct rb_base *b);
/* The frame's G-buffer pass into target (NULL: the frame's own, at pixel centres, the pass
 * "gbuffer"; else "cache_gbuffer"); its shadow maps; its direct light, from the frame's own
 * G-buffer. */
void rb_base_record_gbuffer(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                            const struct rb_frame_ctx *ctx, const struct rb_gbuffer_target *target);
void rb_base_record_shadow(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_frame_ctx *ctx);
void rb_base_record_direct_light(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd);
/* Records animate and, unless the frame is a warm-up, gbuffer, shadow and direct. Returns
 * whether it recorded the frame's passes (false: a warm-up, which records nothing more). */
bool rb_base_record_direct(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_frame_ctx *ctx);
/* Records the animate pass alone (the first of rb_base_record_direct's), for integrators and
 * tools that draw their own views of the frame's world vertices. */
void rb_base_record_animate(struct rb_integrator *it, struct rb_pass_animate *pass,
                            VkCommandBuffer cmd, const struct rb_frame_slot *cur);
/* Records the transparency pass when the scene has blended instances (the pass "transparency":
 * its instances back to front from this frame's camera; DESIGN.md "transparency"), then output.
 * light: NULL, or the RB_BDPT_LIGHT_COUNT images of gathered light; stats: NULL, or the hybrid's
 * samples and tile masks (rb_pass_output_record). */
void rb_base_record_output(struct rb_integrator *it, struct rb_base *b, VkCommandBuffer cmd,
                           const struct rb_gpu_image *light, const struct rb_gpu_image *stats);

/* ---- bdpt.c ------------------------------------------------------------------------------ */

/* The bdpt integrator's own frame resources as its last frame left them (its bundle views; the
 * lists of its last bundle, bundle_count - 1), for tests that look into them; NULL for another
 * integrator. Valid until rb_integrator_destroy. */
const struct rb_bdpt_frame *rb_integrator_bdpt_frame(const struct rb_integrator *it);

/* A device buffer (size 0 is made 16 bytes) and an image (is_array for several layers or
 * layer_views; has_layer_views for layer_views), as the frame's own resources are made. */
enum rb_status rb_frame_buffer(struct rb_gpu *gpu, VkDeviceSize size, VkBufferUsageFlags usage,
                               bool host, const char *name, struct rb_gpu_buffer *out,
                               struct rb_err *err);
enum rb_status rb_frame_image(struct rb_gpu *gpu, uint32_t w, uint32_t h, uint32_t layers,
                              VkFormat format, VkImageUsageFlags usage, bool layer_views,
                              const char *name, struct rb_gpu_image *out, struct rb_err *err);

#endif
