// output: packs the frame's layers into one buffer for a single readback, in the order
// RB_OUT_* gives (beauty RGBA, direct, indirect, albedo, normal, depth, motion). The direct
// integrator has no indirect light: zero. Every value written that is NaN or infinite is
// counted in `nonfinite` (an integer atomic add, so the count does not depend on the order).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"

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

// The band of rows this dispatch writes: Out is bound from the band's first row, so indices
// into it count from there (lib/passes/output.c splits frames larger than one binding may be).
layout(push_constant) uniform Band
{
    uint first_row;
    uint row_count;
} band;

uint bad = 0u;

// Writes one float and counts it when its exponent is all ones (NaN or Inf): a test of the bits,
// which no floating-point optimization can fold away.
void put(uint i, float x)
{
    o[i] = x;
    bad += (floatBitsToUint(x) & 0x7f800000u) == 0x7f800000u ? 1u : 0u;
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
    uint base = (row * g.size.x + px.x) * RB_OUT_FLOATS;
    put(base + RB_OUT_BEAUTY + 0, b.r);
    put(base + RB_OUT_BEAUTY + 1, b.g);
    put(base + RB_OUT_BEAUTY + 2, b.b);
    put(base + RB_OUT_BEAUTY + 3, hit ? 1.0 : 0.0);
    put(base + RB_OUT_DIRECT + 0, d.r);
    put(base + RB_OUT_DIRECT + 1, d.g);
    put(base + RB_OUT_DIRECT + 2, d.b);
    put(base + RB_OUT_INDIRECT + 0, 0.0);
    put(base + RB_OUT_INDIRECT + 1, 0.0);
    put(base + RB_OUT_INDIRECT + 2, 0.0);
    put(base + RB_OUT_ALBEDO + 0, a.r);
    put(base + RB_OUT_ALBEDO + 1, a.g);
    put(base + RB_OUT_ALBEDO + 2, a.b);
    put(base + RB_OUT_NORMAL + 0, n.x);
    put(base + RB_OUT_NORMAL + 1, n.y);
    put(base + RB_OUT_NORMAL + 2, n.z);
    put(base + RB_OUT_DEPTH, hit ? pos.w : 0.0);
    put(base + RB_OUT_MOTION + 0, m.x);
    put(base + RB_OUT_MOTION + 1, m.y);
    put(base + RB_OUT_FLOATS - 1, 0.0);
    if (bad > 0u)
        atomicAdd(nonfinite, bad);
}
