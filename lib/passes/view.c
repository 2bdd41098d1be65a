/* view: the raster-view pass. Renders the scene (a frame slot's world vertices) into one layer
 * per view, for many views of one kind in a batch: perspective (shadow maps, RSM faces),
 * orthographic (directional shadows, the global ray-bundles of seed 000, B.2) and paraboloid
 * (hemispheres around a VPL's normal, seed 000, B.3, after Brabec et al. 2002); and one output:
 * the view depth (R32F), a reflective shadow map (position, normal, flux) or a per-pixel linked
 * list of every fragment with an overflow count that is read back, never silent.
 *
 * Paraboloid views are tessellated (view.tesc) so that a triangle's edges follow the map's
 * curves, and their fragments take the exact distance to the triangle's plane along the pixel
 * centre's direction, so depth does not depend on the tessellation; only the edges do. The
 * image of a straight edge is a circular arc (the map is a stereographic projection of the
 * directions, and a line with the eye spans a great circle), and that circle meets the unit
 * circle at two opposite points, so its radius is at least 1 in NDC, size/2 texels. A chord c
 * of a circle of radius R strays from its arc by at most c^2 / (4R) (the sagitta), so with the
 * pieces of an edge at most RB_VIEW_TESS_CHORD_PX = C texels long an edge lands within
 * C^2 / (2 size) texels of where it belongs: 2 texels for a 256^2 map with C = 32. That holds
 * while the level stays under RB_VIEW_TESS_MAX_LEVEL, on the hemisphere in front of the eye.
 * Lavapipe's tessellator runs on the CPU: with C = 16 (half a texel) the demo's VPL maps took
 * 69 ms a frame at 640x360, with 32 51 ms, and the images kept their error against the reference
 * (the Cornell box's direct light, whose emitter points see through these maps, 0.0024 to
 * 0.0025; with 64, 8 texels, 0.0031). Pieces of 4 texels cost 20 times as much as 16 and moved
 * the demo's indirect light by 4e-6 on average.
 *
 * The pass keeps no state between records; it does not decide what the views are (the
 * integrator and shadow.c do) nor read the results back beyond the list's counters. */
#include "passes/passes.h"

#include <stdlib.h>
#include <string.h>

#include "view.frag.h"
#include "view.tesc.h"
#include "view.tese.h"
#include "view.vert.h"
#include "view_list.frag.h"
#include "view_paraboloid.frag.h"
#include "view_rsm.frag.h"

/* Perspective and orthographic views share the plain pipelines; paraboloid views have their own,
 * with tessellation. */
enum { PLAIN, CURVED, SHAPE_COUNT };
#define OUTPUT_COUNT (RB_VIEW_OUTPUT_LIST + 1)

const VkFormat rb_view_rsm_formats[RB_VIEW_RSM_TARGETS] = {
    VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R32G32B32A32_SFLOAT,
    VK_FORMAT_R32G32_UINT,
};

static const VkDescriptorType binding_types[RB_VIEW_BIND_COUNT] = {
    [RB_VIEW_BIND_VERTICES] = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
    [RB_VIEW_BIND_VIEWS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    [RB_VIEW_BIND_MATERIALS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    [RB_VIEW_BIND_SRGB_TEXTURES] = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    [RB_VIEW_BIND_LINEAR_TEXTURES] = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    [RB_VIEW_BIND_HEADS] = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
    [RB_VIEW_BIND_NODES] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    [RB_VIEW_BIND_COUNTER] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
};

struct rb_pass_view {
    struct rb_gpu *gpu;
    char name[32]; /* the debug label of each batch */
    struct rb_gpu_layout layout;
    VkPipeline pipelines[SHAPE_COUNT][OUTPUT_COUNT];
};

/* The push-descriptor writes of one batch, each binding named by its number. */
struct writes {
    VkWriteDescriptorSet w[RB_VIEW_BIND_COUNT];
    VkDescriptorBufferInfo buffers[RB_VIEW_BIND_COUNT];
    VkDescriptorImageInfo images[RB_VIEW_BIND_COUNT];
    uint32_t count;
};

static void put_buffer(struct writes *w, uint32_t binding, const struct rb_gpu_buffer *buf)
{
    if (w->count >= RB_VIEW_BIND_COUNT)
        RB_BUG("more than %d view bindings", RB_VIEW_BIND_COUNT);
    uint32_t i = w->count++;
    w->buffers[i] = (VkDescriptorBufferInfo){buf->buffer, 0, VK_WHOLE_SIZE};
    w->w[i] = (VkWriteDescriptorSet){
        .sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
        .dstBinding = binding,
        .descriptorCount = 1,
        .descriptorType = binding_types[binding],
        .pBufferInfo = &w->buffers[i],
    };
}

static void put_image(struct writes *w, uint32_t binding, VkImageView view, VkSampler sampler)
{
    if (w->count >= RB_VIEW_BIND_COUNT)
        RB_BUG("more than %d view bindings", RB_VIEW_BIND_COUNT);
    uint32_t i = w->count++;
    w->images[i] = (VkDescriptorImageInfo){sampler, view, VK_IMAGE_LAYOUT_GENERAL};
    w->w[i] = (VkWriteDescriptorSet){
        .sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
        .dstBinding = binding,
        .descriptorCount = 1,
        .descriptorType = binding_types[binding],
        .pImageInfo = &w->images[i],
    };
}

static const char *output_name(enum rb_view_output o)
{
    switch (o) {
    case RB_VIEW_OUTPUT_DEPTH: return "depth";
    case RB_VIEW_OUTPUT_RSM: return "rsm";
    case RB_VIEW_OUTPUT_LIST: return "list";
    default: return "?";
    }
}

static bool is_kind(enum rb_view_kind k)
{
    return k == RB_VIEW_KIND_PERSPECTIVE || k == RB_VIEW_KIND_ORTHOGRAPHIC ||
           k == RB_VIEW_KIND_PARABOLOID;
}

static bool is_output(enum rb_view_output o)
{
    return o == RB_VIEW_OUTPUT_DEPTH || o == RB_VIEW_OUTPUT_RSM || o == RB_VIEW_OUTPUT_LIST;
}

static int shape_of(enum rb_view_kind k)
{
    return k == RB_VIEW_KIND_PARABOLOID ? CURVED : PLAIN;
}

static enum rb_status make_pipeline(struct rb_pass_view *p, int shape, enum rb_view_output output,
                                    const char *name, struct rb_err *err)
{
    static const VkFormat depth_color = VK_FORMAT_R32_SFLOAT;
    struct rb_gpu_graphics_desc d = {
        .vert = rb_spv_view_vert,
        .vert_bytes = sizeof(rb_spv_view_vert),
        .layout = p->layout.pipeline_layout,
        .depth_format = VK_FORMAT_D32_SFLOAT,
        .cull = VK_CULL_MODE_NONE, /* shadows and lists see both faces */
        .debug_name = name,
    };
    switch (output) {
    case RB_VIEW_OUTPUT_DEPTH:
        d.frag = shape == CURVED ? rb_spv_view_paraboloid_frag : rb_spv_view_frag;
        d.frag_bytes =
            shape == CURVED ? sizeof(rb_spv_view_paraboloid_frag) : sizeof(rb_spv_view_frag);
        d.color_formats = &depth_color;
        d.color_count = 1;
        break;
    case RB_VIEW_OUTPUT_RSM:
        d.frag = rb_spv_view_rsm_frag;
        d.frag_bytes = sizeof(rb_spv_view_rsm_frag);
        d.color_formats = rb_view_rsm_formats;
        d.color_count = RB_VIEW_RSM_TARGETS;
        break;
    case RB_VIEW_OUTPUT_LIST:
        d.frag = rb_spv_view_list_frag;
        d.frag_bytes = sizeof(rb_spv_view_list_frag);
        d.depth_format = VK_FORMAT_UNDEFINED; /* every fragment, no depth test */
        break;
    default: RB_BUG("view output %d", (int)output);
    }
    if (shape == CURVED) {
        if (output != RB_VIEW_OUTPUT_DEPTH)
            return rb_errf(err, RB_E_UNSUPPORTED,
                           "raster view '%s': paraboloid views have no '%s' output", name,
                           output_name(output));
        d.tesc = rb_spv_view_tesc;
        d.tesc_bytes = sizeof(rb_spv_view_tesc);
        d.tese = rb_spv_view_tese;
        d.tese_bytes = sizeof(rb_spv_view_tese);
        d.patch_control_points = 3;
    }
    return rb_gpu_graphics_pipeline(p->gpu, &d, &p->pipelines[shape][output], err);
}

enum rb_status rb_pass_view_create(struct rb_gpu *gpu, const struct rb_pass_view_desc *desc,
                                   struct rb_pass_view **out, struct rb_err *err)
{
    const char *name = desc->debug_name ? desc->debug_name : "view";
    struct rb_pass_view *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    rb_strlcpy(p->name, name, sizeof(p->name));
    enum rb_status st = rb_gpu_layout_init(gpu, binding_types, RB_VIEW_BIND_COUNT,
                                           sizeof(struct rb_gpu_view_push), &p->layout, err);
    for (uint32_t i = 0; i < desc->variant_count && st == RB_OK; i++) {
        struct rb_view_variant v = desc->variants[i];
        if (!is_kind(v.kind) || !is_output(v.output)) {
            st = rb_errf(err, RB_E_INVALID, "raster view '%s': variant %u has no kind or output",
                         name, i);
            break;
        }
        int shape = shape_of(v.kind);
        if (!p->pipelines[shape][v.output])
            st = make_pipeline(p, shape, v.output, name, err);
    }
    if (st) {
        rb_pass_view_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

/* The scratch depth image is written by every view: each waits for the last to finish with it. */
static void depth_barrier(VkCommandBuffer cmd, const struct rb_gpu_image *depth)
{
    VkImageMemoryBarrier2 b = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
        .srcStageMask = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT |
                        VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
        .srcAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
        .dstStageMask = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT |
                        VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
        .dstAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                         VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
        .oldLayout = VK_IMAGE_LAYOUT_GENERAL,
        .newLayout = VK_IMAGE_LAYOUT_GENERAL,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .image = depth->image,
        .subresourceRange = {depth->aspect, 0, 1, 0, 1},
    };
    vkCmdPipelineBarrier2(cmd, &(VkDependencyInfo){.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO,
                                                   .imageMemoryBarrierCount = 1,
                                                   .pImageMemoryBarriers = &b});
}

/* A list batch starts from empty heads on its layers and an empty pool (or, for a batch with
 * marked heads, heads that take no fragments but where marked). */
void rb_view_list_clear(VkCommandBuffer cmd, const struct rb_view_list *list, uint32_t first_layer,
                        uint32_t count, uint32_t head, VkPipelineStageFlags2 dst_stage)
{
    /* Whatever read the last batch's lists is done before they are cleared. */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    vkCmdFillBuffer(cmd, list->counter.buffer, 0, sizeof(struct rb_gpu_list_counter), 0);
    VkClearColorValue value = {.uint32 = {head, head, head, head}};
    VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, first_layer, count};
    vkCmdClearColorImage(cmd, list->heads.image, VK_IMAGE_LAYOUT_GENERAL, &value, 1, &range);
    rb_gpu_memory_barrier(
        cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, dst_stage,
        VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
}

void rb_pass_view_record(struct rb_pass_view *p, VkCommandBuffer cmd, const struct rb_frame *frame,
                         const struct rb_frame_slot *slot, const struct rb_view_batch *batch)
{
    enum rb_view_output output = batch->output;
    if (!is_kind(batch->kind) || !is_output(output))
        RB_BUG("raster view batch without a kind or output");
    VkPipeline pipeline = p->pipelines[shape_of(batch->kind)][output];
    if (!pipeline)
        RB_BUG("raster view: kind %d, output '%s' was not asked for at create", (int)batch->kind,
               output_name(output));
    if (batch->view_count == 0)
        return;

    uint32_t width, height, layers;
    if (output == RB_VIEW_OUTPUT_LIST ? !batch->list : !batch->targets[0] || !batch->depth)
        RB_BUG("raster view: a '%s' batch without its %s", output_name(output),
               output == RB_VIEW_OUTPUT_LIST ? "list" : "targets or depth image");
    if (output == RB_VIEW_OUTPUT_LIST) {
        width = batch->list->heads.width_px;
        height = batch->list->heads.height_px;
        layers = batch->list->heads.layer_count;
    } else {
        const struct rb_gpu_image *t = batch->targets[0];
        width = t->width_px;
        height = t->height_px;
        layers = t->layer_count;
        if (batch->size_px) {
            if (batch->size_px > width || batch->size_px > height)
                RB_BUG("raster view: a corner of %u px in %ux%u targets", batch->size_px, width,
                       height);
            width = height = batch->size_px;
        }
        if (!t->layer_views || batch->depth->width_px < width || batch->depth->height_px < height)
            RB_BUG("raster view: targets need layer views and a depth image as large");
    }
    if (batch->first_layer + batch->view_count > layers)
        RB_BUG("raster view: layers %u..%u of %u", batch->first_layer,
               batch->first_layer + batch->view_count - 1, layers);

    if (p->gpu->begin_label)
        p->gpu->begin_label(cmd, &(VkDebugUtilsLabelEXT){
                                     .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_LABEL_EXT,
                                     .pLabelName = p->name,
                                 });
    struct writes w = {0};
    put_buffer(&w, RB_VIEW_BIND_VERTICES, &slot->geometry);
    put_buffer(&w, RB_VIEW_BIND_VIEWS, batch->views);
    put_buffer(&w, RB_VIEW_BIND_MATERIALS, &frame->materials); /* view.vert drops blended ones */
    if (output != RB_VIEW_OUTPUT_DEPTH) {
        put_image(&w, RB_VIEW_BIND_SRGB_TEXTURES, frame->srgb_textures.view,
                  p->gpu->linear_sampler);
        put_image(&w, RB_VIEW_BIND_LINEAR_TEXTURES, frame->linear_textures.view,
                  p->gpu->linear_sampler);
    }
    if (output == RB_VIEW_OUTPUT_LIST) {
        put_image(&w, RB_VIEW_BIND_HEADS, batch->list->heads.view, VK_NULL_HANDLE);
        put_buffer(&w, RB_VIEW_BIND_NODES, &batch->list->nodes);
        put_buffer(&w, RB_VIEW_BIND_COUNTER, &batch->list->counter);
        if (!batch->has_marked_heads)
            rb_view_list_clear(cmd, batch->list, batch->first_layer, batch->view_count, RB_NONE,
                               VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT);
    }

    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
    p->gpu->push_descriptor_set(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->layout.pipeline_layout, 0,
                                w.count, w.w);
    /* The simplified mesh when asked for and the frame has one; the full mesh otherwise. */
    const struct rb_gpu_buffer *indices = rb_view_index_buffer(frame, batch->use_simplified);
    uint32_t index_count = rb_view_index_count(frame, batch->use_simplified);
    if (index_count)
        vkCmdBindIndexBuffer(cmd, indices->buffer, 0, VK_INDEX_TYPE_UINT32);
    VkViewport vp = {0, 0, (float)width, (float)height, 0.0f, 1.0f};
    VkRect2D area = {{0, 0}, {width, height}};
    uint32_t color_count = output == RB_VIEW_OUTPUT_DEPTH ? 1
                           : output == RB_VIEW_OUTPUT_RSM ? RB_VIEW_RSM_TARGETS
                                                          : 0;
    for (uint32_t i = 0; i < batch->view_count; i++) {
        uint32_t layer = batch->first_layer + i;
        VkRenderingAttachmentInfo colors[RB_VIEW_RSM_TARGETS];
        for (uint32_t c = 0; c < color_count; c++)
            colors[c] = (VkRenderingAttachmentInfo){
                .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
                .imageView =
                    batch->targets[c] ? batch->targets[c]->layer_views[layer] : VK_NULL_HANDLE,
                .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
                .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
                .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
                /* depth: nothing is far away; rsm: w = 0, no surface */
                .clearValue = {.color = {{output == RB_VIEW_OUTPUT_DEPTH ? 3.0e38f : 0.0f, 0.0f,
                                          0.0f, 0.0f}}},
            };
        VkRenderingAttachmentInfo depth = {
            .sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
            .imageView = color_count ? batch->depth->view : VK_NULL_HANDLE,
            .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
            .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
            .storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE,
            .clearValue = {.depthStencil = {1.0f, 0}},
        };
        if (color_count)
            depth_barrier(cmd, batch->depth);
        VkRenderingInfo ri = {
            .sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
            .renderArea = area,
            .layerCount = 1,
            .colorAttachmentCount = color_count,
            .pColorAttachments = colors,
            .pDepthAttachment = color_count ? &depth : NULL,
        };
        struct rb_gpu_view_push push = {
            .index = {batch->first_view + i, layer, (uint32_t)batch->kind,
                      batch->list ? batch->list->capacity_nodes : 0},
            .intensity = {batch->intensity[0], batch->intensity[1], batch->intensity[2], 0.0f},
            .size = {(float)width, (float)height, 1.0f / (float)width, 1.0f / (float)height},
        };
        vkCmdBeginRendering(cmd, &ri);
        vkCmdPushConstants(cmd, p->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(push),
                           &push);
        vkCmdSetViewport(cmd, 0, 1, &vp);
        vkCmdSetScissor(cmd, 0, 1, &area);
        if (index_count && batch->draws) /* an empty scene still clears its layers */
            vkCmdDrawIndexedIndirect(cmd, batch->draws->buffer,
                                     (VkDeviceSize)(batch->first_view + i) *
                                         sizeof(VkDrawIndexedIndirectCommand),
                                     1, sizeof(VkDrawIndexedIndirectCommand));
        else if (index_count)
            vkCmdDrawIndexed(cmd, index_count, 1, 0, 0, 0);
        vkCmdEndRendering(cmd);
    }
    /* The counters are read on the host after the submit. */
    if (output == RB_VIEW_OUTPUT_LIST)
        rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                              VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                              VK_ACCESS_2_HOST_READ_BIT);
    if (p->gpu->end_label)
        p->gpu->end_label(cmd);
}

const struct rb_gpu_buffer *rb_view_index_buffer(const struct rb_frame *frame, bool use_simplified)
{
    return use_simplified && frame->view_indices.buffer ? &frame->view_indices : &frame->indices;
}

uint32_t rb_view_index_count(const struct rb_frame *frame, bool use_simplified)
{
    return use_simplified && frame->view_indices.buffer ? frame->view_index_count
                                                        : frame->index_count;
}

enum rb_status rb_view_draws_init(struct rb_gpu *gpu, const struct rb_frame *frame,
                                  bool use_simplified, uint32_t count, struct rb_gpu_buffer *out,
                                  struct rb_err *err)
{
    VkDrawIndexedIndirectCommand *c = calloc(count ? count : 1, sizeof(*c));
    if (!c)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %u draw commands", count);
    for (uint32_t i = 0; i < count; i++)
        c[i] = (VkDrawIndexedIndirectCommand){
            .indexCount = rb_view_index_count(frame, use_simplified), .instanceCount = 1};
    enum rb_status st = rb_gpu_buffer_upload(gpu, out, c, (VkDeviceSize)count * sizeof(*c), err);
    free(c);
    return st;
}

void rb_pass_view_destroy(struct rb_pass_view *p)
{
    if (!p)
        return;
    for (int s = 0; s < SHAPE_COUNT; s++)
        for (int o = 0; o < OUTPUT_COUNT; o++)
            if (p->pipelines[s][o])
                vkDestroyPipeline(p->gpu->device, p->pipelines[s][o], NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
    free(p);
}

/* ---- views --------------------------------------------------------------------------------- */

static void store(float out[16], const struct rb_mat4 *m)
{
    memcpy(out, m->m, sizeof(float) * 16);
}

static void set_frame(struct rb_gpu_view *out, struct rb_vec3 origin, struct rb_vec3 axis)
{
    memcpy(out->origin, (float[4]){origin.x, origin.y, origin.z, 0.0f}, sizeof(out->origin));
    memcpy(out->axis, (float[4]){axis.x, axis.y, axis.z, 0.0f}, sizeof(out->axis));
}

void rb_view_perspective(struct rb_gpu_view *out, struct rb_vec3 eye, struct rb_vec3 dir,
                         struct rb_vec3 up, float fov_y_rad, float aspect, float z_near,
                         float z_far)
{
    dir = rb_v3_normalize(dir);
    struct rb_mat4 view = rb_mat4_look_at(eye, rb_v3_add(eye, dir), up);
    struct rb_mat4 proj = rb_mat4_perspective(fov_y_rad, aspect, z_near, z_far);
    struct rb_mat4 vp = rb_mat4_mul(&proj, &view);
    store(out->transform, &vp);
    set_frame(out, eye, dir);
}

void rb_view_orthographic(struct rb_gpu_view *out, struct rb_vec3 origin, struct rb_vec3 dir,
                          struct rb_vec3 up, float half_width, float half_height, float depth_m)
{
    dir = rb_v3_normalize(dir);
    struct rb_mat4 view = rb_mat4_look_at(origin, rb_v3_add(origin, dir), up);
    struct rb_mat4 proj =
        rb_mat4_ortho(-half_width, half_width, -half_height, half_height, 0.0f, depth_m);
    struct rb_mat4 vp = rb_mat4_mul(&proj, &view);
    store(out->transform, &vp);
    set_frame(out, origin, dir);
}

void rb_view_paraboloid(struct rb_gpu_view *out, struct rb_vec3 eye, struct rb_vec3 axis,
                        struct rb_vec3 right, float z_far)
{
    struct rb_vec3 z = rb_v3_normalize(axis), x = rb_v3_normalize(right);
    struct rb_vec3 y = rb_v3_cross(z, x);
    float s = 1.0f / z_far;
    struct rb_vec3 rows[3] = {x, y, z};
    struct rb_mat4 m = rb_mat4_identity();
    for (int r = 0; r < 3; r++) {
        m.m[0][r] = rows[r].x * s;
        m.m[1][r] = rows[r].y * s;
        m.m[2][r] = rows[r].z * s;
        m.m[3][r] = -rb_v3_dot(rows[r], eye) * s;
    }
    store(out->transform, &m);
    set_frame(out, eye, z);
}

/* ---- linked lists -------------------------------------------------------------------------- */

enum rb_status rb_view_list_init(struct rb_gpu *gpu, const struct rb_view_list_desc *desc,
                                 struct rb_view_list *out, struct rb_err *err)
{
    const char *name = desc->debug_name ? desc->debug_name : "view list";
    if (desc->capacity_nodes == 0)
        return rb_errf(err, RB_E_INVALID, "'%s': a node pool of 0 nodes", name);
    VkDeviceSize bytes = (VkDeviceSize)desc->capacity_nodes * sizeof(struct rb_gpu_list_node);
    if (bytes > gpu->props.limits.maxStorageBufferRange)
        return rb_errf(err, RB_E_INVALID,
                       "'%s': a pool of %u nodes (%llu bytes) is more than the device binds "
                       "(maxStorageBufferRange %u bytes)",
                       name, desc->capacity_nodes, (unsigned long long)bytes,
                       gpu->props.limits.maxStorageBufferRange);
    struct rb_view_list l = {.capacity_nodes = desc->capacity_nodes};
    enum rb_status st = rb_gpu_image_init(gpu,
                                          &(struct rb_gpu_image_desc){
                                              .width_px = desc->width_px,
                                              .height_px = desc->height_px,
                                              .layer_count = desc->layer_count,
                                              .format = VK_FORMAT_R32_UINT,
                                              .usage = VK_IMAGE_USAGE_STORAGE_BIT |
                                                       VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                                       VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                              .is_array = true,
                                              .debug_name = name,
                                          },
                                          &l.heads, err);
    if (st == RB_OK)
        st = rb_gpu_buffer_init(gpu,
                                &(struct rb_gpu_buffer_desc){
                                    .size_bytes = bytes,
                                    .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                             VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                             VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                    .debug_name = name,
                                },
                                &l.nodes, err);
    if (st == RB_OK)
        st = rb_gpu_buffer_init(
            gpu,
            &(struct rb_gpu_buffer_desc){
                .size_bytes = sizeof(struct rb_gpu_list_counter),
                .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                .is_host_visible = true,
                .debug_name = name,
            },
            &l.counter, err);
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    if (st == RB_OK)
        st = rb_gpu_oneshot_begin(gpu, &cmd, err);
    if (st == RB_OK) {
        rb_gpu_image_barrier(gpu, cmd, &l.heads, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        st = rb_gpu_oneshot_end(gpu, cmd, err);
    }
    if (st) {
        rb_view_list_release(gpu, &l);
        return st;
    }
    memset(l.counter.mapped, 0, sizeof(struct rb_gpu_list_counter));
    *out = l;
    return RB_OK;
}

void rb_view_list_release(struct rb_gpu *gpu, struct rb_view_list *list)
{
    if (!list)
        return;
    rb_gpu_buffer_release(gpu, &list->counter);
    rb_gpu_buffer_release(gpu, &list->nodes);
    rb_gpu_image_release(gpu, &list->heads);
    *list = (struct rb_view_list){0};
}

struct rb_gpu_list_counter rb_view_list_usage(const struct rb_view_list *list)
{
    struct rb_gpu_list_counter c;
    memcpy(&c, list->counter.mapped, sizeof(c));
    return c;
}

enum rb_status rb_view_list_check(const struct rb_view_list *list, const char *name,
                                  struct rb_err *err)
{
    struct rb_gpu_list_counter c = rb_view_list_usage(list);
    if (c.dropped == 0)
        return RB_OK;
    return rb_errf(err, RB_E_NOMEM,
                   "'%s' overflowed: %u of %u fragments dropped (a pool of %u nodes, %llu bytes)",
                   name, c.dropped, c.requested, list->capacity_nodes,
                   (unsigned long long)list->capacity_nodes * sizeof(struct rb_gpu_list_node));
}
