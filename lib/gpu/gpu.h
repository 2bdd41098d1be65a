/* The GPU context: a headless Vulkan 1.3 device (lavapipe by default), validation, memory,
 * buffers, images, pipelines with push descriptors, one-shot command submission, per-pass
 * timestamps and debug labels. Passes use the Vulkan handles in struct rb_gpu directly. */
#ifndef RB_GPU_GPU_H
#define RB_GPU_GPU_H

#include "core/core.h"

#include <stdio.h>
#include <vulkan/vulkan.h>

#define RB_GPU_MAX_PASSES 64

struct rb_gpu_desc {
    const char *device; /* name substring or index; NULL: lavapipe, else the first device */
    bool validate;      /* enable VK_LAYER_KHRONOS_validation; any message fails the run */
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
    char device_name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE];
    char driver[256]; /* driver name and info, e.g. "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)" */
    bool is_lavapipe;
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

    /* timestamps: 2 queries per pass, recorded by rb_gpu_pass_begin/end */
    VkQueryPool queries;
    double timestamp_period_ns;
    uint64_t timestamp_mask;
    char pass_names[RB_GPU_MAX_PASSES][32];
    uint32_t pass_count;

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

/* ---- buffers ------------------------------------------------------------------------------- */

struct rb_gpu_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    void *mapped; /* non-NULL for host-visible buffers */
};

struct rb_gpu_buffer_desc {
    VkDeviceSize size_bytes;
    VkBufferUsageFlags usage;
    bool is_host_visible; /* mapped, coherent: uploads each frame, readback */
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

/* ---- commands ------------------------------------------------------------------------------ */

/* Starts recording the device's one command buffer; resets the pass list. */
enum rb_status rb_gpu_begin(struct rb_gpu *gpu, struct rb_err *err);
/* Ends, submits and waits for the command buffer; then checks validation. */
enum rb_status rb_gpu_submit_wait(struct rb_gpu *gpu, struct rb_err *err);

/* A separate command buffer for uploads outside a frame; _end submits it and waits. */
enum rb_status rb_gpu_oneshot_begin(struct rb_gpu *gpu, VkCommandBuffer *out, struct rb_err *err);
enum rb_status rb_gpu_oneshot_end(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_err *err);

/* Opens a named pass: debug label and start timestamp. Passes may not nest. */
void rb_gpu_pass_begin(struct rb_gpu *gpu, VkCommandBuffer cmd, const char *name);
void rb_gpu_pass_end(struct rb_gpu *gpu, VkCommandBuffer cmd);
/* After rb_gpu_submit_wait: the GPU milliseconds of pass i (0 <= i < gpu->pass_count). */
enum rb_status rb_gpu_pass_times(struct rb_gpu *gpu, double *out_ms, struct rb_err *err);

/* ---- pipelines ----------------------------------------------------------------------------- */

/* A push-descriptor set layout and pipeline layout from a list of bindings (binding i gets
 * types[i]) and a push-constant size, visible to all stages. */
struct rb_gpu_layout {
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout pipeline_layout;
};
enum rb_status rb_gpu_layout_init(struct rb_gpu *gpu, const VkDescriptorType *types, uint32_t count,
                                  uint32_t push_bytes, struct rb_gpu_layout *out,
                                  struct rb_err *err);
void rb_gpu_layout_release(struct rb_gpu *gpu, struct rb_gpu_layout *layout);

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
    const char *debug_name;
};
enum rb_status rb_gpu_graphics_pipeline(struct rb_gpu *gpu, const struct rb_gpu_graphics_desc *d,
                                        VkPipeline *out, struct rb_err *err);

/* Push-descriptor writes, built up by a pass at record time. */
struct rb_gpu_bindings {
    VkWriteDescriptorSet writes[16];
    VkDescriptorBufferInfo buffers[16];
    VkDescriptorImageInfo images[16];
    uint32_t count;
};
void rb_gpu_bind_buffer(struct rb_gpu_bindings *b, VkDescriptorType type,
                        const struct rb_gpu_buffer *buf);
void rb_gpu_bind_image(struct rb_gpu_bindings *b, VkDescriptorType type, VkImageView view,
                       VkSampler sampler, VkImageLayout layout);
void rb_gpu_push_bindings(struct rb_gpu *gpu, VkCommandBuffer cmd, VkPipelineBindPoint point,
                          VkPipelineLayout layout, const struct rb_gpu_bindings *b);

#endif
