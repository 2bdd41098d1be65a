/* Buffers and their memory. Host-visible buffers stay mapped; others are filled through a
 * staging copy. One allocation per object: the renderer has few, large objects. */
#include "gpu/gpu.h"
#include "gpu/gpu_int.h"

#include <stdio.h>
#include <string.h>

enum rb_status rb_gpu_alloc(struct rb_gpu *gpu, VkMemoryRequirements req,
                            VkMemoryPropertyFlags want, VkMemoryPropertyFlags need,
                            VkMemoryAllocateFlags alloc_flags, const char *what,
                            VkDeviceMemory *out, struct rb_err *err)
{
    int best = -1;
    for (int pass = 0; pass < 2 && best < 0; pass++) {
        VkMemoryPropertyFlags flags = pass == 0 ? (want | need) : need;
        for (uint32_t i = 0; i < gpu->mem_props.memoryTypeCount; i++)
            if ((req.memoryTypeBits & (1u << i)) &&
                (gpu->mem_props.memoryTypes[i].propertyFlags & flags) == flags) {
                best = (int)i;
                break;
            }
    }
    if (best < 0)
        return rb_errf(err, RB_E_VULKAN, "no memory type for '%s'", what);
    VkMemoryAllocateFlagsInfo fi = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO,
        .flags = alloc_flags,
    };
    VkMemoryAllocateInfo ai = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
        .pNext = alloc_flags ? &fi : NULL,
        .allocationSize = req.size,
        .memoryTypeIndex = (uint32_t)best,
    };
    VkResult vr = vkAllocateMemory(gpu->device, &ai, NULL, out);
    if (vr < 0) {
        /* Say how much: a setting that sizes it (a map size times a count) is the usual fix. */
        char call[64];
        snprintf(call, sizeof(call), "vkAllocateMemory of %.1f MiB",
                 (double)req.size / (1024.0 * 1024.0));
        return rb_gpu_fail(err, vr, call, what);
    }
    return RB_OK;
}

enum rb_status rb_gpu_buffer_init(struct rb_gpu *gpu, const struct rb_gpu_buffer_desc *desc,
                                  struct rb_gpu_buffer *out, struct rb_err *err)
{
    struct rb_gpu_buffer b = {0};
    enum rb_status st = RB_OK;
    VkDeviceSize size = desc->size_bytes ? desc->size_bytes : 16;
    VkBufferCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = size,
        .usage = desc->usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                 (desc->is_addressed ? VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT : 0),
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
    };
    VkResult vr = vkCreateBuffer(gpu->device, &ci, NULL, &b.buffer);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkCreateBuffer", desc->debug_name);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(gpu->device, b.buffer, &req);
    VkMemoryPropertyFlags need = desc->is_host_visible ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                                             VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                                                       : 0;
    VkMemoryPropertyFlags want = desc->is_host_visible ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT
                                                       : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    st = rb_gpu_alloc(gpu, req, want, need,
                      desc->is_addressed ? VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT : 0,
                      desc->debug_name, &b.memory, err);
    if (st)
        goto fail;
    if ((vr = vkBindBufferMemory(gpu->device, b.buffer, b.memory, 0)) < 0) {
        st = rb_gpu_fail(err, vr, "vkBindBufferMemory", desc->debug_name);
        goto fail;
    }
    if (desc->is_host_visible &&
        (vr = vkMapMemory(gpu->device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped)) < 0) {
        st = rb_gpu_fail(err, vr, "vkMapMemory", desc->debug_name);
        goto fail;
    }
    if (desc->is_addressed)
        b.address = vkGetBufferDeviceAddress(
            gpu->device,
            &(VkBufferDeviceAddressInfo){.sType = VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO,
                                         .buffer = b.buffer});
    b.size = size;
    rb_gpu_name(gpu, VK_OBJECT_TYPE_BUFFER, (uint64_t)b.buffer, desc->debug_name);
    *out = b;
    return RB_OK;
fail:
    rb_gpu_buffer_release(gpu, &b);
    return st;
}

void rb_gpu_buffer_release(struct rb_gpu *gpu, struct rb_gpu_buffer *buf)
{
    if (!buf)
        return;
    if (buf->buffer)
        vkDestroyBuffer(gpu->device, buf->buffer, NULL);
    if (buf->memory)
        vkFreeMemory(gpu->device, buf->memory, NULL);
    *buf = (struct rb_gpu_buffer){0};
}

enum rb_status rb_gpu_buffer_upload(struct rb_gpu *gpu, struct rb_gpu_buffer *buf, const void *data,
                                    VkDeviceSize size, struct rb_err *err)
{
    if (size > buf->size)
        RB_BUG("upload of %llu bytes into a %llu-byte buffer", (unsigned long long)size,
               (unsigned long long)buf->size);
    if (size == 0)
        return RB_OK;
    if (buf->mapped) {
        memcpy(buf->mapped, data, size);
        return RB_OK;
    }
    struct rb_gpu_buffer staging = {0};
    enum rb_status st =
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = size,
                                                        .usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = "staging"},
                           &staging, err);
    if (st)
        return st;
    memcpy(staging.mapped, data, size);
    VkCommandBuffer cmd;
    st = rb_gpu_oneshot_begin(gpu, &cmd, err);
    if (st == RB_OK) {
        vkCmdCopyBuffer(cmd, staging.buffer, buf->buffer, 1,
                        &(VkBufferCopy){.srcOffset = 0, .dstOffset = 0, .size = size});
        st = rb_gpu_oneshot_end(gpu, cmd, err);
    }
    rb_gpu_buffer_release(gpu, &staging);
    return st;
}
