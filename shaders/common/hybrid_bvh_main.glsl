// hybrid_bvh: the queued rays through the BVH (seed 003: traverse the BVH later, in a compute
// shader: the default device has no ray queries). A hit is shaded as a screen hit is: its
// material at the hit (textures and normal map, at their full resolution), its emission as the
// camera vertex's direct light (weighed by MIS against hybrid_light's samples, with the pdf the
// ray carries), the punctual lights' shadow-mapped light and what the previous frame gathered
// at the hit (rb_hybrid_feedback), or where it saw no such thing (a surface the camera does not
// see) the triangle's baked light of the emitters and the environment plus, with max_bounces
// unlimited, one explicit secondary ray: a cosine-weighted diffuse ray from the hit through the
// BVH, whose own hit sends what the previous frame gathered there (or its baked light) back, so
// that the hidden surfaces' light has its further bounces too. With a count N, no feedback: the
// baked light and N - 1 further bounces through the BVH (rb_hybrid_chain); with 0, the hit
// reflects nothing. A miss takes the environment, weighed by MIS against hybrid_light's
// samples of it.
// Both faces of every surface are hit and shaded and emit, as the reference's bounce rays find
// them; only double-sided materials have their back's light baked.
// The body of hybrid_bvh.comp and hybrid_bvh_chain.comp: the second defines RB_HYBRID_CHAIN,
// with which a hit goes on through the BVH for a counted path (max_bounces 2 to 8,
// rb_hybrid_chain). Only that pipeline holds the chain's BVH traversal: inlined into every
// variant, it made the default's rays pass 17% (diffuse) and 35% (specular) slower on lavapipe.
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 64) in;

#include "hybrid.glsl"

// The light a hidden hit (p, n, ng) gathers beyond its direct light, by one cosine-weighted ray
// with random numbers u: what the surface that ray finds sends back but its emission (the
// emitters' and the environment's light at p is the bake's), per unit albedo.
vec3 secondary(vec3 p, vec3 n, vec3 ng, vec2 u)
{
    vec3 t, b;
    rb_basis(n, t, b);
    float r = sqrt(u.x), phi = 2.0 * RB_PI * u.y;
    vec3 l = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(1.0 - u.x, 0.0)) * n);
    if (dot(ng, l) <= 0.0)
        return vec3(0.0);
    vec3 o = p + ng * (1e-4 * length(p - g.camera_pos.xyz) + 1e-6 * pc.scene.x);
    rb_bvh_hit hit;
    if (!rb_bvh_intersect(o, l, 0.0, 1e30, hit))
        return vec3(0.0);
    vec3 q, nq, ngq;
    bool front;
    rb_surface sf;
    rb_hybrid_bvh_surface(o, l, hit, q, nq, ngq, front, sf);
    vec3 light;
    bool fed = rb_hybrid_feedback(q, nq, sf.c_diff, sf.f0, light);
    if (!fed)
        light = rb_hybrid_baked(hit.extra, hit.bary, !front);
    return rb_hybrid_shade(q, nq, ngq, -l, sf.c_diff, sf.f0, sf.f90, sf.roughness, light, fed);
}

void main()
{
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * RB_HYBRID_BVH_GROUP +
             gl_LocalInvocationID.x;
    if (i >= counters.more.z)
        return;
    uint slot = queue[i];
    rb_gpu_hybrid_slot s = slots[slot];
    ivec2 px = rb_hybrid_slot_pixel(slot);
    vec3 o = rb_hybrid_origin(px), d = s.a.xyz, weight = s.b.rgb;
    rb_bvh_hit hit;
    if (!rb_bvh_intersect(o, d, 0.0, 1e30, hit)) {
        atomicAdd(counters.more.x, 1u);
        // weighed against the environment's light sample of the same direction
        float w = 1.0;
        if (rb_hybrid_env_lit())
            w = rb_hybrid_mis(s.b.w, rb_hybrid_env_pdf(imageLoad(gb_normal, px).xyz, d));
        slots[slot].a = vec4(weight * rb_hybrid_env(d) * w, uintBitsToFloat(RB_HYBRID_MISS));
        slots[slot].b = vec4(0.0);
        return;
    }
    atomicAdd(counters.rays.w, 1u);
    vec3 p, n, ng;
    bool front;
    rb_surface sf;
    rb_hybrid_bvh_surface(o, d, hit, p, n, ng, front, sf);
    vec3 direct = weight * sf.emission;
    if (max(direct.r, max(direct.g, direct.b)) > 0.0)
        direct *= rb_hybrid_emit_weight(hit.triangle, d, hit.t, s.b.w);
    vec3 baked;
    bool fed = rb_hybrid_feedback(p, n, sf.c_diff, sf.f0, baked);
    uint bounces = rb_hybrid_max_bounces();
    // the slot's (lobe, ray): its random numbers, rotated apart from the camera ray's
    uint lobe_ray = slot / (g.size.x * g.size.y);
    uint lobe = lobe_ray / pc.frame.y;
    uint k = pc.frame.x * pc.frame.y + lobe_ray % pc.frame.y;
    if (!fed) {
        baked = rb_hybrid_baked(hit.extra, hit.bary, !front);
        if (bounces == 0xffffffffu && max(sf.c_diff.r, max(sf.c_diff.g, sf.c_diff.b)) > 0.0)
            baked += secondary(p, n, ng, rb_hybrid_u(k, px, lobe + 6u));
    }
    vec3 lit = bounces == 0u ? vec3(0.0)
                             : rb_hybrid_shade(p, n, ng, -d, sf.c_diff, sf.f0, sf.f90,
                                               sf.roughness, baked, fed);
#ifdef RB_HYBRID_CHAIN
    if (bounces >= 2u && bounces != 0xffffffffu)
        lit += rb_hybrid_chain(p, n, ng, -d, sf.c_diff, sf.f0, sf.f90, sf.roughness, bounces - 1u,
                               k, px, lobe);
#endif
    lit *= weight;
    slots[slot].a = vec4(direct, uintBitsToFloat(RB_HYBRID_BVH));
    slots[slot].b = vec4(lit, 0.0);
}
