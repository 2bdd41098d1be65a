/* gbuffer: rasterizes the world-space vertices once, all instances in one indexed draw, into
 * full-precision attachments (DESIGN.md "gbuffer"): position and view depth, shading normal and
 * face, diffuse albedo, specular F0 and roughness, emission and F90, motion vectors. */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "gbuffer.frag.h"
#include "gbuffer.vert.h"

const VkFormat rb_gbuffer_formats[RB_GBUFFER_COLOR_COUNT] = {
    VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT,
};

struct rb_pass_gbuffer {
    struct rb_pass pass;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_GBUFFER_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_GBUFFER_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_GBUFFER_PREV_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_GBUFFER_MATERIALS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_GBUFFER_SRGB_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_GBUFFER_LINEAR_TEXTURES, COMBINED_IMAGE_SAMPLER),
};
_Static_assert(COUNT(bindings) == RB_BIND_GBUFFER_COUNT, "gbuffer bindings");

enum rb_status rb_pass_gbuffer_create(struct rb_gpu *gpu, struct rb_pass_gbuffer **out,
                                      struct rb_err *err)
{
    struct rb_pass_gbuffer *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_raster_init(
        gpu,
        &(struct rb_pass_raster_desc){
            .name = "gbuffer",
            RB_PASS_BINDINGS(bindings),
            .graphics =
                {
                    .vert = rb_spv_gbuffer_vert,
                    .vert_bytes = sizeof(rb_spv_gbuffer_vert),
                    .frag = rb_spv_gbuffer_frag,
                    .frag_bytes = sizeof(rb_spv_gbuffer_frag),
                    .color_formats = rb_gbuffer_formats,
                    .color_count = RB_GBUFFER_COLOR_COUNT,
                    .depth_format = VK_FORMAT_D32_SFLOAT,
                    .cull = VK_CULL_MODE_NONE, /* single-sided materials discard back faces */
                },
            .push_bytes = sizeof(float[4]),
        },
        &p->pass, err);
    if (st) {
        rb_pass_gbuffer_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_gbuffer_record(struct rb_pass_gbuffer *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *cur,
                            const struct rb_frame_slot *prev,
                            const struct rb_gbuffer_target *target)
{
    const struct rb_gpu_image *gb = target ? target->colors : frame->gbuffer;
    VkRenderingAttachmentInfo colors[RB_GBUFFER_COLOR_COUNT];
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT; i++)
        colors[i] = (VkRenderingAttachmentInfo){
            .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
            .imageView = gb[i].view,
            .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
            .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
            .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
            .clearValue = {.color = {{0.0f, 0.0f, 0.0f, 0.0f}}},
        };
    VkRenderingAttachmentInfo depth = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
        .imageView = target ? target->depth->view : frame->depth.view,
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
    struct rb_pass_bindings b = {.pass = &p->pass};
    rb_pass_bind_buffer(&b, RB_BIND_GBUFFER_GLOBALS, &frame->globals);
    rb_pass_bind_buffer(&b, RB_BIND_GBUFFER_VERTICES, &cur->geometry);
    rb_pass_bind_buffer(&b, RB_BIND_GBUFFER_PREV_VERTICES, &prev->geometry);
    rb_pass_bind_buffer(&b, RB_BIND_GBUFFER_MATERIALS, &frame->materials);
    rb_pass_bind_image(&b, RB_BIND_GBUFFER_SRGB_TEXTURES, frame->srgb_textures.view,
                       p->pass.gpu->linear_sampler);
    rb_pass_bind_image(&b, RB_BIND_GBUFFER_LINEAR_TEXTURES, frame->linear_textures.view,
                       p->pass.gpu->linear_sampler);

    /* Samples at + offset: the image moves by - offset, in clip space -2 offset / size, times w
     * (gbuffer.vert). */
    float jitter[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    if (target) {
        jitter[0] = -2.0f * target->offset_px[0] / (float)frame->width_px;
        jitter[1] = -2.0f * target->offset_px[1] / (float)frame->height_px;
    }
    vkCmdBeginRendering(cmd, &ri);
    rb_pass_record_bindings(cmd, &b);
    vkCmdPushConstants(cmd, p->pass.layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(jitter),
                       jitter);
    rb_pass_draw_frame(cmd, frame);
    vkCmdEndRendering(cmd);
}

void rb_pass_gbuffer_destroy(struct rb_pass_gbuffer *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    free(p);
}
