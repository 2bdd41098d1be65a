/* The frame resources every integrator shares: the scene on the GPU (geometry, materials,
 * textures as arrays, since lavapipe has no descriptor indexing), the animation slots,
 * lights and shadow maps, the environment, the G-buffer and the readback buffer. */
#include "integrators/integrators_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_TEXTURE_SIZE 1024

_Static_assert(RB_KIND_POINT == RB_LIGHT_POINT && RB_KIND_SPOT == RB_LIGHT_SPOT &&
                   RB_KIND_DIRECTIONAL == RB_LIGHT_DIRECTIONAL,
               "a punctual light's kind on the GPU is its type");

/* Point lights and emitter samples (which light both sides of their surface) take a cube. */
static uint32_t shadow_layers_for(enum rb_light_type t)
{
    return t == RB_LIGHT_POINT || t == RB_LIGHT_EMITTER ? 6 : 1;
}

enum rb_status rb_frame_buffer(struct rb_gpu *gpu, VkDeviceSize size, VkBufferUsageFlags usage,
                               bool host, const char *name, struct rb_gpu_buffer *out,
                               struct rb_err *err)
{
    return rb_gpu_buffer_init(gpu,
                              &(struct rb_gpu_buffer_desc){.size_bytes = size ? size : 16,
                                                           .usage = usage,
                                                           .is_host_visible = host,
                                                           .debug_name = name},
                              out, err);
}

static enum rb_status upload_buffer(struct rb_gpu *gpu, const void *data, VkDeviceSize size,
                                    VkBufferUsageFlags usage, const char *name,
                                    struct rb_gpu_buffer *out, struct rb_err *err)
{
    enum rb_status st = rb_frame_buffer(gpu, size, usage, false, name, out, err);
    if (st == RB_OK && size)
        st = rb_gpu_buffer_upload(gpu, out, data, size, err);
    return st;
}

/* As upload_buffer, for the scene's arrays the shaders read by address (geometry_shared.h). */
static enum rb_status upload_addressed(struct rb_gpu *gpu, const void *data, VkDeviceSize size,
                                       VkBufferUsageFlags usage, const char *name,
                                       struct rb_gpu_buffer *out, struct rb_err *err)
{
    enum rb_status st =
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = size ? size : 16,
                                                        .usage = usage,
                                                        .is_addressed = true,
                                                        .debug_name = name},
                           out, err);
    if (st == RB_OK && size)
        st = rb_gpu_buffer_upload(gpu, out, data, size, err);
    return st;
}

static uint32_t next_pow2(uint32_t v)
{
    uint32_t p = 1;
    while (p < v && p < (1u << 30))
        p <<= 1;
    return p;
}

static void blit_barrier(VkCommandBuffer cmd, VkImage image, uint32_t layer, uint32_t mip,
                         VkImageLayout from, VkImageLayout to)
{
    VkImageMemoryBarrier2 b = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
        .srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
        .srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT,
        .dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
        .dstAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT,
        .oldLayout = from,
        .newLayout = to,
        .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
        .image = image,
        .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, mip, 1, layer, 1},
    };
    VkDependencyInfo dep = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO,
                            .imageMemoryBarrierCount = 1,
                            .pImageMemoryBarriers = &b};
    vkCmdPipelineBarrier2(cmd, &dep);
}

/* Copies one texture into a layer of an array: upload at its own size, blit (filtered) to the
 * array's size, then build the layer's mip chain by successive blits. The blits filter in linear
 * space for the sRGB array, as sampling does. */
static enum rb_status upload_texture_layer(struct rb_gpu *gpu, const struct rb_scene_texture *tex,
                                           struct rb_gpu_image *array, uint32_t layer,
                                           struct rb_err *err)
{
    struct rb_gpu_buffer staging = {0};
    struct rb_gpu_image src = {0};
    VkDeviceSize bytes = (VkDeviceSize)tex->width_px * tex->height_px * 4;
    enum rb_status st = rb_frame_buffer(gpu, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true,
                                        "texture staging", &staging, err);
    if (st)
        goto out;
    memcpy(staging.mapped, tex->rgba8, bytes);
    st = rb_gpu_image_init(gpu,
                           &(struct rb_gpu_image_desc){.width_px = tex->width_px,
                                                       .height_px = tex->height_px,
                                                       .format = array->format,
                                                       .usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                                                VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                                VK_IMAGE_USAGE_SAMPLED_BIT,
                                                       .debug_name = tex->name},
                           &src, err);
    if (st)
        goto out;
    VkCommandBuffer cmd;
    if ((st = rb_gpu_oneshot_begin(gpu, &cmd, err)))
        goto out;
    blit_barrier(cmd, src.image, 0, 0, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    VkBufferImageCopy copy = {
        .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .imageExtent = {tex->width_px, tex->height_px, 1},
    };
    vkCmdCopyBufferToImage(cmd, staging.buffer, src.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                           &copy);
    blit_barrier(cmd, src.image, 0, 0, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    int32_t w = (int32_t)tex->width_px, h = (int32_t)tex->height_px;
    VkImage from = src.image;
    uint32_t from_mip = 0, from_layer = 0;
    for (uint32_t mip = 0; mip < array->mip_count; mip++) {
        int32_t dw = (int32_t)(array->width_px >> mip), dh = (int32_t)(array->height_px >> mip);
        dw = dw ? dw : 1;
        dh = dh ? dh : 1;
        blit_barrier(cmd, array->image, layer, mip, VK_IMAGE_LAYOUT_UNDEFINED,
                     VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
        VkImageBlit blit = {
            .srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, from_mip, from_layer, 1},
            .srcOffsets = {{0, 0, 0}, {w, h, 1}},
            .dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, mip, layer, 1},
            .dstOffsets = {{0, 0, 0}, {dw, dh, 1}},
        };
        vkCmdBlitImage(cmd, from, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, array->image,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_LINEAR);
        blit_barrier(cmd, array->image, layer, mip, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
        from = array->image;
        from_mip = mip;
        from_layer = layer;
        w = dw;
        h = dh;
    }
    for (uint32_t mip = 0; mip < array->mip_count; mip++)
        blit_barrier(cmd, array->image, layer, mip, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                     VK_IMAGE_LAYOUT_GENERAL);
    st = rb_gpu_oneshot_end(gpu, cmd, err);
out:
    rb_gpu_image_release(gpu, &src);
    rb_gpu_buffer_release(gpu, &staging);
    return st;
}

static enum rb_status upload_textures(struct rb_gpu *gpu, const struct rb_scene *scene,
                                      struct rb_frame *frame, struct rb_err *err)
{
    uint32_t size = 1;
    for (uint32_t i = 0; i < scene->texture_count; i++) {
        uint32_t m = scene->textures[i].width_px > scene->textures[i].height_px
                         ? scene->textures[i].width_px
                         : scene->textures[i].height_px;
        if (next_pow2(m) > size)
            size = next_pow2(m);
    }
    if (size > MAX_TEXTURE_SIZE)
        size = MAX_TEXTURE_SIZE;
    uint32_t mips = 1;
    while ((size >> mips) > 0)
        mips++;
    uint32_t layers = scene->texture_count ? scene->texture_count : 1;
    struct {
        struct rb_gpu_image *img;
        VkFormat format;
        const char *name;
    } arrays[2] = {
        {&frame->srgb_textures, VK_FORMAT_R8G8B8A8_SRGB, "textures.srgb"},
        {&frame->linear_textures, VK_FORMAT_R8G8B8A8_UNORM, "textures.linear"},
    };
    static const uint8_t white[4] = {255, 255, 255, 255};
    struct rb_scene_texture fallback = {
        .name = "white", .width_px = 1, .height_px = 1, .rgba8 = (uint8_t *)white};
    for (int a = 0; a < 2; a++) {
        enum rb_status st =
            rb_gpu_image_init(gpu,
                              &(struct rb_gpu_image_desc){.width_px = size,
                                                          .height_px = size,
                                                          .layer_count = layers,
                                                          .mip_count = mips,
                                                          .format = arrays[a].format,
                                                          .usage = VK_IMAGE_USAGE_SAMPLED_BIT |
                                                                   VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                                                   VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                                          .is_array = true,
                                                          .debug_name = arrays[a].name},
                              arrays[a].img, err);
        if (st)
            return st;
        for (uint32_t l = 0; l < layers; l++) {
            const struct rb_scene_texture *t =
                scene->texture_count ? &scene->textures[l] : &fallback;
            if ((st = upload_texture_layer(gpu, t, arrays[a].img, l, err))) {
                rb_err_prefix(err, "texture '%s'", t->name ? t->name : "?");
                return st;
            }
        }
    }
    return RB_OK;
}

static int tex_layer(uint32_t index)
{
    return index == RB_SCENE_NONE ? -1 : (int)index;
}

static enum rb_status upload_materials(struct rb_gpu *gpu, const struct rb_scene *scene,
                                       struct rb_frame *frame, struct rb_err *err)
{
    struct rb_gpu_material *m =
        calloc(scene->material_count ? scene->material_count : 1, sizeof(*m));
    if (!m)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    for (uint32_t i = 0; i < scene->material_count; i++) {
        const struct rb_scene_material *s = &scene->materials[i];
        memcpy(m[i].base_color, s->base_color, sizeof(m[i].base_color));
        m[i].emissive[0] = s->emissive[0];
        m[i].emissive[1] = s->emissive[1];
        m[i].emissive[2] = s->emissive[2];
        m[i].emissive[3] = s->normal_scale;
        m[i].params[0] = s->metallic;
        m[i].params[1] = s->roughness;
        m[i].params[2] = s->alpha_mode == RB_ALPHA_MASK    ? s->alpha_cutoff
                         : s->alpha_mode == RB_ALPHA_BLEND ? (float)RB_ALPHA_BLENDED
                                                           : 0.0f;
        m[i].params[3] = s->specular_factor;
        m[i].specular_color[0] = s->specular_color[0];
        m[i].specular_color[1] = s->specular_color[1];
        m[i].specular_color[2] = s->specular_color[2];
        m[i].specular_color[3] = s->double_sided ? 1.0f : 0.0f;
        m[i].textures[0] = tex_layer(s->base_color_tex);
        m[i].textures[1] = tex_layer(s->metallic_roughness_tex);
        m[i].textures[2] = tex_layer(s->normal_tex);
        m[i].textures[3] = tex_layer(s->emissive_tex);
    }
    enum rb_status st =
        upload_buffer(gpu, m, sizeof(*m) * scene->material_count,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "materials", &frame->materials, err);
    free(m);
    return st;
}

uint32_t *rb_frame_world_indices(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                                 uint64_t *count)
{
    uint64_t icount = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++)
        icount += scene->primitives[pose->instances[i].primitive].index_count;
    *count = icount;
    uint32_t *indices = malloc((icount ? icount : 1) * sizeof(uint32_t));
    if (!indices)
        return NULL;
    uint32_t dst = 0;
    uint64_t k = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        for (uint32_t j = 0; j < p->index_count; j++)
            indices[k++] = dst + scene->indices[p->first_index + j];
        dst += p->vertex_count;
    }
    return indices;
}

/* The world vertex buffer holds each instance's vertices in instance order; the index buffer
 * points into it, so one indexed draw covers the scene.
 *
 * Design: the arrays that grow with the scene's triangles (the source and world vertices, the
 * morph deltas, the indices) are read by the shaders through their device addresses, kept in
 * each slot's geometry record (shaders/common/geometry_shared.h), not bound as storage buffers.
 * A binding spans at most maxStorageBufferRange (128 MiB on lavapipe: 1.6 M source vertices);
 * splitting an array over several bindings would need descriptor indexing, which lavapipe
 * lacks, or a switch over the bindings in every shader that reads a vertex. An address has no
 * range: each array is one buffer and one allocation, bound only by maxBufferSize and
 * maxMemoryAllocationSize (check_limits, raybundle-job(5) LIMITS). */
static enum rb_status upload_geometry(struct rb_gpu *gpu, const struct rb_scene *scene,
                                      const struct rb_scene_pose *pose, struct rb_frame *frame,
                                      struct rb_err *err)
{
    uint64_t vcount = 0, icount = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        vcount += p->vertex_count;
        icount += p->index_count;
    }
    if (vcount > UINT32_MAX / 2 || icount > UINT32_MAX / 4)
        return rb_errf(err, RB_E_UNSUPPORTED, "scene too large: %llu vertices, %llu indices",
                       (unsigned long long)vcount, (unsigned long long)icount);
    uint32_t *indices = rb_frame_world_indices(scene, pose, &icount);
    if (!indices)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %llu indices",
                       (unsigned long long)icount);
    frame->vertex_count = (uint32_t)vcount;
    frame->index_count = (uint32_t)icount;
    frame->instance_count = pose->instance_count;
    enum rb_status st =
        upload_addressed(gpu, indices, icount * sizeof(uint32_t),
                         VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                         "indices", &frame->indices, err);
    free(indices);
    if (st == RB_OK)
        st = upload_addressed(gpu, scene->vertices,
                              (VkDeviceSize)scene->vertex_count * sizeof(struct rb_scene_vertex),
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "vertices.source",
                              &frame->src_vertices, err);
    if (st == RB_OK)
        st = upload_addressed(
            gpu, scene->morph_deltas,
            (VkDeviceSize)scene->morph_delta_count * sizeof(struct rb_scene_morph_delta),
            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "morph.deltas", &frame->morph_deltas, err);
    for (uint32_t s = 0; s < frame->slot_count && st == RB_OK; s++) {
        struct rb_frame_slot *slot = &frame->slots[s];
        st = rb_frame_buffer(
            gpu, (VkDeviceSize)pose->instance_count * sizeof(struct rb_gpu_instance),
            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "instances", &slot->instances, err);
        if (st == RB_OK)
            st = rb_frame_buffer(gpu, (VkDeviceSize)pose->joint_matrix_count * 64,
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "joints", &slot->joints,
                                 err);
        if (st == RB_OK)
            st = rb_frame_buffer(gpu, (VkDeviceSize)pose->morph_weight_count * sizeof(float),
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "weights",
                                 &slot->weights, err);
        if (st == RB_OK)
            st = rb_gpu_buffer_init(
                gpu,
                &(struct rb_gpu_buffer_desc){
                    .size_bytes = vcount ? vcount * sizeof(struct rb_gpu_vertex) : 16,
                    .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    .is_addressed = true,
                    .debug_name = "vertices.world"},
                &slot->vertices, err);
        if (st == RB_OK)
            st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_geometry),
                                 VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true, "geometry",
                                 &slot->geometry, err);
        if (st == RB_OK)
            memcpy(slot->geometry.mapped,
                   &(struct rb_gpu_geometry){.vertices = slot->vertices.address,
                                             .src_vertices = frame->src_vertices.address,
                                             .morph_deltas = frame->morph_deltas.address,
                                             .indices = frame->indices.address},
                   sizeof(struct rb_gpu_geometry));
    }
    return st;
}

/* The simplified mesh the bdpt integrator's many small views draw (integrator.bdpt.view_triangles;
 * LAVAPIPE.md on why): the budget is split over the instances in proportion to their triangles
 * (rb_scene_simplify_targets), so every instance of a primitive gets the same target and the
 * primitive is simplified once, in its bind pose: the file's positions, the vertices the animate
 * pass skins and morphs for every index buffer alike. Other integrators, a budget of 0 and one
 * the scene fits in leave view_indices empty: the views draw the full index buffer. */
static enum rb_status upload_view_indices(struct rb_gpu *gpu, const struct rb_job *job,
                                          const struct rb_scene *scene,
                                          const struct rb_scene_pose *pose, struct rb_frame *frame,
                                          struct rb_err *err)
{
    uint64_t budget = job->integrator.bdpt.view_triangles;
    uint32_t full = frame->index_count / 3, n = pose->instance_count;
    frame->view_index_count = frame->index_count;
    if (rb_integrator_resolve(job->integrator.name) != RB_INTEGRATOR_BDPT || budget == 0 ||
        budget >= full)
        return RB_OK;
    uint32_t *triangles = malloc(sizeof(uint32_t) * n);
    uint32_t *targets = malloc(sizeof(uint32_t) * n);
    uint32_t *done = malloc(sizeof(uint32_t) * scene->primitive_count); /* target, or NONE */
    uint32_t *counts = malloc(sizeof(uint32_t) * scene->primitive_count);
    uint32_t *local = malloc(sizeof(uint32_t) * scene->index_count); /* as scene->indices */
    uint32_t *indices = NULL;
    enum rb_status st = RB_OK;
    if (!triangles || !targets || !done || !counts || !local) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for the simplified mesh");
        goto out;
    }
    for (uint32_t i = 0; i < n; i++)
        triangles[i] = scene->primitives[pose->instances[i].primitive].index_count / 3;
    rb_scene_simplify_targets(triangles, n, budget, targets);
    memset(done, 0xff, sizeof(uint32_t) * scene->primitive_count);
    uint64_t total = 0;                             /* indices */
    uint32_t drawn = 0, simplified = 0, sloppy = 0; /* primitives */
    float worst = 0.0f;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t pi = pose->instances[i].primitive;
        const struct rb_scene_primitive *p = &scene->primitives[pi];
        if (done[pi] == RB_SCENE_NONE && p->index_count) {
            const struct rb_scene_vertex *v = &scene->vertices[p->first_vertex];
            struct rb_scene_simplified r;
            st = rb_scene_simplify(
                &(struct rb_scene_simplify_mesh){.positions = v->position,
                                                 .normals = v->normal,
                                                 .stride_bytes = sizeof(*v),
                                                 .vertex_count = p->vertex_count,
                                                 .indices = &scene->indices[p->first_index],
                                                 .index_count = p->index_count},
                targets[i], &local[p->first_index], &r, err);
            if (st) {
                rb_err_prefix(err, "simplifying primitive %u", pi);
                goto out;
            }
            counts[pi] = r.index_count;
            drawn++;
            simplified += r.index_count < p->index_count;
            sloppy += r.is_sloppy;
            worst = r.error > worst ? r.error : worst;
        } else if (done[pi] == RB_SCENE_NONE) {
            counts[pi] = 0;
        } else if (done[pi] != targets[i]) {
            RB_BUG("instances of primitive %u with targets %u and %u", pi, done[pi], targets[i]);
        }
        done[pi] = targets[i];
        total += counts[pi];
    }
    indices = malloc(sizeof(uint32_t) * (total ? total : 1));
    if (!indices) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for %llu indices", (unsigned long long)total);
        goto out;
    }
    uint32_t dst = 0, k = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t pi = pose->instances[i].primitive;
        for (uint32_t j = 0; j < counts[pi]; j++)
            indices[k++] = dst + local[scene->primitives[pi].first_index + j];
        dst += scene->primitives[pi].vertex_count;
    }
    frame->view_index_count = (uint32_t)total;
    st = upload_buffer(gpu, indices, total * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                       "indices.view", &frame->view_indices, err);
    if (st == RB_OK)
        rb_log(RB_LOG_INFO,
               "view mesh: %llu of %u triangles for a budget of %llu (%u of %u primitives "
               "simplified, %u sloppily); largest error %.3g of a primitive's size",
               (unsigned long long)total / 3, full, (unsigned long long)budget, simplified, drawn,
               sloppy, (double)worst);
out:
    free(indices);
    free(local);
    free(counts);
    free(done);
    free(targets);
    free(triangles);
    return st;
}

enum rb_status rb_frame_image(struct rb_gpu *gpu, uint32_t w, uint32_t h, uint32_t layers,
                              VkFormat format, VkImageUsageFlags usage, bool layer_views,
                              const char *name, struct rb_gpu_image *out, struct rb_err *err)
{
    return rb_gpu_image_init(gpu,
                             &(struct rb_gpu_image_desc){.width_px = w,
                                                         .height_px = h,
                                                         .layer_count = layers,
                                                         .format = format,
                                                         .usage = usage,
                                                         .is_array = layers > 1 || layer_views,
                                                         .has_layer_views = layer_views,
                                                         .debug_name = name},
                             out, err);
}

static enum rb_status upload_env(struct rb_gpu *gpu, const struct rb_integrator_desc *desc,
                                 struct rb_frame *frame, struct rb_err *err)
{
    static const float black[4] = {0, 0, 0, 0};
    const float *px = desc->env_rgba ? desc->env_rgba : black;
    uint32_t w = desc->env_rgba ? desc->env_width_px : 1;
    uint32_t h = desc->env_rgba ? desc->env_height_px : 1;
    enum rb_status st = rb_frame_image(gpu, w, h, 1, VK_FORMAT_R32G32B32A32_SFLOAT,
                                       VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                       false, "environment", &frame->env_map, err);
    if (st)
        return st;
    struct rb_gpu_buffer staging = {0};
    VkDeviceSize bytes = (VkDeviceSize)w * h * 16;
    st = rb_frame_buffer(gpu, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, "environment staging",
                         &staging, err);
    if (st)
        return st;
    memcpy(staging.mapped, px, bytes);
    VkCommandBuffer cmd;
    st = rb_gpu_oneshot_begin(gpu, &cmd, err);
    if (st == RB_OK) {
        rb_gpu_image_barrier(gpu, cmd, &frame->env_map, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
        VkBufferImageCopy copy = {
            .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
            .imageExtent = {w, h, 1},
        };
        vkCmdCopyBufferToImage(cmd, staging.buffer, frame->env_map.image,
                               VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
        rb_gpu_image_barrier(gpu, cmd, &frame->env_map, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                             VK_IMAGE_LAYOUT_GENERAL);
        st = rb_gpu_oneshot_end(gpu, cmd, err);
    }
    rb_gpu_buffer_release(gpu, &staging);
    return st;
}

/* The device limits the frame's sizes must respect, checked before anything is allocated: the
 * readback (one buffer the host reads, bound by the output pass in aligned bands of rows), the
 * scene's arrays (the vertices and indices read by address, each one buffer and one allocation;
 * the rest bound whole by animate, gbuffer and shadow) and every dispatch's workgroup counts.
 * The workgroup sizes are the local sizes of shaders/output.comp and direct.comp (8 x 8 pixels);
 * animate splits an instance's vertices over dispatches itself (rb_pass_animate_record). */
static enum rb_status check_limits(const struct rb_gpu *gpu, const struct rb_scene *scene,
                                   const struct rb_scene_pose *pose, uint32_t w, uint32_t h,
                                   uint32_t floats_per_pixel, struct rb_err *err)
{
    VkDeviceSize row_bytes = (VkDeviceSize)w * floats_per_pixel * sizeof(float);
    enum rb_status st = rb_gpu_check_buffer_size(gpu, "output", "readback", row_bytes * h, err);
    if (st == RB_OK)
        st = rb_gpu_check_storage_bands(gpu, "output", "readback", row_bytes, h, err);
    uint32_t band_rows = rb_gpu_storage_band_rows(gpu, row_bytes, h);
    if (st == RB_OK)
        st = rb_gpu_check_dispatch(gpu, "output", (w + 7) / 8, (band_rows + 7) / 8, 1, err);
    if (st == RB_OK)
        st = rb_gpu_check_dispatch(gpu, "direct", (w + 7) / 8, (h + 7) / 8, 1, err);
    if (st) {
        rb_err_prefix(err, "resolution %ux%u", w, h);
        return st;
    }

    uint64_t world_vertices = 0, world_indices = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        world_vertices += p->vertex_count;
        world_indices += p->index_count;
    }
    const struct {
        const char *pass, *name;
        VkDeviceSize bytes;
        bool is_addressed; /* one buffer read by address, else one storage binding */
    } bound[] = {
        {"animate", "vertices.source",
         (VkDeviceSize)scene->vertex_count * sizeof(struct rb_scene_vertex), true},
        {"animate", "morph.deltas",
         (VkDeviceSize)scene->morph_delta_count * sizeof(struct rb_scene_morph_delta), true},
        {"animate", "vertices.world", world_vertices * sizeof(struct rb_gpu_vertex), true},
        {"gbuffer", "indices", world_indices * sizeof(uint32_t), true},
        {"animate", "instances",
         (VkDeviceSize)pose->instance_count * sizeof(struct rb_gpu_instance), false},
        {"animate", "joints", (VkDeviceSize)pose->joint_matrix_count * sizeof(struct rb_mat4),
         false},
        {"animate", "weights", (VkDeviceSize)pose->morph_weight_count * sizeof(float), false},
        {"gbuffer", "materials",
         (VkDeviceSize)scene->material_count * sizeof(struct rb_gpu_material), false},
    };
    for (size_t i = 0; i < sizeof(bound) / sizeof(bound[0]) && st == RB_OK; i++)
        st = bound[i].is_addressed
                 ? rb_gpu_check_buffer_size(gpu, bound[i].pass, bound[i].name, bound[i].bytes, err)
                 : rb_gpu_check_storage_range(gpu, bound[i].pass, bound[i].name, bound[i].bytes,
                                              err);
    if (st) /* the vertices as the loader keeps them: flat-shaded triangles unshared */
        rb_err_prefix(err, "scene '%s' (%u vertices, %llu as posed)",
                      scene->path ? scene->path : "?", scene->vertex_count,
                      (unsigned long long)world_vertices);
    return st;
}

bool rb_frame_has_blended(const struct rb_scene *scene)
{
    for (uint32_t i = 0; i < scene->material_count; i++)
        if (scene->materials[i].alpha_mode == RB_ALPHA_BLEND)
            return true;
    return false;
}

/* The transparency pass's target: blended as a colour attachment, read as a storage image by
 * the output pass, in full float precision like the other light images. */
static enum rb_status transparency_init(struct rb_gpu *gpu, struct rb_frame *frame,
                                        struct rb_err *err)
{
    const VkFormat format = VK_FORMAT_R32G32B32A32_SFLOAT;
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(gpu->phys, format, &fp);
    VkFormatFeatureFlags need =
        VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT;
    if ((fp.optimalTilingFeatures & need) != need)
        return rb_errf(err, RB_E_UNSUPPORTED,
                       "the device cannot blend into RGBA32F, which the transparency pass of "
                       "the scene's blended materials needs");
    return rb_frame_image(gpu, frame->width_px, frame->height_px, 1, format,
                          VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT, false,
                          "transparency", &frame->transparency, err);
}

enum rb_status rb_frame_init(struct rb_gpu *gpu, const struct rb_integrator_desc *desc,
                             const struct rb_moment *first, uint32_t slot_count,
                             struct rb_frame *frame, struct rb_err *err)
{
    const struct rb_job *job = desc->job;
    const struct rb_scene *scene = desc->scene;
    uint32_t w = job->width_px, h = job->height_px;
    memset(frame, 0, sizeof(*frame));
    frame->width_px = w;
    frame->height_px = h;
    frame->layer_mask = job->layer_mask;
    frame->readback_floats = rb_layer_stride(job->layer_mask);
    frame->slots = calloc(slot_count, sizeof(*frame->slots));
    if (!frame->slots)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %u frame slots", slot_count);
    frame->slot_count = slot_count;

    enum rb_status st = check_limits(gpu, scene, first->pose, w, h, frame->readback_floats, err);
    if (st == RB_OK)
        st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_globals), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                             true, "globals", &frame->globals, err);
    if (st == RB_OK)
        st = upload_geometry(gpu, scene, first->pose, frame, err);
    if (st == RB_OK)
        st = upload_view_indices(gpu, job, scene, first->pose, frame, err);
    if (st == RB_OK)
        st = upload_materials(gpu, scene, frame, err);
    if (st == RB_OK)
        st = upload_textures(gpu, scene, frame, err);
    if (st == RB_OK)
        st = upload_env(gpu, desc, frame, err);
    if (st)
        return st;

    /* Lights keep their kinds over the sequence, so shadow layers are assigned once. */
    frame->light_count = first->light_count;
    frame->layer_light_count = first->layer_light_count;
    uint32_t own = first->light_count - first->layer_light_count;
    for (uint32_t i = 0; i < first->light_count; i++) {
        uint32_t need = shadow_layers_for(first->lights[i].type);
        if (frame->shadow_layer_count + need > RB_MAX_SHADOW_LAYERS) {
            if (i < own)
                rb_log(RB_LOG_WARN,
                       "light %u and later lights cast no shadows: more than %d "
                       "shadow-map layers would be needed",
                       i, RB_MAX_SHADOW_LAYERS);
            else
                rb_log(RB_LOG_WARN,
                       "%u of the %u lights of the blended surfaces (emitter samples, then "
                       "environment directions) light nothing: more than %d shadow-map layers "
                       "would be needed",
                       first->light_count - i, first->layer_light_count, RB_MAX_SHADOW_LAYERS);
            break;
        }
        frame->shadow_layer_count += need;
        if (i < own)
            frame->own_shadow_layer_count = frame->shadow_layer_count;
    }
    uint32_t shadow_size = job->integrator.direct.shadow_size_px;
    st = rb_frame_buffer(
        gpu, sizeof(struct rb_gpu_light) * (first->light_capacity ? first->light_capacity : 1),
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "lights", &frame->lights, err);
    if (st == RB_OK)
        st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_shadow_view) * RB_MAX_SHADOW_LAYERS,
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "shadow views",
                             &frame->shadow_views, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, shadow_size, shadow_size,
                            frame->shadow_layer_count ? frame->shadow_layer_count : 1,
                            VK_FORMAT_R32_SFLOAT,
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, true,
                            "shadow maps", &frame->shadow_maps, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, shadow_size, shadow_size, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "shadow depth",
                            &frame->shadow_depth, err);

    static const char *const gb_names[RB_GBUFFER_COLOR_COUNT] = {
        "gbuffer.position", "gbuffer.normal",   "gbuffer.albedo",
        "gbuffer.specular", "gbuffer.emission", "gbuffer.motion"};
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT && st == RB_OK; i++)
        st = rb_frame_image(gpu, w, h, 1, rb_gbuffer_formats[i],
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
                                VK_IMAGE_USAGE_SAMPLED_BIT,
                            false, gb_names[i], &frame->gbuffer[i], err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, w, h, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "gbuffer.depth",
                            &frame->depth, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, w, h, 1, VK_FORMAT_R32G32B32A32_SFLOAT,
                            VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, false,
                            "direct", &frame->direct, err);
    if (st == RB_OK)
        st = rb_frame_buffer(gpu, (VkDeviceSize)w * h * frame->readback_floats * sizeof(float),
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                             true, "readback", &frame->readback, err);
    if (st == RB_OK && !gpu->is_unified_memory)
        st = rb_frame_buffer(gpu, (VkDeviceSize)w * h * frame->readback_floats * sizeof(float),
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                             false, "readback.device", &frame->readback_device, err);
    if (st == RB_OK && rb_frame_has_blended(scene))
        st = transparency_init(gpu, frame, err);
    if (st)
        return st;
    frame->beauty = &frame->direct;

    VkCommandBuffer cmd;
    if ((st = rb_gpu_oneshot_begin(gpu, &cmd, err)))
        return st;
    struct rb_gpu_image *general[] = {
        &frame->shadow_maps, &frame->shadow_depth, &frame->gbuffer[0], &frame->gbuffer[1],
        &frame->gbuffer[2],  &frame->gbuffer[3],   &frame->gbuffer[4], &frame->gbuffer[5],
        &frame->depth,       &frame->direct,
    };
    for (size_t i = 0; i < sizeof(general) / sizeof(general[0]); i++)
        rb_gpu_image_barrier(gpu, cmd, general[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    if (frame->transparency.image)
        rb_gpu_image_barrier(gpu, cmd, &frame->transparency, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    /* Defined contents for the slots a chunk's first warm-up frame reads as its past. */
    for (uint32_t s = 0; s < frame->slot_count; s++)
        vkCmdFillBuffer(cmd, frame->slots[s].vertices.buffer, 0, VK_WHOLE_SIZE, 0);
    rb_gpu_barrier(cmd);
    return rb_gpu_oneshot_end(gpu, cmd, err);
}

void rb_frame_release(struct rb_gpu *gpu, struct rb_frame *frame)
{
    if (!gpu || !frame)
        return;
    rb_gpu_buffer_release(gpu, &frame->readback);
    rb_gpu_buffer_release(gpu, &frame->readback_device);
    rb_gpu_image_release(gpu, &frame->transparency);
    rb_gpu_image_release(gpu, &frame->direct);
    rb_gpu_image_release(gpu, &frame->depth);
    for (int i = RB_GBUFFER_COLOR_COUNT - 1; i >= 0; i--)
        rb_gpu_image_release(gpu, &frame->gbuffer[i]);
    rb_gpu_image_release(gpu, &frame->shadow_depth);
    rb_gpu_image_release(gpu, &frame->shadow_maps);
    rb_gpu_buffer_release(gpu, &frame->shadow_views);
    rb_gpu_buffer_release(gpu, &frame->lights);
    rb_gpu_image_release(gpu, &frame->env_map);
    for (uint32_t s = frame->slot_count; s-- > 0 && frame->slots;) {
        rb_gpu_buffer_release(gpu, &frame->slots[s].geometry);
        rb_gpu_buffer_release(gpu, &frame->slots[s].vertices);
        rb_gpu_buffer_release(gpu, &frame->slots[s].weights);
        rb_gpu_buffer_release(gpu, &frame->slots[s].joints);
        rb_gpu_buffer_release(gpu, &frame->slots[s].instances);
    }
    free(frame->slots);
    rb_gpu_image_release(gpu, &frame->linear_textures);
    rb_gpu_image_release(gpu, &frame->srgb_textures);
    rb_gpu_buffer_release(gpu, &frame->materials);
    rb_gpu_buffer_release(gpu, &frame->morph_deltas);
    rb_gpu_buffer_release(gpu, &frame->src_vertices);
    rb_gpu_buffer_release(gpu, &frame->view_indices);
    rb_gpu_buffer_release(gpu, &frame->indices);
    rb_gpu_buffer_release(gpu, &frame->globals);
    memset(frame, 0, sizeof(*frame));
}

uint32_t rb_layer_env_lights(const struct rb_job *job, const float *rgba, uint32_t w, uint32_t h,
                             struct rb_world_light out[RB_LAYER_ENV_LIGHTS])
{
    const uint32_t n = RB_LAYER_ENV_LIGHTS;
    float k = job->environment.intensity;
    struct rb_vec3 dir[RB_LAYER_ENV_LIGHTS]; /* towards the environment */
    double sum[RB_LAYER_ENV_LIGHTS][3] = {{0}};
    for (uint32_t i = 0; i < n; i++) {
        double y = 1.0 - (2.0 * i + 1.0) / n, r = sqrt(1.0 - y * y);
        double phi = i * RB_PI * (3.0 - sqrt(5.0)); /* the golden angle */
        dir[i] = rb_v3((float)(r * cos(phi)), (float)y, (float)(r * sin(phi)));
    }
    if (!rgba || !w || !h) {
        for (uint32_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                sum[i][c] = job->environment.color[c] * 4.0 * RB_PI / n;
    } else {
        /* Each texel's direction as rb_equirect_uv maps it (u from atan(x, -z), v = 0 at +Y,
         * the map turned by the rotation about +Y), and its solid angle. */
        float rot = job->environment.rotation_deg * (float)RB_PI / 180.0f;
        float cr = cosf(-rot), sr = sinf(-rot);
        for (uint32_t y = 0; y < h; y++) {
            double theta = (y + 0.5) / h * RB_PI, st = sin(theta);
            double area = (2.0 * RB_PI / w) * (RB_PI / h) * st;
            for (uint32_t x = 0; x < w; x++) {
                double phi = ((x + 0.5) / w - 0.5) * 2.0 * RB_PI;
                float m[3] = {(float)(st * sin(phi)), (float)cos(theta), (float)(-st * cos(phi))};
                struct rb_vec3 d = rb_v3(cr * m[0] - sr * m[2], m[1], sr * m[0] + cr * m[2]);
                uint32_t best = 0;
                for (uint32_t i = 1; i < n; i++)
                    if (rb_v3_dot(d, dir[i]) > rb_v3_dot(d, dir[best]))
                        best = i;
                const float *t = &rgba[((size_t)y * w + x) * 4];
                for (int c = 0; c < 3; c++)
                    sum[best][c] += t[c] * area;
            }
        }
    }
    bool any = false;
    for (uint32_t i = 0; i < n; i++) {
        out[i] = (struct rb_world_light){.type = RB_LIGHT_DIRECTIONAL,
                                         .direction = rb_v3_scale(dir[i], -1.0f)};
        for (int c = 0; c < 3; c++) {
            out[i].color[c] = (float)(sum[i][c] * k);
            any = any || out[i].color[c] > 0.0f;
        }
    }
    return any ? n : 0;
}

enum rb_status rb_moment_evaluate(const struct rb_job *job, const struct rb_scene *scene,
                                  const struct rb_anim_selection *sel, double time_s,
                                  struct rb_moment *m, struct rb_err *err)
{
    rb_scene_evaluate(scene, sel, time_s, m->pose);
    enum rb_status st = rb_camera_evaluate(job, scene, m->setup, m->pose, time_s, &m->camera, err);
    if (st)
        return st;
    uint32_t cap = m->light_capacity;
    uint32_t total = rb_scene_world_lights(job, scene, m->setup, m->pose, m->lights, cap);
    uint32_t world = total;
    if (m->has_emitter_lights || m->has_layer_lights) {
        uint32_t at = total < cap ? total : cap;
        total += rb_scene_emitter_lights(scene, m->pose, job->integrator.direct.emitter_lights,
                                         m->lights + at, cap - at);
    }
    if (m->has_layer_lights) {
        for (uint32_t i = 0; i < m->layer_env_count; i++)
            if (total + i < cap)
                m->lights[total + i] = m->layer_env[i];
        total += m->layer_env_count;
    }
    m->layer_light_count = m->has_layer_lights ? total - world : 0;
    if (total > cap)
        RB_BUG("%u lights in a moment made for %u", total, cap);
    m->light_count = total;
    return RB_OK;
}

enum rb_status rb_moment_lights_init(const struct rb_job *job, const struct rb_scene *scene,
                                     struct rb_moment *m, struct rb_err *err)
{
    uint64_t cap = rb_scene_world_lights(job, scene, m->setup, m->pose, NULL, 0);
    if (m->has_emitter_lights || m->has_layer_lights)
        cap += job->integrator.direct.emitter_lights;
    if (m->has_layer_lights)
        cap += m->layer_env_count;
    if (cap > UINT32_MAX / sizeof(struct rb_gpu_light))
        return rb_errf(err, RB_E_UNSUPPORTED, "%s%s%llu lights: more than a light buffer holds",
                       RB_JOB_AT(job->at.lights), (unsigned long long)cap);
    free(m->lights);
    if (!(m->lights = calloc(cap ? cap : 1, sizeof(*m->lights))))
        return rb_errf(err, RB_E_NOMEM, "out of memory for %llu lights", (unsigned long long)cap);
    m->light_capacity = (uint32_t)cap;
    return RB_OK;
}

static void mat_store(float out[16], const struct rb_mat4 *m)
{
    memcpy(out, m->m, sizeof(float) * 16);
}

void rb_frame_write_slot(struct rb_frame *frame, const struct rb_scene *scene,
                         const struct rb_moment *m, struct rb_frame_slot *slot)
{
    const struct rb_scene_pose *pose = m->pose;
    struct rb_gpu_instance *out = slot->instances.mapped;
    uint32_t dst = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_instance *in = &pose->instances[i];
        const struct rb_scene_primitive *p = &scene->primitives[in->primitive];
        const struct rb_mat4 *world = &pose->node_world[in->node];
        struct rb_mat4 inv = rb_mat4_inverse(world, NULL);
        struct rb_mat4 nm = rb_mat4_transpose(&inv);
        mat_store(out[i].world, world);
        mat_store(out[i].normal_matrix, &nm);
        out[i].range[0] = p->first_vertex;
        out[i].range[1] = p->vertex_count;
        out[i].range[2] = dst;
        out[i].range[3] = p->material;
        out[i].deform[0] = p->first_morph;
        out[i].deform[1] = in->first_weight == RB_SCENE_NONE ? 0 : p->morph_target_count;
        out[i].deform[2] = in->first_weight == RB_SCENE_NONE ? 0 : in->first_weight;
        out[i].deform[3] = in->first_joint == RB_SCENE_NONE ? RB_NONE : in->first_joint;
        dst += p->vertex_count;
    }
    if (pose->joint_matrix_count)
        memcpy(slot->joints.mapped, pose->joint_matrices,
               sizeof(struct rb_mat4) * pose->joint_matrix_count);
    if (pose->morph_weight_count)
        memcpy(slot->weights.mapped, pose->morph_weights, sizeof(float) * pose->morph_weight_count);
    frame->instances = out;
}

struct rb_mat4 rb_frame_projection(const struct rb_frame *frame, const struct rb_camera *cam)
{
    return rb_mat4_perspective(cam->fov_y_rad, (float)frame->width_px / (float)frame->height_px,
                               cam->z_near, cam->z_far);
}

/* Shadow-map views: six 90-degree faces for a point light, the cone for a spot, a box around
 * the scene for a directional light. The box and the depth ranges come from the job's bounds
 * (every pose of the animation), so they do not change from frame to frame. */
static uint32_t write_shadow_views(const struct rb_world_light *l, const struct rb_moment *m,
                                   uint32_t size, struct rb_gpu_shadow_view *out)
{
    struct rb_vec3 lo = m->setup->bounds_min, hi = m->setup->bounds_max;
    struct rb_vec3 center = rb_v3_scale(rb_v3_add(lo, hi), 0.5f);
    float radius = 0.5f * rb_v3_length(rb_v3_sub(hi, lo));
    if (!(radius > 0.0f))
        radius = 1.0f;
    if (l->type == RB_LIGHT_DIRECTIONAL) {
        struct rb_vec3 d = rb_v3_normalize(l->direction);
        struct rb_vec3 origin = rb_v3_sub(center, rb_v3_scale(d, radius * 1.05f));
        struct rb_mat4 view = rb_mat4_look_at(origin, center, rb_v3(0, 1, 0));
        struct rb_mat4 proj = rb_mat4_ortho(-radius, radius, -radius, radius, 0.0f, radius * 2.1f);
        struct rb_mat4 vp = rb_mat4_mul(&proj, &view);
        mat_store(out[0].view_proj, &vp);
        memcpy(out[0].light, (float[4]){origin.x, origin.y, origin.z, RB_KIND_DIRECTIONAL}, 16);
        memcpy(out[0].axis, (float[4]){d.x, d.y, d.z, 2.0f * radius / (float)size}, 16);
        return 1;
    }
    /* far: the farthest corner of the bounds; near: small against the scene, never zero */
    float far = 0.0f;
    for (int c = 0; c < 8; c++) {
        struct rb_vec3 corner =
            rb_v3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
        float dist = rb_v3_length(rb_v3_sub(corner, l->position));
        if (dist > far)
            far = dist;
    }
    far = far * 1.05f + 1e-3f;
    float near = far * 1e-4f;
    if (l->type == RB_LIGHT_SPOT) {
        float fov = 2.0f * l->outer_cone_rad + 0.1f;
        if (fov > 170.0f * RB_PI / 180.0f)
            fov = 170.0f * RB_PI / 180.0f;
        struct rb_vec3 d = rb_v3_normalize(l->direction);
        struct rb_vec3 up = fabsf(d.y) > 0.99f ? rb_v3(1, 0, 0) : rb_v3(0, 1, 0);
        struct rb_mat4 view = rb_mat4_look_at(l->position, rb_v3_add(l->position, d), up);
        struct rb_mat4 proj = rb_mat4_perspective(fov, 1.0f, near, far);
        struct rb_mat4 vp = rb_mat4_mul(&proj, &view);
        mat_store(out[0].view_proj, &vp);
        memcpy(out[0].light, (float[4]){l->position.x, l->position.y, l->position.z, RB_KIND_SPOT},
               16);
        memcpy(out[0].axis, (float[4]){d.x, d.y, d.z, 2.0f * tanf(fov * 0.5f) / (float)size}, 16);
        return 1;
    }
    static const float dirs[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    static const float ups[6][3] = {{0, 1, 0}, {0, 1, 0}, {0, 0, -1},
                                    {0, 0, 1}, {0, 1, 0}, {0, 1, 0}};
    struct rb_mat4 proj = rb_mat4_perspective(RB_PI * 0.5f, 1.0f, near, far);
    for (int f = 0; f < 6; f++) {
        struct rb_vec3 d = rb_v3(dirs[f][0], dirs[f][1], dirs[f][2]);
        struct rb_mat4 view = rb_mat4_look_at(l->position, rb_v3_add(l->position, d),
                                              rb_v3(ups[f][0], ups[f][1], ups[f][2]));
        struct rb_mat4 vp = rb_mat4_mul(&proj, &view);
        mat_store(out[f].view_proj, &vp);
        memcpy(out[f].light, (float[4]){l->position.x, l->position.y, l->position.z, RB_KIND_POINT},
               16);
        memcpy(out[f].axis, (float[4]){d.x, d.y, d.z, 2.0f / (float)size}, 16);
    }
    return 6;
}

void rb_frame_write_globals(struct rb_frame *frame, const struct rb_job *job, int frame_index,
                            const struct rb_moment *cur, const struct rb_moment *prev,
                            bool has_env_map)
{
    struct rb_gpu_globals *g = frame->globals.mapped;
    struct rb_mat4 proj = rb_frame_projection(frame, &cur->camera);
    struct rb_mat4 vp = rb_mat4_mul(&proj, &cur->camera.world_to_camera);
    struct rb_mat4 inv = rb_mat4_inverse(&vp, NULL);
    struct rb_mat4 pproj = rb_frame_projection(frame, &prev->camera);
    struct rb_mat4 pvp = rb_mat4_mul(&pproj, &prev->camera.world_to_camera);
    memset(g, 0, sizeof(*g));
    mat_store(g->view, &cur->camera.world_to_camera);
    mat_store(g->proj, &proj);
    mat_store(g->view_proj, &vp);
    mat_store(g->inv_view_proj, &inv);
    mat_store(g->prev_view_proj, &pvp);
    g->camera_pos[0] = cur->camera.position.x;
    g->camera_pos[1] = cur->camera.position.y;
    g->camera_pos[2] = cur->camera.position.z;
    g->camera_pos[3] = cur->camera.fov_y_rad;
    g->size[0] = frame->width_px;
    g->size[1] = frame->height_px;
    g->size[2] = frame->light_count - frame->layer_light_count;
    g->size[3] = (uint32_t)frame_index;
    g->env[0] = job->environment.intensity;
    g->env[1] = job->environment.rotation_deg * RB_PI / 180.0f;
    g->env[2] = has_env_map ? 1.0f : 0.0f;
    memcpy(g->env_color, job->environment.color, sizeof(float) * 3);
    g->shadow[0] = job->integrator.direct.shadow_bias;
    g->shadow[1] = job->integrator.direct.pcf_radius_px;
    g->shadow[2] = (float)frame->shadow_maps.width_px;
    g->shadow[3] = (float)frame->layer_light_count;

    struct rb_gpu_light *lights = frame->lights.mapped;
    struct rb_gpu_shadow_view *views = frame->shadow_views.mapped;
    uint32_t layer = 0;
    for (uint32_t i = 0; i < frame->light_count; i++) {
        const struct rb_world_light *l = &cur->lights[i];
        struct rb_gpu_light *o = &lights[i];
        bool shadowed = layer + shadow_layers_for(l->type) <= frame->shadow_layer_count;
        uint32_t kind = l->type == RB_LIGHT_EMITTER ? RB_KIND_EMITTER : (uint32_t)l->type;
        memcpy(o->position, (float[4]){l->position.x, l->position.y, l->position.z, (float)kind},
               16);
        memcpy(o->direction, (float[4]){l->direction.x, l->direction.y, l->direction.z, l->range},
               16);
        memcpy(o->color,
               (float[4]){l->color[0], l->color[1], l->color[2], shadowed ? (float)layer : -1.0f},
               16);
        /* A layer light without a shadow map would light the layers through every wall. */
        if (!shadowed && i >= frame->light_count - frame->layer_light_count)
            memset(o->color, 0, 3 * sizeof(float));
        o->cone[0] = cosf(l->inner_cone_rad);
        o->cone[1] = cosf(l->outer_cone_rad);
        if (shadowed)
            layer += write_shadow_views(l, cur, frame->shadow_maps.width_px, &views[layer]);
    }
}
