// hybrid_hiz: one level of the hierarchical depth buffer the screen-space rays march through
// (seed 003's screen-space check): level 0 is the G-buffer's view depth; cell (x, y) of level
// L + 1 holds the minimum and maximum of cells (2x .. 2x + 1, 2y .. 2y + 1) of level L (those
// that exist), so cell (x >> L, y >> L) of level L bounds pixel (x, y) at every level. Where no
// surface is, the depth is RB_HYBRID_FAR: a ray is always in front of it.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "hybrid.glsl"

const float RB_HYBRID_FAR = 1e30;

void main()
{
    uvec2 c = gl_GlobalInvocationID.xy;
    uvec2 size = pc.level.yz;
    if (any(greaterThanEqual(c, size)))
        return;
    uint dst = pc.level.w + c.y * size.x + c.x;
    if (pc.level.x == 0u) {
        float d = imageLoad(gb_position, ivec2(c)).w;
        d = d > 0.0 ? d : RB_HYBRID_FAR;
        hiz[dst] = vec2(d);
        return;
    }
    uvec2 src_size = pc.more.yz;
    vec2 r = vec2(RB_HYBRID_FAR, 0.0);
    for (uint y = 0u; y < 2u; y++)
        for (uint x = 0u; x < 2u; x++) {
            uvec2 s = c * 2u + uvec2(x, y);
            if (all(lessThan(s, src_size))) {
                vec2 v = hiz[pc.more.x + s.y * src_size.x + s.x];
                r = vec2(min(r.x, v.x), max(r.y, v.y));
            }
        }
    hiz[dst] = r;
}
