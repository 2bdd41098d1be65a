// hybrid_tiles: the noise of each 16 x 16 tile of the younger accumulator (the one the rays'
// requests follow), seed 003's sigma = sqrt(E[x^2] - E[x]^2) of each pixel's samples, as the
// standard error of the pixel's mean over the square root of the pixels the filter averages (so
// the noise of what the output shows), relative to the tile's mean. A tile is done (1) when that
// is under the noise target and every pixel with a surface has at least 4 samples a lobe it
// samples; phase 1 erodes the mask by one tile (a tile counts as done only where its neighbours
// are), for the lobe whose filter reaches across tiles.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 16, local_size_y = 16) in;

#include "hybrid.glsl"

shared vec4 part[256];

void main()
{
    uvec2 tiles_n = (g.size.xy + RB_HYBRID_TILE - 1u) / RB_HYBRID_TILE;
    uint tile = gl_WorkGroupID.y * tiles_n.x + gl_WorkGroupID.x;
    uint i = gl_LocalInvocationIndex;
    if (pc.level.x == 1u) {
        if (i != 0u)
            return;
        float e = 1.0;
        for (int y = -1; y <= 1; y++)
            for (int x = -1; x <= 1; x++) {
                ivec2 t = clamp(ivec2(gl_WorkGroupID.xy) + ivec2(x, y), ivec2(0), ivec2(tiles_n) - 1);
                e = min(e, tiles[uint(t.y) * tiles_n.x + uint(t.x)]);
            }
        tiles[tiles_n.x * tiles_n.y + tile] = e;
        return;
    }
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    vec4 mine = vec4(0.0); // variance of the mean, mean, pixels, pixels short of samples
    if (all(lessThan(uvec2(px), g.size.xy)) && imageLoad(gb_position, px).w > 0.0) {
        uint set = pc.history.w;
        bool has_diffuse = rb_luminance(imageLoad(gb_albedo, px).rgb) > 0.0;
        for (uint lobe = 0u; lobe < 2u; lobe++) {
            bool sampled = lobe == RB_HYBRID_SPECULAR || has_diffuse;
            vec4 d = imageLoad(acc, ivec3(px, 4u * set + 2u * lobe));
            vec4 ind = imageLoad(acc, ivec3(px, 4u * set + 2u * lobe + 1u));
            if (d.w <= 0.0) {
                mine.w += sampled ? 1.0 : 0.0;
                continue;
            }
            float mean = rb_luminance(d.rgb + ind.rgb) / d.w;
            // The variance of the pixel's mean, then of what the output shows: the filter
            // averages about pi radius^2 pixels' means (a Gaussian of sigma radius / 2, within
            // its window), with the radius hybrid_filter.comp gives the lobe's indirect light.
            float radius = float(pc.more.w) * pow(d.w, -0.25);
            if (lobe == RB_HYBRID_SPECULAR)
                radius *= clamp(2.0 * imageLoad(gb_specular, px).a, 0.0, 1.0);
            float window = 2.0 * floor(radius) + 1.0;
            float n_eff = radius < 1.0 ? 1.0 : min(RB_PI * radius * radius, window * window);
            float var = max(ind.w / d.w - mean * mean, 0.0) / d.w / n_eff;
            mine += vec4(var, mean, 0.0, d.w < 4.0 ? 1.0 : 0.0);
        }
        mine.z = 1.0;
    }
    part[i] = mine;
    barrier();
    for (uint d = 128u; d > 0u; d >>= 1) {
        if (i < d)
            part[i] += part[i + d];
        barrier();
    }
    if (i == 0u) {
        vec4 t = part[0];
        float sigma = t.z > 0.0 ? sqrt(t.x / t.z) / (t.y / t.z + 1e-4) : 0.0;
        tiles[tile] = t.w == 0.0 && sigma < pc.params.x ? 1.0 : 0.0;
    }
}
