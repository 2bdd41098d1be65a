// bdpt, emitters (BDPT.md "As implemented", emitters): the CDF over the emissive triangles by
// emitted power, built each frame from where the animate pass put them, so that generate picks
// an emitter's point by a binary search. One workgroup: each invocation sums a fixed run of
// triangles, the runs' sums are scanned in order, then each invocation writes its run's
// running sums: the same order every frame, so the same bits.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "geometry_shared.h"

layout(local_size_x = 256) in;

layout(std140, binding = RB_BIND_BDPT_EMITTERS_VERTICES) uniform Geometry { rb_gpu_geometry geo; };
layout(std430, binding = RB_BIND_BDPT_EMITTERS_EMITTERS) readonly buffer Emitters { rb_gpu_bdpt_emitter emitters[]; };
layout(std430, binding = RB_BIND_BDPT_EMITTERS_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(std430, binding = RB_BIND_BDPT_EMITTERS_CDF) writeonly buffer Cdf { float cdf[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_emitters_push pc; };

#include "bdpt_emitters.glsl"

shared float partial[256];

void main()
{
    uint t = gl_LocalInvocationID.x, count = pc.counts.x;
    uint run = (count + 255u) / 256u, first = min(t * run, count), end = min(first + run, count);
    vec3 p0, p1, p2;
    float sum = 0.0;
    for (uint e = first; e < end; e++)
        sum += emitter_weight(e, p0, p1, p2);
    partial[t] = sum;
    barrier();
    if (t == 0u) {
        float before = 0.0;
        for (uint i = 0u; i < 256u; i++) {
            float s = partial[i];
            partial[i] = before;
            before += s;
        }
    }
    barrier();
    float running = partial[t];
    for (uint e = first; e < end; e++) {
        running += emitter_weight(e, p0, p1, p2);
        cdf[e] = running;
    }
}
