/* Images, their views and layout barriers. */
#include "gpu/gpu.h"
#include "gpu/gpu_int.h"

#include <stdlib.h>

static VkImageAspectFlags aspect_of(VkFormat f)
{
    switch (f) {
    case VK_FORMAT_D32_SFLOAT:
    case VK_FORMAT_D16_UNORM: return VK_IMAGE_ASPECT_DEPTH_BIT;
    case VK_FORMAT_D24_UNORM_S8_UINT:
    case VK_FORMAT_D32_SFLOAT_S8_UINT:
        return VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
    default: return VK_IMAGE_ASPECT_COLOR_BIT;
    }
}

static VkResult make_view(struct rb_gpu *gpu, struct rb_gpu_image *img, VkImageViewType type,
                          uint32_t first_layer, uint32_t layers, uint32_t mips, VkImageView *out)
{
    VkImageViewCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
        .image = img->image,
        .viewType = type,
        .format = img->format,
        .subresourceRange = {img->aspect, 0, mips, first_layer, layers},
    };
    return vkCreateImageView(gpu->device, &ci, NULL, out);
}

enum rb_status rb_gpu_image_init(struct rb_gpu *gpu, const struct rb_gpu_image_desc *desc,
                                 struct rb_gpu_image *out, struct rb_err *err)
{
    struct rb_gpu_image img = {
        .format = desc->format,
        .width_px = desc->width_px ? desc->width_px : 1,
        .height_px = desc->height_px ? desc->height_px : 1,
        .layer_count = desc->layer_count ? desc->layer_count : 1,
        .mip_count = desc->mip_count ? desc->mip_count : 1,
        .aspect = aspect_of(desc->format),
    };
    enum rb_status st = RB_OK;
    VkImageCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
        .imageType = VK_IMAGE_TYPE_2D,
        .format = desc->format,
        .extent = {img.width_px, img.height_px, 1},
        .mipLevels = img.mip_count,
        .arrayLayers = img.layer_count,
        .samples = VK_SAMPLE_COUNT_1_BIT,
        .tiling = VK_IMAGE_TILING_OPTIMAL,
        .usage = desc->usage,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
        .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED,
    };
    VkResult vr = vkCreateImage(gpu->device, &ci, NULL, &img.image);
    if (vr < 0)
        return rb_gpu_fail(err, vr, "vkCreateImage", desc->debug_name);
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(gpu->device, img.image, &req);
    st = rb_gpu_alloc(gpu, req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, 0, desc->debug_name,
                      &img.memory, err);
    if (st)
        goto fail;
    if ((vr = vkBindImageMemory(gpu->device, img.image, img.memory, 0)) < 0) {
        st = rb_gpu_fail(err, vr, "vkBindImageMemory", desc->debug_name);
        goto fail;
    }
    bool array = desc->is_array || img.layer_count > 1;
    vr = make_view(gpu, &img, array ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D, 0,
                   img.layer_count, img.mip_count, &img.view);
    if (vr < 0) {
        st = rb_gpu_fail(err, vr, "vkCreateImageView", desc->debug_name);
        goto fail;
    }
    if (desc->has_layer_views) {
        img.layer_views = calloc(img.layer_count, sizeof(VkImageView));
        if (!img.layer_views) {
            st = rb_errf(err, RB_E_NOMEM, "out of memory");
            goto fail;
        }
        for (uint32_t l = 0; l < img.layer_count; l++)
            if ((vr = make_view(gpu, &img, VK_IMAGE_VIEW_TYPE_2D, l, 1, 1, &img.layer_views[l])) <
                0) {
                st = rb_gpu_fail(err, vr, "vkCreateImageView", desc->debug_name);
                goto fail;
            }
    }
    rb_gpu_name(gpu, VK_OBJECT_TYPE_IMAGE, (uint64_t)img.image, desc->debug_name);
    *out = img;
    return RB_OK;
fail:
    rb_gpu_image_release(gpu, &img);
    return st;
}

void rb_gpu_image_release(struct rb_gpu *gpu, struct rb_gpu_image *img)
{
    if (!img)
        return;
    if (img->layer_views) {
        for (uint32_t l = 0; l < img->layer_count; l++)
            if (img->layer_views[l])
                vkDestroyImageView(gpu->device, img->layer_views[l], NULL);
        free(img->layer_views);
    }
    if (img->view)
        vkDestroyImageView(gpu->device, img->view, NULL);
    if (img->image)
        vkDestroyImage(gpu->device, img->image, NULL);
    if (img->memory)
        vkFreeMemory(gpu->device, img->memory, NULL);
    *img = (struct rb_gpu_image){0};
}

void rb_gpu_image_barrier(struct rb_gpu *gpu, VkCommandBuffer cmd, struct rb_gpu_image *img,
                          VkImageLayout from, VkImageLayout to)
{
    (void)gpu;
    VkImageMemoryBarrier2 b = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
        .srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
        .srcAccessMask = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
        .dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
        .dstAccessMask = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
        .oldLayout = from,
        .newLayout = to,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .image = img->image,
        .subresourceRange = {img->aspect, 0, VK_REMAINING_MIP_LEVELS, 0, VK_REMAINING_ARRAY_LAYERS},
    };
    VkDependencyInfo dep = {
        .sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO,
        .imageMemoryBarrierCount = 1,
        .pImageMemoryBarriers = &b,
    };
    vkCmdPipelineBarrier2(cmd, &dep);
}

void rb_gpu_memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stages,
                           VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stages,
                           VkAccessFlags2 dst_access)
{
    VkMemoryBarrier2 b = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
        .srcStageMask = src_stages,
        .srcAccessMask = src_access,
        .dstStageMask = dst_stages,
        .dstAccessMask = dst_access,
    };
    VkDependencyInfo dep = {
        .sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO,
        .memoryBarrierCount = 1,
        .pMemoryBarriers = &b,
    };
    vkCmdPipelineBarrier2(cmd, &dep);
}

void rb_gpu_barrier(VkCommandBuffer cmd)
{
    VkAccessFlags2 all = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT;
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, all,
                          VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, all);
}
