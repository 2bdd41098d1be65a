// animate: applies morph targets, skins and node transforms to one instance's vertices,
// writing world-space vertices for the raster passes. One dispatch per instance and run of
// at most maxComputeWorkGroupCount[0] groups of its vertices.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "geometry_shared.h"

layout(local_size_x = 64) in;

layout(std140, binding = RB_BIND_ANIMATE_GEOMETRY) uniform Geometry { rb_gpu_geometry geo; };
layout(std430, binding = RB_BIND_ANIMATE_INSTANCES) readonly buffer Instances { rb_gpu_instance instances[]; };
layout(std430, binding = RB_BIND_ANIMATE_JOINTS) readonly buffer Joints { mat4 joints[]; };
layout(std430, binding = RB_BIND_ANIMATE_WEIGHTS) readonly buffer Weights { float weights[]; };

layout(push_constant) uniform Push { uint instance, first; } pc; // first: the run's first vertex

vec3 safe_normalize(vec3 v, vec3 fallback)
{
    float l = length(v);
    return l > 1e-20 ? v / l : fallback;
}

void main()
{
    rb_gpu_instance inst = instances[pc.instance];
    uint v = pc.first + gl_GlobalInvocationID.x;
    if (v >= inst.range.y)
        return;
    rb_float_array src = geo.src_vertices, morph = geo.morph_deltas;
    uint s = (inst.range.x + v) * RB_SRC_VERTEX_FLOATS;
    vec3 p = vec3(src.f[s + 0], src.f[s + 1], src.f[s + 2]);
    vec3 n = vec3(src.f[s + 3], src.f[s + 4], src.f[s + 5]);
    vec4 t = vec4(src.f[s + 6], src.f[s + 7], src.f[s + 8], src.f[s + 9]);
    vec2 uv = vec2(src.f[s + 10], src.f[s + 11]);
    uvec4 j = floatBitsToUint(vec4(src.f[s + 12], src.f[s + 13], src.f[s + 14], src.f[s + 15]));
    vec4 w = vec4(src.f[s + 16], src.f[s + 17], src.f[s + 18], src.f[s + 19]);

    for (uint k = 0; k < inst.deform.y; k++) {
        float wk = weights[inst.deform.z + k];
        uint m = (inst.deform.x + k * inst.range.y + v) * RB_MORPH_DELTA_FLOATS;
        p += wk * vec3(morph.f[m + 0], morph.f[m + 1], morph.f[m + 2]);
        n += wk * vec3(morph.f[m + 3], morph.f[m + 4], morph.f[m + 5]);
    }

    mat4 M = inst.world;
    mat3 N = mat3(inst.normal_matrix);
    float wsum = w.x + w.y + w.z + w.w;
    if (inst.deform.w != RB_NONE && wsum > 0.0) {
        uint f = inst.deform.w;
        M = (w.x * joints[f + j.x] + w.y * joints[f + j.y] + w.z * joints[f + j.z] +
             w.w * joints[f + j.w]) / wsum;
        N = transpose(inverse(mat3(M)));
    }
    vec3 wn = safe_normalize(N * n, vec3(0.0, 1.0, 0.0));
    vec3 wt = safe_normalize(mat3(M) * t.xyz, vec3(1.0, 0.0, 0.0));
    float handed = t.w < 0.0 ? -1.0 : 1.0;
    rb_gpu_vertex o;
    o.position = vec4((M * vec4(p, 1.0)).xyz, 1.0);
    o.normal = vec4(wn, 0.0);
    o.tangent = vec4(wt, handed);
    o.uv = vec4(uv, uintBitsToFloat(inst.range.w), 0.0);
    geo.vertices.v[inst.range.z + v] = o;
}
