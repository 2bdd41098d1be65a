// transparency: the blended materials' triangles (world-space vertices from animate) to clip
// space, as gbuffer.vert projects them, so they meet the G-buffer's depth where it does.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "geometry_shared.h"

layout(std140, binding = RB_BIND_TRANSPARENCY_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std140, binding = RB_BIND_TRANSPARENCY_VERTICES) uniform Geometry { rb_gpu_geometry geo; };

invariant gl_Position;

layout(location = 0) out vec3 o_pos;
layout(location = 1) out vec3 o_normal;
layout(location = 2) out vec4 o_tangent;
layout(location = 3) out vec2 o_uv;
layout(location = 4) flat out uint o_material;

void main()
{
    rb_gpu_vertex v = geo.vertices.v[gl_VertexIndex];
    o_pos = v.position.xyz;
    o_normal = v.normal.xyz;
    o_tangent = v.tangent;
    o_uv = v.uv.xy;
    o_material = floatBitsToUint(v.uv.z);
    gl_Position = g.view_proj * vec4(v.position.xyz, 1.0);
}
