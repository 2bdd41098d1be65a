/* Command submission (one frame command buffer, one-shot uploads), pass timestamps and labels. */
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
    vkCmdResetQueryPool(gpu->cmd, gpu->queries, 0, 2 * RB_GPU_MAX_PASSES);
    gpu->pass_count = 0;
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

void rb_gpu_pass_begin(struct rb_gpu *gpu, VkCommandBuffer cmd, const char *name)
{
    if (gpu->pass_count >= RB_GPU_MAX_PASSES)
        RB_BUG("more than %d passes in a frame", RB_GPU_MAX_PASSES);
    rb_strlcpy(gpu->pass_names[gpu->pass_count], name, sizeof(gpu->pass_names[0]));
    if (gpu->begin_label) {
        VkDebugUtilsLabelEXT label = {.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_LABEL_EXT,
                                      .pLabelName = name};
        gpu->begin_label(cmd, &label);
    }
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, gpu->queries,
                         2 * gpu->pass_count);
}

void rb_gpu_pass_end(struct rb_gpu *gpu, VkCommandBuffer cmd)
{
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, gpu->queries,
                         2 * gpu->pass_count + 1);
    if (gpu->end_label)
        gpu->end_label(cmd);
    gpu->pass_count++;
}

enum rb_status rb_gpu_pass_times(struct rb_gpu *gpu, double *out_ms, struct rb_err *err)
{
    uint64_t ts[2 * RB_GPU_MAX_PASSES];
    if (gpu->pass_count == 0)
        return RB_OK;
    VkResult vr =
        vkGetQueryPoolResults(gpu->device, gpu->queries, 0, 2 * gpu->pass_count, sizeof(ts), ts,
                              sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkGetQueryPoolResults", "timestamps");
    for (uint32_t i = 0; i < gpu->pass_count; i++) {
        uint64_t d = (ts[2 * i + 1] - ts[2 * i]) & gpu->timestamp_mask;
        out_ms[i] = (double)d * gpu->timestamp_period_ns * 1e-6;
    }
    return RB_OK;
}
