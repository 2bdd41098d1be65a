/* Render passes: one file each, each with create, record and destroy. record cannot fail;
 * everything fallible happens in create. The frame resources the passes share belong to the
 * integrator and are passed in (struct rb_frame). */
#ifndef RB_PASSES_PASSES_H
#define RB_PASSES_PASSES_H

#include "gpu/gpu.h"
#include "scene/scene.h"
#include "shared.h"

_Static_assert(sizeof(struct rb_gpu_globals) == 400, "globals layout");
_Static_assert(sizeof(struct rb_gpu_vertex) == 64, "vertex layout");
_Static_assert(sizeof(struct rb_gpu_instance) == 160, "instance layout");
_Static_assert(sizeof(struct rb_gpu_material) == 80, "material layout");
_Static_assert(sizeof(struct rb_gpu_light) == 64, "light layout");
_Static_assert(sizeof(struct rb_gpu_shadow_view) == 96, "shadow view layout");
_Static_assert(sizeof(struct rb_scene_vertex) == RB_SRC_VERTEX_FLOATS * 4, "source vertex");
_Static_assert(sizeof(struct rb_scene_morph_delta) == RB_MORPH_DELTA_FLOATS * 4, "morph delta");

#define RB_GBUFFER_COLOR_COUNT 6

/* Per-time geometry state: the animate pass fills vertices from instances, joints and weights.
 * Frame f uses slot f mod slot_count (history_frames + 1 slots), so a frame's motion vectors
 * read the previous frame's vertices from the slot that frame filled. */
struct rb_frame_slot {
    struct rb_gpu_buffer instances; /* struct rb_gpu_instance, host-visible */
    struct rb_gpu_buffer joints;    /* mat4, host-visible */
    struct rb_gpu_buffer weights;   /* float, host-visible */
    struct rb_gpu_buffer vertices;  /* struct rb_gpu_vertex, written by animate */
};

struct rb_frame {
    uint32_t width_px, height_px;
    struct rb_gpu_buffer globals; /* struct rb_gpu_globals, host-visible */

    /* static geometry and materials */
    struct rb_gpu_buffer src_vertices; /* struct rb_scene_vertex */
    struct rb_gpu_buffer morph_deltas; /* struct rb_scene_morph_delta */
    struct rb_gpu_buffer indices;      /* uint32, into the world vertex buffers */
    uint32_t index_count;
    struct rb_gpu_buffer materials;                     /* struct rb_gpu_material */
    struct rb_gpu_image srgb_textures, linear_textures; /* RGBA8 arrays, one layer a texture */

    struct rb_frame_slot *slots; /* slot_count of them */
    uint32_t slot_count;
    uint32_t instance_count;
    const struct rb_gpu_instance *instances; /* host copy of the slot being animated */
    uint32_t vertex_count;                   /* world vertices */

    /* lights and shadows */
    struct rb_gpu_buffer lights;       /* struct rb_gpu_light, host-visible */
    struct rb_gpu_buffer shadow_views; /* struct rb_gpu_shadow_view, host-visible */
    uint32_t light_count, shadow_layer_count;
    struct rb_gpu_image shadow_maps;  /* R32F array, a view per layer */
    struct rb_gpu_image shadow_depth; /* D32 scratch depth for rendering a layer */
    struct rb_gpu_image env_map;      /* RGBA32F equirectangular (1x1 when none) */

    /* G-buffer and outputs (all in VK_IMAGE_LAYOUT_GENERAL) */
    struct rb_gpu_image gbuffer[RB_GBUFFER_COLOR_COUNT]; /* position, normal, albedo, specular,
                                                          * emission, motion */
    struct rb_gpu_image depth;
    struct rb_gpu_image direct;
    const struct rb_gpu_image *beauty; /* what the integrator composes; direct's own image for
                                        * the direct integrator */
    struct rb_gpu_buffer readback;     /* RB_OUT_FLOATS per pixel, host-visible */
};

enum {
    RB_GB_POSITION = 0,
    RB_GB_NORMAL,
    RB_GB_ALBEDO,
    RB_GB_SPECULAR,
    RB_GB_EMISSION,
    RB_GB_MOTION
};

/* The formats of the G-buffer attachments, in order. */
extern const VkFormat rb_gbuffer_formats[RB_GBUFFER_COLOR_COUNT];

struct rb_pass_animate;
enum rb_status rb_pass_animate_create(struct rb_gpu *gpu, struct rb_pass_animate **out,
                                      struct rb_err *err);
/* Deforms every instance of frame->instances (slot's data) into slot->vertices. */
void rb_pass_animate_record(struct rb_pass_animate *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *slot);
void rb_pass_animate_destroy(struct rb_pass_animate *p);

struct rb_pass_gbuffer;
enum rb_status rb_pass_gbuffer_create(struct rb_gpu *gpu, struct rb_pass_gbuffer **out,
                                      struct rb_err *err);
void rb_pass_gbuffer_record(struct rb_pass_gbuffer *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *cur,
                            const struct rb_frame_slot *prev);
void rb_pass_gbuffer_destroy(struct rb_pass_gbuffer *p);

struct rb_pass_shadow;
enum rb_status rb_pass_shadow_create(struct rb_gpu *gpu, struct rb_pass_shadow **out,
                                     struct rb_err *err);
void rb_pass_shadow_record(struct rb_pass_shadow *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *cur);
void rb_pass_shadow_destroy(struct rb_pass_shadow *p);

struct rb_pass_direct;
enum rb_status rb_pass_direct_create(struct rb_gpu *gpu, struct rb_pass_direct **out,
                                     struct rb_err *err);
void rb_pass_direct_record(struct rb_pass_direct *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame);
void rb_pass_direct_destroy(struct rb_pass_direct *p);

struct rb_pass_output;
enum rb_status rb_pass_output_create(struct rb_gpu *gpu, struct rb_pass_output **out,
                                     struct rb_err *err);
/* Packs beauty and layers into frame->readback, and counts the NaN and infinite floats among
 * them. */
void rb_pass_output_record(struct rb_pass_output *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame);
/* After the frame's submit has completed: how many floats the last record wrote to the readback
 * were NaN or infinite (0 for a clean frame). */
uint32_t rb_pass_output_nonfinite_count(const struct rb_pass_output *p);
void rb_pass_output_destroy(struct rb_pass_output *p);

#endif
