/* Private to lib/gpu. */
#ifndef RB_GPU_GPU_INT_H
#define RB_GPU_GPU_INT_H

#include "gpu/gpu.h"

enum rb_status rb_gpu_alloc(struct rb_gpu *gpu, VkMemoryRequirements req,
                            VkMemoryPropertyFlags want, VkMemoryPropertyFlags need,
                            const char *what, VkDeviceMemory *out, struct rb_err *err);

/* Reads the limits that are not in VkPhysicalDeviceLimits into gpu (lib/gpu/limits.c). */
void rb_gpu_read_limits(struct rb_gpu *gpu);

#endif
