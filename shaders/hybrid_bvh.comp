// hybrid_bvh: the queued rays through the BVH (seed 003: traverse the BVH later, in a compute
// shader: the default device has no ray queries). A hit is shaded as a screen hit is: its
// material at the hit (textures and normal map, at their full resolution), its emission as the
// camera vertex's direct light (weighed by MIS against hybrid_light's samples, with the pdf the
// ray carries), the punctual lights' shadow-mapped light and the triangle's baked light of the
// emitters and the environment as the bounce; a miss takes the environment.
// Both faces of every surface are hit and shaded and emit, as the reference's bounce rays find
// them; only double-sided materials have their back's light baked.
#version 460
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

#include "hybrid.glsl"

void main()
{
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * RB_HYBRID_BVH_GROUP +
             gl_LocalInvocationID.x;
    if (i >= counters.more.z)
        return;
    uint slot = queue[i];
    rb_gpu_hybrid_slot s = slots[slot];
    vec3 o = rb_hybrid_origin(rb_hybrid_slot_pixel(slot)), d = s.a.xyz, weight = s.b.rgb;
    rb_bvh_hit hit;
    if (!rb_bvh_intersect(o, d, 0.0, 1e30, hit)) {
        atomicAdd(counters.more.x, 1u);
        slots[slot].a = vec4(weight * rb_hybrid_env(d), uintBitsToFloat(RB_HYBRID_MISS));
        slots[slot].b = vec4(0.0);
        return;
    }
    atomicAdd(counters.rays.w, 1u);
    uint t = hit.triangle;
    rb_gpu_vertex v0 = verts[indices[3u * t]], v1 = verts[indices[3u * t + 1u]],
                  v2 = verts[indices[3u * t + 2u]];
    vec3 b = vec3(1.0 - hit.bary.x - hit.bary.y, hit.bary);
    vec3 ng = normalize(cross(v1.position.xyz - v0.position.xyz, v2.position.xyz - v0.position.xyz));
    vec3 n = normalize(b.x * v0.normal.xyz + b.y * v1.normal.xyz + b.z * v2.normal.xyz);
    vec2 uv = b.x * v0.uv.xy + b.y * v1.uv.xy + b.z * v2.uv.xy;
    rb_gpu_material m = materials[floatBitsToUint(v0.uv.z)];
    bool front = dot(ng, d) < 0.0;
    if (!front)
        ng = -ng;
    if (dot(n, ng) < 0.0)
        n = -n;
    if (m.textures.z >= 0) {
        vec4 tangent = b.x * v0.tangent + b.y * v1.tangent + b.z * v2.tangent;
        vec3 tn = textureLod(linear_textures, vec3(uv, float(m.textures.z)), 0.0).xyz;
        n = rb_normal_map(n, tangent, tn * 2.0 - 1.0, m.emissive.w);
    }
    rb_surface sf = rb_material_eval(m, uv, srgb_textures, linear_textures);
    vec3 p = o + hit.t * d;
    vec3 direct = weight * sf.emission;
    if (max(direct.r, max(direct.g, direct.b)) > 0.0)
        direct *= rb_hybrid_emit_weight(t, d, hit.t, s.b.w);
    vec3 baked = rb_hybrid_baked(hit.extra, hit.bary, !front);
    vec3 lit = weight * rb_hybrid_shade(p, n, ng, -d, sf.c_diff, sf.f0, sf.f90, sf.roughness, baked);
    slots[slot].a = vec4(direct, uintBitsToFloat(RB_HYBRID_BVH));
    slots[slot].b = vec4(lit, 0.0);
}
