/* Device limits that the renderer's sizes depend on: storage-buffer ranges, buffer and
 * allocation sizes, compute workgroup counts and push-descriptor counts. They are checked when a
 * resource is created, so that a frame or scene too large for the device fails with the limit
 * named, instead of in the validation layer or, without it, as undefined behaviour. This file
 * only reads limits. Splitting work to fit them is the job of the passes (output.c: bands). */
#include "gpu/gpu.h"
#include "gpu/gpu_int.h"

void rb_gpu_read_limits(struct rb_gpu *gpu)
{
    VkPhysicalDevicePushDescriptorPropertiesKHR push = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PUSH_DESCRIPTOR_PROPERTIES_KHR};
    VkPhysicalDeviceVulkan13Properties p13 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_PROPERTIES, .pNext = &push};
    VkPhysicalDeviceVulkan11Properties p11 = {
        .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES, .pNext = &p13};
    VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2,
                                      .pNext = &p11};
    vkGetPhysicalDeviceProperties2(gpu->phys, &p2);
    gpu->max_push_descriptors = push.maxPushDescriptors;
    gpu->max_buffer_bytes = p13.maxBufferSize;
    gpu->max_allocation_bytes = p11.maxMemoryAllocationSize;
}

/* Every limit error names the pass first, when there is one: "pass 'output': ...". */
static enum rb_status in_pass(struct rb_err *err, const char *pass)
{
    if (pass)
        rb_err_prefix(err, "pass '%s'", pass);
    return RB_E_UNSUPPORTED;
}

enum rb_status rb_gpu_check_storage_range(const struct rb_gpu *gpu, const char *pass,
                                          const char *resource, VkDeviceSize range_bytes,
                                          struct rb_err *err)
{
    uint32_t limit = gpu->props.limits.maxStorageBufferRange;
    if (range_bytes <= limit)
        return RB_OK;
    rb_errf(err, RB_E_UNSUPPORTED,
            "storage buffer '%s' binds %llu bytes, more than the device's "
            "maxStorageBufferRange (%u bytes)",
            resource, (unsigned long long)range_bytes, limit);
    return in_pass(err, pass);
}

enum rb_status rb_gpu_check_buffer_size(const struct rb_gpu *gpu, const char *pass,
                                        const char *resource, VkDeviceSize size_bytes,
                                        struct rb_err *err)
{
    const char *name = NULL;
    VkDeviceSize limit = 0;
    if (gpu->max_buffer_bytes && size_bytes > gpu->max_buffer_bytes) {
        name = "maxBufferSize";
        limit = gpu->max_buffer_bytes;
    } else if (gpu->max_allocation_bytes && size_bytes > gpu->max_allocation_bytes) {
        name = "maxMemoryAllocationSize";
        limit = gpu->max_allocation_bytes;
    }
    if (!name)
        return RB_OK;
    rb_errf(err, RB_E_UNSUPPORTED,
            "buffer '%s' needs %llu bytes, more than the device's %s (%llu bytes)", resource,
            (unsigned long long)size_bytes, name, (unsigned long long)limit);
    return in_pass(err, pass);
}

enum rb_status rb_gpu_check_dispatch(const struct rb_gpu *gpu, const char *pass, uint32_t x,
                                     uint32_t y, uint32_t z, struct rb_err *err)
{
    const uint32_t *limit = gpu->props.limits.maxComputeWorkGroupCount;
    const uint32_t count[3] = {x, y, z};
    for (int i = 0; i < 3; i++) {
        if (count[i] <= limit[i])
            continue;
        rb_errf(err, RB_E_UNSUPPORTED,
                "dispatch of %u x %u x %u workgroups: %u in %c, more than the device's "
                "maxComputeWorkGroupCount[%d] (%u)",
                x, y, z, count[i], "xyz"[i], i, limit[i]);
        return in_pass(err, pass);
    }
    return RB_OK;
}

enum rb_status rb_gpu_check_push_descriptors(const struct rb_gpu *gpu, const char *pass,
                                             uint32_t binding_count, struct rb_err *err)
{
    if (binding_count <= gpu->max_push_descriptors)
        return RB_OK;
    rb_errf(err, RB_E_UNSUPPORTED,
            "push-descriptor set of %u bindings, more than the device's maxPushDescriptors (%u)",
            binding_count, gpu->max_push_descriptors);
    return in_pass(err, pass);
}

static VkDeviceSize gcd(VkDeviceSize a, VkDeviceSize b)
{
    while (b) {
        VkDeviceSize t = a % b;
        a = b;
        b = t;
    }
    return a;
}

/* The fewest rows whose bytes are a multiple of minStorageBufferOffsetAlignment (a power of
 * two by the spec; gcd does not depend on it). */
static VkDeviceSize aligned_rows(const struct rb_gpu *gpu, VkDeviceSize row_bytes)
{
    VkDeviceSize align = gpu->props.limits.minStorageBufferOffsetAlignment;
    if (align <= 1 || row_bytes == 0)
        return 1;
    return align / gcd(row_bytes, align);
}

uint32_t rb_gpu_storage_band_rows(const struct rb_gpu *gpu, VkDeviceSize row_bytes,
                                  uint32_t row_count)
{
    VkDeviceSize limit = gpu->props.limits.maxStorageBufferRange;
    if (row_bytes * row_count <= limit)
        return row_count;
    VkDeviceSize fit = limit / row_bytes;
    fit -= fit % aligned_rows(gpu, row_bytes);
    return (uint32_t)fit; /* < row_count, since all rows do not fit */
}

enum rb_status rb_gpu_check_storage_bands(const struct rb_gpu *gpu, const char *pass,
                                          const char *resource, VkDeviceSize row_bytes,
                                          uint32_t row_count, struct rb_err *err)
{
    if (row_count == 0 || rb_gpu_storage_band_rows(gpu, row_bytes, row_count) > 0)
        return RB_OK;
    VkDeviceSize rows = aligned_rows(gpu, row_bytes);
    rb_errf(err, RB_E_UNSUPPORTED,
            "storage buffer '%s' binds at least %llu bytes (%llu rows of %llu bytes, the fewest "
            "that start every band on minStorageBufferOffsetAlignment, %llu bytes), more than "
            "the device's maxStorageBufferRange (%u bytes)",
            resource, (unsigned long long)(rows * row_bytes), (unsigned long long)rows,
            (unsigned long long)row_bytes,
            (unsigned long long)gpu->props.limits.minStorageBufferOffsetAlignment,
            gpu->props.limits.maxStorageBufferRange);
    return in_pass(err, pass);
}
