// view, paraboloid views, depth output: the distance from the eye to the triangle along the
// pixel centre's direction, from the triangle's plane (exact, whatever the tessellation), into
// an R32F layer; the depth test uses it too. The map is the unit disk; texels outside it, and
// directions that meet the triangle's plane outside the triangle by more than a texel's
// footprint (pieces of a cut triangle reaching past its curved edges), draw nothing; nor does
// anything nearer than RB_VIEW_PARABOLOID_NEAR of the far distance, such as the surface a VPL
// sits on (its eye is best lifted off it a little, so that surface falls behind and is culled).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"

layout(std430, binding = RB_VIEW_BIND_VIEWS) readonly buffer Views { rb_gpu_view views[]; };
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 4) flat in vec3 i_tri[3];
layout(location = 0) out float o_depth;

// Signed distance of h from the edge a-b, positive on the triangle's side (normal n, unit).
float inside(vec3 a, vec3 b, vec3 h, vec3 n)
{
    vec3 e = b - a;
    return dot(cross(e, h - a), n) / length(e);
}

void main()
{
    vec2 q = gl_FragCoord.xy * pc.size.zw * 2.0 - 1.0;
    float r2 = dot(q, q);
    if (r2 > 1.0)
        discard;
    // The inverse of the map: the unit direction of the pixel centre in the view's frame.
    vec3 w = vec3(2.0 * q, 1.0 - r2) / (1.0 + r2);
    vec3 a = i_tri[0], b = i_tri[1], c = i_tri[2];
    vec3 n = cross(b - a, c - a);
    float t = dot(a, n) / dot(w, n); // distance, in units of the far distance
    if (!(t > RB_VIEW_PARABOLOID_NEAR && t <= 1.0))
        discard;
    // One texel spans at most 4 / size radians (the map's scale is at least 1/2).
    float tol = -t * 4.0 * pc.size.z;
    vec3 h = t * w, un = normalize(n);
    if (inside(a, b, h, un) < tol || inside(b, c, h, un) < tol || inside(c, a, h, un) < tol)
        discard;
    gl_FragDepth = t;
    o_depth = t / length(views[pc.index.x].transform[0].xyz);
}
