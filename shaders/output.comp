// output: packs the frame's layers into one buffer for a single readback: the beauty (RGBA),
// then the layers the job writes, in the order direct, indirect, albedo, normal, depth, motion,
// indirect_diffuse, indirect_specular, samples, tiles (with all of them, the RB_OUT_* layout).
// The direct integrator has no indirect light: zero; bdpt's is textured and added here, its two
// parts summed exactly into indirect. samples and tiles are the hybrid's stats image as its
// diffuse filter wrote it, zero without one. After the transparency pass, the blended layers'
// light goes over the beauty and the direct layer (premultiplied), and the light behind them
// passes scaled by their transmittance. Every value written that is NaN or infinite is
// counted in `nonfinite` (an integer atomic add, so the count does not depend on the order).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "brdf.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std140, binding = RB_BIND_OUTPUT_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(binding = RB_BIND_OUTPUT_BEAUTY, rgba32f) uniform readonly image2D beauty;
layout(binding = RB_BIND_OUTPUT_DIRECT, rgba32f) uniform readonly image2D direct;
layout(binding = RB_BIND_OUTPUT_ALBEDO, rgba32f) uniform readonly image2D gb_albedo;
layout(binding = RB_BIND_OUTPUT_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_OUTPUT_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_OUTPUT_MOTION, rgba32f) uniform readonly image2D gb_motion;
layout(std430, binding = RB_BIND_OUTPUT_READBACK) writeonly buffer Out { float o[]; };
layout(std430, binding = RB_BIND_OUTPUT_NONFINITE) buffer Nonfinite { uint nonfinite; };
layout(binding = RB_BIND_OUTPUT_SPECULAR, rgba32f) uniform readonly image2D gb_specular;
layout(binding = RB_BIND_OUTPUT_LIGHT + RB_BDPT_DIRECT_DIFFUSE, rgba32f) uniform readonly image2D direct_diffuse;
layout(binding = RB_BIND_OUTPUT_LIGHT + RB_BDPT_DIRECT_SPECULAR, rgba32f) uniform readonly image2D direct_specular;
layout(binding = RB_BIND_OUTPUT_LIGHT + RB_BDPT_INDIRECT_DIFFUSE, rgba32f) uniform readonly image2D indirect_diffuse;
layout(binding = RB_BIND_OUTPUT_LIGHT + RB_BDPT_INDIRECT_SPECULAR, rgba32f) uniform readonly image2D indirect_specular;
layout(binding = RB_BIND_OUTPUT_STATS, rgba32f) uniform readonly image2D stats;
layout(binding = RB_BIND_OUTPUT_TRANSPARENCY, rgba32f) uniform readonly image2D transparency;

// The band of rows this dispatch writes: Out is bound from the band's first row, so indices
// into it count from there (lib/passes/output.c splits frames larger than one binding may be).
// A pixel holds the beauty, then the job's layers in RB_LAYER order (rb_layer_offset in
// lib/core/layers.c): only what the EXR will hold is written and read back.
layout(push_constant) uniform Band
{
    uint first_row;
    uint row_count;
    uint layer_mask;
    uint floats_per_pixel;
    uint has_light; // bdpt's gathered light is bound
    uint has_stats; // the hybrid's samples (rg) and tile masks (ba) are bound
    uint has_transparency; // the transparency pass's light (rgb) and transmittance (a) are bound
} band;

uint bad = 0u;

// Writes one float and counts it when its exponent is all ones (NaN or Inf): a test of the bits,
// which no floating-point optimization can fold away.
void put(uint i, float x)
{
    o[i] = x;
    bad += (floatBitsToUint(x) & 0x7f800000u) == 0x7f800000u ? 1u : 0u;
}

// Writes the n components of v as layer `layer` when the job asks for it; advances at.
void layer(uint layer, vec3 v, uint n, inout uint at)
{
    if ((band.layer_mask & (1u << layer)) == 0u)
        return;
    for (uint c = 0u; c < n; c++)
        put(at + c, v[c]);
    at += n;
}

void main()
{
    uint row = gl_GlobalInvocationID.y; // within the band
    uvec2 px = uvec2(gl_GlobalInvocationID.x, band.first_row + row);
    if (px.x >= g.size.x || row >= band.row_count)
        return;
    ivec2 ip = ivec2(px);
    vec4 pos = imageLoad(gb_position, ip);
    bool hit = pos.w > 0.0;
    vec4 b = imageLoad(beauty, ip);
    vec3 d = imageLoad(direct, ip).rgb;
    vec3 a = hit ? imageLoad(gb_albedo, ip).rgb : vec3(0.0);
    vec3 n = hit ? imageLoad(gb_normal, ip).xyz : vec3(0.0);
    vec2 m = hit ? imageLoad(gb_motion, ip).xy : vec2(0.0);
    // precise: no product is fused into the sum, so ind is exactly ind_d + ind_s as written.
    precise vec3 ind_d = vec3(0.0), ind_s = vec3(0.0), ind = vec3(0.0);
    if (band.has_light != 0u && hit) {
        // Texturing (seed 000, Figure 3 b): the light was gathered without the maps.
        float s = rb_spec_map(imageLoad(gb_specular, ip).rgb);
        vec3 more = a * imageLoad(direct_diffuse, ip).rgb + s * imageLoad(direct_specular, ip).rgb;
        ind_d = a * imageLoad(indirect_diffuse, ip).rgb;
        ind_s = s * imageLoad(indirect_specular, ip).rgb;
        ind = ind_d + ind_s;
        d += more;
        b.rgb += more + ind;
    }
    float alpha = hit ? 1.0 : 0.0;
    if (band.has_transparency != 0u) {
        // Premultiplied over: the blended layers' light, plus what lies behind them times the
        // fraction that passes. Their light is direct light; the indirect light behind passes.
        vec4 t = imageLoad(transparency, ip);
        b.rgb = t.rgb + t.a * b.rgb;
        d = t.rgb + t.a * d;
        ind_d *= t.a;
        ind_s *= t.a;
        ind = ind_d + ind_s;
        alpha = 1.0 - t.a * (1.0 - alpha);
    }
    uint base = (row * g.size.x + px.x) * band.floats_per_pixel;
    put(base + 0u, b.r);
    put(base + 1u, b.g);
    put(base + 2u, b.b);
    put(base + 3u, alpha);
    uint at = base + 4u;
    layer(RB_LAYER_DIRECT, d, 3u, at);
    layer(RB_LAYER_INDIRECT, ind, 3u, at); // the direct integrator has none
    layer(RB_LAYER_ALBEDO, a, 3u, at);
    layer(RB_LAYER_NORMAL, n, 3u, at);
    layer(RB_LAYER_DEPTH, vec3(hit ? pos.w : 0.0, 0.0, 0.0), 1u, at);
    layer(RB_LAYER_MOTION, vec3(m, 0.0), 2u, at);
    layer(RB_LAYER_INDIRECT_DIFFUSE, ind_d, 3u, at);
    layer(RB_LAYER_INDIRECT_SPECULAR, ind_s, 3u, at);
    bool wants_stats = (band.layer_mask & (3u << RB_LAYER_SAMPLES)) != 0u; // samples, tiles
    vec4 st = band.has_stats != 0u && wants_stats ? imageLoad(stats, ip) : vec4(0.0);
    layer(RB_LAYER_SAMPLES, vec3(st.rg, 0.0), 2u, at);
    layer(RB_LAYER_TILES, vec3(st.ba, 0.0), 2u, at);
    for (; at < base + band.floats_per_pixel; at++)
        put(at, 0.0); // padding to 16 bytes a pixel
    if (bad > 0u)
        atomicAdd(nonfinite, bad);
}
