/* direct: direct light from punctual lights (shadow-mapped) and emission at each G-buffer pixel,
 * the environment where there is no geometry (DESIGN.md "direct"). */
#include "passes/passes.h"

#include <stdlib.h>

#include "direct.comp.h"

struct rb_pass_direct {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
};

static const VkDescriptorType bindings[] = {
    VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,         VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
    VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,          VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
    VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,          VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
    VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,          VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,         VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
};

enum rb_status rb_pass_direct_create(struct rb_gpu *gpu, struct rb_pass_direct **out,
                                     struct rb_err *err)
{
    struct rb_pass_direct *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    enum rb_status st = rb_gpu_layout_init(gpu, bindings, 12, 0, &p->layout, err);
    if (st == RB_OK)
        st = rb_gpu_compute_pipeline(gpu, rb_spv_direct_comp, sizeof(rb_spv_direct_comp),
                                     p->layout.pipeline_layout, "direct", &p->pipeline, err);
    if (st) {
        rb_pass_direct_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_direct_record(struct rb_pass_direct *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame)
{
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &frame->globals);
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT; i++)
        rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, frame->gbuffer[i].view,
                          VK_NULL_HANDLE, VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->lights);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->shadow_views);
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, frame->shadow_maps.view,
                      p->gpu->nearest_sampler, VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, frame->env_map.view,
                      p->gpu->env_sampler, VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, frame->direct.view, VK_NULL_HANDLE,
                      VK_IMAGE_LAYOUT_GENERAL);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    rb_gpu_push_bindings(p->gpu, cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout.pipeline_layout,
                         &b);
    vkCmdDispatch(cmd, (frame->width_px + 7) / 8, (frame->height_px + 7) / 8, 1);
}

void rb_pass_direct_destroy(struct rb_pass_direct *p)
{
    if (!p)
        return;
    if (p->pipeline)
        vkDestroyPipeline(p->gpu->device, p->pipeline, NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
    free(p);
}
