// view, paraboloid views: how finely each triangle is cut so that its edges follow the
// projection's curves (Brabec et al. 2002; seed 000, B.3). The points arrive in the view's frame,
// scaled so that the far distance is 1. A segment of length s at distance d from the eye moves
// the map by at most s / d in NDC units (the projection's scale is 1 / (1 + cos theta) <= 1 over
// the hemisphere), so cutting an edge of length L into n = ceil(L size / (2 d_min C)) equal parts
// keeps every projected piece within C texels.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"

layout(vertices = 3) out;
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

// The level of edge a-b; the same bits whichever triangle shares the edge and in which order,
// so neighbours cut it at the same points.
float edge_level(vec3 a, vec3 b)
{
    if (a.x > b.x || (a.x == b.x && (a.y > b.y || (a.y == b.y && a.z > b.z)))) {
        vec3 t = a;
        a = b;
        b = t;
    }
    vec3 e = b - a;
    float len = length(e);
    float s = clamp(-dot(a, e) / max(dot(e, e), 1e-30), 0.0, 1.0);
    float d_min = max(length(a + s * e), 1e-30);
    float n = ceil(len * pc.size.x / (2.0 * d_min * RB_VIEW_TESS_CHORD_PX));
    return clamp(n, 1.0, RB_VIEW_TESS_MAX_LEVEL);
}

void main()
{
    gl_out[gl_InvocationID].gl_Position = gl_in[gl_InvocationID].gl_Position;
    if (gl_InvocationID != 0)
        return;
    vec3 p0 = gl_in[0].gl_Position.xyz, p1 = gl_in[1].gl_Position.xyz;
    vec3 p2 = gl_in[2].gl_Position.xyz;
    // Wholly behind the hemisphere, or without area: level 0 drops the patch.
    bool behind = p0.z < 0.0 && p1.z < 0.0 && p2.z < 0.0;
    bool empty = cross(p1 - p0, p2 - p0) == vec3(0.0);
    if (behind || empty) {
        gl_TessLevelOuter[0] = gl_TessLevelOuter[1] = gl_TessLevelOuter[2] = 0.0;
        gl_TessLevelInner[0] = 0.0;
        return;
    }
    // Outer level i is the edge opposite point i. The outer levels alone shape the patch's
    // outline on the map, which is all the coverage depends on (depth comes from the plane in
    // the fragment shader); the inner level only cuts the inside into pieces, and at the outer
    // levels' maximum a patch next to the eye made level^2 of them (a VPL on a curved surface:
    // 19 times the whole pass's time), so it is an eighth of it.
    float l0 = edge_level(p1, p2), l1 = edge_level(p2, p0), l2 = edge_level(p0, p1);
    gl_TessLevelOuter[0] = l0;
    gl_TessLevelOuter[1] = l1;
    gl_TessLevelOuter[2] = l2;
    gl_TessLevelInner[0] = max(1.0, ceil(max(l0, max(l1, l2)) / 8.0));
}
