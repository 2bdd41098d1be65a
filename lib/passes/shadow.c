/* shadow: one render per shadow-map layer (six cube faces per point light, one map per spot or
 * directional light) of the distance to the light into an R32F array (DESIGN.md "shadow"). The
 * direct pass filters it by hand with 16-tap PCF. */
#include "passes/passes.h"

#include <stdlib.h>

#include "shadow.frag.h"
#include "shadow.vert.h"

struct rb_pass_shadow {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
};

static const VkDescriptorType bindings[] = {
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
};

enum rb_status rb_pass_shadow_create(struct rb_gpu *gpu, struct rb_pass_shadow **out,
                                     struct rb_err *err)
{
    struct rb_pass_shadow *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    VkFormat color = VK_FORMAT_R32_SFLOAT;
    enum rb_status st = rb_gpu_layout_init(gpu, bindings, 2, sizeof(uint32_t), &p->layout, err);
    if (st == RB_OK)
        st = rb_gpu_graphics_pipeline(gpu,
                                      &(struct rb_gpu_graphics_desc){
                                          .vert = rb_spv_shadow_vert,
                                          .vert_bytes = sizeof(rb_spv_shadow_vert),
                                          .frag = rb_spv_shadow_frag,
                                          .frag_bytes = sizeof(rb_spv_shadow_frag),
                                          .layout = p->layout.pipeline_layout,
                                          .color_formats = &color,
                                          .color_count = 1,
                                          .depth_format = VK_FORMAT_D32_SFLOAT,
                                          .cull = VK_CULL_MODE_NONE,
                                          .debug_name = "shadow",
                                      },
                                      &p->pipeline, err);
    if (st) {
        rb_pass_shadow_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_shadow_record(struct rb_pass_shadow *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *cur)
{
    uint32_t size = frame->shadow_maps.width_px;
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &cur->vertices);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->shadow_views);
    for (uint32_t layer = 0; layer < frame->shadow_layer_count; layer++) {
        VkRenderingAttachmentInfo color = {
            .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
            .imageView = frame->shadow_maps.layer_views[layer],
            .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
            .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
            .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
            .clearValue = {.color = {{3.0e38f, 0.0f, 0.0f, 0.0f}}}, /* nothing: far away */
        };
        VkRenderingAttachmentInfo depth = {
            .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
            .imageView = frame->shadow_depth.view,
            .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
            .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
            .storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE,
            .clearValue = {.depthStencil = {1.0f, 0}},
        };
        VkRenderingInfo ri = {
            .sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
            .renderArea = {{0, 0}, {size, size}},
            .layerCount = 1,
            .colorAttachmentCount = 1,
            .pColorAttachments = &color,
            .pDepthAttachment = &depth,
        };
        vkCmdBeginRendering(cmd, &ri);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipeline);
        rb_gpu_push_bindings(p->gpu, cmd, VK_PIPELINE_BIND_POINT_GRAPHICS,
                             p->layout.pipeline_layout, &b);
        vkCmdPushConstants(cmd, p->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(uint32_t),
                           &layer);
        VkViewport vp = {0, 0, (float)size, (float)size, 0.0f, 1.0f};
        VkRect2D sc = {{0, 0}, {size, size}};
        vkCmdSetViewport(cmd, 0, 1, &vp);
        vkCmdSetScissor(cmd, 0, 1, &sc);
        if (frame->index_count) {
            vkCmdBindIndexBuffer(cmd, frame->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
            vkCmdDrawIndexed(cmd, frame->index_count, 1, 0, 0, 0);
        }
        vkCmdEndRendering(cmd);
        /* The scratch depth image is reused by the next layer. */
        rb_gpu_barrier(cmd);
    }
}

void rb_pass_shadow_destroy(struct rb_pass_shadow *p)
{
    if (!p)
        return;
    if (p->pipeline)
        vkDestroyPipeline(p->gpu->device, p->pipeline, NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
    free(p);
}
