// hybrid_emitters: the emitter table's running sums of emitted power (hybrid_shared.h), from
// where the animate pass put the emissive triangles this frame, so that the light samples pick an
// emitter by power with a binary search (as bdpt_emitters.comp does for bdpt). One workgroup:
// each invocation sums a fixed run of triangles, the runs' sums are added up in order, then each
// invocation writes its run's running sums: the same order every frame, so the same bits.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 256) in;

#include "hybrid.glsl"

shared float partial[256];

// Emitter e's area times the luminance of its emissive factor.
float emitter_power(uint e)
{
    uint t = index_at(floatBitsToUint(pc.scene.z) + e);
    rb_gpu_vertex v0 = vertex_at(index_at(3u * t));
    vec3 p1 = vertex_at(index_at(3u * t + 1u)).position.xyz, p2 = vertex_at(index_at(3u * t + 2u)).position.xyz;
    float area = 0.5 * length(cross(p1 - v0.position.xyz, p2 - v0.position.xyz));
    return area * rb_luminance(max(materials[floatBitsToUint(v0.uv.z)].emissive.rgb, vec3(0.0)));
}

void main()
{
    uint t = gl_LocalInvocationID.x, count = pc.bake.w, base = rb_hybrid_cdf_base();
    uint run = (count + 255u) / 256u, first = min(t * run, count), end = min(first + run, count);
    float sum = 0.0;
    for (uint e = first; e < end; e++)
        sum += emitter_power(e);
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
        running += emitter_power(e);
        blocks[base + e] = floatBitsToUint(running);
    }
}
