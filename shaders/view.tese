// view, paraboloid views: each tessellated point onto the map, (x, y) / (|p| + z) for the point
// p in the view's frame (Brabec et al. 2002). The triangle itself goes on, flat, so the fragment
// shader can intersect its plane exactly instead of trusting interpolation in a curved map.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"

layout(triangles, equal_spacing, ccw) in;

layout(location = 4) flat out vec3 o_tri[3];

void main()
{
    vec3 a = gl_in[0].gl_Position.xyz, b = gl_in[1].gl_Position.xyz, c = gl_in[2].gl_Position.xyz;
    vec3 p = gl_TessCoord.x * a + gl_TessCoord.y * b + gl_TessCoord.z * c;
    float d = length(p);
    // Straight behind the eye the map goes to infinity: keep it finite, far off the map.
    float den = max(d + p.z, max(1e-6 * d, 1e-30));
    gl_Position = vec4(p.xy / den, 0.5, 1.0);
    o_tri[0] = a;
    o_tri[1] = b;
    o_tri[2] = c;
}
