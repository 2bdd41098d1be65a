// hybrid_trace: one lobe's rays of every pixel (seed 003, "ray traversal scheme"). A pixel asks
// for rays only while its samples are fewer than it wants (the lazy request: the count it wants
// follows from its albedo, its roughness and how much direct light hides its indirect light)
// and its tile is not done. Each ray samples the lobe with fixed quasi-random numbers of
// (frame, pixel, lobe, ray) and marches in screen space through the hierarchical depth buffer:
// a hit is shaded from the G-buffer where it lands (with the baked light of the triangle the
// G-buffer names there), the emission it finds weighed by MIS against hybrid_light's samples; a ray that leaves the screen, turns toward
// the camera past the near plane, passes behind a surface by more than the thickness, or runs
// out of steps waits in its slot for the BVH.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "hybrid.glsl"

// Where each level of the hierarchical depth buffer starts in it, and its width: filled once by
// main, before the pixel's rays.
uint hiz_offset[16];
uint hiz_width[16];

void hiz_levels()
{
    uint off = 0u;
    uvec2 s = g.size.xy;
    for (uint i = 0u; i < 16u; i++) {
        hiz_offset[i] = off;
        hiz_width[i] = s.x;
        off += s.x * s.y;
        s = (s + 1u) / 2u;
    }
}

// The ray parameter at which clip-space x / w (axis 0) or y / w (axis 1) reaches ndc.
float t_at(vec4 c0, vec4 c1, uint axis, float ndc)
{
    float den = c1[axis] - ndc * c1.w;
    return abs(den) > 1e-20 ? (ndc * c0.w - c0[axis]) / den : 1e30;
}

// Marches o + t d (t > 0) through the hierarchical depth buffer. Returns the pixel it hits, or
// (-1, -1) for the BVH.
ivec2 screen_trace(vec3 o, vec3 d, float thickness, uint steps)
{
    vec4 c0 = g.view_proj * vec4(o, 1.0);
    vec4 c1 = g.view_proj * vec4(d, 0.0);
    vec2 size = vec2(g.size.xy);
    uint levels = pc.sizes.w;
    // The direction the ray moves across the screen: the sign of d(ndc)/dt, constant while w > 0.
    vec2 dir = vec2(c1.x * c0.w - c0.x * c1.w, c1.y * c0.w - c0.y * c1.w);
    float t_near = c1.w < 0.0 ? (1e-4 * c0.w - c0.w) / c1.w : 1e30;
    float t = 0.0;
    uint level = 0u;
    bool first = true; // the origin's own pixel is skipped
    for (uint i = 0u; i < steps; i++) {
        vec4 c = c0 + t * c1;
        if (c.w <= 0.0)
            return ivec2(-1);
        vec2 s = (c.xy / c.w * 0.5 + 0.5) * size;
        if (any(lessThan(s, vec2(0.0))) || any(greaterThanEqual(s, size)))
            return ivec2(-1);
        ivec2 pix = ivec2(floor(s));
        ivec2 cell = pix >> int(level);
        // Where the ray leaves the cell, across x or y.
        vec2 edge = vec2((cell + ivec2(greaterThan(dir, vec2(0.0)))) << int(level));
        vec2 ndc = edge / size * 2.0 - 1.0;
        float tx = dir.x != 0.0 ? t_at(c0, c1, 0u, ndc.x) : 1e30;
        float ty = dir.y != 0.0 ? t_at(c0, c1, 1u, ndc.y) : 1e30;
        float t_exit = min(max(tx, t), max(ty, t));
        if (t_exit >= t_near)
            return ivec2(-1);
        // Just past the edge, so the next step lands in the next cell.
        float t_next = t_exit + max(abs(t_exit), 1e-6) * 1e-5;
        if (first) {
            first = false;
            t = t_next;
            continue;
        }
        float za = c.w, zb = c0.w + t_exit * c1.w;
        float zmin = min(za, zb), zmax = max(za, zb);
        vec2 cellz = hiz[hiz_offset[level] + uint(cell.y) * hiz_width[level] + uint(cell.x)];
        if (zmax < cellz.x) { // in front of everything in the cell
            t = t_next;
            level = min(level + 1u, levels - 1u);
            continue;
        }
        if (zmin > cellz.y * (1.0 + thickness)) // behind everything in it: unknown depth
            return ivec2(-1);
        if (level > 0u) {
            level--;
            continue;
        }
        // One depth sample: the ray reaches it within this pixel, no more than the thickness
        // behind.
        return pix;
    }
    return ivec2(-1);
}

// The samples a lobe of this pixel wants (seed 003: from albedo, material and the amount of
// direct light): fewer for a dark or glossy-mirror lobe, and fewer where the direct light
// outshines the indirect light estimated so far.
uint desired(uint lobe, vec3 c_diff, vec3 f0, float roughness, float direct_lum, float est)
{
    float spp = float(pc.sizes.x);
    float w;
    if (lobe == RB_HYBRID_DIFFUSE) {
        float a = rb_lum(c_diff);
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
        float texture_w = lobe == RB_HYBRID_DIFFUSE ? rb_lum(c_diff) : rb_spec_map(spec.rgb);
        float est = have.w > 0.0 ? texture_w * rb_lum(have.rgb + have_ind.rgb) / have.w : 0.0;
        uint want = desired(lobe, c_diff, spec.rgb, spec.a, rb_lum(imageLoad(direct_light, px).rgb), est);
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
        vec3 lit = rb_hybrid_shade(pq.xyz, nq.xyz, ngq, -l, aq.rgb, sq.rgb, eq.w, sq.a, baked, fed);
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
