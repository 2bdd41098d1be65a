/* gbuffer: rasterizes the world-space vertices once, all instances in one indexed draw, into
 * full-precision attachments (DESIGN.md "gbuffer"): position and view depth, shading normal and
 * face, diffuse albedo, specular F0 and roughness, emission and F90, motion vectors. */
#include "passes/passes.h"

#include <stdlib.h>

#include "gbuffer.frag.h"
#include "gbuffer.vert.h"

const VkFormat rb_gbuffer_formats[RB_GBUFFER_COLOR_COUNT] = {
    VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT,
};

struct rb_pass_gbuffer {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
};

static const VkDescriptorType bindings[] = {
    VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,         VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,         VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
};

enum rb_status rb_pass_gbuffer_create(struct rb_gpu *gpu, struct rb_pass_gbuffer **out,
                                      struct rb_err *err)
{
    struct rb_pass_gbuffer *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    enum rb_status st = rb_gpu_layout_init(gpu, bindings, 6, 0, &p->layout, err);
    if (st == RB_OK)
        st = rb_gpu_graphics_pipeline(
            gpu,
            &(struct rb_gpu_graphics_desc){
                .vert = rb_spv_gbuffer_vert,
                .vert_bytes = sizeof(rb_spv_gbuffer_vert),
                .frag = rb_spv_gbuffer_frag,
                .frag_bytes = sizeof(rb_spv_gbuffer_frag),
                .layout = p->layout.pipeline_layout,
                .color_formats = rb_gbuffer_formats,
                .color_count = RB_GBUFFER_COLOR_COUNT,
                .depth_format = VK_FORMAT_D32_SFLOAT,
                .cull = VK_CULL_MODE_NONE, /* single-sided materials discard back faces */
                .debug_name = "gbuffer",
            },
            &p->pipeline, err);
    if (st) {
        rb_pass_gbuffer_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_gbuffer_record(struct rb_pass_gbuffer *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *cur,
                            const struct rb_frame_slot *prev)
{
    VkRenderingAttachmentInfo colors[RB_GBUFFER_COLOR_COUNT];
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT; i++)
        colors[i] = (VkRenderingAttachmentInfo){
            .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
            .imageView = frame->gbuffer[i].view,
            .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
            .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
            .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
            .clearValue = {.color = {{0.0f, 0.0f, 0.0f, 0.0f}}},
        };
    VkRenderingAttachmentInfo depth = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
        .imageView = frame->depth.view,
        .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
        .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
        .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
        .clearValue = {.depthStencil = {1.0f, 0}},
    };
    VkRenderingInfo ri = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
        .renderArea = {{0, 0}, {frame->width_px, frame->height_px}},
        .layerCount = 1,
        .colorAttachmentCount = RB_GBUFFER_COLOR_COUNT,
        .pColorAttachments = colors,
        .pDepthAttachment = &depth,
    };
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, &frame->globals);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &cur->vertices);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &prev->vertices);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->materials);
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, frame->srgb_textures.view,
                      p->gpu->linear_sampler, VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, frame->linear_textures.view,
                      p->gpu->linear_sampler, VK_IMAGE_LAYOUT_GENERAL);

    vkCmdBeginRendering(cmd, &ri);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipeline);
    rb_gpu_push_bindings(p->gpu, cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->layout.pipeline_layout,
                         &b);
    VkViewport vp = {0, 0, (float)frame->width_px, (float)frame->height_px, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {frame->width_px, frame->height_px}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &sc);
    if (frame->index_count) {
        vkCmdBindIndexBuffer(cmd, frame->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(cmd, frame->index_count, 1, 0, 0, 0);
    }
    vkCmdEndRendering(cmd);
}

void rb_pass_gbuffer_destroy(struct rb_pass_gbuffer *p)
{
    if (!p)
        return;
    if (p->pipeline)
        vkDestroyPipeline(p->gpu->device, p->pipeline, NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
    free(p);
}
