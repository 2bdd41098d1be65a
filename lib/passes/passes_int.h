/* Private to lib/passes: what every pass repeats, written once (pass.c). A pass names its
 * bindings in shaders/common/bindings_shared.h, lists their types in a table indexed by those
 * names, creates its layout and pipeline from the table, and binds by name at record time. */
#ifndef RB_PASSES_PASSES_INT_H
#define RB_PASSES_PASSES_INT_H

#include "passes/passes.h"

#include "bindings_shared.h"

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* One row of a pass's binding table. Write tables with RB_PASS_BIND, indexed by the shared
 * names, and check their length against the pass's _COUNT:
 *
 *     static const struct rb_pass_binding bindings[] = {
 *         RB_PASS_BIND(RB_BIND_OUTPUT_GLOBALS, UNIFORM_BUFFER),
 *         RB_PASS_BIND(RB_BIND_OUTPUT_BEAUTY, STORAGE_IMAGE), ...
 *     };
 *     _Static_assert(COUNT(bindings) == RB_BIND_OUTPUT_COUNT, "output bindings");
 *
 * A binding given twice is a compiler warning (-Woverride-init, an error under CI), one missing
 * at the end fails the assertion, one missing in between stops the pass's create (RB_BUG). */
struct rb_pass_binding {
    VkDescriptorType type;
    const char *name; /* the RB_BIND_ name, for messages; NULL marks a hole in the table */
};
#define RB_PASS_BIND(slot, vk_type) [slot] = {VK_DESCRIPTOR_TYPE_##vk_type, #slot}
/* The .bindings and .binding_count of a desc, from a table. */
#define RB_PASS_BINDINGS(table) .bindings = (table), .binding_count = COUNT(table)

/* What a pass holds: its layout, from its binding table, and its pipeline. */
struct rb_pass {
    struct rb_gpu *gpu;
    const char *name; /* the pass's name: the debug name of its objects */
    VkPipelineBindPoint point;
    const struct rb_pass_binding *bindings; /* the table, static */
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
};

struct rb_pass_compute_desc {
    const char *name;
    const struct rb_pass_binding *bindings;
    uint32_t binding_count;
    uint32_t push_bytes; /* 0: no push constants */
    const uint32_t *spv;
    size_t spv_bytes;
};

/* Creates the layout and compute pipeline of a pass into caller storage. On failure nothing is
 * left to release; the message names the pass. A hole in the binding table is a bug (RB_BUG). */
enum rb_status rb_pass_compute_init(struct rb_gpu *gpu, const struct rb_pass_compute_desc *desc,
                                    struct rb_pass *out, struct rb_err *err);

struct rb_pass_raster_desc {
    const char *name;
    const struct rb_pass_binding *bindings;
    uint32_t binding_count;
    uint32_t push_bytes;
    struct rb_gpu_graphics_desc graphics; /* .layout and .debug_name are filled in */
};

/* As rb_pass_compute_init, for a graphics pipeline. */
enum rb_status rb_pass_raster_init(struct rb_gpu *gpu, const struct rb_pass_raster_desc *desc,
                                   struct rb_pass *out, struct rb_err *err);

/* Inside a rendering begun over the whole frame, after the pass's bindings: the frame's
 * viewport and scissor, and one indexed draw of all its instances' world vertices (the
 * G-buffer pass's, and every pass that draws the same surfaces again). */
void rb_pass_draw_frame(VkCommandBuffer cmd, const struct rb_frame *frame);

/* Destroys the pipeline and layout; a zeroed pass is fine. */
void rb_pass_release(struct rb_pass *pass);

/* A pass's bindings for one push, set by name in any order: start from
 * `struct rb_pass_bindings b = {.pass = &p->pass};`. */
struct rb_pass_bindings {
    const struct rb_pass *pass;
    struct rb_gpu_bindings set;
};

/* Binds a buffer or image at a binding of the pass's table; the type comes from the table.
 * Images are in VK_IMAGE_LAYOUT_GENERAL (struct rb_frame); sampler is VK_NULL_HANDLE except for
 * combined image samplers. A binding outside the table, set twice, or of the wrong kind is a
 * bug (RB_BUG). */
void rb_pass_bind_buffer(struct rb_pass_bindings *b, uint32_t binding,
                         const struct rb_gpu_buffer *buf);
void rb_pass_bind_image(struct rb_pass_bindings *b, uint32_t binding, VkImageView view,
                        VkSampler sampler);
/* Binds range_bytes of a buffer from offset_bytes (a band of one larger than a binding). */
void rb_pass_bind_buffer_range(struct rb_pass_bindings *b, uint32_t binding,
                               const struct rb_gpu_buffer *buf, VkDeviceSize offset_bytes,
                               VkDeviceSize range_bytes);

/* Binds the pass's pipeline and pushes b, which must set every binding of the table: one left
 * unset is a bug (RB_BUG, naming it). */
void rb_pass_record_bindings(VkCommandBuffer cmd, const struct rb_pass_bindings *b);

#endif
