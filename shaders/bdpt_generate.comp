// bdpt, generate (seed 000, B.1; BDPT.md "How each vertex is generated"): from the frame's
// fixed quasi-random table, VPL i (a light chosen by power, a direction from it, and the surface
// its reflective shadow map sees there) with its paraboloid view, and bundle i's orthographic
// view: direction uniform over the sphere, its grid fitted across the box of the points the
// G-buffer sees (bounds), its depth range spanning the job's bounds, so that every occluder
// along a bundle ray is in its list.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "geometry_shared.h"
#include "brdf.glsl"
#include "lights.glsl"
#include "material.glsl"
#include "view.glsl"
#include "bdpt_views.glsl"

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
layout(std140, binding = RB_BIND_BDPT_GENERATE_VERTICES) uniform Geometry { rb_gpu_geometry geo; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_EMITTERS) readonly buffer Emitters { rb_gpu_bdpt_emitter emitters[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(binding = RB_BIND_BDPT_GENERATE_SRGB_TEXTURES) uniform sampler2DArray srgb_textures;
layout(binding = RB_BIND_BDPT_GENERATE_LINEAR_TEXTURES) uniform sampler2DArray linear_textures;
layout(std430, binding = RB_BIND_BDPT_GENERATE_EMIT_INFO) writeonly buffer EmitInfo { rb_gpu_bdpt_emit_info emit_info; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_PROBE_VIEWS) writeonly buffer ProbeViews { rb_gpu_view probe_views[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_VPL_DRAWS) writeonly buffer VplDraws { uint vpl_draws[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_PROBE_DRAWS) writeonly buffer ProbeDraws { uint probe_draws[]; };
layout(std430, binding = RB_BIND_BDPT_GENERATE_EMITTER_CDF) readonly buffer Cdf { float cdf[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_generate_push pc; };

#include "bdpt_emitters.glsl"

// S, the emitters' summed weight: the end of bdpt_emitters.comp's CDF.
float emitter_sum()
{
    return cdf[uint(pc.sizes.w) - 1u];
}

float unordered(uint u)
{
    return uintBitsToFloat((u & 0x80000000u) != 0u ? u & 0x7fffffffu : ~u);
}

vec3 sphere(vec2 u)
{
    float z = 1.0 - 2.0 * u.x, r = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * RB_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
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

// VPL i as a point y0 on an emitter (u.x rescaled to [0, 1) by the caller): the triangle by
// its weight, then uniformly by area, and a side by the remainder of u.x; it sends its
// emission Le over that side's hemisphere. Its power is Le / p_A(y0), p_A(y0) = P_e w_t / S /
// area_t / 2 = P_e lum_t / (2 S); its density for MIS takes lum_t from the emission as the
// bundles' nodes store it, so that the two strategies' weights are computed from one value.
rb_gpu_vpl emitter_vpl(vec3 u, float p_e, float sum)
{
    rb_gpu_vpl o = no_vpl(vec4(0.0, 0.0, 0.0, float(RB_BDPT_VPL_EMITTER)), 0xffffffffu);
    // The first triangle whose running sum passes the target: a binary search of the CDF.
    float target = u.x * sum;
    uint lo = 0u, hi = uint(pc.sizes.w) - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[mid] > target)
            hi = mid;
        else
            lo = mid + 1u;
    }
    uint e = lo;
    vec3 p0, p1, p2;
    float cum = e > 0u ? cdf[e - 1u] : 0.0, w = emitter_weight(e, p0, p1, p2);
    if (!(w > 0.0))
        return o;
    float rest = clamp((target - cum) / max(cdf[e] - cum, 1e-30), 0.0, 1.0);
    float su = sqrt(u.y), b1 = su * (1.0 - u.z), b2 = su * u.z, b0 = 1.0 - b1 - b2;
    uvec4 t = emitters[e].tri;
    vec3 n = normalize(cross(p1 - p0, p2 - p0)) * (rest < 0.5 ? 1.0 : -1.0);
    vec2 uv = b0 * geo.vertices.v[t.x].uv.xy + b1 * geo.vertices.v[t.y].uv.xy + b2 * geo.vertices.v[t.z].uv.xy;
    rb_surface m = rb_material_eval(materials[t.w], uv, srgb_textures, linear_textures);
    float lum = rb_luminance(max(materials[t.w].emissive.rgb, vec3(0.0)));
    float pdf = p_e * lum / (2.0 * sum);
    if (!(pdf > 0.0))
        return o;
    rb_material q = rb_material_unpack(rb_material_pack(vec3(0.0), vec3(0.0), 1.0, m.emission));
    o.position = vec4(b0 * p0 + b1 * p1 + b2 * p2, 1.0);
    o.normal = vec4(n, p_e * rb_luminance(max(q.emission, vec3(0.0))) / (2.0 * sum));
    o.power = vec4(m.emission / pdf, 0.0);
    return o;
}

// VPL i of a punctual light (u.x rescaled to [0, 1) by the caller): the light by power, a
// direction from it, and the surface its RSM sees there, reflecting what it receives.
rb_gpu_vpl light_vpl(vec3 u, float p_e)
{
    uint count = pc.counts.z, j = 0u;
    while (j + 1u < count && u.x >= blights[j].choice.y)
        j++;
    rb_gpu_light L = lights[j];
    rb_gpu_bdpt_light B = blights[j];
    uint kind = uint(L.position.w);
    int first = int(L.color.w);
    float size = float(pc.counts.w);
    rb_gpu_vpl o =
        no_vpl(vec4(kind == RB_KIND_DIRECTIONAL ? -L.direction.xyz : L.position.xyz, float(kind)), j);
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
            float pdf = (1.0 - p_e) * B.choice.x * B.choice.z;
            o.position = vec4(p.xyz, 1.0);
            o.normal = vec4(n, rb_bdpt_vpl_density(pdf, cos_in, dist2)); // dist2 = 1: directional
            o.power = vec4(intensity / pdf, 0.0);
            o.material.xy = imageLoad(rsm_material, ivec3(texel, int(layer))).xy;
        }
    }
    return o;
}

// The chance P_e that a VPL is a point on an emitter rather than a punctual light's: the
// emitters' power (pi Le A on each of two sides) over all (BDPT.md, emitters); sum: S.
float emitter_chance(out float sum)
{
    sum = pc.sizes.w > 0.0 ? emitter_sum() : 0.0;
    float flux = 2.0 * RB_PI * sum, total = flux + pc.sizes.z;
    return total > 0.0 ? flux / total : 0.0;
}

void vpl(uint i)
{
    vec3 u = samples[i].u.xyz;
    float sum, p_e = emitter_chance(sum);
    rb_gpu_vpl o = u.x < p_e ? emitter_vpl(vec3(u.x / p_e, u.yz), p_e, sum)
                             : light_vpl(vec3(min((u.x - p_e) / (1.0 - p_e), 1.0), u.yz), p_e);
    vpls[i] = o;
    vec3 n = o.normal.xyz;
    vpl_views[i] = vpl_view(o.position.xyz, n, pc.scene.w);
    // A VPL also probes, along a cosine-distributed direction about the side its light leaves
    // from, for the surface that light reaches first: the bounce VPL (bdpt_bounce.comp). A VPL
    // without a surface draws no map, and its probe nothing (its view is empty: every corner
    // at the clip origin).
    vpl_draws[i * RB_BDPT_DRAW_UINTS + RB_BDPT_DRAW_INSTANCES] = o.position.w > 0.0 ? 1u : 0u;
    bool probes = o.position.w > 0.0;
    probe_draws[i * RB_BDPT_DRAW_UINTS + RB_BDPT_DRAW_INSTANCES] = probes ? 1u : 0u;
    probe_views[i] = bounce_probe(probes, o.position.xyz, n, samples[i].v.xy, pc.scene.w);
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    uint count = uint(pc.sizes.w);
    bool closed = count <= uint(RB_BDPT_ANALYTIC_MAX);
    for (uint e = 0u; closed && e < count; e++)
        closed = materials[emitters[e].tri.w].textures.w < 0;
    if (i == 0u) {
        float sum, p_e = emitter_chance(sum);
        emit_info.info = vec4(p_e, sum > 0.0 ? p_e / (2.0 * sum) : 0.0,
                              closed ? float(count) : 0.0, 0.0);
    }
    if (closed && i < count) {
        uvec4 t = emitters[i].tri;
        emit_info.tris[4u * i + 0u] = vec4(geo.vertices.v[t.x].position.xyz, 0.0);
        emit_info.tris[4u * i + 1u] = vec4(geo.vertices.v[t.y].position.xyz, 0.0);
        emit_info.tris[4u * i + 2u] = vec4(geo.vertices.v[t.z].position.xyz, 0.0);
        emit_info.tris[4u * i + 3u] = vec4(materials[t.w].emissive.rgb, 0.0);
    }
    if (i < pc.counts.x)
        vpl(i);
    if (i < pc.counts.y)
        bundle(i);
}
