// shadow: stores the distance to the light (point, spot) or along the light (directional) in
// R32F, so the direct pass can filter by hand (lavapipe cannot filter depth formats).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared.h"

layout(std430, binding = 1) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(push_constant) uniform Push { uint layer; } pc;

layout(location = 0) in vec3 i_pos;
layout(location = 0) out float o_distance;

void main()
{
    rb_gpu_shadow_view v = views[pc.layer];
    if (uint(v.light.w) == RB_KIND_DIRECTIONAL)
        o_distance = dot(i_pos - v.light.xyz, v.axis.xyz);
    else
        o_distance = length(i_pos - v.light.xyz);
}
