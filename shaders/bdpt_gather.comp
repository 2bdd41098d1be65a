// bdpt, gather (seed 000, A.1): the sub-images' light back to image order, the inverse of split.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BDPT_GATHER_IN + 0, rgba32f) uniform readonly image2D i0;
layout(binding = RB_BIND_BDPT_GATHER_IN + 1, rgba32f) uniform readonly image2D i1;
layout(binding = RB_BIND_BDPT_GATHER_IN + 2, rgba32f) uniform readonly image2D i2;
layout(binding = RB_BIND_BDPT_GATHER_IN + 3, rgba32f) uniform readonly image2D i3;
layout(binding = RB_BIND_BDPT_GATHER_OUT + 0, rgba32f) uniform writeonly image2D o0;
layout(binding = RB_BIND_BDPT_GATHER_OUT + 1, rgba32f) uniform writeonly image2D o1;
layout(binding = RB_BIND_BDPT_GATHER_OUT + 2, rgba32f) uniform writeonly image2D o2;
layout(binding = RB_BIND_BDPT_GATHER_OUT + 3, rgba32f) uniform writeonly image2D o3;
layout(push_constant) uniform Push { rb_gpu_bdpt_image_push pc; };

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, imageSize(o0))))
        return;
    int n = int(pc.split.x);
    ivec2 sp = (px % n) * ivec2(pc.split.yz) + px / n;
    imageStore(o0, px, imageLoad(i0, sp));
    imageStore(o1, px, imageLoad(i1, sp));
    imageStore(o2, px, imageLoad(i2, sp));
    imageStore(o3, px, imageLoad(i3, sp));
}
