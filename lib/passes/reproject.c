/* reproject: reverse reprojection for bdpt's temporal caches (seed 000, section A). It draws the
 * frame's geometry again right after the G-buffer, testing depth for equality against the
 * G-buffer's (the same invariant position), so only the surfaces the G-buffer holds shade; each
 * such pixel stores, for every age a < l, where its surface was in frame f - a: the previous
 * world vertices of its own triangle (nodes, skins, morphs as the animate pass left them) through
 * that frame's camera. The seed runs this inside the G-buffer pass; here it is a pass of its own
 * because the G-buffer already uses 6 of the 8 colour attachments lavapipe has, and the targets
 * are written as storage (one layer per age), so l is not bound by the attachment count. */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "reproject.frag.h"
#include "reproject.vert.h"

struct rb_pass_reproject {
    struct rb_pass pass;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_REPROJECT_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_HISTORY, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_OUT, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 0, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 1, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 2, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 3, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 4, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 5, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 6, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_REPROJECT_VERTICES + 7, UNIFORM_BUFFER),
};
_Static_assert(COUNT(bindings) == RB_BIND_REPROJECT_COUNT, "reproject bindings");
_Static_assert(RB_BIND_REPROJECT_COUNT - RB_BIND_REPROJECT_VERTICES == RB_BDPT_MAX_CACHES,
               "a vertex buffer per age");

enum rb_status rb_pass_reproject_create(struct rb_gpu *gpu, struct rb_pass_reproject **out,
                                        struct rb_err *err)
{
    struct rb_pass_reproject *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_raster_init(gpu,
                                            &(struct rb_pass_raster_desc){
                                                .name = "reproject",
                                                RB_PASS_BINDINGS(bindings),
                                                .graphics =
                                                    {
                                                        .vert = rb_spv_reproject_vert,
                                                        .vert_bytes = sizeof(rb_spv_reproject_vert),
                                                        .frag = rb_spv_reproject_frag,
                                                        .frag_bytes = sizeof(rb_spv_reproject_frag),
                                                        .depth_format = VK_FORMAT_D32_SFLOAT,
                                                        .cull = VK_CULL_MODE_NONE,
                                                        .is_depth_equal = true,
                                                    },
                                            },
                                            &p->pass, err);
    if (st) {
        rb_pass_reproject_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_reproject_record(struct rb_pass_reproject *p, VkCommandBuffer cmd,
                              const struct rb_frame *frame, const struct rb_pass_reproject_in *in)
{
    /* Pixels without a surface keep w = 0: the targets start cleared, after whatever read them
     * last and before the fragment shader's stores. */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkClearColorValue zero = {.float32 = {0.0f, 0.0f, 0.0f, 0.0f}};
    VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, in->target->layer_count};
    vkCmdClearColorImage(cmd, in->target->image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);

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
        .pDepthAttachment = &depth,
    };
    struct rb_pass_bindings b = {.pass = &p->pass};
    rb_pass_bind_buffer(&b, RB_BIND_REPROJECT_GLOBALS, &frame->globals);
    rb_pass_bind_buffer(&b, RB_BIND_REPROJECT_HISTORY, in->history);
    rb_pass_bind_image(&b, RB_BIND_REPROJECT_OUT, in->target->view, VK_NULL_HANDLE);
    for (uint32_t a = 0; a < RB_BDPT_MAX_CACHES; a++)
        rb_pass_bind_buffer(&b, RB_BIND_REPROJECT_VERTICES + a,
                            &in->slots[a < in->age_count ? a : 0]->geometry);

    vkCmdBeginRendering(cmd, &ri);
    rb_pass_record_bindings(cmd, &b);
    rb_pass_draw_frame(cmd, frame);
    vkCmdEndRendering(cmd);
}

void rb_pass_reproject_destroy(struct rb_pass_reproject *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    free(p);
}
