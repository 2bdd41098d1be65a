/* bdpt: the compute passes of the bdpt integrator's frame (seed 000, A.1 and B.1-B.3; DESIGN.md
 * "bdpt", BDPT.md). The raster views they read (RSMs, VPL maps, bundle lists) are view.c's;
 * these passes find the G-buffer's bounds, generate VPLs and bundle views, split the G-buffer
 * into interleaved sub-images, connect, gather and filter. */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "bdpt_bounce.comp.h"
#include "bdpt_bounds.comp.h"
#include "bdpt_connect.comp.h"
#include "bdpt_emitter_direct.comp.h"
#include "bdpt_emitters.comp.h"
#include "bdpt_filter.comp.h"
#include "bdpt_gather.comp.h"
#include "bdpt_generate.comp.h"
#include "bdpt_mark.comp.h"
#include "bdpt_reconstruct.comp.h"
#include "bdpt_split.comp.h"

struct rb_pass_bdpt {
    struct rb_pass bounds, emitters, generate, bounce, split, mark, connect, emitter_direct, gather,
        filter, reconstruct;
};

static const struct rb_pass_binding bounds_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_BOUNDS_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNDS_OUT, STORAGE_BUFFER),
};
_Static_assert(COUNT(bounds_bindings) == RB_BIND_BDPT_BOUNDS_COUNT, "bounds bindings");

static const struct rb_pass_binding emitters_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_EMITTERS_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_EMITTERS_EMITTERS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_EMITTERS_MATERIALS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_EMITTERS_CDF, STORAGE_BUFFER),
};
_Static_assert(COUNT(emitters_bindings) == RB_BIND_BDPT_EMITTERS_COUNT, "emitters bindings");

static const struct rb_pass_binding generate_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_BOUNDS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_SAMPLES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_BDPT_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_RSM_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_RSM_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_RSM_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_RSM_MATERIAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_VPLS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_VPL_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_BUNDLE_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_EMITTERS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_MATERIALS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_SRGB_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_LINEAR_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_EMIT_INFO, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_PROBE_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_VPL_DRAWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_PROBE_DRAWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_GENERATE_EMITTER_CDF, STORAGE_BUFFER),
};
_Static_assert(COUNT(generate_bindings) == RB_BIND_BDPT_GENERATE_COUNT, "generate bindings");

static const struct rb_pass_binding bounce_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_VPLS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_VPL_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_PROBE_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_PROBE_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_PROBE_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_PROBE_MATERIAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_VPL_DRAWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_SAMPLES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_BOUNCE_PROBE_DRAWS, STORAGE_BUFFER),
};
_Static_assert(COUNT(bounce_bindings) == RB_BIND_BDPT_BOUNCE_COUNT, "bounce bindings");

static const struct rb_pass_binding split_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_GB_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_GB_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_GB_SPECULAR, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_GB_EMISSION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_GB_MOTION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_OUT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_OUT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_OUT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_SPLIT_OUT + 3, STORAGE_IMAGE),
};
_Static_assert(COUNT(split_bindings) == RB_BIND_BDPT_SPLIT_COUNT, "split bindings");

static const struct rb_pass_binding mark_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_MARK_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_MARK_BUNDLE_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_MARK_HEADS, STORAGE_IMAGE),
};
_Static_assert(COUNT(mark_bindings) == RB_BIND_BDPT_MARK_COUNT, "mark bindings");

static const struct rb_pass_binding connect_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SPLIT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SPLIT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SPLIT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SPLIT + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_VPLS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_VPL_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_VPL_MAPS, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_BUNDLE_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_HEADS, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_NODES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_BDPT_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SHADOW_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_SHADOW_MAPS, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_ENV_MAP, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LIGHT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LIGHT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LIGHT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LIGHT + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_EMIT_INFO, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_EMITTED + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_EMITTED + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_CONNECT_LTC, STORAGE_BUFFER),
};
_Static_assert(COUNT(connect_bindings) == RB_BIND_BDPT_CONNECT_COUNT, "connect bindings");

static const struct rb_pass_binding gather_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_IN + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_IN + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_IN + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_IN + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_OUT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_OUT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_OUT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_GATHER_OUT + 3, STORAGE_IMAGE),
};
_Static_assert(COUNT(gather_bindings) == RB_BIND_BDPT_GATHER_COUNT, "gather bindings");

static const struct rb_pass_binding filter_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_GB_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_GB_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_IN + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_IN + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_IN + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_IN + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_OUT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_OUT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_OUT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_OUT + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_EMITTED + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_FILTER_EMITTED + 1, STORAGE_IMAGE),
};
_Static_assert(COUNT(filter_bindings) == RB_BIND_BDPT_FILTER_COUNT, "filter bindings");

static const struct rb_pass_binding reconstruct_bindings[] = {
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_HISTORY, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_GB_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_REPROJECT, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_CACHE + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_CACHE + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_CACHE + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_CACHE + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_OUT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_OUT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_OUT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_OUT + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_HITS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_BDPT_RECONSTRUCT_GB_NORMAL, STORAGE_IMAGE),
};
_Static_assert(COUNT(reconstruct_bindings) == RB_BIND_BDPT_RECONSTRUCT_COUNT,
               "reconstruct bindings");

#define COMPUTE(field, nm, table, push, spv_name)                                                  \
    rb_pass_compute_init(gpu,                                                                      \
                         &(struct rb_pass_compute_desc){.name = (nm),                              \
                                                        RB_PASS_BINDINGS(table),                   \
                                                        .push_bytes = (push),                      \
                                                        .spv = (spv_name),                         \
                                                        .spv_bytes = sizeof(spv_name)},            \
                         &p->field, err)

enum rb_status rb_pass_bdpt_create(struct rb_gpu *gpu, struct rb_pass_bdpt **out,
                                   struct rb_err *err)
{
    struct rb_pass_bdpt *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    const uint32_t image_push = sizeof(struct rb_gpu_bdpt_image_push);
    enum rb_status st;
    if ((st = COMPUTE(bounds, "bounds", bounds_bindings, 0, rb_spv_bdpt_bounds_comp)) ||
        (st = COMPUTE(emitters, "emitters", emitters_bindings,
                      sizeof(struct rb_gpu_bdpt_emitters_push), rb_spv_bdpt_emitters_comp)) ||
        (st = COMPUTE(generate, "generate", generate_bindings,
                      sizeof(struct rb_gpu_bdpt_generate_push), rb_spv_bdpt_generate_comp)) ||
        (st = COMPUTE(bounce, "bounce", bounce_bindings, sizeof(struct rb_gpu_bdpt_bounce_push),
                      rb_spv_bdpt_bounce_comp)) ||
        (st = COMPUTE(split, "split", split_bindings, image_push, rb_spv_bdpt_split_comp)) ||
        (st = COMPUTE(mark, "mark", mark_bindings, sizeof(struct rb_gpu_bdpt_mark_push),
                      rb_spv_bdpt_mark_comp)) ||
        (st = COMPUTE(connect, "connect", connect_bindings, sizeof(struct rb_gpu_bdpt_connect_push),
                      rb_spv_bdpt_connect_comp)) ||
        (st = COMPUTE(emitter_direct, "emitter_direct", connect_bindings,
                      sizeof(struct rb_gpu_bdpt_connect_push), rb_spv_bdpt_emitter_direct_comp)) ||
        (st = COMPUTE(gather, "gather", gather_bindings, image_push, rb_spv_bdpt_gather_comp)) ||
        (st = COMPUTE(filter, "filter", filter_bindings, image_push, rb_spv_bdpt_filter_comp)) ||
        (st = COMPUTE(reconstruct, "reconstruct", reconstruct_bindings, 0,
                      rb_spv_bdpt_reconstruct_comp))) {
        rb_pass_bdpt_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_bdpt_destroy(struct rb_pass_bdpt *p)
{
    if (!p)
        return;
    rb_pass_release(&p->reconstruct);
    rb_pass_release(&p->filter);
    rb_pass_release(&p->gather);
    rb_pass_release(&p->emitter_direct);
    rb_pass_release(&p->connect);
    rb_pass_release(&p->mark);
    rb_pass_release(&p->split);
    rb_pass_release(&p->bounce);
    rb_pass_release(&p->generate);
    rb_pass_release(&p->emitters);
    rb_pass_release(&p->bounds);
    free(p);
}

static uint32_t groups(uint32_t n, uint32_t size)
{
    return (n + size - 1) / size;
}

/* The filter's kernels (bdpt_filter.comp): for indirect light a tent of half-width h, the
 * radius rounded to a multiple of the interleave n (at least n); for direct light a box of
 * radius n / 2, one interleave block; the pixel alone with radius 0. */
static struct rb_gpu_bdpt_image_push image_push(const struct rb_bdpt_frame *b)
{
    uint32_t n = b->interleave, r = b->filter_radius_px, m = (r + n / 2) / n;
    uint32_t h = r ? n * (m > 1 ? m : 1) : 1, rd = r ? n / 2 : 0;
    while (h > RB_BDPT_MAX_FILTER) /* the shader's row masks */
        h -= n;
    /* sub-image s sees iteration k when k mod n^2 = s: the first min(n^2, max(K_v, K_b)) */
    uint32_t loops = b->vpl_count > b->bundle_count ? b->vpl_count : b->bundle_count;
    uint32_t active = loops < n * n ? loops : n * n;
    return (struct rb_gpu_bdpt_image_push){
        .split = {n, b->sub_width_px, b->sub_height_px, h},
        .stops = {b->filter_depth, b->filter_normal, (float)rd, (float)active},
        .light = {b->filter_light, 0.0f, 0.0f, 0.0f},
    };
}

static void push(VkCommandBuffer cmd, const struct rb_pass *pass, const void *data, uint32_t bytes)
{
    vkCmdPushConstants(cmd, pass->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, bytes, data);
}

void rb_pass_bdpt_bounds_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b)
{
    /* The box starts empty (lo = ~0, hi = 0 in the shader's ordered encoding), after whatever
     * read it last, and before the shader's atomics. */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    vkCmdFillBuffer(cmd, b->bounds.buffer, 0, 4 * sizeof(uint32_t), ~0u);
    vkCmdFillBuffer(cmd, b->bounds.buffer, 4 * sizeof(uint32_t), 4 * sizeof(uint32_t), 0u);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                              VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    struct rb_pass_bindings bind = {.pass = &p->bounds};
    rb_pass_bind_image(&bind, RB_BIND_BDPT_BOUNDS_POSITION, b->gbuffer[RB_GB_POSITION].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNDS_OUT, &b->bounds);
    rb_pass_record_bindings(cmd, &bind);
    vkCmdDispatch(cmd, groups(frame->width_px, RB_BDPT_BOUNDS_TILE_PX),
                  groups(frame->height_px, RB_BDPT_BOUNDS_TILE_PX), 1);
}

void rb_pass_bdpt_emitters_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                  const struct rb_frame *frame, const struct rb_frame_slot *slot,
                                  const struct rb_bdpt_frame *b)
{
    struct rb_pass_bindings bind = {.pass = &p->emitters};
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_EMITTERS_VERTICES, &slot->geometry);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_EMITTERS_EMITTERS, &b->emitters);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_EMITTERS_MATERIALS, &frame->materials);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_EMITTERS_CDF, &b->emitter_cdf);
    rb_pass_record_bindings(cmd, &bind);
    struct rb_gpu_bdpt_emitters_push pc = {.counts = {b->emitter_count, 0, 0, 0}};
    push(cmd, &p->emitters, &pc, sizeof(pc));
    vkCmdDispatch(cmd, 1, 1, 1);
}

void rb_pass_bdpt_generate_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                  const struct rb_frame *frame, const struct rb_frame_slot *slot,
                                  const struct rb_bdpt_frame *b)
{
    struct rb_pass_bindings bind = {.pass = &p->generate};
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_BOUNDS, &b->bounds);
    rb_pass_bind_buffer_range(&bind, RB_BIND_BDPT_GENERATE_SAMPLES, &b->samples,
                              b->slot * b->sample_block_bytes, b->sample_block_bytes);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_LIGHTS, &frame->lights);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_BDPT_LIGHTS, &b->lights);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_RSM_VIEWS, &frame->shadow_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_GENERATE_RSM_POSITION, b->rsm[0].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_GENERATE_RSM_NORMAL, b->rsm[1].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_GENERATE_RSM_MATERIAL, b->rsm[3].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_VPLS, &b->vpls);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_VPL_VIEWS, &b->vpl_views);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_BUNDLE_VIEWS, &b->bundle_views);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_VERTICES, &slot->geometry);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_EMITTERS, &b->emitters);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_MATERIALS, &frame->materials);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_GENERATE_SRGB_TEXTURES, frame->srgb_textures.view,
                       p->generate.gpu->linear_sampler);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_GENERATE_LINEAR_TEXTURES, frame->linear_textures.view,
                       p->generate.gpu->linear_sampler);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_EMIT_INFO, &b->emit_info);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_PROBE_VIEWS, &b->probe_views);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_VPL_DRAWS, &b->vpl_draws);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_PROBE_DRAWS, &b->probe_draws);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_GENERATE_EMITTER_CDF, &b->emitter_cdf);
    rb_pass_record_bindings(cmd, &bind);
    struct rb_gpu_bdpt_generate_push pc = {
        .counts = {b->vpl_count, b->bundle_count, frame->light_count - frame->layer_light_count,
                   b->rsm[0].width_px},
        .scene = {b->scene_centre[0], b->scene_centre[1], b->scene_centre[2], b->scene_radius},
        .sizes = {(float)b->bundle_size_px, (float)b->vpl_size_px, b->punctual_power,
                  (float)b->emitter_count},
    };
    push(cmd, &p->generate, &pc, sizeof(pc));
    uint32_t n = b->vpl_count > b->bundle_count ? b->vpl_count : b->bundle_count;
    vkCmdDispatch(cmd, groups(n, 64), 1, 1);
}

void rb_pass_bdpt_bounce_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_bdpt_frame *b, uint32_t round)
{
    struct rb_pass_bindings bind = {.pass = &p->bounce};
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNCE_VPLS, &b->vpls);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNCE_VPL_VIEWS, &b->vpl_views);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNCE_PROBE_VIEWS, &b->probe_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_BOUNCE_PROBE_POSITION, b->probe[0].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_BOUNCE_PROBE_NORMAL, b->probe[1].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_BOUNCE_PROBE_MATERIAL, b->probe[3].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNCE_VPL_DRAWS, &b->vpl_draws);
    rb_pass_bind_buffer_range(&bind, RB_BIND_BDPT_BOUNCE_SAMPLES, &b->samples,
                              b->slot * b->sample_block_bytes, b->sample_block_bytes);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_BOUNCE_PROBE_DRAWS, &b->probe_draws);
    rb_pass_record_bindings(cmd, &bind);
    uint32_t k = b->vpl_count;
    struct rb_gpu_bdpt_bounce_push pc = {
        .counts = {k, round * k, (round + 1) * k, round == 0 && b->has_chain},
        .scene = {b->scene_centre[0], b->scene_centre[1], b->scene_centre[2], b->scene_radius},
        .brdf = {b->min_roughness, 0.0f, 0.0f, 0.0f},
    };
    push(cmd, &p->bounce, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(b->vpl_count, 64), 1, 1);
}

void rb_pass_bdpt_split_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                               const struct rb_bdpt_frame *b)
{
    const struct rb_gpu_image *gb = b->gbuffer;
    struct rb_pass_bindings bind = {.pass = &p->split};
    rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_GB_POSITION, gb[RB_GB_POSITION].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_GB_NORMAL, gb[RB_GB_NORMAL].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_GB_SPECULAR, gb[RB_GB_SPECULAR].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_GB_EMISSION, gb[RB_GB_EMISSION].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_GB_MOTION, gb[RB_GB_MOTION].view, VK_NULL_HANDLE);
    for (uint32_t i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        rb_pass_bind_image(&bind, RB_BIND_BDPT_SPLIT_OUT + i, b->split[i].view, VK_NULL_HANDLE);
    rb_pass_record_bindings(cmd, &bind);
    /* The accumulators start at zero: a clear, after whatever read them, before connect. */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkClearColorValue zero = {.float32 = {0.0f, 0.0f, 0.0f, 0.0f}};
    VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        vkCmdClearColorImage(cmd, b->accum[i].image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                              VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    struct rb_gpu_bdpt_image_push pc = image_push(b);
    push(cmd, &p->split, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(b->split[0].width_px, 8), groups(b->split[0].height_px, 8), 1);
}

void rb_pass_bdpt_mark_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                              const struct rb_bdpt_frame *b, uint32_t k)
{
    struct rb_pass_bindings bind = {.pass = &p->mark};
    rb_pass_bind_image(&bind, RB_BIND_BDPT_MARK_POSITION, b->split[0].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_MARK_BUNDLE_VIEWS, &b->bundle_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_MARK_HEADS, b->bundle.heads.view, VK_NULL_HANDLE);
    rb_pass_record_bindings(cmd, &bind);
    uint32_t n = b->interleave, s = k % (n * n);
    struct rb_gpu_bdpt_mark_push pc = {
        .index = {k, b->bundle_size_px, 0, 0},
        .region = {(s % n) * b->sub_width_px, (s / n) * b->sub_height_px, b->sub_width_px,
                   b->sub_height_px},
    };
    push(cmd, &p->mark, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(b->sub_width_px, 8), groups(b->sub_height_px, 8), 1);
}

/* Connect's bindings, which the emitters' dispatch shares (common/bdpt_connect.glsl). */
static void bind_connect(struct rb_pass *pass, VkCommandBuffer cmd, const struct rb_frame *frame,
                         const struct rb_bdpt_frame *b)
{
    struct rb_pass_bindings bind = {.pass = pass};
    struct rb_gpu *gpu = pass->gpu;
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_GLOBALS, &frame->globals);
    for (uint32_t i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_SPLIT + i, b->split[i].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_VPLS, &b->vpls);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_VPL_VIEWS, &b->vpl_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_VPL_MAPS, b->vpl_maps.view,
                       gpu->nearest_sampler);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_BUNDLE_VIEWS, &b->bundle_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_HEADS, b->bundle.heads.view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_NODES, &b->bundle.nodes);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_LIGHTS, &frame->lights);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_BDPT_LIGHTS, &b->lights);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_SHADOW_VIEWS, &frame->shadow_views);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_SHADOW_MAPS, frame->shadow_maps.view,
                       gpu->nearest_sampler);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_ENV_MAP, frame->env_map.view, gpu->env_sampler);
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_LIGHT + i, b->accum[i].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_EMIT_INFO, &b->emit_info);
    for (uint32_t i = 0; i < RB_BDPT_EMITTED_COUNT; i++)
        rb_pass_bind_image(&bind, RB_BIND_BDPT_CONNECT_EMITTED + i, b->emitted[i].view,
                           VK_NULL_HANDLE);
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_CONNECT_LTC, &b->ltc);
    rb_pass_record_bindings(cmd, &bind);
}

/* The frame's counts of VPLs, bundles and the interleave, as connect's push has them. */
static void frame_counts(const struct rb_bdpt_frame *b, float out[4])
{
    out[0] = b->min_roughness;
    out[1] = (float)b->vpl_count;
    out[2] = (float)b->bundle_count;
    out[3] = (float)b->interleave;
}

void rb_pass_bdpt_connect_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                 const struct rb_frame *frame, const struct rb_bdpt_frame *b,
                                 uint32_t k)
{
    bind_connect(&p->connect, cmd, frame, b);
    uint32_t n = b->interleave, count = n * n, s = k % count;
    uint32_t pairs = b->vpl_count < b->bundle_count ? b->vpl_count : b->bundle_count;
    struct rb_gpu_bdpt_connect_push pc = {
        .index = {k, k < b->vpl_count, k < b->bundle_count, (uint32_t)b->strategies},
        .region = {(s % n) * b->sub_width_px, (s / n) * b->sub_height_px, b->sub_width_px,
                   b->sub_height_px},
        .counts = {(float)rb_bdpt_share(b->vpl_count, s, count),
                   (float)rb_bdpt_share(b->bundle_count, s, count),
                   (float)rb_bdpt_share(pairs, s, count), b->clamp_g},
        .params = {b->vpl_bias, (float)b->vpl_size_px, (float)b->bundle_size_px,
                   (float)b->bundle.capacity_nodes},
        .bounce = {b->has_bounce && k < b->vpl_count ? b->vpl_count + k : RB_NONE,
                   b->has_chain && k < b->vpl_count ? 2 * b->vpl_count + k : RB_NONE,
                   b->bounce_vpl_size_px, 0},
        .offset = {0.0f, 0.0f, b->vpl_spread, 0.0f},
    };
    frame_counts(b, pc.frame);
    push(cmd, &p->connect, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(b->sub_width_px, 8), groups(b->sub_height_px, 8), 1);
}

void rb_pass_bdpt_emitters_direct_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                         const struct rb_frame *frame,
                                         const struct rb_bdpt_frame *b)
{
    bind_connect(&p->emitter_direct, cmd, frame, b);
    uint32_t n = b->interleave;
    struct rb_gpu_bdpt_connect_push pc = {
        .index = {0, 0, 0, (uint32_t)b->strategies},
        .region = {0, 0, b->sub_width_px, b->sub_height_px},
        .counts = {0.0f, 0.0f, 0.0f, b->clamp_g},
        .params = {b->vpl_bias, (float)b->vpl_size_px, (float)b->bundle_size_px,
                   (float)b->bundle.capacity_nodes},
        .bounce = {RB_NONE, RB_NONE, b->bounce_vpl_size_px, 0},
        .offset = {b->offset_px[0], b->offset_px[1], 0.0f, 0.0f},
    };
    frame_counts(b, pc.frame);
    push(cmd, &p->emitter_direct, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(b->sub_width_px * n, 8), groups(b->sub_height_px * n, 8), 1);
}

void rb_pass_bdpt_gather_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b)
{
    struct rb_pass_bindings bind = {.pass = &p->gather};
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_pass_bind_image(&bind, RB_BIND_BDPT_GATHER_IN + i, b->accum[i].view, VK_NULL_HANDLE);
        rb_pass_bind_image(&bind, RB_BIND_BDPT_GATHER_OUT + i, b->gathered[i].view, VK_NULL_HANDLE);
    }
    rb_pass_record_bindings(cmd, &bind);
    struct rb_gpu_bdpt_image_push pc = image_push(b);
    push(cmd, &p->gather, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

void rb_pass_bdpt_filter_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                const struct rb_frame *frame, const struct rb_bdpt_frame *b)
{
    const struct rb_gpu_image *gb = b->gbuffer;
    struct rb_pass_bindings bind = {.pass = &p->filter};
    rb_pass_bind_image(&bind, RB_BIND_BDPT_FILTER_GB_POSITION, gb[RB_GB_POSITION].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_FILTER_GB_NORMAL, gb[RB_GB_NORMAL].view, VK_NULL_HANDLE);
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_pass_bind_image(&bind, RB_BIND_BDPT_FILTER_IN + i, b->gathered[i].view, VK_NULL_HANDLE);
        rb_pass_bind_image(&bind, RB_BIND_BDPT_FILTER_OUT + i, b->filtered[i].layer_views[b->slot],
                           VK_NULL_HANDLE);
    }
    for (uint32_t i = 0; i < RB_BDPT_EMITTED_COUNT; i++)
        rb_pass_bind_image(&bind, RB_BIND_BDPT_FILTER_EMITTED + i, b->emitted[i].view,
                           VK_NULL_HANDLE);
    rb_pass_record_bindings(cmd, &bind);
    struct rb_gpu_bdpt_image_push pc = image_push(b);
    push(cmd, &p->filter, &pc, sizeof(pc));
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

void rb_pass_bdpt_reconstruct_record(struct rb_pass_bdpt *p, VkCommandBuffer cmd,
                                     const struct rb_frame *frame, const struct rb_bdpt_frame *b)
{
    struct rb_pass_bindings bind = {.pass = &p->reconstruct};
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_RECONSTRUCT_HISTORY, &b->history);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_RECONSTRUCT_GB_POSITION,
                       frame->gbuffer[RB_GB_POSITION].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_RECONSTRUCT_GB_NORMAL, frame->gbuffer[RB_GB_NORMAL].view,
                       VK_NULL_HANDLE);
    rb_pass_bind_image(&bind, RB_BIND_BDPT_RECONSTRUCT_REPROJECT, b->reproject.view,
                       VK_NULL_HANDLE);
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_pass_bind_image(&bind, RB_BIND_BDPT_RECONSTRUCT_CACHE + i, b->filtered[i].view,
                           VK_NULL_HANDLE);
        rb_pass_bind_image(&bind, RB_BIND_BDPT_RECONSTRUCT_OUT + i, b->light[i].view,
                           VK_NULL_HANDLE);
    }
    rb_pass_bind_buffer(&bind, RB_BIND_BDPT_RECONSTRUCT_HITS, &b->hits);
    rb_pass_record_bindings(cmd, &bind);
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}
