// shadow: world-space vertices into one layer of the shadow-map array (a cube face of a
// point light, a spot light's frustum, or a directional light's box).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared.h"

layout(std430, binding = 0) readonly buffer Verts { rb_gpu_vertex verts[]; };
layout(std430, binding = 1) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(push_constant) uniform Push { uint layer; } pc;

layout(location = 0) out vec3 o_pos;

void main()
{
    vec3 p = verts[gl_VertexIndex].position.xyz;
    o_pos = p;
    gl_Position = views[pc.layer].view_proj * vec4(p, 1.0);
}
