/* The GPU context: a headless Vulkan 1.3 device (lavapipe by default), validation, memory,
 * buffers, images, pipelines with push descriptors, one-shot command submission, per-pass
 * timestamps and debug labels. Passes use the Vulkan handles in struct rb_gpu directly. */
#ifndef RB_GPU_GPU_H
#define RB_GPU_GPU_H

#include "core/core.h"

#include <stdio.h>
#include <vulkan/vulkan.h>

struct rb_gpu_desc {
    const char *device; /* name substring or index; NULL: lavapipe, else the first device */
    bool validate;      /* enable VK_LAYER_KHRONOS_validation and its synchronization validation;
                         * any message fails the run */
};

struct rb_gpu {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice phys;
    VkDevice device;
    VkQueue queue;
    uint32_t queue_family;
    VkPhysicalDeviceProperties props;
    VkPhysicalDeviceMemoryProperties mem_props;
    uint32_t max_push_descriptors;     /* VkPhysicalDevicePushDescriptorPropertiesKHR */
    VkDeviceSize max_buffer_bytes;     /* maxBufferSize (Vulkan 1.3) */
    VkDeviceSize max_allocation_bytes; /* maxMemoryAllocationSize (Vulkan 1.1) */
    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    char driver[256]; /* driver name and info, e.g. "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)" */
    bool is_lavapipe;
    /* Whether the GPU writes host-cached memory at its own memory's speed (a CPU device, an
     * integrated GPU: one memory type is device-local, host-visible and host-cached). Elsewhere a
     * shader writing host-visible memory writes across the bus, a few GB/s: a frame's readback
     * is written to device memory and copied (rb_frame's readback_device). RB_GPU_STAGED_READBACK=1
     * takes the copy anyway, so that lavapipe tests that path. */
    bool is_unified_memory;
    bool has_debug_utils;
    bool validate;
    unsigned validation_messages; /* warnings and errors from the validation layer */
    char first_validation_message[512];

    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkSampler linear_sampler;  /* repeat, trilinear */
    VkSampler clamp_sampler;   /* clamp to edge, linear */
    VkSampler nearest_sampler; /* clamp to edge, nearest */
    VkSampler env_sampler;     /* equirectangular maps: u repeats (azimuth), v clamps; linear */

    /* timestamps (query.c): 2 queries per pass, recorded by rb_gpu_pass_begin/end into pools
     * that are added as a frame records more passes */
    VkQueryPool *query_pools;
    uint32_t query_pool_count;
    double timestamp_period_ns;
    uint64_t timestamp_mask;
    struct rb_gpu_pass *passes; /* this frame's, in recording order */
    uint32_t pass_count, pass_cap;
    enum rb_status timing_status; /* a pool or record that could not be made: said at submit */

    PFN_vkCmdPushDescriptorSetKHR push_descriptor_set;
    PFN_vkCmdBeginDebugUtilsLabelEXT begin_label;
    PFN_vkCmdEndDebugUtilsLabelEXT end_label;
    PFN_vkSetDebugUtilsObjectNameEXT set_object_name;
};

/* Creates the instance and device. Fails with RB_E_NODEVICE when no Vulkan device (or none
 * matching desc->device, or none with the required features) exists; the message says which and
 * what is missing. */
enum rb_status rb_gpu_create(const struct rb_gpu_desc *desc, struct rb_gpu **out,
                             struct rb_err *err);
void rb_gpu_destroy(struct rb_gpu *gpu);

/* Prints every physical device with its type, API and driver versions, and whether it has what
 * the renderer needs (for `raybundle info`). */
enum rb_status rb_gpu_print_devices(FILE *f, struct rb_err *err);

/* Names a Vulkan object for validation messages and debuggers (no-op without debug utils). */
void rb_gpu_name(struct rb_gpu *gpu, VkObjectType type, uint64_t handle, const char *name);

/* Records a VkResult failure: "vkCreateImage 'gbuffer.normal': VK_ERROR_OUT_OF_DEVICE_MEMORY". */
enum rb_status rb_gpu_fail(struct rb_err *err, VkResult vr, const char *call, const char *what);
const char *rb_gpu_result_name(VkResult vr);

/* Fails when the validation layer has spoken since creation (tests run with validation on). */
enum rb_status rb_gpu_check_validation(struct rb_gpu *gpu, struct rb_err *err);

/* ---- device limits ------------------------------------------------------------------------- */

/* Checks a size the renderer is about to use against a device limit, at create time, so that a
 * frame or a scene too large for the device fails with a message naming the pass, the resource,
 * the size and the limit, instead of in the validation layer (or silently without it). Each
 * returns RB_E_UNSUPPORTED with that message, or RB_OK. pass may be NULL where no pass is known.
 * Thread-safe: they only read the limits read at rb_gpu_create. */

/* A storage-buffer binding of range_bytes against maxStorageBufferRange. */
enum rb_status rb_gpu_check_storage_range(const struct rb_gpu *gpu, const char *pass,
                                          const char *resource, VkDeviceSize range_bytes,
                                          struct rb_err *err);
/* One buffer of size_bytes against maxBufferSize and maxMemoryAllocationSize (one allocation per
 * buffer, as lib/gpu/memory.c allocates). */
enum rb_status rb_gpu_check_buffer_size(const struct rb_gpu *gpu, const char *pass,
                                        const char *resource, VkDeviceSize size_bytes,
                                        struct rb_err *err);
/* A dispatch of x * y * z workgroups against maxComputeWorkGroupCount, per dimension. */
enum rb_status rb_gpu_check_dispatch(const struct rb_gpu *gpu, const char *pass, uint32_t x,
                                     uint32_t y, uint32_t z, struct rb_err *err);
/* A push-descriptor set layout of binding_count bindings against maxPushDescriptors. */
enum rb_status rb_gpu_check_push_descriptors(const struct rb_gpu *gpu, const char *pass,
                                             uint32_t binding_count, struct rb_err *err);

/* A buffer of row_count rows of row_bytes each, bound as storage one band of rows at a time:
 * the rows per band. All rows when the whole buffer fits in maxStorageBufferRange; otherwise the
 * most rows that fit whose bytes are a multiple of minStorageBufferOffsetAlignment, so every band
 * starts aligned (the last band may be shorter). 0 when not even one aligned band fits. Pure
 * arithmetic on the limits: safe in a pass's record once its create has checked it with
 * rb_gpu_check_storage_bands. */
uint32_t rb_gpu_storage_band_rows(const struct rb_gpu *gpu, VkDeviceSize row_bytes,
                                  uint32_t row_count);
/* Fails when rb_gpu_storage_band_rows would return 0, naming the smallest aligned band. */
enum rb_status rb_gpu_check_storage_bands(const struct rb_gpu *gpu, const char *pass,
                                          const char *resource, VkDeviceSize row_bytes,
                                          uint32_t row_count, struct rb_err *err);

/* ---- buffers ------------------------------------------------------------------------------- */

struct rb_gpu_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    void *mapped;            /* non-NULL for host-visible buffers */
    VkDeviceAddress address; /* its device address when created is_addressed, else 0 */
};

struct rb_gpu_buffer_desc {
    VkDeviceSize size_bytes;
    VkBufferUsageFlags usage;
    bool is_host_visible; /* mapped, coherent: uploads each frame, readback */
    /* Read by shaders through its device address (GL_EXT_buffer_reference), which no
     * maxStorageBufferRange bounds: the scene's arrays, which grow with its triangles. Its size
     * is bound by maxBufferSize and maxMemoryAllocationSize alone (rb_gpu_check_buffer_size). */
    bool is_addressed;
    const char *debug_name;
};

enum rb_status rb_gpu_buffer_init(struct rb_gpu *gpu, const struct rb_gpu_buffer_desc *desc,
                                  struct rb_gpu_buffer *out, struct rb_err *err);
void rb_gpu_buffer_release(struct rb_gpu *gpu, struct rb_gpu_buffer *buf);
/* Copies data into a buffer (through a staging buffer when it is not host-visible). Waits. */
enum rb_status rb_gpu_buffer_upload(struct rb_gpu *gpu, struct rb_gpu_buffer *buf, const void *data,
                                    VkDeviceSize size, struct rb_err *err);

/* ---- images -------------------------------------------------------------------------------- */

struct rb_gpu_image {
    VkImage image;
    VkDeviceMemory memory;
    VkImageView view;         /* all layers and mips (2D or 2D array view) */
    VkImageView *layer_views; /* one 2D view per layer, when desc asked for them */
    VkFormat format;
    uint32_t width_px, height_px, layer_count, mip_count;
    VkImageAspectFlags aspect;
};

struct rb_gpu_image_desc {
    uint32_t width_px, height_px;
    uint32_t layer_count; /* 0 == 1 */
    uint32_t mip_count;   /* 0 == 1 */
    VkFormat format;
    VkImageUsageFlags usage;
    bool is_array;        /* view as 2D array even with one layer */
    bool has_layer_views; /* create a 2D view per layer (render targets of array layers) */
    const char *debug_name;
};

enum rb_status rb_gpu_image_init(struct rb_gpu *gpu, const struct rb_gpu_image_desc *desc,
                                 struct rb_gpu_image *out, struct rb_err *err);
void rb_gpu_image_release(struct rb_gpu *gpu, struct rb_gpu_image *img);

/* Full barrier helper for an image: all commands, all memory, layout change. */
void rb_gpu_image_barrier(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_gpu_image *img,
                          VkImageLayout from, VkImageLayout to);
/* A global memory barrier between everything before and everything after (simple and correct;
 * passes are few and large). */
void rb_gpu_barrier(VkCommandBuffer cmd);
/* A global memory barrier from src_stages/src_access to dst_stages/dst_access. */
void rb_gpu_memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stages,
                           VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stages,
                           VkAccessFlags2 dst_access);

/* ---- barriers between passes (barrier.c) --------------------------------------------------- */

/* How a pass uses a resource: one row each in barrier.c's table, which gives its pipeline
 * stages and access. Attachments are cleared on load (their load is a write, no blending);
 * transfers are fills and copies; a host read happens after the frame's fence. */
enum rb_gpu_use {
    RB_GPU_USE_INVALID = 0,
    RB_GPU_COMPUTE_UNIFORM,     /* uniform buffer, compute shader */
    RB_GPU_COMPUTE_READ,        /* storage buffer or image, read by a compute shader */
    RB_GPU_COMPUTE_WRITE,       /* storage buffer or image, written by a compute shader */
    RB_GPU_COMPUTE_READ_WRITE,  /* storage, read and written (atomics, accumulation) */
    RB_GPU_COMPUTE_SAMPLED,     /* sampled image, compute shader */
    RB_GPU_GRAPHICS_UNIFORM,    /* uniform buffer, vertex and fragment shaders */
    RB_GPU_VERTEX_READ,         /* storage buffer, read by a vertex shader */
    RB_GPU_GRAPHICS_READ,       /* storage buffer, read by vertex and fragment shaders */
    RB_GPU_FRAGMENT_READ,       /* storage buffer, read by a fragment shader */
    RB_GPU_FRAGMENT_SAMPLED,    /* sampled image, fragment shader */
    RB_GPU_FRAGMENT_READ_WRITE, /* storage, read and written by a fragment shader (lists) */
    RB_GPU_INDEX_READ,          /* index buffer */
    RB_GPU_INDIRECT_READ,       /* indirect draw commands */
    RB_GPU_COLOR_ATTACHMENT,    /* cleared and drawn into */
    RB_GPU_DEPTH_ATTACHMENT,    /* cleared, tested and written */
    RB_GPU_TRANSFER_READ,       /* source of a copy */
    RB_GPU_TRANSFER_WRITE,      /* filled, or the destination of a copy */
    RB_GPU_HOST_READ,           /* read by the host after the frame's fence */
    RB_GPU_USE_COUNT
};

/* One resource a pass reads or writes: a buffer or an image (exactly one of them), whole. */
struct rb_gpu_access {
    const struct rb_gpu_buffer *buffer;
    const struct rb_gpu_image *image;
    enum rb_gpu_use use;
    VkImageLayout layout; /* images: the layout the pass uses; 0: VK_IMAGE_LAYOUT_GENERAL */
};

/* What the queue has done to each resource since the barriers that cover it: the last write
 * and the stages that read it since, what that write was made visible to, and the image's
 * layout. Declared uses of a pass go in, the barriers the pass needs after everything recorded
 * before it come out: read after write, write after read, write after write, and layout
 * changes, one buffer or image barrier per resource (so an undeclared resource stays unsynced,
 * and synchronization validation says so); two reads need none. The state carries over from
 * one command buffer to the next on the same queue (barriers order later submissions too).
 * A resource first seen is in VK_IMAGE_LAYOUT_GENERAL with nothing pending (the frame's
 * resources after rb_frame_init's barrier and wait). Resources are told apart by handle.
 * Caller storage: start from RB_GPU_BARRIERS_INIT, end with rb_gpu_barriers_release. Not
 * thread-safe; one per queue of passes. */
struct rb_gpu_barriers {
    struct rb_gpu_tracked *tracked; /* one per resource seen */
    uint32_t tracked_count, tracked_cap;
    uint32_t *touched; /* scratch: the tracked resources of the pass being derived */
    VkBufferMemoryBarrier2 *buffer_barriers;
    VkImageMemoryBarrier2 *image_barriers;
    uint32_t scratch_cap;  /* of touched, buffer_barriers and image_barriers */
    enum rb_status status; /* a derivation that failed in rb_gpu_barriers_record */
};
#define RB_GPU_BARRIERS_INIT                                                                       \
    {                                                                                              \
        0                                                                                          \
    }

/* Derives the barriers that uses (use_count of them, one pass's; a resource may appear more
 * than once, its uses are joined) need after everything b has seen, into *out (its arrays are
 * b's, valid until the next call; no barriers: both counts 0), and notes the uses in b. Pure:
 * records nothing, needs no device. RB_E_NOMEM when b cannot grow, before b changes. A use
 * with no resource or two, an unknown use, or two layouts for one image in one pass is a bug
 * (RB_BUG). */
enum rb_status rb_gpu_barriers_derive(struct rb_gpu_barriers *b, const struct rb_gpu_access *uses,
                                      uint32_t use_count, VkDependencyInfo *out,
                                      struct rb_err *err);
/* rb_gpu_barriers_derive into cmd (nothing when no barrier is needed). It cannot fail: when
 * the derivation does, a full barrier is recorded instead and the failure kept in b->status,
 * for the caller to report after the submit (rb_gpu_barriers_check). */
void rb_gpu_barriers_record(struct rb_gpu_barriers *b, VkCommandBuffer cmd,
                            const struct rb_gpu_access *uses, uint32_t use_count);
/* The failure rb_gpu_barriers_record kept, if any (then cleared), as a message naming it. */
enum rb_status rb_gpu_barriers_check(struct rb_gpu_barriers *b, struct rb_err *err);
void rb_gpu_barriers_release(struct rb_gpu_barriers *b);

/* ---- commands ------------------------------------------------------------------------------ */

/* Starts recording the device's one command buffer; resets the pass list. */
enum rb_status rb_gpu_begin(struct rb_gpu *gpu, struct rb_err *err);
/* Ends, submits and waits for the command buffer; then checks validation. */
enum rb_status rb_gpu_submit_wait(struct rb_gpu *gpu, struct rb_err *err);

/* A separate command buffer for uploads outside a frame; _end submits it and waits. */
enum rb_status rb_gpu_oneshot_begin(struct rb_gpu *gpu, VkCommandBuffer *out, struct rb_err *err);
enum rb_status rb_gpu_oneshot_end(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_err *err);

/* ---- pass timestamps (query.c) -------------------------------------------------------------- */

/* One recorded pass of the frame: its name and, after rb_gpu_pass_times, its GPU time. */
struct rb_gpu_pass {
    char name[32];
    double gpu_ms;
};

/* Opens a named pass: debug label and start timestamp. Passes may not nest, and are recorded
 * outside render-pass instances (a new query pool is reset in the command buffer when the
 * frame's passes outgrow the pools). There is no fixed limit on passes a frame; an allocation
 * that fails stops the timing, and rb_gpu_pass_times reports it. */
void rb_gpu_pass_begin(struct rb_gpu *gpu, VkCommandBuffer cmd, const char *name);
void rb_gpu_pass_end(struct rb_gpu *gpu, VkCommandBuffer cmd);
/* After rb_gpu_submit_wait: fills gpu->passes[i].gpu_ms for the frame's gpu->pass_count passes.
 * RB_E_NOMEM or RB_E_VULKAN when the timing could not be recorded. */
enum rb_status rb_gpu_pass_times(struct rb_gpu *gpu, struct rb_err *err);
/* Resets the frame's pass records and the pools' queries in cmd (rb_gpu_begin calls it). */
void rb_gpu_queries_reset(struct rb_gpu *gpu, VkCommandBuffer cmd);
/* Destroys the query pools and pass records (rb_gpu_destroy calls it). */
void rb_gpu_queries_release(struct rb_gpu *gpu);

/* ---- pipelines ----------------------------------------------------------------------------- */

/* The most bindings a push-descriptor set holds here: the maxPushDescriptors every Vulkan device
 * with VK_KHR_push_descriptor guarantees (lavapipe's exactly). A layout with more is refused at
 * create time; the binding list below is sized by it and checked against it. */
#define RB_GPU_MAX_BINDINGS 32

/* A push-descriptor set layout and pipeline layout from a list of bindings (binding i gets
 * types[i]) and a push-constant size, visible to all stages. */
struct rb_gpu_layout {
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout pipeline_layout;
    VkDescriptorType types[RB_GPU_MAX_BINDINGS]; /* binding i's type */
    uint32_t binding_count;
};
/* Fails with RB_E_UNSUPPORTED, before creating anything, when the bindings exceed the device's
 * limits (see rb_gpu_layout_check). */
enum rb_status rb_gpu_layout_init(struct rb_gpu *gpu, const VkDescriptorType *types, uint32_t count,
                                  uint32_t push_bytes, struct rb_gpu_layout *out,
                                  struct rb_err *err);
void rb_gpu_layout_release(struct rb_gpu *gpu, struct rb_gpu_layout *layout);
/* Checks one push-descriptor set of these bindings, visible to every stage, against a device's
 * limits (maxPushDescriptors, the maxPerStageDescriptor* counts, maxPerStageResources) and
 * RB_GPU_MAX_BINDINGS: RB_E_UNSUPPORTED with a message naming the limit and both numbers. Pure,
 * so tests can pass made-up limits. */
enum rb_status rb_gpu_layout_check(const VkPhysicalDeviceLimits *limits,
                                   uint32_t max_push_descriptors, const VkDescriptorType *types,
                                   uint32_t count, struct rb_err *err);

enum rb_status rb_gpu_compute_pipeline(struct rb_gpu *gpu, const uint32_t *spv, size_t spv_bytes,
                                       VkPipelineLayout layout, const char *debug_name,
                                       VkPipeline *out, struct rb_err *err);

struct rb_gpu_graphics_desc {
    const uint32_t *vert;
    size_t vert_bytes;
    const uint32_t *tesc; /* NULL: no tessellation; else tese too, and patches of triangles */
    size_t tesc_bytes;
    const uint32_t *tese;
    size_t tese_bytes;
    uint32_t patch_control_points; /* 0 == 3 (a triangle per patch) */
    const uint32_t *frag;
    size_t frag_bytes;
    VkPipelineLayout layout;
    const VkFormat *color_formats;
    uint32_t color_count;
    VkFormat depth_format; /* VK_FORMAT_UNDEFINED: none */
    VkCullModeFlags cull;
    bool has_depth_bias;
    bool is_depth_equal; /* test EQUAL and write no depth: the surfaces an earlier pass drew */
    bool is_blend_over;  /* test LESS and write no depth; each fragment's premultiplied colour
                          * goes over what is there, its alpha multiplies the destination's by
                          * 1 - alpha (the transparency pass: rgb gathers, a transmits) */
    const char *debug_name;
};
enum rb_status rb_gpu_graphics_pipeline(struct rb_gpu *gpu, const struct rb_gpu_graphics_desc *d,
                                        VkPipeline *out, struct rb_err *err);

/* Push-descriptor writes, built up by a pass at record time: writes[i] is binding i. Start from
 * {0}. Setting a binding twice or one at or past RB_GPU_MAX_BINDINGS is a bug (RB_BUG). */
struct rb_gpu_bindings {
    VkWriteDescriptorSet writes[RB_GPU_MAX_BINDINGS]; /* sType 0 while the binding is unset */
    VkDescriptorBufferInfo buffers[RB_GPU_MAX_BINDINGS];
    VkDescriptorImageInfo images[RB_GPU_MAX_BINDINGS];
    uint32_t count; /* one past the highest binding set */
};
/* Sets the given binding, whatever the order of the calls. */
void rb_gpu_bindings_set_buffer(struct rb_gpu_bindings *b, uint32_t binding, VkDescriptorType type,
                                const struct rb_gpu_buffer *buf);
/* Binds range_bytes of buf from offset_bytes at binding: a band of a buffer larger than a
 * binding may be (rb_gpu_storage_band_rows). */
void rb_gpu_bindings_set_buffer_range(struct rb_gpu_bindings *b, uint32_t binding,
                                      VkDescriptorType type, const struct rb_gpu_buffer *buf,
                                      VkDeviceSize offset_bytes, VkDeviceSize range_bytes);
void rb_gpu_bindings_set_image(struct rb_gpu_bindings *b, uint32_t binding, VkDescriptorType type,
                               VkImageView view, VkSampler sampler, VkImageLayout layout);
/* Set the next binding (b->count): the calls' order is the binding order. */
void rb_gpu_bind_buffer(struct rb_gpu_bindings *b, VkDescriptorType type,
                        const struct rb_gpu_buffer *buf);
void rb_gpu_bind_image(struct rb_gpu_bindings *b, VkDescriptorType type, VkImageView view,
                       VkSampler sampler, VkImageLayout layout);
/* Pushes bindings 0 to b->count - 1 as set 0; a binding left unset below b->count is a bug
 * (RB_BUG). */
void rb_gpu_push_bindings(struct rb_gpu *gpu, VkCommandBuffer cmd, VkPipelineBindPoint point,
                          VkPipelineLayout layout, const struct rb_gpu_bindings *b);

#endif
