// hybrid_trace: one lobe's rays of every pixel (seed 003, "ray traversal scheme"). A pixel asks
// for rays only while its samples are fewer than it wants (the lazy request: the count it wants
// follows from its albedo, its roughness and how much direct light hides its indirect light)
// and its tile is not done. Each ray samples the lobe with fixed quasi-random numbers of
// (frame, pixel, lobe, ray) and marches in screen space through the hierarchical depth buffer:
// a hit is shaded from the G-buffer where it lands (with the baked light of the triangle the
// G-buffer names there), the emission it finds weighed by MIS against hybrid_light's samples; a ray that leaves the screen, turns toward
// the camera past the near plane, passes behind a surface by more than the thickness, or runs
// out of steps waits in its slot for the BVH.
// The body of hybrid_trace.comp and hybrid_trace_chain.comp: the second defines RB_HYBRID_CHAIN,
// with which a hit goes on through the BVH for a counted path (max_bounces 2 to 8,
// rb_hybrid_chain). Only that pipeline holds the chain's BVH traversal: inlined into every
// variant, it made the default's rays pass 17% (diffuse) and 35% (specular) slower on lavapipe.
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "hybrid.glsl"

#include "hybrid_screen.glsl"

// The samples a lobe of this pixel wants (seed 003: from albedo, material and the amount of
// direct light): fewer for a dark or glossy-mirror lobe, and fewer where the direct light
// outshines the indirect light estimated so far.
uint desired(uint lobe, vec3 c_diff, vec3 f0, float roughness, float direct_lum, float est)
{
    float spp = float(pc.sizes.x);
    float w;
    if (lobe == RB_HYBRID_DIFFUSE) {
        float a = rb_luminance(c_diff);
        if (a <= 0.0)
            return 0u;
        w = clamp(2.0 * a, 0.5, 1.0);
    } else {
        w = max(clamp(4.0 * rb_spec_map(f0), 0.5, 1.0) * clamp(2.0 * roughness, 0.5, 1.0), 0.5);
    }
    float masking = clamp(2.0 * est / (est + direct_lum + 1e-6), 0.5, 1.0);
    return uint(max(ceil(spp * w * masking), 1.0));
}

// check_screen: whether the BVH finds the surface the screen trace hit at pixel `hit` (G-buffer
// point pq, geometric normal ngq, depth): the ray's closest BVH hit must project to that pixel
// or one beside it and lie on the plane of the G-buffer's surface there, within the thickness.
bool bvh_agrees(vec3 o, vec3 l, ivec2 hit, vec3 pq, vec3 ngq, float depth)
{
    rb_bvh_hit h;
    if (!rb_bvh_intersect(o, l, 0.0, 1e30, h))
        return false;
    vec3 pb = o + h.t * l;
    vec4 c = g.view_proj * vec4(pb, 1.0);
    if (!(c.w > 0.0))
        return false;
    vec2 s = (c.xy / c.w * 0.5 + 0.5) * vec2(g.size.xy);
    return all(lessThanEqual(abs(s - (vec2(hit) + 0.5)), vec2(1.5))) &&
           abs(dot(pb - pq, ngq)) <= pc.params.y * depth;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), g.size.xy)))
        return;
    uint lobe = pc.frame.z, rays = pc.frame.y;
    vec4 pos = imageLoad(gb_position, px);
    bool request = pos.w > 0.0;
    vec3 p = pos.xyz, n = vec3(0.0), ng = vec3(0.0), v = vec3(0.0), c_diff = vec3(0.0);
    vec4 spec = vec4(0.0), emission = vec4(0.0);
    if (request) {
        n = imageLoad(gb_normal, px).xyz;
        c_diff = imageLoad(gb_albedo, px).rgb;
        spec = imageLoad(gb_specular, px);
        emission = imageLoad(gb_emission, px);
        ng = rb_oct_decode(imageLoad(gb_motion, px).zw);
        v = normalize(g.camera_pos.xyz - p);
        // What the younger accumulator holds here (nothing when it starts again this frame).
        uint younger = pc.history.w;
        bool fresh = (younger == 0u ? pc.history.x : pc.history.y) != 0u;
        ivec2 q = rb_hybrid_reproject(px, pos.w, n);
        uint direct_layer = 4u * younger + 2u * lobe;
        vec4 have = fresh || q.x < 0 ? vec4(0.0) : imageLoad(acc_prev, ivec3(q, direct_layer));
        vec4 have_ind = fresh || q.x < 0 ? vec4(0.0) : imageLoad(acc_prev, ivec3(q, direct_layer + 1u));
        float texture_w = lobe == RB_HYBRID_DIFFUSE ? rb_luminance(c_diff) : rb_spec_map(spec.rgb);
        float est = have.w > 0.0 ? texture_w * rb_luminance(have.rgb + have_ind.rgb) / have.w : 0.0;
        uint want = desired(lobe, c_diff, spec.rgb, spec.a, rb_luminance(imageLoad(direct_light, px).rgb), est);
        // A tile's mask counts only once its accumulator has started: the frame that starts
        // it asks for what every pixel wants, whatever came before.
        bool done = !fresh && pc.params.x > 0.0 && rb_hybrid_tile_done(px, lobe == RB_HYBRID_DIFFUSE) >= 0.5;
        request = have.w < float(want) && !done;
    }
    if (request)
        hiz_levels();
    for (uint r = 0u; r < rays; r++) {
        uint slot = rb_hybrid_slot(lobe, r, px);
        if (!request) {
            slots[slot].a = vec4(0.0, 0.0, 0.0, uintBitsToFloat(RB_HYBRID_NONE));
            continue;
        }
        atomicAdd(counters.rays.x, 1u);
        vec2 u = rb_hybrid_u(pc.frame.x * rays + r, px, lobe);
        vec3 l, weight;
        if (!rb_hybrid_sample(lobe, n, ng, v, spec.rgb, emission.w, spec.a, u, l, weight)) {
            slots[slot].a = vec4(0.0, 0.0, 0.0, uintBitsToFloat(RB_HYBRID_ABSORBED));
            slots[slot].b = vec4(0.0);
            continue;
        }
        vec3 o = rb_hybrid_origin(px);
        ivec2 hit = pc.sizes.y > 0u ? screen_trace(o, l, pc.params.y, pc.sizes.y) : ivec2(-1);
        vec3 ngq = hit.x >= 0 ? rb_oct_decode(imageLoad(gb_motion, hit).zw) : vec3(0.0);
        // The camera sees the hit surface's front; a ray reaching it from behind went behind it.
        if (hit.x < 0 || dot(ngq, l) >= 0.0) {
            atomicAdd(counters.rays.z, 1u);
            slots[slot].a = vec4(l, uintBitsToFloat(RB_HYBRID_QUEUED));
            slots[slot].b = vec4(weight, rb_hybrid_pdf(lobe, n, v, l, spec.a));
            continue;
        }
        atomicAdd(counters.rays.y, 1u);
        vec4 pq = imageLoad(gb_position, hit);
        vec4 sq = imageLoad(gb_specular, hit);
        vec4 eq = imageLoad(gb_emission, hit);
        if (pc.scene.w > 0.0) {
            atomicAdd(counters.check.x, 1u);
            if (bvh_agrees(o, l, hit, pq.xyz, ngq, pq.w))
                atomicAdd(counters.check.y, 1u);
        }
        vec4 aq = imageLoad(gb_albedo, hit);
        vec4 nq = imageLoad(gb_normal, hit);
        vec3 baked;
        bool fed = rb_hybrid_feedback(pq.xyz, nq.xyz, aq.rgb, sq.rgb, baked);
        if (!fed)
            baked = rb_hybrid_baked_at(pq.xyz, ngq, pq.w, aq.w, nq.w < 0.0);
        uint bounces = rb_hybrid_max_bounces();
        vec3 lit = bounces == 0u ? vec3(0.0)
                                 : rb_hybrid_shade(pq.xyz, nq.xyz, ngq, -l, aq.rgb, sq.rgb, eq.w,
                                                   sq.a, baked, fed);
        // A counted path (max_bounces N >= 2) goes on from the hit through the BVH.
#ifdef RB_HYBRID_CHAIN
        if (bounces >= 2u && bounces != 0xffffffffu)
            lit += rb_hybrid_chain(pq.xyz, nq.xyz, ngq, -l, aq.rgb, sq.rgb, eq.w, sq.a,
                                   bounces - 1u, pc.frame.x * rays + r, px, lobe);
#endif
        // Emission found is weighed against the light sample of the same point (its triangle
        // from the G-buffer).
        vec3 found = vec3(0.0);
        if (max(eq.r, max(eq.g, eq.b)) > 0.0)
            found = weight * eq.rgb *
                    rb_hybrid_emit_weight(uint(aq.w), l, length(pq.xyz - o),
                                          rb_hybrid_pdf(lobe, n, v, l, spec.a));
        slots[slot].a = vec4(found, uintBitsToFloat(RB_HYBRID_SCREEN));
        slots[slot].b = vec4(weight * lit, 0.0);
    }
}
