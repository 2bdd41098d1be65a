// view: world-space vertices (from animate) into one view of the raster-view pass. Perspective
// and orthographic views project here; for paraboloid views gl_Position is the vertex in the
// view's frame (its transform is affine), which view.tesc and view.tese project.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "view_shared.h"
#include "geometry_shared.h"

layout(std140, binding = RB_VIEW_BIND_VERTICES) uniform Geometry { rb_gpu_geometry geo; };
layout(std430, binding = RB_VIEW_BIND_VIEWS) readonly buffer Views { rb_gpu_view views[]; };
layout(std430, binding = RB_VIEW_BIND_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 0) out vec3 o_pos;
layout(location = 1) out vec3 o_normal;
layout(location = 2) out vec2 o_uv;
layout(location = 3) flat out uint o_material;

void main()
{
    rb_gpu_vertex v = geo.vertices.v[gl_VertexIndex];
    vec3 p = v.position.xyz;
    o_pos = p;
    o_normal = v.normal.xyz;
    o_uv = v.uv.xy;
    o_material = floatBitsToUint(v.uv.z);
    gl_Position = views[pc.index.x].transform * vec4(p, 1.0);
    // A blended material's triangle is in no view (no shadow, VPL, bundle or probe sees it):
    // all its vertices at one point make it empty, whatever the projection after this stage.
    if (materials[o_material].params.z < 0.0)
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
}
