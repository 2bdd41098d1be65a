// hybrid_queue: compacts the rays waiting for the BVH into a queue in slot order, so the BVH
// pass traces them densely and the order never depends on which thread got there first. Phase 0
// counts the waiting rays of each block of RB_HYBRID_QUEUE_GROUP slots; phase 1 (one workgroup)
// turns the counts into offsets and writes the queue's length and the BVH pass's dispatch;
// phase 2 writes each waiting slot's index at its block's offset plus its rank in the block.
// Rays past the queue's capacity are marked dropped and counted: they are not samples.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 256) in;

#include "hybrid.glsl"

shared uint partial[RB_HYBRID_QUEUE_GROUP];
shared uint group_total;

// Inclusive prefix sum of x over the workgroup (Hillis-Steele), in a fixed order; the
// workgroup's total in group_total.
uint scan(uint x)
{
    uint i = gl_LocalInvocationID.x;
    partial[i] = x;
    barrier();
    for (uint d = 1u; d < RB_HYBRID_QUEUE_GROUP; d <<= 1) {
        uint add = i >= d ? partial[i - d] : 0u;
        barrier();
        partial[i] += add;
        barrier();
    }
    uint r = partial[i];
    if (i == RB_HYBRID_QUEUE_GROUP - 1u)
        group_total = r;
    barrier();
    return r;
}

bool waiting(uint slot, uint slot_count)
{
    return slot < slot_count && floatBitsToUint(slots[slot].a.w) == RB_HYBRID_QUEUED;
}

void main()
{
    uint phase = pc.level.x;
    uint slot_count = 2u * pc.frame.w;
    uint block_count = (slot_count + RB_HYBRID_QUEUE_GROUP - 1u) / RB_HYBRID_QUEUE_GROUP;
    uint i = gl_LocalInvocationID.x;
    if (phase == 1u) {
        uint total = 0u;
        for (uint base = 0u; base < block_count; base += RB_HYBRID_QUEUE_GROUP) {
            uint b = base + i;
            uint c = b < block_count ? blocks[b] : 0u;
            uint inclusive = scan(c);
            if (b < block_count)
                blocks[b] = total + inclusive - c;
            total += group_total;
            barrier();
        }
        if (i == 0u) {
            uint traced = min(total, pc.sizes.z);
            counters.more.z = traced;
            counters.more.y = total - traced;
            uint groups = (traced + RB_HYBRID_BVH_GROUP - 1u) / RB_HYBRID_BVH_GROUP;
            counters.dispatch = uvec4(min(groups, 65535u), (groups + 65534u) / 65535u, 1u, 0u);
        }
        return;
    }
    uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (block >= block_count)
        return; // the whole workgroup: no barrier is left waiting
    uint slot = block * RB_HYBRID_QUEUE_GROUP + i;
    bool w = waiting(slot, slot_count);
    uint inclusive = scan(w ? 1u : 0u);
    if (phase == 0u) {
        if (i == 0u)
            blocks[block] = group_total;
        return;
    }
    if (!w)
        return;
    uint at = blocks[block] + inclusive - 1u;
    if (at < pc.sizes.z)
        queue[at] = slot;
    else
        slots[slot].a.w = uintBitsToFloat(RB_HYBRID_DROPPED);
}
