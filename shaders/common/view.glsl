// The raster views' shared GLSL: the depth each kind stores and the list node's normal encoding.
// Needs rb_gpu_view (view_shared.h).
#ifndef RB_VIEW_GLSL
#define RB_VIEW_GLSL

// The depth a view stores for world point p: the distance from the eye (perspective) or from
// the near plane along the axis (orthographic). Paraboloid views store the distance from the
// eye too, computed per pixel in view_paraboloid.frag.
float rb_view_depth(rb_gpu_view v, uint kind, vec3 p)
{
    if (kind == RB_VIEW_ORTHOGRAPHIC)
        return dot(p - v.origin.xyz, v.axis.xyz);
    return length(p - v.origin.xyz);
}

// A unit vector as polar angles, 16 bits each (seed 000, B.2): theta = acos(z) in [0, pi] in the
// low half, phi = atan(y, x) in [-pi, pi] (0 at the poles) in the high half, both rounded to the
// nearest step.
uint rb_view_polar_encode(vec3 n)
{
    const float pi = 3.14159265358979;
    float theta = acos(clamp(n.z, -1.0, 1.0));
    float phi = n.x == 0.0 && n.y == 0.0 ? 0.0 : atan(n.y, n.x); // atan(0, 0) is undefined
    uint t = uint(round(theta / pi * 65535.0));
    uint f = uint(round((phi / (2.0 * pi) + 0.5) * 65535.0));
    return min(t, 65535u) | (min(f, 65535u) << 16);
}

#endif
