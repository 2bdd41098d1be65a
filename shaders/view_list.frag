// view, linked-list output (Yang et al. 2010; seed 000, B.2): every fragment of the view, front
// and back faces, appended to its pixel's list. A fragment that finds the node pool full writes
// nothing and is counted, so the overflow is reported, never silent. Perspective and
// orthographic views.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"
#include "view.glsl"

layout(std430, binding = RB_VIEW_BIND_VIEWS) readonly buffer Views { rb_gpu_view views[]; };
layout(binding = RB_VIEW_BIND_HEADS, r32ui) uniform coherent uimage2DArray heads;
layout(std430, binding = RB_VIEW_BIND_NODES) writeonly buffer Nodes { rb_gpu_list_node nodes[]; };
layout(std430, binding = RB_VIEW_BIND_COUNTER) coherent buffer Counter
{
    rb_gpu_list_counter counter;
};
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 0) in vec3 i_pos;
layout(location = 1) in vec3 i_normal;

void main()
{
    uint index = atomicAdd(counter.requested, 1u);
    if (index >= pc.index.w) {
        atomicAdd(counter.dropped, 1u);
        return;
    }
    float depth = abs(rb_view_depth(views[pc.index.x], pc.index.z, i_pos));
    ivec3 texel = ivec3(ivec2(gl_FragCoord.xy), int(pc.index.y));
    uint next = imageAtomicExchange(heads, texel, index);
    nodes[index].depth = gl_FrontFacing ? depth : -depth;
    nodes[index].normal = rb_view_polar_encode(normalize(i_normal));
    nodes[index].next = next;
}
