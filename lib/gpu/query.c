/* Pass timestamps and labels: two timestamp queries a pass, in pools of POOL_QUERIES. A frame
 * that records more passes than the pools hold gets another pool, created and reset in the
 * command buffer as it records (bdpt's loop records hundreds of passes), so no fixed cap aborts
 * the program; the driver groups the passes by name for the timing sidecar. */
#include "gpu/gpu.h"

#include <stdlib.h>
#include <string.h>

#define POOL_QUERIES 256u

void rb_gpu_queries_reset(struct rb_gpu *gpu, VkCommandBuffer cmd)
{
    for (uint32_t i = 0; i < gpu->query_pool_count; i++)
        vkCmdResetQueryPool(cmd, gpu->query_pools[i], 0, POOL_QUERIES);
    gpu->pass_count = 0;
    gpu->timing_status = RB_OK;
}

/* Room for one more pass record and its two queries; false (and timing_status set) when it
 * cannot be made. */
static bool reserve(struct rb_gpu *gpu, VkCommandBuffer cmd)
{
    if (gpu->pass_count == gpu->pass_cap) {
        uint32_t cap = gpu->pass_cap ? 2 * gpu->pass_cap : 64;
        struct rb_gpu_pass *p = realloc(gpu->passes, cap * sizeof(*p));
        if (!p) {
            gpu->timing_status = RB_E_NOMEM;
            return false;
        }
        gpu->passes = p;
        gpu->pass_cap = cap;
    }
    uint32_t pool = 2 * gpu->pass_count / POOL_QUERIES;
    if (pool < gpu->query_pool_count)
        return true;
    VkQueryPool *pools = realloc(gpu->query_pools, (pool + 1) * sizeof(*pools));
    if (!pools) {
        gpu->timing_status = RB_E_NOMEM;
        return false;
    }
    gpu->query_pools = pools;
    VkQueryPoolCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
        .queryType = VK_QUERY_TYPE_TIMESTAMP,
        .queryCount = POOL_QUERIES,
    };
    if (vkCreateQueryPool(gpu->device, &ci, NULL, &pools[pool]) < 0) {
        gpu->timing_status = RB_E_VULKAN;
        return false;
    }
    gpu->query_pool_count = pool + 1;
    rb_gpu_name(gpu, VK_OBJECT_TYPE_QUERY_POOL, (uint64_t)pools[pool], "pass timestamps");
    vkCmdResetQueryPool(cmd, pools[pool], 0, POOL_QUERIES);
    return true;
}

static void write_timestamp(struct rb_gpu *gpu, VkCommandBuffer cmd, uint32_t query)
{
    vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                         gpu->query_pools[query / POOL_QUERIES], query % POOL_QUERIES);
}

void rb_gpu_pass_begin(struct rb_gpu *gpu, VkCommandBuffer cmd, const char *name)
{
    if (gpu->begin_label) {
        VkDebugUtilsLabelEXT label = {.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_LABEL_EXT,
                                      .pLabelName = name};
        gpu->begin_label(cmd, &label);
    }
    if (gpu->timing_status || !reserve(gpu, cmd))
        return;
    struct rb_gpu_pass *p = &gpu->passes[gpu->pass_count];
    rb_strlcpy(p->name, name, sizeof(p->name));
    p->gpu_ms = 0.0;
    write_timestamp(gpu, cmd, 2 * gpu->pass_count);
}

void rb_gpu_pass_end(struct rb_gpu *gpu, VkCommandBuffer cmd)
{
    if (!gpu->timing_status) {
        write_timestamp(gpu, cmd, 2 * gpu->pass_count + 1);
        gpu->pass_count++;
    }
    if (gpu->end_label)
        gpu->end_label(cmd);
}

enum rb_status rb_gpu_pass_times(struct rb_gpu *gpu, struct rb_err *err)
{
    if (gpu->timing_status == RB_E_NOMEM)
        return rb_errf(err, RB_E_NOMEM, "out of memory for the timestamps of %u passes",
                       gpu->pass_count + 1);
    if (gpu->timing_status)
        return rb_errf(err, gpu->timing_status,
                       "vkCreateQueryPool 'pass timestamps' failed after %u passes",
                       gpu->pass_count);
    uint64_t ts[POOL_QUERIES];
    uint32_t queries = 2 * gpu->pass_count;
    for (uint32_t first = 0; first < queries; first += POOL_QUERIES) {
        uint32_t n = queries - first < POOL_QUERIES ? queries - first : POOL_QUERIES;
        VkResult vr = vkGetQueryPoolResults(gpu->device, gpu->query_pools[first / POOL_QUERIES], 0,
                                            n, sizeof(ts), ts, sizeof(uint64_t),
                                            VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
        if (vr < 0)
            return rb_gpu_fail(err, vr, "vkGetQueryPoolResults", "pass timestamps");
        for (uint32_t q = 0; q < n; q += 2) {
            uint64_t d = (ts[q + 1] - ts[q]) & gpu->timestamp_mask;
            gpu->passes[(first + q) / 2].gpu_ms = (double)d * gpu->timestamp_period_ns * 1e-6;
        }
    }
    return RB_OK;
}

void rb_gpu_queries_release(struct rb_gpu *gpu)
{
    for (uint32_t i = 0; i < gpu->query_pool_count; i++)
        vkDestroyQueryPool(gpu->device, gpu->query_pools[i], NULL);
    free(gpu->query_pools);
    free(gpu->passes);
    gpu->query_pools = NULL;
    gpu->passes = NULL;
    gpu->query_pool_count = gpu->pass_count = gpu->pass_cap = 0;
}
