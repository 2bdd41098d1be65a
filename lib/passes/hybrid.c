/* hybrid: the compute passes of the hybrid integrator's frame (seed 003; DESIGN.md "hybrid"):
 * the hierarchical depth buffer, the emitter table, each lobe's rays and their screen-space
 * trace, the queue of rays for the BVH and its trace, the light samples, the accumulators, the
 * noise tiles and the filter. Every pass shares one binding table (hybrid.glsl declares it), so one
 * function binds them all. */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "hybrid_accumulate.comp.h"
#include "hybrid_bvh.comp.h"
#include "hybrid_bvh_chain.comp.h"
#include "hybrid_emitters.comp.h"
#include "hybrid_filter.comp.h"
#include "hybrid_hiz.comp.h"
#include "hybrid_light.comp.h"
#include "hybrid_queue.comp.h"
#include "hybrid_tiles.comp.h"
#include "hybrid_trace.comp.h"
#include "hybrid_trace_chain.comp.h"

struct rb_pass_hybrid {
    struct rb_pass hiz, emitters, trace, queue, bvh, light, accumulate, tiles, filter;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_HYBRID_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_ALBEDO, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_SPECULAR, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_EMISSION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_GB_MOTION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_SHADOW_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_SHADOW_MAPS, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_HYBRID_ENV_MAP, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_HYBRID_DIRECT, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_HIZ, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_SLOTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_COUNTERS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_QUEUE, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_BLOCKS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_BVH_NODES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_BVH_TRIS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_VERTICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_INDICES, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_MATERIALS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_SRGB_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_HYBRID_LINEAR_TEXTURES, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_HYBRID_ACC_PREV, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_ACC, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_TILES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_HYBRID_STATS, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_LIGHT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_LIGHT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_LIGHT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_HYBRID_LIGHT + 3, STORAGE_IMAGE),
};
_Static_assert(COUNT(bindings) == RB_BIND_HYBRID_COUNT, "hybrid bindings");

#define COMPUTE_SPV(field, code, code_bytes)                                                       \
    rb_pass_compute_init(                                                                          \
        gpu,                                                                                       \
        &(struct rb_pass_compute_desc){.name = "hybrid_" #field,                                   \
                                       RB_PASS_BINDINGS(bindings),                                 \
                                       .push_bytes = sizeof(struct rb_gpu_hybrid_push),            \
                                       .spv = (code),                                              \
                                       .spv_bytes = (code_bytes)},                                 \
        &p->field, err)
#define COMPUTE(field, spv_name) COMPUTE_SPV(field, spv_name, sizeof(spv_name))
/* The plain or the chain variant of a rays' pass (rb_pass_hybrid_create). */
#define COMPUTE_RAYS(field, plain, with_chain)                                                     \
    (chain ? COMPUTE_SPV(field, with_chain, sizeof(with_chain))                                    \
           : COMPUTE_SPV(field, plain, sizeof(plain)))

enum rb_status rb_pass_hybrid_create(struct rb_gpu *gpu, bool chain, struct rb_pass_hybrid **out,
                                     struct rb_err *err)
{
    struct rb_pass_hybrid *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st;
    if ((st = COMPUTE(hiz, rb_spv_hybrid_hiz_comp)) ||
        (st = COMPUTE_RAYS(trace, rb_spv_hybrid_trace_comp, rb_spv_hybrid_trace_chain_comp)) ||
        (st = COMPUTE(queue, rb_spv_hybrid_queue_comp)) ||
        (st = COMPUTE_RAYS(bvh, rb_spv_hybrid_bvh_comp, rb_spv_hybrid_bvh_chain_comp)) ||
        (st = COMPUTE(emitters, rb_spv_hybrid_emitters_comp)) ||
        (st = COMPUTE(light, rb_spv_hybrid_light_comp)) ||
        (st = COMPUTE(accumulate, rb_spv_hybrid_accumulate_comp)) ||
        (st = COMPUTE(tiles, rb_spv_hybrid_tiles_comp)) ||
        (st = COMPUTE(filter, rb_spv_hybrid_filter_comp))) {
        rb_pass_hybrid_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_hybrid_destroy(struct rb_pass_hybrid *p)
{
    if (!p)
        return;
    rb_pass_release(&p->filter);
    rb_pass_release(&p->tiles);
    rb_pass_release(&p->accumulate);
    rb_pass_release(&p->light);
    rb_pass_release(&p->bvh);
    rb_pass_release(&p->emitters);
    rb_pass_release(&p->queue);
    rb_pass_release(&p->trace);
    rb_pass_release(&p->hiz);
    free(p);
}

/* Binds the whole table for pass and pushes h->push. */
static void bind(struct rb_pass *pass, VkCommandBuffer cmd, const struct rb_frame *frame,
                 const struct rb_frame_slot *slot, const struct rb_hybrid_frame *h)
{
    struct rb_gpu *gpu = pass->gpu;
    const struct rb_gpu_image *gb = frame->gbuffer;
    struct rb_pass_bindings b = {.pass = pass};
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_GLOBALS, &frame->globals);
    static const uint32_t gbuffer_bindings[RB_GBUFFER_COLOR_COUNT] = {
        RB_BIND_HYBRID_GB_POSITION, RB_BIND_HYBRID_GB_NORMAL,   RB_BIND_HYBRID_GB_ALBEDO,
        RB_BIND_HYBRID_GB_SPECULAR, RB_BIND_HYBRID_GB_EMISSION, RB_BIND_HYBRID_GB_MOTION};
    for (uint32_t i = 0; i < RB_GBUFFER_COLOR_COUNT; i++)
        rb_pass_bind_image(&b, gbuffer_bindings[i], gb[i].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_LIGHTS, &frame->lights);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_SHADOW_VIEWS, &frame->shadow_views);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_SHADOW_MAPS, frame->shadow_maps.view,
                       gpu->nearest_sampler);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_ENV_MAP, frame->env_map.view, gpu->env_sampler);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_DIRECT, frame->direct.view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_HIZ, &h->hiz);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_SLOTS, &h->slots);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_COUNTERS, &h->counters);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_QUEUE, &h->queue);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_BLOCKS, &h->blocks);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_BVH_NODES, &h->bvh_nodes);
    rb_pass_bind_buffer_range(&b, RB_BIND_HYBRID_BVH_TRIS, &h->bvh_tris, 0, h->bvh_tri_bytes);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_VERTICES, &slot->geometry);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_INDICES, &h->table);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_MATERIALS, &frame->materials);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_SRGB_TEXTURES, frame->srgb_textures.view,
                       gpu->linear_sampler);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_LINEAR_TEXTURES, frame->linear_textures.view,
                       gpu->linear_sampler);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_ACC_PREV, h->acc[h->cur ^ 1u].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_ACC, h->acc[h->cur].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&b, RB_BIND_HYBRID_TILES, &h->tiles);
    rb_pass_bind_image(&b, RB_BIND_HYBRID_STATS, h->stats.view, VK_NULL_HANDLE);
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        rb_pass_bind_image(&b, RB_BIND_HYBRID_LIGHT + i, h->light[i].view, VK_NULL_HANDLE);
    rb_pass_record_bindings(cmd, &b);
    vkCmdPushConstants(cmd, pass->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(h->push),
                       &h->push);
}

/* Compute writes before compute reads and writes, inside one pass. */
static void compute_to_compute(VkCommandBuffer cmd)
{
    rb_gpu_memory_barrier(
        cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
        VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
        VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
            VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT);
}

static uint32_t groups(uint32_t n, uint32_t size)
{
    return (n + size - 1) / size;
}

static void record_hiz(struct rb_pass_hybrid *p, VkCommandBuffer cmd, const struct rb_frame *frame,
                       const struct rb_frame_slot *slot, struct rb_hybrid_frame *h)
{
    uint32_t w = frame->width_px, ht = frame->height_px, offset = 0;
    uint32_t prev_w = 0, prev_h = 0, prev_offset = 0;
    for (uint32_t level = 0; level < h->hiz_levels; level++) {
        if (level)
            compute_to_compute(cmd);
        h->push.level[0] = level;
        h->push.level[1] = w;
        h->push.level[2] = ht;
        h->push.level[3] = offset;
        h->push.more[0] = prev_offset;
        h->push.more[1] = prev_w;
        h->push.more[2] = prev_h;
        bind(&p->hiz, cmd, frame, slot, h);
        vkCmdDispatch(cmd, groups(w, 8), groups(ht, 8), 1);
        prev_w = w;
        prev_h = ht;
        prev_offset = offset;
        offset += w * ht;
        w = (w + 1) / 2;
        ht = (ht + 1) / 2;
    }
}

static void record_trace(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                         const struct rb_frame *frame, const struct rb_frame_slot *slot,
                         struct rb_hybrid_frame *h, uint32_t lobe)
{
    if (lobe == RB_HYBRID_DIFFUSE) {
        /* The counters start at zero, after whatever read them last, before the atomics. */
        rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                              VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                              VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
        vkCmdFillBuffer(cmd, h->counters.buffer, 0, VK_WHOLE_SIZE, 0);
        rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                              VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                              VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                                  VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    }
    if (lobe == RB_HYBRID_DIFFUSE && h->push.bake[3]) {
        /* the emitter table, which the rays' MIS weights and the light samples read */
        bind(&p->emitters, cmd, frame, slot, h);
        vkCmdDispatch(cmd, 1, 1, 1);
        compute_to_compute(cmd);
    }
    h->push.frame[2] = lobe;
    bind(&p->trace, cmd, frame, slot, h);
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

static void record_queue(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                         const struct rb_frame *frame, const struct rb_frame_slot *slot,
                         struct rb_hybrid_frame *h)
{
    uint32_t blocks =
        (uint32_t)((h->slot_count + RB_HYBRID_QUEUE_GROUP - 1) / RB_HYBRID_QUEUE_GROUP);
    uint32_t gx = blocks < 65535 ? blocks : 65535, gy = groups(blocks, 65535);
    for (uint32_t phase = 0; phase < 3; phase++) {
        if (phase)
            compute_to_compute(cmd);
        h->push.level[0] = phase;
        bind(&p->queue, cmd, frame, slot, h);
        if (phase == 1)
            vkCmdDispatch(cmd, 1, 1, 1);
        else
            vkCmdDispatch(cmd, gx, gy, 1);
    }
    /* The BVH pass reads the dispatch the scan wrote. */
    compute_to_compute(cmd);
}

static void record_bvh(struct rb_pass_hybrid *p, VkCommandBuffer cmd, const struct rb_frame *frame,
                       const struct rb_frame_slot *slot, struct rb_hybrid_frame *h)
{
    bind(&p->bvh, cmd, frame, slot, h);
    vkCmdDispatchIndirect(cmd, h->counters.buffer,
                          offsetof(struct rb_gpu_hybrid_counters, dispatch));
}

static void record_light(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                         const struct rb_frame *frame, const struct rb_frame_slot *slot,
                         struct rb_hybrid_frame *h)
{
    if (!h->push.bake[3] && !h->has_env_light)
        return; /* nothing emits and the environment is black: no light sample */
    h->push.more[0] = h->screen_shadows;
    bind(&p->light, cmd, frame, slot, h);
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

static void record_accumulate(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                              const struct rb_frame *frame, const struct rb_frame_slot *slot,
                              struct rb_hybrid_frame *h)
{
    bind(&p->accumulate, cmd, frame, slot, h);
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

static void record_tiles(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                         const struct rb_frame *frame, const struct rb_frame_slot *slot,
                         struct rb_hybrid_frame *h)
{
    uint32_t tx = groups(frame->width_px, RB_HYBRID_TILE),
             ty = groups(frame->height_px, RB_HYBRID_TILE);
    for (uint32_t phase = 0; phase < 2; phase++) {
        if (phase)
            compute_to_compute(cmd);
        h->push.level[0] = phase;
        bind(&p->tiles, cmd, frame, slot, h);
        vkCmdDispatch(cmd, tx, ty, 1);
    }
}

static void record_filter(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                          const struct rb_frame *frame, const struct rb_frame_slot *slot,
                          struct rb_hybrid_frame *h, uint32_t lobe)
{
    h->push.frame[2] = lobe;
    bind(&p->filter, cmd, frame, slot, h);
    vkCmdDispatch(cmd, groups(frame->width_px, 8), groups(frame->height_px, 8), 1);
}

const char *const rb_pass_hybrid_names[RB_HYBRID_PASS_COUNT] = {
    [RB_HYBRID_PASS_HIZ] = "hiz",
    [RB_HYBRID_PASS_DIFFUSE_RAYS] = "diffuse_rays",
    [RB_HYBRID_PASS_SPECULAR_RAYS] = "specular_rays",
    [RB_HYBRID_PASS_RAY_QUEUE] = "ray_queue",
    [RB_HYBRID_PASS_BVH_RAYS] = "bvh_rays",
    [RB_HYBRID_PASS_LIGHT_RAYS] = "light_rays",
    [RB_HYBRID_PASS_ACCUMULATE] = "accumulate",
    [RB_HYBRID_PASS_TILES] = "tiles",
    [RB_HYBRID_PASS_DIFFUSE_FILTER] = "diffuse_filter",
    [RB_HYBRID_PASS_SPECULAR_FILTER] = "specular_filter",
};

void rb_pass_hybrid_record(struct rb_pass_hybrid *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *slot,
                           struct rb_hybrid_frame *h, enum rb_hybrid_pass which)
{
    switch (which) {
    case RB_HYBRID_PASS_HIZ: record_hiz(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_DIFFUSE_RAYS:
        record_trace(p, cmd, frame, slot, h, RB_HYBRID_DIFFUSE);
        return;
    case RB_HYBRID_PASS_SPECULAR_RAYS:
        record_trace(p, cmd, frame, slot, h, RB_HYBRID_SPECULAR);
        return;
    case RB_HYBRID_PASS_RAY_QUEUE: record_queue(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_BVH_RAYS: record_bvh(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_LIGHT_RAYS: record_light(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_ACCUMULATE: record_accumulate(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_TILES: record_tiles(p, cmd, frame, slot, h); return;
    case RB_HYBRID_PASS_DIFFUSE_FILTER:
        record_filter(p, cmd, frame, slot, h, RB_HYBRID_DIFFUSE);
        return;
    case RB_HYBRID_PASS_SPECULAR_FILTER:
        record_filter(p, cmd, frame, slot, h, RB_HYBRID_SPECULAR);
        return;
    case RB_HYBRID_PASS_COUNT: break;
    }
    RB_BUG("hybrid pass %d does not exist", (int)which);
}
