// bdpt, bounds (seed 000, B.1): the bounding box of the points the G-buffer sees, which each
// ray-bundle's projection is fitted to. Each invocation takes a 4x4 lattice of pixels 8 apart
// (RB_BDPT_BOUNDS_TILE_PX across a workgroup), so that the workgroup's reduction in shared
// memory, whose barriers cost more than the fetches on a CPU device, is paid once for 1024
// pixels; then the workgroup adds its box with integer atomic min and max on order-preserving
// float bits, so the box does not depend on the order the workgroups run in. The pass fills lo
// with ~0 and hi with 0.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "bdpt_shared.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BDPT_BOUNDS_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(std430, binding = RB_BIND_BDPT_BOUNDS_OUT) buffer Bounds
{
    uint lo[4];
    uint hi[4];
};

shared vec3 s_lo[64];
shared vec3 s_hi[64];

// Unsigned integers in the order of the floats they encode.
uint ordered(float f)
{
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : u | 0x80000000u;
}

void main()
{
    ivec2 base = ivec2(gl_WorkGroupID.xy) * RB_BDPT_BOUNDS_TILE_PX + ivec2(gl_LocalInvocationID.xy);
    uint i = gl_LocalInvocationIndex;
    ivec2 size = imageSize(gb_position);
    const float big = 3.0e38;
    vec3 lo3 = vec3(big), hi3 = vec3(-big);
    for (int y = 0; y < RB_BDPT_BOUNDS_TILE_PX; y += 8)
        for (int x = 0; x < RB_BDPT_BOUNDS_TILE_PX; x += 8) {
            ivec2 px = base + ivec2(x, y);
            vec4 p = all(lessThan(px, size)) ? imageLoad(gb_position, px) : vec4(0.0);
            if (p.w > 0.0) {
                lo3 = min(lo3, p.xyz);
                hi3 = max(hi3, p.xyz);
            }
        }
    s_lo[i] = lo3;
    s_hi[i] = hi3;
    barrier();
    for (uint step = 32u; step > 0u; step >>= 1) {
        if (i < step) {
            s_lo[i] = min(s_lo[i], s_lo[i + step]);
            s_hi[i] = max(s_hi[i], s_hi[i + step]);
        }
        barrier();
    }
    if (i == 0u && s_lo[0].x <= s_hi[0].x)
        for (int c = 0; c < 3; c++) {
            atomicMin(lo[c], ordered(s_lo[0][c]));
            atomicMax(hi[c], ordered(s_hi[0][c]));
        }
}
