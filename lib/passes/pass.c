/* The boilerplate every pass shares: layout and pipeline from a binding table, binding by name at
 * record time with every binding checked, and teardown. Not a pass itself; see passes_int.h. */
#include "passes/passes_int.h"

#include <stdint.h>

/* Makes the layout from a pass's binding table. */
static enum rb_status layout_init(struct rb_gpu *gpu, const char *name,
                                  const struct rb_pass_binding *bindings, uint32_t binding_count,
                                  uint32_t push_bytes, struct rb_pass *p, struct rb_err *err)
{
    if (binding_count > RB_GPU_MAX_BINDINGS)
        return rb_errf(err, RB_E_UNSUPPORTED, "pass '%s': %u bindings, more than %u", name,
                       binding_count, RB_GPU_MAX_BINDINGS);
    VkDescriptorType types[RB_GPU_MAX_BINDINGS];
    for (uint32_t i = 0; i < binding_count; i++) {
        if (!bindings[i].name)
            RB_BUG("pass '%s': binding %u missing from its table", name, i);
        types[i] = bindings[i].type;
    }
    *p = (struct rb_pass){.gpu = gpu, .name = name, .bindings = bindings};
    enum rb_status st = rb_gpu_layout_init(gpu, types, binding_count, push_bytes, &p->layout, err);
    if (st)
        rb_err_prefix(err, "pass '%s'", name);
    return st;
}

enum rb_status rb_pass_compute_init(struct rb_gpu *gpu, const struct rb_pass_compute_desc *desc,
                                    struct rb_pass *out, struct rb_err *err)
{
    struct rb_pass p = {0};
    enum rb_status st = layout_init(gpu, desc->name, desc->bindings, desc->binding_count,
                                    desc->push_bytes, &p, err);
    if (st)
        return st;
    p.point = VK_PIPELINE_BIND_POINT_COMPUTE;
    st = rb_gpu_compute_pipeline(gpu, desc->spv, desc->spv_bytes, p.layout.pipeline_layout,
                                 desc->name, &p.pipeline, err);
    if (st) {
        rb_pass_release(&p);
        return st;
    }
    *out = p;
    return RB_OK;
}

enum rb_status rb_pass_raster_init(struct rb_gpu *gpu, const struct rb_pass_raster_desc *desc,
                                   struct rb_pass *out, struct rb_err *err)
{
    struct rb_pass p = {0};
    enum rb_status st = layout_init(gpu, desc->name, desc->bindings, desc->binding_count,
                                    desc->push_bytes, &p, err);
    if (st)
        return st;
    p.point = VK_PIPELINE_BIND_POINT_GRAPHICS;
    struct rb_gpu_graphics_desc g = desc->graphics;
    g.layout = p.layout.pipeline_layout;
    g.debug_name = desc->name;
    st = rb_gpu_graphics_pipeline(gpu, &g, &p.pipeline, err);
    if (st) {
        rb_pass_release(&p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_release(struct rb_pass *pass)
{
    if (!pass || !pass->gpu)
        return;
    if (pass->pipeline)
        vkDestroyPipeline(pass->gpu->device, pass->pipeline, NULL);
    rb_gpu_layout_release(pass->gpu, &pass->layout);
    *pass = (struct rb_pass){0};
}

static bool is_buffer(VkDescriptorType type)
{
    return type == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER || type == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

/* The type of a binding of b's pass, or RB_BUG when the table has no such binding. */
static VkDescriptorType binding_type(const struct rb_pass_bindings *b, uint32_t binding)
{
    const struct rb_pass *p = b->pass;
    if (binding >= p->layout.binding_count)
        RB_BUG("pass '%s': binding %u is not in its table of %u", p->name, binding,
               p->layout.binding_count);
    if (b->set.writes[binding].sType)
        RB_BUG("pass '%s': %s bound twice", p->name, p->bindings[binding].name);
    return p->layout.types[binding];
}

void rb_pass_bind_buffer(struct rb_pass_bindings *b, uint32_t binding,
                         const struct rb_gpu_buffer *buf)
{
    VkDescriptorType type = binding_type(b, binding);
    if (!is_buffer(type))
        RB_BUG("pass '%s': %s is not a buffer", b->pass->name, b->pass->bindings[binding].name);
    rb_gpu_bindings_set_buffer(&b->set, binding, type, buf);
}

void rb_pass_bind_buffer_range(struct rb_pass_bindings *b, uint32_t binding,
                               const struct rb_gpu_buffer *buf, VkDeviceSize offset_bytes,
                               VkDeviceSize range_bytes)
{
    VkDescriptorType type = binding_type(b, binding);
    if (!is_buffer(type))
        RB_BUG("pass '%s': %s is not a buffer", b->pass->name, b->pass->bindings[binding].name);
    rb_gpu_bindings_set_buffer_range(&b->set, binding, type, buf, offset_bytes, range_bytes);
}

void rb_pass_bind_image(struct rb_pass_bindings *b, uint32_t binding, VkImageView view,
                        VkSampler sampler)
{
    VkDescriptorType type = binding_type(b, binding);
    bool wants_sampler = type == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    if (is_buffer(type) || wants_sampler != (sampler != VK_NULL_HANDLE))
        RB_BUG("pass '%s': %s is not an image %s a sampler", b->pass->name,
               b->pass->bindings[binding].name, sampler ? "with" : "without");
    rb_gpu_bindings_set_image(&b->set, binding, type, view, sampler, VK_IMAGE_LAYOUT_GENERAL);
}

void rb_pass_record_bindings(VkCommandBuffer cmd, const struct rb_pass_bindings *b)
{
    const struct rb_pass *p = b->pass;
    for (uint32_t i = 0; i < p->layout.binding_count; i++)
        if (!b->set.writes[i].sType)
            RB_BUG("pass '%s': %s never bound", p->name, p->bindings[i].name);
    vkCmdBindPipeline(cmd, p->point, p->pipeline);
    rb_gpu_push_bindings(p->gpu, cmd, p->point, p->layout.pipeline_layout, &b->set);
}

void rb_pass_draw_frame(VkCommandBuffer cmd, const struct rb_frame *frame)
{
    VkViewport vp = {0, 0, (float)frame->width_px, (float)frame->height_px, 0.0f, 1.0f};
    VkRect2D sc = {{0, 0}, {frame->width_px, frame->height_px}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &sc);
    if (frame->index_count) {
        vkCmdBindIndexBuffer(cmd, frame->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(cmd, frame->index_count, 1, 0, 0, 0);
    }
}
