// gbuffer: world-space vertices (from animate) to clip space, with the previous frame's
// position for motion vectors. A G-buffer of bdpt's temporal caches is drawn with its samples
// offset from the pixel centres (the push constant; 0 for the frame's own). The position is
// invariant: the reprojection pass draws the same surfaces again, testing depth for equality.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "geometry_shared.h"

layout(std140, binding = RB_BIND_GBUFFER_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std140, binding = RB_BIND_GBUFFER_VERTICES) uniform Geometry { rb_gpu_geometry geo; };
layout(std140, binding = RB_BIND_GBUFFER_PREV_VERTICES) uniform Prev { rb_gpu_geometry prev; };

layout(push_constant) uniform Jitter { vec4 jitter; } pc; // xy: the offset in clip space / w

invariant gl_Position;

layout(location = 0) out vec3 o_pos;
layout(location = 1) out vec3 o_normal;
layout(location = 2) out vec4 o_tangent;
layout(location = 3) out vec2 o_uv;
layout(location = 4) flat out uint o_material;
layout(location = 5) out vec4 o_clip;
layout(location = 6) out vec4 o_prev_clip;

void main()
{
    rb_gpu_vertex v = geo.vertices.v[gl_VertexIndex];
    o_pos = v.position.xyz;
    o_normal = v.normal.xyz;
    o_tangent = v.tangent;
    o_uv = v.uv.xy;
    o_material = floatBitsToUint(v.uv.z);
    o_clip = g.view_proj * vec4(v.position.xyz, 1.0);
    o_prev_clip = g.prev_view_proj * vec4(prev.vertices.v[gl_VertexIndex].position.xyz, 1.0);
    gl_Position = o_clip;
    gl_Position.xy += pc.jitter.xy * o_clip.w;
}
