// bvh_trace: one ray per invocation through shaders/common/bvh.glsl, closest hit and both
// occlusion queries, so that tests/unit/test_bvh.c can hold the traversal to Embree. Not a pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bvh_shared.h"

layout(local_size_x = 64) in;

layout(std430, binding = RB_BIND_BVH_TRACE_NODES) readonly buffer BvhNodes { rb_gpu_bvh_node bvh_nodes[]; };
layout(std430, binding = RB_BIND_BVH_TRACE_TRIS) readonly buffer BvhTris { rb_gpu_bvh_triangle bvh_tris[]; };
layout(std430, binding = RB_BIND_BVH_TRACE_RAYS) readonly buffer Rays { rb_gpu_bvh_ray rays[]; };
layout(std430, binding = RB_BIND_BVH_TRACE_HITS) writeonly buffer Hits { rb_gpu_bvh_trace_hit hits[]; };
// the rays; has_occlusion 0: closest hits only (for timing)
layout(push_constant) uniform Push { uint count, has_occlusion; } pc;

#include "bvh.glsl"

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    rb_gpu_bvh_ray r = rays[i];
    rb_bvh_hit h;
    rb_gpu_bvh_trace_hit o;
    o.occluded = uvec4(0u);
    vec3 org = r.origin.xyz, dir = r.direction.xyz;
    float tmin = r.origin.w, tmax = r.direction.w;
    if (pc.has_occlusion != 0u)
        o.occluded.x = rb_bvh_occluded(org, dir, tmin, tmax) ? 1u : 0u;
    if (rb_bvh_intersect(org, dir, tmin, tmax, h)) {
        o.hit = vec4(h.t, uintBitsToFloat(h.triangle), h.bary);
        if (pc.has_occlusion != 0u)
            o.occluded.y = rb_bvh_occluded(org, dir, tmin, 0.5 * h.t) ? 1u : 0u;
    } else {
        o.hit = vec4(-1.0, uintBitsToFloat(RB_NONE), 0.0, 0.0);
    }
    hits[i] = o;
}
