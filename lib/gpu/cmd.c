/* Command submission: one frame command buffer, one-shot uploads. */
#include "gpu/gpu.h"

#include <string.h>

enum rb_status rb_gpu_begin(struct rb_gpu *gpu, struct rb_err *err)
{
    VkResult vr = vkResetCommandBuffer(gpu->cmd, 0);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkResetCommandBuffer", NULL);
    VkCommandBufferBeginInfo bi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    if ((vr = vkBeginCommandBuffer(gpu->cmd, &bi)) < 0)
        return rb_gpu_fail(err, vr, "vkBeginCommandBuffer", NULL);
    rb_gpu_queries_reset(gpu, gpu->cmd);
    return RB_OK;
}

static enum rb_status submit_wait(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_err *err)
{
    VkResult vr = vkEndCommandBuffer(cmd);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkEndCommandBuffer", NULL);
    VkSubmitInfo si = {
        .sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
        .commandBufferCount = 1,
        .pCommandBuffers = &cmd,
    };
    if ((vr = vkResetFences(gpu->device, 1, &gpu->fence)) < 0)
        return rb_gpu_fail(err, vr, "vkResetFences", NULL);
    if ((vr = vkQueueSubmit(gpu->queue, 1, &si, gpu->fence)) < 0)
        return rb_gpu_fail(err, vr, "vkQueueSubmit", NULL);
    if ((vr = vkWaitForFences(gpu->device, 1, &gpu->fence, VK_TRUE, UINT64_MAX)) < 0)
        return rb_gpu_fail(err, vr, "vkWaitForFences", NULL);
    return rb_gpu_check_validation(gpu, err);
}

enum rb_status rb_gpu_submit_wait(struct rb_gpu *gpu, struct rb_err *err)
{
    return submit_wait(gpu, gpu->cmd, err);
}

enum rb_status rb_gpu_oneshot_begin(struct rb_gpu *gpu, VkCommandBuffer *out, struct rb_err *err)
{
    VkCommandBufferAllocateInfo ai = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
        .commandPool = gpu->pool,
        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
        .commandBufferCount = 1,
    };
    VkResult vr = vkAllocateCommandBuffers(gpu->device, &ai, out);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkAllocateCommandBuffers", "upload");
    VkCommandBufferBeginInfo bi = {
        .sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
        .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
    };
    if ((vr = vkBeginCommandBuffer(*out, &bi)) < 0) {
        vkFreeCommandBuffers(gpu->device, gpu->pool, 1, out);
        return rb_gpu_fail(err, vr, "vkBeginCommandBuffer", "upload");
    }
    return RB_OK;
}

enum rb_status rb_gpu_oneshot_end(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_err *err)
{
    enum rb_status st = submit_wait(gpu, cmd, err);
    vkFreeCommandBuffers(gpu->device, gpu->pool, 1, &cmd);
    return st;
}
