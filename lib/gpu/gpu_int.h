/* Private to lib/gpu. */
#ifndef RB_GPU_GPU_INT_H
#define RB_GPU_GPU_INT_H

#include "gpu/gpu.h"

/* Allocates memory for req of a type with need (and want, where one has it);
 * alloc_flags are VkMemoryAllocateFlags (VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT for an addressed
 * buffer). */
enum rb_status rb_gpu_alloc(struct rb_gpu *gpu, VkMemoryRequirements req,
                            VkMemoryPropertyFlags want, VkMemoryPropertyFlags need,
                            VkMemoryAllocateFlags alloc_flags, const char *what,
                            VkDeviceMemory *out, struct rb_err *err);

/* Reads the limits that are not in VkPhysicalDeviceLimits into gpu (lib/gpu/limits.c). */
void rb_gpu_read_limits(struct rb_gpu *gpu);

#endif
