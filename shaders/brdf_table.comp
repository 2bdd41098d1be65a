// brdf_table: evaluates rb_brdf (shaders/common/brdf.glsl) over a table of inputs, so a test can
// hold the shaders' BRDF to the CPU reference's (tests/unit/test_brdf_parity.c). Not a pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "brdf.glsl"

layout(local_size_x = 64) in;

// Per entry, 16 floats: n.xyz, roughness; v.xyz, f90; l.xyz, unused; c_diff.rgb, unused;
// then f0.rgb in a second array with the same index.
layout(std430, binding = RB_BIND_BRDF_TABLE_IN) readonly buffer In { vec4 inputs[]; };
layout(std430, binding = RB_BIND_BRDF_TABLE_OUT) writeonly buffer Out { vec4 outputs[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    vec4 a = inputs[5 * i + 0], b = inputs[5 * i + 1], c = inputs[5 * i + 2];
    vec4 d = inputs[5 * i + 3], e = inputs[5 * i + 4];
    outputs[i] = vec4(rb_brdf(a.xyz, b.xyz, c.xyz, d.rgb, e.rgb, b.w, a.w), 0.0);
}
