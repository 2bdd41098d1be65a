// What the bdpt passes that make VPLs share (generate, bounce): an empty VPL, a VPL's
// paraboloid view and an emitter VPL's probe. Needs view_shared.h, shared.h and bdpt_shared.h.

// A VPL that found no surface (position.w 0: connect skips it, and its map draws nothing) from
// the given light (from: as rb_gpu_vpl's; light: the light's index, 0xffffffff for an emitter's
// point or a bounce), which the caller fills in where it finds one.
rb_gpu_vpl no_vpl(vec4 from, uint light)
{
    rb_gpu_vpl o;
    o.position = vec4(0.0);
    o.normal = vec4(0.0, 0.0, 1.0, 0.0);
    o.power = vec4(0.0);
    o.from = from;
    o.material = uvec4(0u, 0u, light, 0u);
    return o;
}

// A unit vector perpendicular to n, the same for the same n.
vec3 perpendicular(vec3 n)
{
    return normalize(cross(abs(n.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0), n));
}

// The paraboloid view of view.c's rb_view_paraboloid: world to the frame (x right,
// y = axis x right, z axis), scaled by 1 / far.
rb_gpu_view paraboloid(vec3 eye, vec3 axis, float far)
{
    vec3 x = perpendicular(axis), y = cross(axis, x), z = axis;
    float s = 1.0 / far;
    rb_gpu_view v;
    v.transform = mat4(vec4(x.x, y.x, z.x, 0.0) * s, vec4(x.y, y.y, z.y, 0.0) * s,
                       vec4(x.z, y.z, z.z, 0.0) * s,
                       vec4(-dot(x, eye) * s, -dot(y, eye) * s, -dot(z, eye) * s, 1.0));
    v.origin = vec4(eye, far);
    v.axis = vec4(axis, 0.0);
    return v;
}

// How far a VPL's view reaches: the job's bounds across (radius r), with a margin.
float vpl_far(float r)
{
    return 2.1 * r;
}

// How far a VPL's (or a probe's) eye sits above its surface, so the surface itself is behind.
float vpl_lift(float r)
{
    return 2e-4 * vpl_far(r);
}

// A VPL's view: the hemisphere around its normal, from its lifted eye.
rb_gpu_view vpl_view(vec3 position, vec3 normal, float r)
{
    return paraboloid(position + normal * vpl_lift(r), normal, vpl_far(r));
}

// A probe: a perspective view along dir from eye, a 1x1 target whose one sample, at the
// pixel centre, looks exactly along dir, so its reflective-shadow-map texel is the first
// surface that ray meets (a ray cast by rasterization). Depth runs from near to far; the
// field of view is a milliradian.
rb_gpu_view probe_view(vec3 eye, vec3 dir, float near, float far)
{
    vec3 x = perpendicular(dir), y = cross(dir, x);
    float s = 1000.0, a = far / (far - near), b = -near * a;
    vec4 r0 = vec4(x * s, -dot(x, eye) * s), r1 = vec4(y * s, -dot(y, eye) * s);
    vec4 r3 = vec4(dir, -dot(dir, eye)), r2 = a * r3 + vec4(0.0, 0.0, 0.0, b);
    rb_gpu_view v;
    v.transform = transpose(mat4(r0, r1, r2, r3)); // rows r0..r3: world to clip
    v.origin = vec4(eye, far);
    v.axis = vec4(dir, 0.0);
    return v;
}

// A direction about n, distributed as its cosine, from two uniform numbers.
vec3 cosine_direction(vec3 n, vec2 u)
{
    vec3 x = perpendicular(n), y = cross(n, x);
    float r = sqrt(u.x), phi = 2.0 * RB_PI * u.y;
    return normalize(x * (r * cos(phi)) + y * (r * sin(phi)) + n * sqrt(max(0.0, 1.0 - u.x)));
}

// The probe of a VPL at position (normal n, on the side its light leaves from) for its bounce:
// along a cosine-distributed direction from two uniform numbers u, from its lifted eye; an
// empty view (every corner at the clip origin, which draws nothing) where it makes none.
rb_gpu_view bounce_probe(bool probes, vec3 position, vec3 n, vec2 u, float r)
{
    rb_gpu_view probe;
    probe.transform = mat4(0.0);
    probe.origin = vec4(0.0);
    probe.axis = vec4(0.0);
    if (probes) {
        float far = vpl_far(r);
        probe = probe_view(position + n * vpl_lift(r), cosine_direction(n, u), 1e-4 * far, far);
    }
    return probe;
}
