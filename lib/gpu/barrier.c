/* Barriers between passes, derived from the resources each pass declares it reads and writes
 * (struct rb_gpu_access), instead of a full barrier after every pass. For each resource it
 * remembers the last write, the reads since, what that write was made visible to and the image
 * layout, and emits one buffer or image barrier per resource that needs one: read after write
 * (the write made available and visible to the reader), write after read (the reads finished),
 * write after write, and layout changes (which wait for every earlier access). It knows nothing
 * of passes or frames; the frame driver (lib/integrators/driver.c) feeds it. */
#include "gpu/gpu.h"

#include <stdlib.h>

#define STAGE(x) VK_PIPELINE_STAGE_2_##x##_BIT
#define ACCESS(x) VK_ACCESS_2_##x##_BIT

/* The accesses that write memory; every other access bit reads. */
#define WRITE_ACCESS                                                                               \
    (ACCESS(SHADER_WRITE) | ACCESS(SHADER_STORAGE_WRITE) | ACCESS(COLOR_ATTACHMENT_WRITE) |        \
     ACCESS(DEPTH_STENCIL_ATTACHMENT_WRITE) | ACCESS(TRANSFER_WRITE) | ACCESS(HOST_WRITE) |        \
     ACCESS(MEMORY_WRITE))

/* Each use's stages and access: the one table enum rb_gpu_use names. */
static const struct {
    VkPipelineStageFlags2 stages;
    VkAccessFlags2 access;
} use_table[RB_GPU_USE_COUNT] = {
    [RB_GPU_COMPUTE_UNIFORM] = {STAGE(COMPUTE_SHADER), ACCESS(UNIFORM_READ)},
    [RB_GPU_COMPUTE_READ] = {STAGE(COMPUTE_SHADER), ACCESS(SHADER_STORAGE_READ)},
    [RB_GPU_COMPUTE_WRITE] = {STAGE(COMPUTE_SHADER), ACCESS(SHADER_STORAGE_WRITE)},
    [RB_GPU_COMPUTE_READ_WRITE] = {STAGE(COMPUTE_SHADER),
                                   ACCESS(SHADER_STORAGE_READ) | ACCESS(SHADER_STORAGE_WRITE)},
    [RB_GPU_COMPUTE_SAMPLED] = {STAGE(COMPUTE_SHADER), ACCESS(SHADER_SAMPLED_READ)},
    [RB_GPU_GRAPHICS_UNIFORM] = {STAGE(VERTEX_SHADER) | STAGE(FRAGMENT_SHADER),
                                 ACCESS(UNIFORM_READ)},
    [RB_GPU_VERTEX_READ] = {STAGE(VERTEX_SHADER), ACCESS(SHADER_STORAGE_READ)},
    [RB_GPU_GRAPHICS_READ] = {STAGE(VERTEX_SHADER) | STAGE(FRAGMENT_SHADER),
                              ACCESS(SHADER_STORAGE_READ)},
    [RB_GPU_FRAGMENT_READ] = {STAGE(FRAGMENT_SHADER), ACCESS(SHADER_STORAGE_READ)},
    [RB_GPU_FRAGMENT_SAMPLED] = {STAGE(FRAGMENT_SHADER), ACCESS(SHADER_SAMPLED_READ)},
    [RB_GPU_FRAGMENT_READ_WRITE] = {STAGE(FRAGMENT_SHADER),
                                    ACCESS(SHADER_STORAGE_READ) | ACCESS(SHADER_STORAGE_WRITE)},
    [RB_GPU_INDEX_READ] = {STAGE(INDEX_INPUT), ACCESS(INDEX_READ)},
    [RB_GPU_INDIRECT_READ] = {STAGE(DRAW_INDIRECT), ACCESS(INDIRECT_COMMAND_READ)},
    /* a cleared attachment: the clear and the draws write, nothing blends */
    [RB_GPU_COLOR_ATTACHMENT] = {STAGE(COLOR_ATTACHMENT_OUTPUT), ACCESS(COLOR_ATTACHMENT_WRITE)},
    /* a cleared depth attachment, tested and written in either fragment-test stage */
    [RB_GPU_DEPTH_ATTACHMENT] = {STAGE(EARLY_FRAGMENT_TESTS) | STAGE(LATE_FRAGMENT_TESTS),
                                 ACCESS(DEPTH_STENCIL_ATTACHMENT_READ) |
                                     ACCESS(DEPTH_STENCIL_ATTACHMENT_WRITE)},
    [RB_GPU_TRANSFER_READ] = {STAGE(ALL_TRANSFER), ACCESS(TRANSFER_READ)},
    [RB_GPU_TRANSFER_WRITE] = {STAGE(ALL_TRANSFER), ACCESS(TRANSFER_WRITE)},
    [RB_GPU_HOST_READ] = {STAGE(HOST), ACCESS(HOST_READ)},
};

/* One resource: what the queue has done to it since the barriers that cover it. A buffer's
 * layout is VK_IMAGE_LAYOUT_UNDEFINED, always. */
struct rb_gpu_tracked {
    VkBuffer buffer; /* the resource: one of the two */
    VkImage image;
    bool is_image;
    VkImageAspectFlags aspect;
    VkImageLayout layout;
    VkPipelineStageFlags2 write_stages;   /* the last write (a layout change counts), or 0 */
    VkAccessFlags2 write_access;          /* its access; 0 after a layout change alone */
    VkPipelineStageFlags2 visible_stages; /* the last barrier made the write visible to these */
    VkAccessFlags2 visible_access;        /* stages, for these accesses */
    VkPipelineStageFlags2 read_stages;    /* stages that read it since the last write */
    /* the pass being derived: its uses of the resource, joined */
    bool is_touched;
    VkPipelineStageFlags2 pass_stages;
    VkAccessFlags2 pass_access;
    VkImageLayout pass_layout;
};

static bool covers(uint64_t have, uint64_t want)
{
    return (want & ~have) == 0;
}

/* Room for use_count more resources and a pass of use_count uses, before anything changes. */
static enum rb_status reserve(struct rb_gpu_barriers *b, uint32_t use_count, struct rb_err *err)
{
    if (use_count > UINT32_MAX / 2 - b->tracked_count)
        return rb_errf(err, RB_E_NOMEM, "%u uses in one pass are too many to track", use_count);
    uint32_t need = b->tracked_count + use_count;
    if (need > b->tracked_cap) {
        uint32_t cap = b->tracked_cap ? 2 * b->tracked_cap : 32;
        cap = cap < need ? need : cap;
        struct rb_gpu_tracked *t = realloc(b->tracked, cap * sizeof(*t));
        if (!t)
            return rb_errf(err, RB_E_NOMEM, "out of memory for %u tracked resources", cap);
        b->tracked = t;
        b->tracked_cap = cap;
    }
    if (use_count > b->scratch_cap) {
        uint32_t cap = 2 * b->scratch_cap > use_count ? 2 * b->scratch_cap : use_count;
        cap = cap < 32 ? 32 : cap;
        uint32_t *touched = realloc(b->touched, cap * sizeof(*touched));
        if (touched)
            b->touched = touched;
        VkBufferMemoryBarrier2 *bb = realloc(b->buffer_barriers, cap * sizeof(*bb));
        if (bb)
            b->buffer_barriers = bb;
        VkImageMemoryBarrier2 *ib = realloc(b->image_barriers, cap * sizeof(*ib));
        if (ib)
            b->image_barriers = ib;
        if (!touched || !bb || !ib)
            return rb_errf(err, RB_E_NOMEM, "out of memory for the barriers of %u uses", cap);
        b->scratch_cap = cap;
    }
    return RB_OK;
}

static void check_use(const struct rb_gpu_access *u, uint32_t i)
{
    if (!u->buffer == !u->image)
        RB_BUG("use %u names %s", i, u->buffer ? "a buffer and an image" : "no resource");
    if (u->use <= RB_GPU_USE_INVALID || u->use >= RB_GPU_USE_COUNT)
        RB_BUG("use %u: unknown use %d", i, (int)u->use);
    if (u->image ? u->image->image == VK_NULL_HANDLE : u->buffer->buffer == VK_NULL_HANDLE)
        RB_BUG("use %u: the %s was never created", i, u->image ? "image" : "buffer");
}

/* The tracked resource of a use, added (in GENERAL, nothing pending) when first seen. */
static uint32_t find_or_add(struct rb_gpu_barriers *b, const struct rb_gpu_access *u)
{
    bool is_image = u->image != NULL;
    VkBuffer buffer = is_image ? VK_NULL_HANDLE : u->buffer->buffer;
    VkImage image = is_image ? u->image->image : VK_NULL_HANDLE;
    for (uint32_t i = 0; i < b->tracked_count; i++)
        if (b->tracked[i].is_image == is_image && b->tracked[i].buffer == buffer &&
            b->tracked[i].image == image)
            return i;
    b->tracked[b->tracked_count] = (struct rb_gpu_tracked){
        .buffer = buffer,
        .image = image,
        .is_image = is_image,
        .aspect = is_image ? u->image->aspect : 0,
        .layout = is_image ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_UNDEFINED,
    };
    return b->tracked_count++;
}

/* The barrier one resource needs before the pass's uses of it, if any, and its new state. */
static bool derive_one(struct rb_gpu_tracked *t, VkPipelineStageFlags2 *src_stages,
                       VkAccessFlags2 *src_access, VkPipelineStageFlags2 *dst_stages,
                       VkAccessFlags2 *dst_access)
{
    VkPipelineStageFlags2 s = t->pass_stages;
    VkAccessFlags2 a = t->pass_access, w = a & WRITE_ACCESS, r = a & ~WRITE_ACCESS;
    bool is_transition = t->is_image && t->pass_layout != t->layout;
    bool is_needed = false;
    *src_stages = *src_access = *dst_stages = *dst_access = 0;
    if (w || is_transition) {
        /* Write after read and after write; a layout change also waits for every access. */
        is_needed = is_transition || t->write_stages || t->read_stages;
        *src_stages = t->write_stages | t->read_stages;
        *src_access = t->write_access;
        *dst_stages = s;
        *dst_access = a;
    } else if (t->write_stages && !(covers(t->visible_stages, s) && covers(t->visible_access, r))) {
        /* Read after write, unless an earlier barrier made the write visible to this read. */
        is_needed = true;
        *src_stages = t->write_stages;
        *src_access = t->write_access;
        *dst_stages = s;
        *dst_access = r;
    }

    if (s & VK_PIPELINE_STAGE_2_HOST_BIT) {
        /* The host reads after the frame's fence, and the next submission is ordered after the
         * host: nothing is left for a later pass to wait for. */
        t->layout = t->pass_layout;
        t->write_stages = t->write_access = t->read_stages = 0;
        t->visible_stages = t->visible_access = 0;
    } else if (w || is_transition) {
        /* A layout change alone writes too (made available and visible by its barrier). */
        t->layout = t->pass_layout;
        t->write_stages = s;
        t->write_access = w;
        t->visible_stages = w ? 0 : s;
        t->visible_access = w ? 0 : r;
        t->read_stages = w ? 0 : s;
    } else {
        t->read_stages |= s;
        if (is_needed) {
            /* Visibility is to the last barrier's stages and accesses (all pairs of them);
             * an earlier barrier's are forgotten, which costs at most a redundant barrier. */
            t->visible_stages = s;
            t->visible_access = r;
        }
    }
    return is_needed;
}

enum rb_status rb_gpu_barriers_derive(struct rb_gpu_barriers *b, const struct rb_gpu_access *uses,
                                      uint32_t use_count, VkDependencyInfo *out, struct rb_err *err)
{
    *out = (VkDependencyInfo){.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    for (uint32_t i = 0; i < use_count; i++)
        check_use(&uses[i], i);
    enum rb_status st = reserve(b, use_count, err);
    if (st)
        return st;

    /* Join the pass's uses per resource, in the order each resource first appears. */
    uint32_t touched_count = 0;
    for (uint32_t i = 0; i < use_count; i++) {
        const struct rb_gpu_access *u = &uses[i];
        uint32_t k = find_or_add(b, u);
        struct rb_gpu_tracked *t = &b->tracked[k];
        VkImageLayout layout = !u->image   ? VK_IMAGE_LAYOUT_UNDEFINED
                               : u->layout ? u->layout
                                           : VK_IMAGE_LAYOUT_GENERAL;
        if (!t->is_touched) {
            t->is_touched = true;
            t->pass_stages = t->pass_access = 0;
            t->pass_layout = layout;
            b->touched[touched_count++] = k;
        } else if (t->pass_layout != layout) {
            RB_BUG("use %u: an image in two layouts (%d, %d) in one pass", i, (int)t->pass_layout,
                   (int)layout);
        }
        t->pass_stages |= use_table[u->use].stages;
        t->pass_access |= use_table[u->use].access;
    }

    uint32_t buffer_count = 0, image_count = 0;
    for (uint32_t i = 0; i < touched_count; i++) {
        struct rb_gpu_tracked *t = &b->tracked[b->touched[i]];
        VkImageLayout old_layout = t->layout;
        VkPipelineStageFlags2 src_stages, dst_stages;
        VkAccessFlags2 src_access, dst_access;
        t->is_touched = false;
        if (!derive_one(t, &src_stages, &src_access, &dst_stages, &dst_access))
            continue;
        if (t->is_image)
            b->image_barriers[image_count++] = (VkImageMemoryBarrier2){
                .sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
                .srcStageMask = src_stages,
                .srcAccessMask = src_access,
                .dstStageMask = dst_stages,
                .dstAccessMask = dst_access,
                .oldLayout = old_layout,
                .newLayout = t->layout,
                .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                .image = t->image,
                .subresourceRange = {t->aspect, 0, VK_REMAINING_MIP_LEVELS, 0,
                                     VK_REMAINING_ARRAY_LAYERS},
            };
        else
            b->buffer_barriers[buffer_count++] = (VkBufferMemoryBarrier2){
                .sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2,
                .srcStageMask = src_stages,
                .srcAccessMask = src_access,
                .dstStageMask = dst_stages,
                .dstAccessMask = dst_access,
                .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                .buffer = t->buffer,
                .offset = 0,
                .size = VK_WHOLE_SIZE,
            };
    }
    out->bufferMemoryBarrierCount = buffer_count;
    out->pBufferMemoryBarriers = buffer_count ? b->buffer_barriers : NULL;
    out->imageMemoryBarrierCount = image_count;
    out->pImageMemoryBarriers = image_count ? b->image_barriers : NULL;
    return RB_OK;
}

void rb_gpu_barriers_record(struct rb_gpu_barriers *b, VkCommandBuffer cmd,
                            const struct rb_gpu_access *uses, uint32_t use_count)
{
    VkDependencyInfo dep;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_gpu_barriers_derive(b, uses, use_count, &dep, &err);
    if (st) {
        /* Correct, if slow; the frame still fails after its submit (rb_gpu_barriers_check). */
        if (!b->status)
            b->status = st;
        rb_gpu_barrier(cmd);
        return;
    }
    if (dep.bufferMemoryBarrierCount || dep.imageMemoryBarrierCount)
        vkCmdPipelineBarrier2(cmd, &dep);
}

enum rb_status rb_gpu_barriers_check(struct rb_gpu_barriers *b, struct rb_err *err)
{
    enum rb_status st = b->status;
    b->status = RB_OK;
    if (st)
        return rb_errf(err, st, "out of memory for the barriers between passes");
    return RB_OK;
}

void rb_gpu_barriers_release(struct rb_gpu_barriers *b)
{
    if (!b)
        return;
    free(b->image_barriers);
    free(b->buffer_barriers);
    free(b->touched);
    free(b->tracked);
    *b = (struct rb_gpu_barriers)RB_GPU_BARRIERS_INIT;
}
