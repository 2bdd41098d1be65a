// bdpt, generate (seed 000, B.1; BDPT.md "How each vertex is generated"): from the frame's
// fixed quasi-random table, VPL i (a light chosen by power, a direction from it, and the surface
// its reflective shadow map sees there) with its paraboloid view, and bundle i's orthographic
// view: direction uniform over the sphere, its grid fitted across the box of the points the
// G-buffer sees (bounds), its depth range spanning the job's bounds, so that every occluder
// along a bundle ray is in its list.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "brdf.glsl"
#include "lights.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = RB_BIND_BDPT_GENERATE_BOUNDS) readonly buffer Bounds
{
    uint lo[4];
    uint hi[4];
};
layout(std430, binding = RB_BIND_BDPT_GENERATE_SAMPLES) readonly buffer Samples { rb_gpu_bdpt_sample samples[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_BDPT_LIGHTS) readonly buffer BdptLights { rb_gpu_bdpt_light blights[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_RSM_VIEWS) readonly buffer RsmViews { rb_gpu_shadow_view rsm_views[]; };
layout(binding = RB_BIND_BDPT_GENERATE_RSM_POSITION, rgba32f) uniform readonly image2DArray rsm_position;
layout(binding = RB_BIND_BDPT_GENERATE_RSM_NORMAL, rgba32f) uniform readonly image2DArray rsm_normal;
layout(binding = RB_BIND_BDPT_GENERATE_RSM_MATERIAL, rg32ui) uniform readonly uimage2DArray rsm_material;
layout(std430, binding = RB_BIND_BDPT_GENERATE_VPLS) writeonly buffer Vpls { rb_gpu_vpl vpls[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_VPL_VIEWS) writeonly buffer VplViews { rb_gpu_view vpl_views[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_BUNDLE_VIEWS) writeonly buffer BundleViews { rb_gpu_view bundle_views[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_generate_push pc; };

float unordered(uint u)
{
    return uintBitsToFloat((u & 0x80000000u) != 0u ? u & 0x7fffffffu : ~u);
}

vec3 sphere(vec2 u)
{
    float z = 1.0 - 2.0 * u.x, r = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * RB_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
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

void bundle(uint i)
{
    vec3 d = sphere(samples[pc.counts.x + i].u.xy);
    vec3 right = perpendicular(d), up = cross(d, right);
    vec3 blo = vec3(unordered(lo[0]), unordered(lo[1]), unordered(lo[2]));
    vec3 bhi = vec3(unordered(hi[0]), unordered(hi[1]), unordered(hi[2]));
    if (!(blo.x <= bhi.x)) { // the camera sees nothing: the job's bounds
        blo = pc.scene.xyz - vec3(pc.scene.w);
        bhi = pc.scene.xyz + vec3(pc.scene.w);
    }
    vec2 a = vec2(3.0e38), b = vec2(-3.0e38);
    for (int c = 0; c < 8; c++) {
        vec3 corner = vec3((c & 1) != 0 ? bhi.x : blo.x, (c & 2) != 0 ? bhi.y : blo.y,
                           (c & 4) != 0 ? bhi.z : blo.z);
        vec2 q = vec2(dot(corner, right), dot(corner, up));
        a = min(a, q);
        b = max(b, q);
    }
    // Square texels, a texel's margin around the box.
    float half_size = max(max(b.x - a.x, b.y - a.y) * 0.5, 1e-6 * pc.scene.w);
    half_size *= 1.0 + 2.0 / pc.sizes.x;
    vec2 c = 0.5 * (a + b);
    float near = dot(pc.scene.xyz, d) - pc.scene.w * 1.01, depth = pc.scene.w * 2.02;
    rb_gpu_view v;
    v.transform = mat4(vec4(right.x / half_size, up.x / half_size, d.x / depth, 0.0),
                       vec4(right.y / half_size, up.y / half_size, d.y / depth, 0.0),
                       vec4(right.z / half_size, up.z / half_size, d.z / depth, 0.0),
                       vec4(-c.x / half_size, -c.y / half_size, -near / depth, 1.0));
    v.origin = vec4(right * c.x + up * c.y + d * near, half_size);
    v.axis = vec4(d, 2.0 * half_size / pc.sizes.x);
    bundle_views[i] = v;
}

void vpl(uint i)
{
    vec3 u = samples[i].u.xyz;
    uint count = pc.counts.z, j = 0u;
    while (j + 1u < count && u.x >= blights[j].choice.y)
        j++;
    rb_gpu_light L = lights[j];
    rb_gpu_bdpt_light B = blights[j];
    uint kind = uint(L.position.w);
    int first = int(L.color.w);
    float size = float(pc.counts.w);
    rb_gpu_vpl o;
    o.position = vec4(0.0);
    o.normal = vec4(0.0, 0.0, 1.0, 0.0);
    o.power = vec4(0.0);
    o.from = vec4(kind == RB_KIND_DIRECTIONAL ? -L.direction.xyz : L.position.xyz, float(kind));
    o.material = uvec4(0u, 0u, j, 0u);
    uint layer;
    ivec2 texel;
    vec3 w = vec3(0.0);
    if (kind == RB_KIND_DIRECTIONAL) {
        layer = uint(first);
        texel = ivec2(u.yz * size);
    } else {
        if (kind == RB_KIND_SPOT) {
            vec3 a = L.direction.xyz, x = perpendicular(a), y = cross(a, x);
            float ct = 1.0 - u.y * (1.0 - B.choice.w), st = sqrt(max(0.0, 1.0 - ct * ct));
            float phi = 2.0 * RB_PI * u.z;
            w = normalize(x * (st * cos(phi)) + y * (st * sin(phi)) + a * ct);
            layer = uint(first);
        } else {
            w = sphere(u.yz);
            layer = uint(first) + rb_cube_face(w);
        }
        vec4 clip = rsm_views[layer].view_proj * vec4(L.position.xyz + w, 1.0);
        texel = ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * size));
    }
    texel = clamp(texel, ivec2(0), ivec2(int(size) - 1));
    vec4 p = imageLoad(rsm_position, ivec3(texel, int(layer)));
    if (first >= 0 && p.w > 0.0 && B.choice.x > 0.0) {
        vec3 n = imageLoad(rsm_normal, ivec3(texel, int(layer))).xyz;
        vec3 to_light;
        float dist2 = 1.0;
        vec3 intensity = L.color.rgb;
        if (kind == RB_KIND_DIRECTIONAL) {
            to_light = -L.direction.xyz;
        } else {
            vec3 t = L.position.xyz - p.xyz;
            dist2 = dot(t, t);
            float dist = sqrt(dist2);
            to_light = t / dist;
            intensity *= rb_light_falloff(dist, L.direction.w) * dist2; // the window alone
            if (kind == RB_KIND_SPOT)
                intensity *= rb_spot_factor(L.direction.xyz, -to_light, L.cone.xy);
        }
        float cos_in = dot(n, to_light);
        if (cos_in > 0.0) {
            // B.choice.z: the density of the direction (point, spot) or of the beam point.
            float pdf = B.choice.x * B.choice.z;
            o.position = vec4(p.xyz, 1.0);
            o.normal = vec4(n, rb_bdpt_vpl_density(pdf, cos_in, dist2)); // dist2 = 1: directional
            o.power = vec4(intensity / pdf, 0.0);
            o.material.xy = imageLoad(rsm_material, ivec3(texel, int(layer))).xy;
        }
    }
    vpls[i] = o;
    // The VPL's hemisphere, its eye a hair above the surface so the surface itself is behind.
    float far = 2.1 * pc.scene.w;
    vec3 n = o.normal.xyz;
    vpl_views[i] = paraboloid(o.position.xyz + n * (2e-4 * far), n, far);
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.counts.x)
        vpl(i);
    if (i < pc.counts.y)
        bundle(i);
}
