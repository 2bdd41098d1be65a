/* transparency: the materials with glTF alphaMode BLEND, drawn forward after the deferred
 * passes (seed 003's "Transparency" row). The deferred passes and the raster views leave them out
 * (gbuffer.frag, view.vert), so they are no occluders for shadows or global illumination; here
 * each blended instance is drawn, in the order the caller gives (back to front), against the
 * G-buffer's depth without writing it, lit as direct.comp lights a pixel, and blended into one
 * image: the light the layers add and the fraction of the light behind them that passes, which
 * the output pass composites the frame under. Fixed-function blending in primitive order, one
 * draw after another, so the result is the same bits on every run. */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "transparency.frag.h"
#include "transparency.vert.h"

struct rb_pass_transparency {
    struct rb_pass pass;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_MATERIALS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_SRGB_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_LINEAR_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_SHADOW_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_TRANSPARENCY_SHADOW_MAPS, COMBINED_IMAGE_SAMPLER),
};
_Static_assert(COUNT(bindings) == RB_BIND_TRANSPARENCY_COUNT, "transparency bindings");

enum rb_status rb_pass_transparency_create(struct rb_gpu *gpu, VkFormat format,
                                           struct rb_pass_transparency **out, struct rb_err *err)
{
    struct rb_pass_transparency *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_raster_init(
        gpu,
        &(struct rb_pass_raster_desc){
            .name = "transparency",
            RB_PASS_BINDINGS(bindings),
            .graphics =
                {
                    .vert = rb_spv_transparency_vert,
                    .vert_bytes = sizeof(rb_spv_transparency_vert),
                    .frag = rb_spv_transparency_frag,
                    .frag_bytes = sizeof(rb_spv_transparency_frag),
                    .color_formats = &format,
                    .color_count = 1,
                    .depth_format = VK_FORMAT_D32_SFLOAT,
                    .cull = VK_CULL_MODE_NONE, /* single-sided materials discard back faces */
                    .is_blend_over = true,
                },
        },
        &p->pass, err);
    if (st) {
        rb_pass_transparency_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_transparency_record(struct rb_pass_transparency *p, VkCommandBuffer cmd,
                                 const struct rb_frame *frame, const struct rb_frame_slot *cur,
                                 const struct rb_transparency_draw *draws, uint32_t draw_count)
{
    VkRenderingAttachmentInfo color = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
        .imageView = frame->transparency.view,
        .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
        .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
        .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
        .clearValue = {.color = {{0.0f, 0.0f, 0.0f, 1.0f}}}, /* nothing added, all passes */
    };
    VkRenderingAttachmentInfo depth = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
        .imageView = frame->depth.view,
        .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
        .loadOp = VK_ATTACHMENT_LOAD_OP_LOAD,
        .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
    };
    VkRenderingInfo ri = {
        .sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
        .renderArea = {{0, 0}, {frame->width_px, frame->height_px}},
        .layerCount = 1,
        .colorAttachmentCount = 1,
        .pColorAttachments = &color,
        .pDepthAttachment = &depth,
    };
    struct rb_pass_bindings b = {.pass = &p->pass};
    VkSampler linear = p->pass.gpu->linear_sampler;
    rb_pass_bind_buffer(&b, RB_BIND_TRANSPARENCY_GLOBALS, &frame->globals);
    rb_pass_bind_buffer(&b, RB_BIND_TRANSPARENCY_VERTICES, &cur->geometry);
    rb_pass_bind_buffer(&b, RB_BIND_TRANSPARENCY_MATERIALS, &frame->materials);
    rb_pass_bind_image(&b, RB_BIND_TRANSPARENCY_SRGB_TEXTURES, frame->srgb_textures.view, linear);
    rb_pass_bind_image(&b, RB_BIND_TRANSPARENCY_LINEAR_TEXTURES, frame->linear_textures.view,
                       linear);
    rb_pass_bind_buffer(&b, RB_BIND_TRANSPARENCY_LIGHTS, &frame->lights);
    rb_pass_bind_buffer(&b, RB_BIND_TRANSPARENCY_SHADOW_VIEWS, &frame->shadow_views);
    rb_pass_bind_image(&b, RB_BIND_TRANSPARENCY_SHADOW_MAPS, frame->shadow_maps.view,
                       p->pass.gpu->nearest_sampler);

    vkCmdBeginRendering(cmd, &ri);
    rb_pass_record_bindings(cmd, &b);
    VkViewport vp = {0, 0, (float)frame->width_px, (float)frame->height_px, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {frame->width_px, frame->height_px}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &sc);
    vkCmdBindIndexBuffer(cmd, frame->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
    for (uint32_t i = 0; i < draw_count; i++)
        vkCmdDrawIndexed(cmd, draws[i].index_count, 1, draws[i].first_index, 0, 0);
    vkCmdEndRendering(cmd);
}

void rb_pass_transparency_destroy(struct rb_pass_transparency *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    free(p);
}
