// The hybrid's screen-space march through the hierarchical depth buffer (seed 003, "ray
// traversal scheme"), for the BRDF rays (hybrid_trace.comp) and the light samples' shadow rays
// (hybrid_light.comp). Needs hybrid.glsl's bindings (the G-buffer's size in g, hiz, the push
// constants).
#ifndef RB_HYBRID_SCREEN_GLSL
#define RB_HYBRID_SCREEN_GLSL

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

#endif
