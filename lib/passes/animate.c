/* animate: morph targets, skins and node transforms on the GPU (DESIGN.md "animate"). The CPU
 * evaluates the animation curves into per-instance matrices and weights; this pass deforms the
 * vertices, one dispatch per instance, into the slot's world-space vertex buffer. */
#include "passes/passes.h"

#include <stdint.h>
#include <stdlib.h>

#include "animate.comp.h"

struct rb_pass_animate {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
};

static const VkDescriptorType bindings[] = {
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
};

enum rb_status rb_pass_animate_create(struct rb_gpu *gpu, struct rb_pass_animate **out,
                                      struct rb_err *err)
{
    struct rb_pass_animate *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    enum rb_status st = rb_gpu_layout_init(gpu, bindings, 6, sizeof(uint32_t), &p->layout, err);
    if (st == RB_OK)
        st = rb_gpu_compute_pipeline(gpu, rb_spv_animate_comp, sizeof(rb_spv_animate_comp),
                                     p->layout.pipeline_layout, "animate", &p->pipeline, err);
    if (st) {
        rb_pass_animate_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_animate_record(struct rb_pass_animate *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *slot)
{
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->src_vertices);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &frame->morph_deltas);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &slot->instances);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &slot->joints);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &slot->weights);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &slot->vertices);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    rb_gpu_push_bindings(p->gpu, cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout.pipeline_layout,
                         &b);
    for (uint32_t i = 0; i < frame->instance_count; i++) {
        uint32_t count = frame->instances[i].range[1];
        if (count == 0)
            continue;
        vkCmdPushConstants(cmd, p->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(uint32_t),
                           &i);
        vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
    }
}

void rb_pass_animate_destroy(struct rb_pass_animate *p)
{
    if (!p)
        return;
    if (p->pipeline)
        vkDestroyPipeline(p->gpu->device, p->pipeline, NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
    free(p);
}
