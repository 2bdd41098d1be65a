/* Render passes: one file each, each with create, record and destroy. record cannot fail;
 * everything fallible happens in create. The frame resources the passes share belong to the
 * integrator and are passed in (struct rb_frame). */
#ifndef RB_PASSES_PASSES_H
#define RB_PASSES_PASSES_H

#include "gpu/gpu.h"
#include "scene/scene.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "geometry_shared.h"
#include "hybrid_shared.h"

_Static_assert(sizeof(struct rb_gpu_globals) == 400, "globals layout");
_Static_assert(sizeof(struct rb_gpu_vertex) == 64, "vertex layout");
_Static_assert(sizeof(struct rb_gpu_instance) == 160, "instance layout");
_Static_assert(sizeof(struct rb_gpu_geometry) == 32, "geometry record layout (std140)");
_Static_assert(sizeof(struct rb_gpu_hybrid_table) == 32, "hybrid table layout (std140)");
_Static_assert(sizeof(struct rb_gpu_material) == 80, "material layout");
_Static_assert(sizeof(struct rb_gpu_light) == 64, "light layout");
_Static_assert(sizeof(struct rb_gpu_shadow_view) == 96, "shadow view layout");
_Static_assert(sizeof(struct rb_gpu_view) == 96, "view layout");
_Static_assert(sizeof(struct rb_gpu_view_push) == 48, "view push constants");
_Static_assert(sizeof(struct rb_gpu_list_node) == 20, "list node layout: seed 000's struct Node");
_Static_assert(sizeof(struct rb_gpu_list_counter) == 16, "list counter layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_history) == 800, "bdpt history layout (std140)");
_Static_assert(sizeof(struct rb_gpu_vpl) == 80, "VPL layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_light) == 16, "bdpt light layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_sample) == 32, "bdpt sample layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_emitter) == 16, "bdpt emitter layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_emit_info) == 16 + 64 * RB_BDPT_ANALYTIC_MAX,
               "bdpt emitter summary layout");
_Static_assert(sizeof(struct rb_gpu_bdpt_generate_push) == 48, "generate push constants");
_Static_assert(sizeof(struct rb_gpu_bdpt_connect_push) == 112, "connect push constants");
_Static_assert(sizeof(struct rb_gpu_bdpt_bounce_push) == 48, "bounce push constants");
_Static_assert(sizeof(struct rb_gpu_bdpt_emitters_push) == 16, "emitters push constants");
_Static_assert(sizeof(struct rb_gpu_bdpt_image_push) == 48, "split/gather/filter push constants");
_Static_assert(sizeof(struct rb_gpu_hybrid_slot) == 32, "hybrid ray slot layout");
_Static_assert(sizeof(struct rb_gpu_hybrid_counters) == 64, "hybrid counters layout");
_Static_assert(sizeof(struct rb_gpu_hybrid_push) == 128, "hybrid push constants: the least limit");
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
    struct rb_gpu_buffer vertices;  /* struct rb_gpu_vertex, written by animate; addressed */
    /* struct rb_gpu_geometry, host-visible, written once: the addresses of vertices and of the
     * frame's source vertices, morph deltas and indices, which the passes bind in their place */
    struct rb_gpu_buffer geometry;
};

struct rb_frame {
    uint32_t width_px, height_px;
    struct rb_gpu_buffer globals; /* struct rb_gpu_globals, host-visible */

    /* static geometry and materials */
    /* addressed (shaders/common/geometry_shared.h): read through each slot's geometry record */
    struct rb_gpu_buffer src_vertices; /* struct rb_scene_vertex */
    struct rb_gpu_buffer morph_deltas; /* struct rb_scene_morph_delta */
    struct rb_gpu_buffer indices;      /* uint32, into the world vertex buffers */
    uint32_t index_count;

    /* The simplified mesh of the small views (integrator.bdpt.view_triangles), into the same
     * world vertices; no buffer (VK_NULL_HANDLE) when it would be the full mesh, and then
     * view_index_count is index_count. */
    struct rb_gpu_buffer view_indices;
    uint32_t view_index_count;

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
    /* The last layer_light_count lights light the blended layers alone (the globals' shadow.w);
     * the integrator's passes read the others (size.z), whose shadow layers come first. */
    uint32_t layer_light_count, own_shadow_layer_count;
    struct rb_gpu_image shadow_maps;  /* R32F array, a view per layer */
    struct rb_gpu_image shadow_depth; /* D32 scratch depth for rendering a layer */
    struct rb_gpu_image env_map;      /* RGBA32F equirectangular (1x1 when none) */

    /* G-buffer and outputs (all in VK_IMAGE_LAYOUT_GENERAL) */
    struct rb_gpu_image gbuffer[RB_GBUFFER_COLOR_COUNT]; /* position, normal, albedo, specular,
                                                          * emission, motion */
    struct rb_gpu_image depth;
    struct rb_gpu_image direct;
    /* The transparency pass's target (rb_pass_transparency_record): rgb the light the blended
     * layers add, a the fraction of the light behind them that passes; no image (VK_NULL_HANDLE)
     * when the scene has no blended material, and then no pass runs. */
    struct rb_gpu_image transparency;
    const struct rb_gpu_image *beauty;    /* what the integrator composes; direct's own image for
                                           * the direct integrator */
    struct rb_gpu_buffer readback;        /* readback_floats per pixel, host-visible */
    struct rb_gpu_buffer readback_device; /* where output writes them and they are copied from
                                           * into readback, without unified memory; else none */
    uint32_t layer_mask;                  /* the job's layers: what the output pass packs */
    uint32_t readback_floats;             /* rb_layer_stride(layer_mask) */
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
/* Where a G-buffer is drawn: RB_GBUFFER_COLOR_COUNT images and a depth image of the frame's
 * size, and the subpixel offset of its samples from the pixel centres, in pixels (0, 0: the
 * frame's own G-buffer; bdpt's temporal caches draw theirs at other offsets). */
struct rb_gbuffer_target {
    const struct rb_gpu_image *colors;
    const struct rb_gpu_image *depth;
    float offset_px[2];
};
/* Draws the G-buffer of cur (motion from prev) into target, or the frame's when NULL. */
void rb_pass_gbuffer_record(struct rb_pass_gbuffer *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *cur,
                            const struct rb_frame_slot *prev,
                            const struct rb_gbuffer_target *target);
void rb_pass_gbuffer_destroy(struct rb_pass_gbuffer *p);

/* reproject.c: where each pixel's surface was in the frames of bdpt's temporal caches. */
struct rb_pass_reproject_in {
    const struct rb_gpu_buffer *history;      /* struct rb_gpu_bdpt_history */
    const struct rb_frame_slot *const *slots; /* age_count: frame f - a's slot at [a] */
    uint32_t age_count;                       /* l, at most RB_BDPT_MAX_CACHES */
    const struct rb_gpu_image *target;        /* RGBA32F, a layer per age (l), storage */
};
struct rb_pass_reproject;
enum rb_status rb_pass_reproject_create(struct rb_gpu *gpu, struct rb_pass_reproject **out,
                                        struct rb_err *err);
/* Clears in->target and draws the frame's geometry against its G-buffer depth into it. */
void rb_pass_reproject_record(struct rb_pass_reproject *p, VkCommandBuffer cmd,
                              const struct rb_frame *frame, const struct rb_pass_reproject_in *in);
void rb_pass_reproject_destroy(struct rb_pass_reproject *p);

/* ---- raster views (view.c): the scene from many views, each into a layer ------------------- */

enum rb_view_kind {
    RB_VIEW_KIND_INVALID = 0,
    RB_VIEW_KIND_PERSPECTIVE = RB_VIEW_PERSPECTIVE,   /* a pinhole: shadow maps, RSM faces */
    RB_VIEW_KIND_ORTHOGRAPHIC = RB_VIEW_ORTHOGRAPHIC, /* parallel: ray-bundles, directional */
    RB_VIEW_KIND_PARABOLOID = RB_VIEW_PARABOLOID,     /* a hemisphere: VPL shadow maps */
};

enum rb_view_output {
    RB_VIEW_OUTPUT_INVALID = 0,
    RB_VIEW_OUTPUT_DEPTH, /* the view depth into an R32F layer (all kinds) */
    RB_VIEW_OUTPUT_RSM,   /* position, normal, flux, material (perspective, ortho) */
    RB_VIEW_OUTPUT_LIST,  /* every fragment into a per-pixel linked list (perspective, ortho) */
};

/* The formats of the reflective-shadow-map attachments: position, normal, flux (RGBA32F) and
 * material (RG32UI: the albedo and gloss words of a bundle node, rb_material_pack). */
#define RB_VIEW_RSM_TARGETS 4
extern const VkFormat rb_view_rsm_formats[RB_VIEW_RSM_TARGETS];

/* The views a pass will record: each (kind, output) pair it is asked for gets a pipeline. */
struct rb_view_variant {
    enum rb_view_kind kind;
    enum rb_view_output output;
};

struct rb_pass_view_desc {
    const struct rb_view_variant *variants;
    uint32_t variant_count;
    const char *debug_name; /* NULL == "view" */
};

/* A per-pixel linked list of fragments for each layer (seed 000, B.2): a head image and one node
 * pool that a batch's views share. */
struct rb_view_list {
    struct rb_gpu_image heads;    /* R32_UINT array: a pixel's first node, RB_NONE when empty */
    struct rb_gpu_buffer nodes;   /* struct rb_gpu_list_node [capacity_nodes] */
    struct rb_gpu_buffer counter; /* struct rb_gpu_list_counter, host-visible */
    uint32_t capacity_nodes;      /* how many nodes a batch may write; the rest are counted */
};

struct rb_view_list_desc {
    uint32_t width_px, height_px;
    uint32_t layer_count;    /* 0 == 1 */
    uint32_t capacity_nodes; /* required */
    const char *debug_name;  /* NULL == "view list" */
};

/* One batch: views[first_view + i] renders into layer first_layer + i, for i < view_count, in
 * one go (one pipeline, one set of bindings). */
struct rb_view_batch {
    enum rb_view_kind kind;
    enum rb_view_output output;
    const struct rb_gpu_buffer *views; /* struct rb_gpu_view */
    uint32_t first_view, first_layer, view_count;
    const struct rb_gpu_image *targets[RB_VIEW_RSM_TARGETS]; /* depth: [0], R32F; rsm: in
                                                              * rb_view_rsm_formats; arrays
                                                              * with layer views, in
                                                              * VK_IMAGE_LAYOUT_GENERAL; rsm:
                                                              * NULL after [0] drops that
                                                              * output */
    const struct rb_gpu_image *depth; /* depth, rsm: D32 scratch at least the targets' size,
                                       * reused by every view of the batch */
    const struct rb_view_list *list;  /* list: its heads have the layers */
    uint32_t size_px; /* depth, rsm: draw into the size_px x size_px corner of each layer;
                       * 0: the whole layer */
    /* list: the caller cleared the heads and the counter (rb_view_list_clear), the heads to
     * RB_VIEW_LIST_SKIP but for the texels it will read, which get lists alone */
    bool has_marked_heads;
    float intensity[3]; /* rsm: radiant intensity in W/sr (perspective) or irradiance in W/m^2
                         * across the beam (orthographic) of the light the view looks from */

    /* Draw frame->view_indices, the simplified mesh, rather than frame->indices (the same
     * when the frame has none). Off by default: the shadow pass and full-size views keep the
     * full mesh, bit for bit. */
    bool use_simplified;

    /* When set, view i draws the VkDrawIndexedIndirectCommand at index first_view + i of this
     * buffer (rb_view_draws_init fills them; a shader before the batch may set a view's
     * instance count to 0, so that a view with nothing to see costs its clear alone). */
    const struct rb_gpu_buffer *draws;
};

/* The index buffer a batch draws, and how many indices (use_simplified as in struct
 * rb_view_batch). */
const struct rb_gpu_buffer *rb_view_index_buffer(const struct rb_frame *frame, bool use_simplified);
uint32_t rb_view_index_count(const struct rb_frame *frame, bool use_simplified);
/* count draw commands into out (created with VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, storage and
 * transfer destination): each draws the whole mesh once. */
enum rb_status rb_view_draws_init(struct rb_gpu *gpu, const struct rb_frame *frame,
                                  bool use_simplified, uint32_t count, struct rb_gpu_buffer *out,
                                  struct rb_err *err);

struct rb_pass_view;
/* Builds a pipeline for each variant of desc. Fails with RB_E_UNSUPPORTED for a pair this pass
 * does not draw (a paraboloid view's rsm or list output), RB_E_VULKAN as Vulkan does. */
enum rb_status rb_pass_view_create(struct rb_gpu *gpu, const struct rb_pass_view_desc *desc,
                                   struct rb_pass_view **out, struct rb_err *err);
/* Draws frame->indices (frame->view_indices for batch->use_simplified) over slot->vertices
 * into each view of the batch: depth and rsm clear their target layers first; a list batch
 * clears its layers' heads and resets the node pool, which its views then share. The batch's
 * pair must be one the pass was created with. */
void rb_pass_view_record(struct rb_pass_view *p, VkCommandBuffer cmd, const struct rb_frame *frame,
                         const struct rb_frame_slot *slot, const struct rb_view_batch *batch);
void rb_pass_view_destroy(struct rb_pass_view *p);

/* A perspective view from eye along dir (up: the map's up), vertical field fov_y_rad, square
 * texels for the given aspect, depths near..far. */
void rb_view_perspective(struct rb_gpu_view *out, struct rb_vec3 eye, struct rb_vec3 dir,
                         struct rb_vec3 up, float fov_y_rad, float aspect, float z_near,
                         float z_far);
/* An orthographic view whose near plane is centred on origin, looking along dir: half_width x
 * half_height metres across (up: the map's up), depth_m deep. */
void rb_view_orthographic(struct rb_gpu_view *out, struct rb_vec3 origin, struct rb_vec3 dir,
                          struct rb_vec3 up, float half_width, float half_height, float depth_m);
/* A paraboloid view of the hemisphere around axis, from eye, from RB_VIEW_PARABOLOID_NEAR z_far
 * out to z_far: a direction d (unit, in the frame x = right, y = axis x right, z = axis) lands
 * at NDC (d.x, d.y) / (1 + d.z). right must be perpendicular to axis; both are normalized here. */
void rb_view_paraboloid(struct rb_gpu_view *out, struct rb_vec3 eye, struct rb_vec3 axis,
                        struct rb_vec3 right, float z_far);

/* Allocates the heads (cleared by each list batch) and the node pool. */
enum rb_status rb_view_list_init(struct rb_gpu *gpu, const struct rb_view_list_desc *desc,
                                 struct rb_view_list *out, struct rb_err *err);
void rb_view_list_release(struct rb_gpu *gpu, struct rb_view_list *list);
/* Empties layers first_layer.. of the list's heads to head (RB_NONE: empty lists) and its pool,
 * after whatever read them, before the stages in dst_stage (transfer writes). */
void rb_view_list_clear(VkCommandBuffer cmd, const struct rb_view_list *list, uint32_t first_layer,
                        uint32_t count, uint32_t head, VkPipelineStageFlags2 dst_stage);
/* After the submit that recorded a list batch: its counters (requested, dropped). */
struct rb_gpu_list_counter rb_view_list_usage(const struct rb_view_list *list);
/* After that submit: RB_E_NOMEM, with the numbers and name in the message, when fragments found
 * the pool full and were dropped; RB_OK otherwise. The caller decides whether that is fatal. */
enum rb_status rb_view_list_check(const struct rb_view_list *list, const char *name,
                                  struct rb_err *err);

/* ---- shadow.c: the direct light's shadow maps, as raster views ------------------------------ */

struct rb_pass_shadow;
enum rb_status rb_pass_shadow_create(struct rb_gpu *gpu, struct rb_pass_shadow **out,
                                     struct rb_err *err);
/* Renders frame->shadow_layer_count layers of frame->shadow_maps from frame->shadow_views. Reads
 * the views' kinds from the host copy of frame->shadow_views, so it records after they are
 * written for the frame. */
void rb_pass_shadow_record(struct rb_pass_shadow *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *cur);
void rb_pass_shadow_destroy(struct rb_pass_shadow *p);

struct rb_pass_direct;
enum rb_status rb_pass_direct_create(struct rb_gpu *gpu, struct rb_pass_direct **out,
                                     struct rb_err *err);
void rb_pass_direct_record(struct rb_pass_direct *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame);
void rb_pass_direct_destroy(struct rb_pass_direct *p);

/* ---- transparency.c: blended materials, forward, after the deferred passes (seed 003) ------ */

/* One blended instance's triangles: a range of frame->indices. */
struct rb_transparency_draw {
    uint32_t first_index, index_count;
};

struct rb_pass_transparency;
/* format: frame->transparency's, which must support blending as a colour attachment. */
enum rb_status rb_pass_transparency_create(struct rb_gpu *gpu, VkFormat format,
                                           struct rb_pass_transparency **out, struct rb_err *err);
/* Clears frame->transparency to (0, 0, 0, 1) and draws the ranges in the order given (the caller
 * sorts them back to front) over cur's world vertices, depth-tested against frame->depth
 * (unwritten), each fragment lit by frame's lights and shadow maps and blended over the ones
 * before it (shaders/transparency.frag). */
void rb_pass_transparency_record(struct rb_pass_transparency *p, VkCommandBuffer cmd,
                                 const struct rb_frame *frame, const struct rb_frame_slot *cur,
                                 const struct rb_transparency_draw *draws, uint32_t draw_count);
void rb_pass_transparency_destroy(struct rb_pass_transparency *p);

struct rb_pass_output;
enum rb_status rb_pass_output_create(struct rb_gpu *gpu, struct rb_pass_output **out,
                                     struct rb_err *err);
/* Packs beauty and layers into target (frame->readback, or the device buffer it is copied from),
 * and counts the NaN and infinite floats among them. light: NULL, or bdpt's RB_BDPT_LIGHT_COUNT
 * images of gathered light (bdpt_shared.h), which it textures with the diffuse and gray specular
 * maps and adds: the direct part to the direct layer, the rest as the indirect layer, both to the
 * beauty. stats: NULL (the samples and tiles layers are zero), or the hybrid's per-pixel sample
 * counts (R diffuse, G specular) and tile masks (B diffuse, A specular), copied into those layers.
 * has_transparency: the transparency pass ran this frame, and frame->transparency is composited
 * over the beauty and the direct layer (the layers' light passes through it scaled by its
 * alpha; the indirect layers take that scale alone; alpha covers what the layers cover).
 */
void rb_pass_output_record(struct rb_pass_output *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_gpu_buffer *target,
                           const struct rb_gpu_image *light, const struct rb_gpu_image *stats,
                           bool has_transparency);
/* After the frame's submit has completed: how many floats the last record wrote to the readback
 * were NaN or infinite (0 for a clean frame). */
uint32_t rb_pass_output_nonfinite_count(const struct rb_pass_output *p);
void rb_pass_output_destroy(struct rb_pass_output *p);

/* ---- bdpt.c: the bdpt integrator's compute passes (seed 000, A.1, B.1-B.3) --------------------
 */

/* The split G-buffer: position and view depth, shading normal and roughness, F0 and F90, the
 * octahedral geometric normal. */
#define RB_BDPT_SPLIT_COUNT 4

/* The fits of the specular lobe that the emitters' closed form reads (bdpt_shared.h's
 * RB_LTC_SIZE): 4 floats an entry, as tools/ltcfit.c writes them. */
extern const float rb_pass_ltc_ggx[RB_LTC_SIZE * RB_LTC_SIZE * 4];

/* What the bdpt passes read and write besides the frame: the integrator's own resources and
 * settings (lib/integrators/bdpt.c fills it). All images RGBA32F unless said. */
struct rb_bdpt_frame {
    uint32_t vpl_count, bundle_count;     /* K_v, K_b: per frame */
    uint32_t interleave;                  /* n: n x n sub-images */
    uint32_t sub_width_px, sub_height_px; /* a sub-image: the frame's size / n, rounded up */
    uint32_t vpl_size_px, bundle_size_px;
    uint32_t bounce_vpl_size_px; /* the bounce VPLs' maps: a corner of their vpl_maps layers */
    float offset_px[2];          /* the cache's subpixel offset this frame (its G-buffer's) */
    uint32_t filter_radius_px;
    float filter_depth, filter_normal;
    float filter_light;  /* the least ratio of two pixels' direct light the filter joins; 0: any */
    float clamp_g;       /* the bound on G of a VPL connection, in 1/m^2; 0: none */
    float vpl_bias;      /* fraction of the distance */
    float min_roughness; /* the least roughness at a VPL and a bundle's hit (bdpt_vpl.glsl) */
    float vpl_spread;    /* a VPL's disk, in the areas it stands for among the frame's K_v */
    enum rb_bdpt_strategies strategies;
    float scene_centre[3], scene_radius; /* the job's bounds */
    uint32_t emitter_count;              /* emissive triangles */
    float punctual_power;                /* W: the punctual lights' that have VPLs, this frame */
    bool has_bounce;                     /* VPLs probe for their bounces: VPLs K_v..2 K_v - 1 */
    bool has_chain; /* and the emitters' bounces for theirs: VPLs 2 K_v..3 K_v - 1 */

    struct rb_gpu_buffer bounds;      /* lo[4], hi[4]: the G-buffer's box (bdpt_bounds.comp) */
    struct rb_gpu_buffer samples;     /* struct rb_gpu_bdpt_sample [K_v + K_b] */
    struct rb_gpu_buffer lights;      /* struct rb_gpu_bdpt_light per light, host-visible */
    struct rb_gpu_buffer vpls;        /* struct rb_gpu_vpl [K_v], [2 K_v] or [3 K_v] with bounces */
    struct rb_gpu_buffer vpl_views;   /* struct rb_gpu_view, as vpls: paraboloid */
    struct rb_gpu_buffer probe_views; /* struct rb_gpu_view [K_v]: perspective, 1x1 */
    struct rb_gpu_buffer vpl_draws;   /* VkDrawIndexedIndirectCommand, as vpls */
    struct rb_gpu_buffer probe_draws; /* VkDrawIndexedIndirectCommand [K_v] */
    struct rb_gpu_buffer bundle_views; /* struct rb_gpu_view [K_b]: orthographic */
    struct rb_gpu_buffer emitters;     /* struct rb_gpu_bdpt_emitter [emitter_count] */
    struct rb_gpu_buffer emit_info;    /* struct rb_gpu_bdpt_emit_info */
    struct rb_gpu_buffer emitter_cdf;  /* float [emitter_count]: running sums of their weights */
    struct rb_gpu_buffer ltc;          /* rb_pass_ltc_ggx, uploaded once */
    struct rb_gpu_image rsm[RB_VIEW_RSM_TARGETS];   /* a layer per shadow layer of the frame */
    struct rb_gpu_image rsm_depth;                  /* D32 scratch */
    struct rb_gpu_image probe[RB_VIEW_RSM_TARGETS]; /* 1x1, a layer per VPL (with bounces) */
    struct rb_gpu_image probe_depth;                /* D32 scratch, 1x1 */
    struct rb_gpu_image vpl_maps;                   /* R32F, a layer per VPL */
    struct rb_gpu_image vpl_depth;                  /* D32 scratch */
    struct rb_view_list bundle;                     /* one layer: the bundle being connected */
    struct rb_gpu_image split[RB_BDPT_SPLIT_COUNT]; /* sub_* x n in size */
    struct rb_gpu_image accum[RB_BDPT_LIGHT_COUNT]; /* split order, added to by connect */
    struct rb_gpu_image gathered[RB_BDPT_LIGHT_COUNT];
    struct rb_gpu_image emitted[RB_BDPT_EMITTED_COUNT]; /* image order: the emitters' points */

    /* The temporal caches (seed 000, section A): the filter writes the light of cache `slot`
     * (a layer of each array; the first one's alpha holds the depth), computed from `gbuffer`,
     * the G-buffer at that cache's subpixel offset, which each frame's record picks (the
     * frame's own when l is 1, or when the cache is at the pixels' centre and the frame draws
     * one); generate and bounce read that slot's block of the sampling table. */
    uint32_t cache_count, slot;
    VkDeviceSize sample_block_bytes;    /* a slot's rows, aligned for a storage offset */
    const struct rb_gpu_image *gbuffer; /* RB_GBUFFER_COLOR_COUNT images */
    struct rb_gpu_image filtered[RB_BDPT_LIGHT_COUNT]; /* the caches: a layer per slot */
    struct rb_gpu_buffer history;                   /* struct rb_gpu_bdpt_history, host-visible */
    struct rb_gpu_image reproject;                  /* RGBA32F, a layer per age (reproject.c) */
    struct rb_gpu_image light[RB_BDPT_LIGHT_COUNT]; /* reconstructed: what output textures */
    struct rb_gpu_buffer hits;                      /* a float per pixel, host-visible */
};

_Static_assert(RB_BDPT_STRATEGIES_MIS == RB_BDPT_MIS && RB_BDPT_STRATEGIES_VPL == RB_BDPT_VPL &&
                   RB_BDPT_STRATEGIES_BUNDLE == RB_BDPT_BUNDLE,
               "the strategies as the connect shader numbers them");

struct rb_pass_bdpt;
enum rb_status rb_pass_bdpt_create(struct rb_gpu *gpu, struct rb_pass_bdpt **out,
                                   struct rb_err *err);
void rb_pass_bdpt_destroy(struct rb_pass_bdpt *p);
/* The box of the G-buffer's points into b->bounds (it fills the box empty first). */
void rb_pass_bdpt_bounds_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b);
/* The emissive triangles' CDF by power into b->emitter_cdf (one workgroup). */
void rb_pass_bdpt_emitters_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                  const struct rb_frame *frame, const struct rb_frame_slot *slot,
                                  const struct rb_bdpt_frame *b);
/* VPLs from the RSMs and the sampling table, their paraboloid views, the bundles' views. */
void rb_pass_bdpt_generate_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                  const struct rb_frame *frame, const struct rb_frame_slot *slot,
                                  const struct rb_bdpt_frame *b);
/* Round 0: VPLs K_v + i, the bounces of VPLs i, from their probes, and their views (and, with
 * has_chain, the probes of the emitters' bounces); round 1: VPLs 2 K_v + i, the bounces of
 * VPLs K_v + i. */
void rb_pass_bdpt_bounce_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_bdpt_frame *b, uint32_t round);
/* The G-buffer into n x n sub-images (b->split); clears b->accum to zero. */
void rb_pass_bdpt_split_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                               const struct rb_bdpt_frame *b);
/* Bundle k's heads (layer 0 of b->bundle, cleared to RB_VIEW_LIST_SKIP): RB_NONE where a point
 * of sub-image k mod n^2 lands, the texels its connect pass reads. */
void rb_pass_bdpt_mark_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                              const struct rb_bdpt_frame *b, uint32_t k);
/* Iteration k: VPL k and bundle k (in b->bundle's list) with sub-image k mod n^2, added to
 * b->accum. */
void rb_pass_bdpt_connect_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                 const struct rb_frame *frame, const struct rb_bdpt_frame *b,
                                 uint32_t k);
/* b->accum back to image order, into b->gathered. */
/* The emitters' dispatch of connect: every emitter point among the frame's VPLs at every pixel,
 * into b->emitted. */
void rb_pass_bdpt_emitters_direct_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                         const struct rb_frame *frame,
                                         const struct rb_bdpt_frame *b);
void rb_pass_bdpt_gather_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b);
/* The geometry-aware filter of b->gathered into cache b->slot of b->filtered. */
void rb_pass_bdpt_filter_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b);
/* Equation (1) over the caches into b->light, and the hit ratio into b->hits. */
void rb_pass_bdpt_reconstruct_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                     const struct rb_frame *frame, const struct rb_bdpt_frame *b);

/* ---- hybrid.c: the hybrid integrator's compute passes (seed 003) ----------------------------- */

/* What the hybrid passes read and write besides the frame (lib/integrators/hybrid.c fills it). */
struct rb_hybrid_frame {
    struct rb_gpu_hybrid_push push; /* the frame's settings; each record sets its own fields */
    uint32_t hiz_levels;
    uint64_t slot_count;           /* every lobe's */
    struct rb_gpu_buffer hiz;      /* vec2 per cell of every level */
    struct rb_gpu_buffer slots;    /* struct rb_gpu_hybrid_slot [slot_count] */
    struct rb_gpu_buffer counters; /* struct rb_gpu_hybrid_counters, host-visible */
    struct rb_gpu_buffer queue;    /* uint [queue capacity] */
    struct rb_gpu_buffer blocks;   /* uint per block of slots */
    struct rb_gpu_buffer bvh_nodes;
    struct rb_gpu_buffer bvh_tris; /* the BVH's triangles, then the baked points and words;
                                    * addressed (table), bound as far as the triangles */
    VkDeviceSize bvh_tri_bytes;    /* the triangles' part of bvh_tris: the bound range */
    struct rb_gpu_buffer indices;  /* the frame's triangles, then the BVH's coarser objects',
                                    * the emitter list, the environment's importance table;
                                    * host-visible, addressed (geometry_shared.h) */
    struct rb_gpu_buffer table;    /* struct rb_gpu_hybrid_table: indices' and bvh_tris'
                                    * addresses */
    struct rb_gpu_buffer tiles;    /* float [2 x tiles] */
    struct rb_gpu_image acc[2];    /* RB_HYBRID_ACC_LAYERS layers; frame f writes f mod 2 */
    struct rb_gpu_image stats;     /* samples (diffuse, specular), tile mask */
    struct rb_gpu_image light[RB_BDPT_LIGHT_COUNT]; /* what the output pass textures */
    uint32_t cur;                                   /* the accumulator written: frame mod 2 */
    bool has_env_light;  /* the environment is lit: light samples of it (hybrid_light.comp) */
    bool screen_shadows; /* the light samples' shadow rays also march the screen: the BVH's
                          * budget leaves surfaces out */
};

struct rb_pass_hybrid;
/* chain: the rays' passes that trace a counted path's further bounces (max_bounces 2 to 8;
 * hybrid_trace_chain.comp and hybrid_bvh_chain.comp), which the other counts never run. */
enum rb_status rb_pass_hybrid_create(struct rb_gpu *gpu, bool chain, struct rb_pass_hybrid **out,
                                     struct rb_err *err);
void rb_pass_hybrid_destroy(struct rb_pass_hybrid *p);
/* The hybrid frame's compute passes, in the order they run (lib/integrators/hybrid.c records
 * the first RB_HYBRID_PASS_TILES + 1 of them in a warm-up). */
enum rb_hybrid_pass {
    RB_HYBRID_PASS_HIZ = 0,         /* the hierarchical depth buffer, level by level */
    RB_HYBRID_PASS_DIFFUSE_RAYS,    /* zeroes the counters; the emitter table; requests, screen
                                     * trace, screen hits */
    RB_HYBRID_PASS_SPECULAR_RAYS,   /* the same for the specular lobe */
    RB_HYBRID_PASS_RAY_QUEUE,       /* the rays for the BVH, in slot order (three dispatches) */
    RB_HYBRID_PASS_BVH_RAYS,        /* the queued rays through the BVH (indirect dispatch) */
    RB_HYBRID_PASS_LIGHT_RAYS,      /* a light sample per traced ray (next-event estimation) */
    RB_HYBRID_PASS_ACCUMULATE,      /* both accumulators */
    RB_HYBRID_PASS_TILES,           /* the tile mask, then its erosion */
    RB_HYBRID_PASS_DIFFUSE_FILTER,  /* the diffuse lobe's light for the output pass */
    RB_HYBRID_PASS_SPECULAR_FILTER, /* the specular lobe's */
    RB_HYBRID_PASS_COUNT
};
/* Each pass's name in the timing sidecars. */
extern const char *const rb_pass_hybrid_names[RB_HYBRID_PASS_COUNT];
/* Records pass `which` (barriers between its own dispatches are its own). */
void rb_pass_hybrid_record(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *slot,
                           struct rb_hybrid_frame *h, enum rb_hybrid_pass which);

#endif
