// bdpt, reconstruct (seed 000, section A, equations 1 to 3): the light of the pixel from every
// temporal cache that holds its surface. For each cache (in slot order, so that a static shot
// sums the same numbers in the same order every frame), the pixel's surface as it was in the
// frame that wrote the cache (the reproject pass) picks the cache's texel whose sample, offset
// by the cache's subpixel offset, lies nearest (at an edge, where that sample saw another
// surface, h < 1/2, the best of the four samples around), and the depths give the hit weight h:
// equation (3), exp(-log^2(z / z_c) / (2 sigma^2)), or equation (2), |z - z_c| < epsilon, for a
// sample whose normal is within the filter's threshold of the pixel's (h = 0 otherwise: at a
// concave edge two surfaces share their depth, and only the normal tells them apart). The light is
// the h-weighted mean (equation 1); one cache alone gives its own light, unweighted; where no
// cache hits, this frame's cache alone. Sum h / l is the hit ratio, 1 where there is no surface
// (nothing to miss). Cache images: light in rgb; alpha of the first holds the depth of the
// cache's sample, 0 where it saw no surface, alpha of the third its normal (rb_normal_pack),
// and alpha of the second and fourth the slope of
// 1 / z across the image there, which carries it to where the pixel's surface lands: z_c, so
// that a sample a fraction of a pixel away on a slanted surface still hits.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "encode.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std140, binding = RB_BIND_BDPT_RECONSTRUCT_HISTORY) uniform History { rb_gpu_bdpt_history h; };
layout(binding = RB_BIND_BDPT_RECONSTRUCT_GB_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_GB_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_REPROJECT, rgba32f) uniform readonly image2DArray where;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_CACHE + 0, rgba32f) uniform readonly image2DArray c0;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_CACHE + 1, rgba32f) uniform readonly image2DArray c1;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_CACHE + 2, rgba32f) uniform readonly image2DArray c2;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_CACHE + 3, rgba32f) uniform readonly image2DArray c3;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_OUT + 0, rgba32f) uniform writeonly image2D o0;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_OUT + 1, rgba32f) uniform writeonly image2D o1;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_OUT + 2, rgba32f) uniform writeonly image2D o2;
layout(binding = RB_BIND_BDPT_RECONSTRUCT_OUT + 3, rgba32f) uniform writeonly image2D o3;
layout(std430, binding = RB_BIND_BDPT_RECONSTRUCT_HITS) writeonly buffer Hits { float hits[]; };

float weight(float z, float zc)
{
    if (h.info.z == RB_BDPT_HIT_TEST_BINARY)
        return abs(z - zc) < h.params.y ? 1.0 : 0.0;
    float l = log(z / zc);
    return exp(-(l * l) / h.params.x);
}

// The hit weight of cache texel t (slot j) for a surface (normal n) that lands at w.xy at depth
// w.z: 0 outside the image, where the cache saw no surface, and where it saw another surface
// than the pixel's: a normal further from n than the filter's threshold. Depth alone passes a
// wall's sample to the ceiling's pixel beside it where the two meet (a concave corner, where
// depth is continuous), and the wall's light then lines the ceiling's edge.
float sample_weight(ivec3 t, uint j, vec4 w, vec3 n, ivec2 size)
{
    if (any(lessThan(t.xy, ivec2(0))) || any(greaterThanEqual(t.xy, size)))
        return 0.0;
    float zc = imageLoad(c0, t).w;
    if (!(zc > 0.0) || dot(rb_normal_unpack(imageLoad(c2, t).w), n) < h.params.z)
        return 0.0;
    // z_c where the surface lands: the sample's 1 / z moved along its slope
    vec2 slope = vec2(imageLoad(c1, t).w, imageLoad(c3, t).w);
    vec2 from = vec2(t.xy) + 0.5 + h.offset[j].xy;
    float inv_zc = 1.0 / zc + dot(slope, w.xy - from);
    return inv_zc > 0.0 ? weight(w.z, 1.0 / inv_zc) : 0.0;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(gb_position);
    if (any(greaterThanEqual(px, size)))
        return;
    uint l = h.info.x, mine = h.info.w;
    vec3 s0 = vec3(0.0), s1 = vec3(0.0), s2 = vec3(0.0), s3 = vec3(0.0);
    float sum = 0.0;
    uint count = 0u;
    ivec3 one = ivec3(px, int(mine)); // the texel of the one cache used alone
    bool surface = imageLoad(gb_position, px).w > 0.0;
    vec3 n = imageLoad(gb_normal, px).xyz;
    for (uint j = 0u; j < l && surface; j++) {
        uint a = (mine + l - j) % l; // slot j was written a frames ago
        if ((h.info.y & (1u << a)) == 0u)
            continue;
        vec4 w = imageLoad(where, ivec3(px, int(a)));
        if (w.w <= 0.0)
            continue;
        // The sample nearest the surface's position; at an edge, where that one saw another
        // surface (h below 1/2), the best of the four around it.
        vec2 at = w.xy - h.offset[j].xy; // in the cache's texels, samples at + 0.5
        ivec2 nearest = ivec2(floor(at)), corner = ivec2(floor(at - 0.5));
        ivec3 t = ivec3(nearest, int(j));
        float hj = sample_weight(t, j, w, n, size);
        bool edge = hj < 0.5;
        for (int k = 0; k < 4 && edge; k++) {
            ivec3 c = ivec3(corner + ivec2(k & 1, k >> 1), int(j));
            float hc = c.xy == nearest ? 0.0 : sample_weight(c, j, w, n, size);
            if (hc > hj) {
                hj = hc;
                t = c;
            }
        }
        if (!(hj > 0.0))
            continue;
        vec4 d0 = imageLoad(c0, t), d1 = imageLoad(c1, t), d3 = imageLoad(c3, t);
        s0 += hj * d0.rgb;
        s1 += hj * d1.rgb;
        s2 += hj * imageLoad(c2, t).rgb;
        s3 += hj * d3.rgb;
        sum += hj;
        count++;
        one = t;
    }
    vec3 r0, r1, r2, r3;
    if (count == 1u || count == 0u) { // its light as it is, not h L / h
        r0 = imageLoad(c0, one).rgb;
        r1 = imageLoad(c1, one).rgb;
        r2 = imageLoad(c2, one).rgb;
        r3 = imageLoad(c3, one).rgb;
    } else {
        float inv = 1.0 / sum;
        r0 = s0 * inv;
        r1 = s1 * inv;
        r2 = s2 * inv;
        r3 = s3 * inv;
    }
    imageStore(o0, px, vec4(r0, 0.0));
    imageStore(o1, px, vec4(r1, 0.0));
    imageStore(o2, px, vec4(r2, 0.0));
    imageStore(o3, px, vec4(r3, 0.0));
    hits[px.y * size.x + px.x] = surface ? sum / float(l) : 1.0;
}
