// reproject (seed 000, section A; Nehab et al. 2007): reverse reprojection, drawn after the
// G-buffer. Each vertex of the frame is also placed where it was a frames ago, for every age a
// the caches have: frame f - a's world vertex (the animate pass's, so its nodes, skin and
// morphs as they were then) through frame f - a's camera. The position is the G-buffer's,
// bit for bit (invariant, the same expression), so the depth test EQUAL keeps exactly the
// surfaces the G-buffer holds.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "geometry_shared.h"

layout(std140, binding = RB_BIND_REPROJECT_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std140, binding = RB_BIND_REPROJECT_HISTORY) uniform History { rb_gpu_bdpt_history h; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 0) uniform V0 { rb_gpu_geometry v0; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 1) uniform V1 { rb_gpu_geometry v1; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 2) uniform V2 { rb_gpu_geometry v2; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 3) uniform V3 { rb_gpu_geometry v3; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 4) uniform V4 { rb_gpu_geometry v4; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 5) uniform V5 { rb_gpu_geometry v5; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 6) uniform V6 { rb_gpu_geometry v6; };
layout(std140, binding = RB_BIND_REPROJECT_VERTICES + 7) uniform V7 { rb_gpu_geometry v7; };

invariant gl_Position;

// Per age: clip x, y, w in frame f - a, and the view depth there.
layout(location = 0) out vec4 o_then[RB_BDPT_MAX_CACHES];

vec3 then_position(uint a)
{
    uint i = uint(gl_VertexIndex);
    switch (a) {
    case 0u: return v0.vertices.v[i].position.xyz;
    case 1u: return v1.vertices.v[i].position.xyz;
    case 2u: return v2.vertices.v[i].position.xyz;
    case 3u: return v3.vertices.v[i].position.xyz;
    case 4u: return v4.vertices.v[i].position.xyz;
    case 5u: return v5.vertices.v[i].position.xyz;
    case 6u: return v6.vertices.v[i].position.xyz;
    default: return v7.vertices.v[i].position.xyz;
    }
}

void main()
{
    // As gbuffer.vert computes it (the frame's own G-buffer: no offset).
    vec4 clip = g.view_proj * vec4(v0.vertices.v[gl_VertexIndex].position.xyz, 1.0);
    gl_Position = clip;
    for (uint a = 0u; a < h.info.x; a++) { // the ages past l are never read
        vec4 x = vec4(then_position(a), 1.0);
        vec4 c = h.view_proj[a] * x;
        o_then[a] = vec4(c.xy, c.w, dot(h.depth_row[a], x));
    }
}
