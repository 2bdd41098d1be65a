// The connect and emitter_direct passes' shared part (bdpt_connect.comp and
// bdpt_emitter_direct.comp): their bindings, one layout for both, the connections from VPLs
// and bundle hits, and whether the emitters are in closed form.
#ifndef RB_BDPT_CONNECT_GLSL
#define RB_BDPT_CONNECT_GLSL

#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "brdf.glsl"
#include "encode.glsl"
#include "lights.glsl"
#include "view.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// What the bundles' emitter paths count for in their weights against the bounce VPLs, times
// their number: (c) of every bundle connects to all the frame's emitter points (emitters_at), and
// the emitter's bounce's (c) shares its bundle; twice the count measured best (the Cornell box at
// 128x128: relMSE 0.0093 at 1, 0.0080 at 2, 0.0081 at 3, 0.0084 at 4; the demo the same within
// 1%). The weights of a path still sum to one: only how it is shared changes.
const float emitter_bundle_count = 2.0;

layout(std140, binding = RB_BIND_BDPT_CONNECT_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(binding = RB_BIND_BDPT_CONNECT_SPLIT + 0, rgba32f) uniform readonly image2D s_position;
layout(binding = RB_BIND_BDPT_CONNECT_SPLIT + 1, rgba32f) uniform readonly image2D s_normal;
layout(binding = RB_BIND_BDPT_CONNECT_SPLIT + 2, rgba32f) uniform readonly image2D s_fresnel;
layout(binding = RB_BIND_BDPT_CONNECT_SPLIT + 3, rgba32f) uniform readonly image2D s_geometric;
layout(std430, binding = RB_BIND_BDPT_CONNECT_VPLS) readonly buffer Vpls { rb_gpu_vpl vpls[]; };
layout(std430, binding = RB_BIND_BDPT_CONNECT_VPL_VIEWS) readonly buffer VplViews { rb_gpu_view vpl_views[]; };
layout(binding = RB_BIND_BDPT_CONNECT_VPL_MAPS) uniform sampler2DArray vpl_maps;
layout(std430, binding = RB_BIND_BDPT_CONNECT_BUNDLE_VIEWS) readonly buffer BundleViews { rb_gpu_view bundle_views[]; };
layout(binding = RB_BIND_BDPT_CONNECT_HEADS, r32ui) uniform readonly uimage2DArray heads;
layout(std430, binding = RB_BIND_BDPT_CONNECT_NODES) readonly buffer Nodes { rb_gpu_list_node nodes[]; };
layout(std430, binding = RB_BIND_BDPT_CONNECT_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_BDPT_CONNECT_BDPT_LIGHTS) readonly buffer BdptLights { rb_gpu_bdpt_light blights[]; };
layout(std430, binding = RB_BIND_BDPT_CONNECT_SHADOW_VIEWS) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(binding = RB_BIND_BDPT_CONNECT_SHADOW_MAPS) uniform sampler2DArray shadow_maps;
layout(binding = RB_BIND_BDPT_CONNECT_ENV_MAP) uniform sampler2D env_map;
layout(binding = RB_BIND_BDPT_CONNECT_LIGHT + RB_BDPT_DIRECT_DIFFUSE, rgba32f) uniform image2D a_direct_diffuse;
layout(binding = RB_BIND_BDPT_CONNECT_LIGHT + RB_BDPT_DIRECT_SPECULAR, rgba32f) uniform image2D a_direct_specular;
layout(binding = RB_BIND_BDPT_CONNECT_LIGHT + RB_BDPT_INDIRECT_DIFFUSE, rgba32f) uniform image2D a_indirect_diffuse;
layout(binding = RB_BIND_BDPT_CONNECT_LIGHT + RB_BDPT_INDIRECT_SPECULAR, rgba32f) uniform image2D a_indirect_specular;
layout(std430, binding = RB_BIND_BDPT_CONNECT_EMIT_INFO) readonly buffer EmitInfo { rb_gpu_bdpt_emit_info emit_info; };
layout(binding = RB_BIND_BDPT_CONNECT_EMITTED + 0, rgba32f) uniform writeonly image2D e_diffuse;
layout(binding = RB_BIND_BDPT_CONNECT_EMITTED + 1, rgba32f) uniform writeonly image2D e_specular;
layout(std430, binding = RB_BIND_BDPT_CONNECT_LTC) readonly buffer Ltc { vec4 ltc[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_connect_push pc; };

#define RB_BDPT_LEAST_ROUGHNESS pc.frame.x
#include "bdpt_vpl.glsl"

#include "shadow.glsl"
#include "bundle_search.glsl"

// Whether VPL k sees p (geometric normal ng) through its paraboloid map: p is lifted off its
// surface by a texel's footprint along ng (at most 4 / size radians at the distance; 2 for an
// emitter's point, whose map draws the area light's shadows: at 4 the floor beside the Cornell
// box's short box saw past its bottom edge, and the direct layer measured 0.0015 against 0.0008,
// at 1 the surfaces shadowed themselves, 0.0014; the VPLs of the indirect light keep 4, at 2 the
// demo's floor under its hovering box took light), but never
// more than halfway to the VPL's plane, and its distance from the VPL's eye tested against the
// stored one with a bias of vpl_bias of it. Each of the K_v VPLs has a whole layer; their
// bounces (k >= K_v) a corner. Without the bound, a surface just above the VPL's plane, facing
// it, was lifted behind its hemisphere: the Cornell box's light quad hangs 0.9 units below the
// ceiling, and its points on the quad's back saw none of the ceiling farther than 58 units away
// (0.9 size / 4), which their light reaches beyond the quad's edges (the direct layer 0.0024,
// 0.0021 with the bound; the classic view's 0.0030, 0.0024).
float vpl_visibility(uint k, vec3 p, vec3 ng)
{
    rb_gpu_view v = vpl_views[k];
    float far = v.origin.w, size = k < uint(pc.frame.y) ? pc.params.y : float(pc.bounce.z);
    vec3 from_eye = p - v.origin.xyz;
    float texels = uint(vpls[k].from.w) == RB_BDPT_VPL_EMITTER ? 2.0 : 4.0;
    float lift = length(from_eye) * texels / size;
    float height = dot(from_eye, v.axis.xyz), toward = -dot(ng, v.axis.xyz);
    if (toward > 0.0 && height > 0.0)
        lift = min(lift, 0.5 * height / toward);
    p += ng * lift;
    vec3 q = (v.transform * vec4(p, 1.0)).xyz;
    float len = length(q);
    if (!(len > 0.0))
        return 0.0;
    vec3 w = q / len;
    if (w.z <= 0.0)
        return 0.0; // behind the VPL's hemisphere: it sends nothing there
    float dist = len * far;
    vec2 ndc = w.xy / (1.0 + w.z);
    ivec2 t = clamp(ivec2(floor((ndc * 0.5 + 0.5) * size)), ivec2(0), ivec2(int(size) - 1));
    float stored = texelFetch(vpl_maps, ivec3(t, int(k)), 0).r;
    return dist * (1.0 - pc.params.x) <= stored ? 1.0 : 0.0;
}

vec3 environment(vec3 dir)
{
    vec3 env = g.env_color.rgb;
    if (g.env.z > 0.5)
        env = textureLod(env_map, rb_equirect_uv(dir, g.env.y), 0.0).rgb;
    return env * g.env.x;
}

// Radiance VPL k sends from its surface towards p (normal n at p, facing the VPL), times the
// cosine at p, unshadowed: f_z power G, G = cos_z cos_p / (r^2 + spread), clamped at the clamp
// when one is set; an emitter's point sends its emission: power G. In vis, whether the VPL sees
// p through its map (0 or 1).
vec3 from_vpl_unshadowed(uint k, vec3 p, vec3 n, vec3 ng, bool clamp_g, float spread, out vec3 l,
                         out float r2, out float vis)
{
    rb_gpu_vpl z = vpls[k];
    vec3 d = z.position.xyz - p;
    r2 = dot(d, d);
    l = d * inversesqrt(max(r2, 1e-20));
    vis = 0.0;
    float cos_p = dot(n, l), cos_z = -dot(z.normal.xyz, l);
    if (cos_p <= 0.0 || cos_z <= 0.0 || dot(ng, l) <= 0.0)
        return vec3(0.0);
    float geo = cos_p * cos_z / max(r2 + spread, 1e-20);
    if (clamp_g && pc.counts.w > 0.0)
        geo = min(geo, pc.counts.w);
    vis = vpl_visibility(k, p, ng);
    if (uint(z.from.w) == RB_BDPT_VPL_EMITTER)
        return z.power.rgb * geo;
    return vpl_brdf(z, -l) * z.power.rgb * geo;
}

// The same, shadowed (times V).
vec3 from_vpl(uint k, vec3 p, vec3 n, vec3 ng, bool clamp_g, float spread, out vec3 l,
              out float r2)
{
    float vis;
    vec3 x = from_vpl_unshadowed(k, p, n, ng, clamp_g, spread, l, r2, vis);
    return vis > 0.0 ? x : vec3(0.0);
}

// a / pi for VPL k's disk of the area it stands for among the frame's K_v VPLs, a = 1 / (K_v p)
// (p its area density, normal.w): the emitters' points light as such disks in their direct light
// (bdpt_emitter_direct.comp), and every VPL does as vpl_spread of them under mis (vpl_disk). A
// bounce's p is its density given its parent (K_v earlier), which is where its parent happened to
// be: it stands for its parent's area and its own, 1 / p summed down to the first generation (the
// spread of a point found from a spread point). With its own p alone, a bounce's bounce that
// landed 0.9 units below its parent (the back of the Cornell box's light quad, under the ceiling,
// p = 0.26) lit as a point, where its first generation, a point on the quad (p = 3.6e-5), stands
// for a disk of radius 20.
float vpl_area(uint k)
{
    uint kv = uint(pc.frame.y);
    if (kv == 0u)
        return 0.0;
    float sum = 0.0;
    for (uint j = k;; j -= kv) {
        if (!(vpls[j].normal.w > 0.0))
            return 0.0;
        sum += 1.0 / vpls[j].normal.w;
        if (j < kv)
            break;
    }
    return sum / (RB_PI * pc.frame.y);
}

// The direction l from x toward punctual light L, its attenuation there (falloff and spot cone),
// and the squared distance (1 for a directional light).
void toward_light(rb_gpu_light L, vec3 x, out vec3 l, out float atten, out float dist2)
{
    uint kind = uint(L.position.w);
    dist2 = 1.0;
    if (kind == RB_KIND_DIRECTIONAL) {
        l = -L.direction.xyz;
        atten = 1.0;
        return;
    }
    vec3 d = L.position.xyz - x;
    dist2 = dot(d, d);
    float dist = sqrt(dist2);
    l = d / max(dist, 1e-8);
    atten = rb_light_falloff(dist, L.direction.w);
    if (kind == RB_KIND_SPOT)
        atten *= rb_spot_factor(L.direction.xyz, -l, L.cone.xy);
}

// The light z1 reflects towards x1 (direction v) from the punctual lights, each weighted
// against VPLs finding z1 (pdf_bundle: the bundle's area density of z1 seen from x1). The shadow
// test is one texel, a hard shadow: the VPLs that make the same paths see z1 through the light's
// reflective shadow map, hard too, and so does a point light (16-tap PCF cost the connect pass a
// quarter of its time on the demo and blurred a shadow that the bundle then averages anyway).
vec3 from_lights(vec3 z1, vec3 n, vec3 v, rb_material m, float pdf_bundle)
{
    vec3 sum = vec3(0.0);
    for (uint j = 0u; j < g.size.z; j++) {
        rb_gpu_light L = lights[j];
        uint kind = uint(L.position.w);
        vec3 l;
        float atten, dist2;
        toward_light(L, z1, l, atten, dist2);
        float cos_z = dot(n, l);
        if (cos_z <= 0.0 || atten <= 0.0)
            continue;
        int first = int(L.color.w);
        float vis = 1.0, w = 1.0;
        if (first >= 0) {
            uint layer = uint(first) + (kind == RB_KIND_POINT ? rb_cube_face(-l) : 0u);
            vis = shadow_lookup(layer, z1, n, cos_z, false);
            // VPLs come from shadowed lights only (generate): weigh against them.
            vec4 c = blights[j].choice;
            float pdf_vpl = rb_bdpt_vpl_density((1.0 - emit_info.info.x) * c.x * c.z, cos_z,
                                                kind == RB_KIND_DIRECTIONAL ? 1.0 : dist2);
            if (pc.index.w == RB_BDPT_MIS)
                w = rb_bdpt_balance(pc.counts.y, pdf_bundle, pc.counts.x, pdf_vpl);
        }
        if (vis <= 0.0)
            continue;
        sum += w * vis * surface_brdf(n, v, l, m) * L.color.rgb * atten * cos_z;
    }
    return sum;
}

void add(inout vec3 diffuse, inout vec3 specular, vec3 n, vec3 v, vec3 l, vec3 f0, float f90,
         float rough, vec3 x)
{
    vec3 kd, ks;
    rb_brdf_parts(n, v, l, f0, f90, rough, kd, ks);
    diffuse += kd * x;
    specular += ks * x;
}

// The squared radius over pi of the disk VPL j lights as, at x1 in (a) and at a bundle's hit in
// (c): vpl_spread (pc.offset.z) times the area it stands for among the frame's K_v,
// a = 1 / (K_v p), p its area density, as the emitters' points do in their direct light
// (Hasan et al. 2009 spread a VPL over a sphere for the same reason): cos cos / (r^2 + a / pi).
// A VPL drawn where its density is low stands for much of the surface around it, and as a point
// it lit what lies beside it: in (a), the bounce of a punctual VPL on the demo column's side
// (p = 0.0087, the floor at its foot seen from it at a grazing angle, where the bundles that
// weigh against it find the column as seldom) threw a spot of indirect 0.59 on the floor beside
// the column where the reference has 0.2, for four frames of 640x360 (0.23 with the disk); in
// (c), a punctual VPL on the back wall 0.2 below the ceiling lit the ceiling beside it, and
// the bundles from the wall below carried that corner's light back to it: the demo's two-bounce
// light at the top of the back wall came out twice the reference's, in every frame (the wall's
// top 0.72 against 0.53 at 640x360; 0.54 with the disk), a power heuristic weight of a third
// against the bounce VPL that makes the same paths still keeping a G twenty times the usual.
// The demo's frames 3-6, 11, 22 and 23 at 320x180 measured relMSE 0.0074, 0.0068, 0.0064,
// 0.0047, 0.0048, 0.0072, 0.0060 as points, 0.0068, 0.0062, 0.0058, 0.0041, 0.0042, 0.0062,
// 0.0050 with disks in (a), 0.0065, 0.0060, 0.0056, 0.0038, 0.0039, 0.0058, 0.0045 in both; the
// Cornell box, whose VPLs are the light quad's points and bounces, 0.0064, 0.0063, 0.0062.
// Under mis only: a strategy alone (vpl, bundle) keeps its points and converges to the reference
// as a point's estimate does (t0400: the bundles' mean indirect light 12% low with disks, at 128
// VPLs and bundles), which is what comparing the strategies is for.
float vpl_disk(uint j)
{
    return pc.index.w == RB_BDPT_MIS ? pc.offset.z * vpl_area(j) : 0.0;
}

// The roughness with which a surface reflects a VPL that lights as a disk of squared radius
// disk (vpl_disk) r2 away: at least the least roughness, and its alpha (roughness^2) widened by
// half the disk's radius over its distance, as Karis (2013) widens a lobe for a sphere light: a
// glossy lobe evaluated toward the disk's centre alone throws the whole disk's light into one
// direction. On the Cornell box, a bounce's bounce on the back of the light quad, 13.7 units
// from the ceiling beside it and 3.7 degrees below it, met the ceiling's lobe where the camera
// sees it at 15 degrees: 74 times the reference's light in one sample (with fresh samples,
// frames 70 to 73: relMSE 0.054); 2.4 with the lobe widened (and the disk of vpl_area).
float disk_roughness(float rough, float disk, float r2)
{
    float alpha = max(rough, RB_BDPT_LEAST_ROUGHNESS);
    if (!(disk > 0.0))
        return alpha;
    alpha = min(alpha * alpha + 0.5 * sqrt(disk / max(r2, 1e-20)), 1.0);
    return sqrt(alpha);
}

// (a) for VPL j: its light at x1 (lighting as a disk, vpl_disk), weighed by MIS against the
// bundle strategy that makes the same paths (n_o of its samples in this sub-image: bundles for
// punctual and emitter VPLs, with the balance heuristic; pairs for bounce VPLs, against their
// parent's (c), with the power heuristic), into the direct (an emitter's point) or indirect
// accumulators. Indirect light is reflected at x1 with the least roughness, as the bundles
// reflect it (and wider for a disk that is near, disk_roughness): MIS weighs two estimates of one
// integrand. With the material's own lobe here, a glossy face seen edge-on (the top of the
// demo's column in frame 23 at 320x180, n.v = 0.016) took a VPL near its mirror direction:
// indirect 27.6 under MIS before the filter (92.5 with VPLs alone), 13.8 in the image, where the
// reference has 0.8.
void from_vpl_at_x1(uint j, vec3 x1, vec3 n1, vec3 ng1, vec3 v1, vec3 f0, float f90, float rough,
                    float n_o, inout vec3 dd, inout vec3 ds, inout vec3 id, inout vec3 is)
{
    uint strategies = pc.index.w;
    float n_a = pc.counts.x;
    vec3 l;
    float r2;
    vec3 x = from_vpl(j, x1, n1, ng1, strategies == RB_BDPT_VPL, vpl_disk(j), l, r2);
    if (!any(greaterThan(x, vec3(0.0))))
        return;
    float w = 1.0;
    if (strategies == RB_BDPT_MIS) {
        float pdf_bundle = rb_bdpt_bundle_density(-dot(vpls[j].normal.xyz, l), r2);
        w = j == pc.index.x ? rb_bdpt_balance(n_a, vpls[j].normal.w, n_o, pdf_bundle)
                            : rb_bdpt_power(n_a, vpls[j].normal.w, n_o, pdf_bundle);
        // The clamp bounds w G, which the bundles' density keeps below it wherever a bundle can
        // make the same path; it bites where none can: a VPL on the back of a double-sided
        // surface, which the bundle search never finds (the Cornell box's light quad: a bounce's
        // bounce on its back lit the ceiling 0.9 units away at 29 times the reference).
        float geo = dot(n1, l) * -dot(vpls[j].normal.xyz, l) / max(r2, 1e-20);
        if (pc.counts.w > 0.0 && w * geo > pc.counts.w)
            w = pc.counts.w / geo;
    }
    if (uint(vpls[j].from.w) == RB_BDPT_VPL_EMITTER)
        add(dd, ds, n1, v1, l, f0, f90, rough, x * (w / n_a));
    else
        add(id, is, n1, v1, l, f0, f90, disk_roughness(rough, vpl_disk(j), r2), x * (w / n_a));
}

// The light VPL j sends to the bundle's hit z1 (normal nz, reached along dir from x1, cos_in
// there), lighting as a disk (vpl_disk), reflected at z1 towards x1, and in w its weight: with
// mis, the power heuristic against VPL j's bounce finding z1 through (a), p(z1 | z) against the
// bundle's density of z1 (its count n_c times count): where z1 is near z, the bounce's density
// grows as the 1/r^2 of G does, and takes most of those paths over; nothing is clamped.
vec3 at_bundle_hit(uint j, vec3 z1, vec3 nz, vec3 dir, rb_bundle_hit h, float cos_in, bool mis,
                   float count, out float w)
{
    vec3 l;
    float r2;
    w = 1.0;
    vec3 x = from_vpl(j, z1, nz, nz, false, vpl_disk(j), l, r2);
    if (!any(greaterThan(x, vec3(0.0))))
        return vec3(0.0);
    rb_material m = h.m;
    m.roughness = disk_roughness(m.roughness, vpl_disk(j), r2);
    x *= surface_brdf(nz, -dir, l, m);
    if (mis) {
        float pdf_bounce = rb_bdpt_bounce_density(-dot(vpls[j].normal.xyz, l), dot(nz, l), r2);
        float pdf_bundle = rb_bdpt_bundle_density(cos_in, h.t * h.t);
        w = rb_bdpt_power(pc.counts.z * count, pdf_bundle, pc.counts.x, pdf_bounce);
    }
    return x;
}

// (c) for VPL j: at_bundle_hit's light, times scale (the bundle's 2 pi cos1 / n_c), into x1's
// indirect accumulators.
void via_bundle(uint j, vec3 z1, vec3 nz, vec3 dir, rb_bundle_hit h, float cos_in, vec3 n1,
                vec3 v1, vec3 f0, float f90, float rough, float scale, bool mis, float count,
                inout vec3 id, inout vec3 is)
{
    float w;
    vec3 x = at_bundle_hit(j, z1, nz, dir, h, cos_in, mis, count, w);
    if (!any(greaterThan(x, vec3(0.0))))
        return;
    add(id, is, n1, v1, dir, f0, f90, max(rough, RB_BDPT_LEAST_ROUGHNESS), // as (b) does
        x * (w * scale));
}

// (c) from every emitter point among the frame's K_v VPLs at once: the light they send to the
// bundle's hit z1, reflected there towards x1, each weighed by at_bundle_hit (against the
// point's bounce, the bundles counting emitter_bundle_count times n_c), summed and divided by
// K_v as the emitters' dispatch divides its (a). With only VPL k's point, z1 saw one point's
// hard shadows, and each of the few bundle directions carried them across the surfaces near it:
// bands across the Cornell box's short box and streaks down the tall one's face, which the
// filter's block squared off. The points together draw the area light's soft shadow.
vec3 emitters_at(vec3 z1, vec3 nz, vec3 dir, rb_bundle_hit h, float cos_in, bool mis)
{
    vec3 sum = vec3(0.0);
    for (uint j = 0u; j < uint(pc.frame.y); j++) {
        if (!(vpls[j].position.w > 0.0) || uint(vpls[j].from.w) != RB_BDPT_VPL_EMITTER)
            continue;
        float w;
        vec3 x = at_bundle_hit(j, z1, nz, dir, h, cos_in, mis, emitter_bundle_count, w);
        sum += x * w;
    }
    return sum / max(pc.frame.y, 1.0);
}

// Whether the emitters' light is in closed form this frame (bdpt_generate.comp found few
// untextured emissive triangles, and the frame has points to shadow it with): then the emitters'
// dispatch makes all of it, and the bundles' emission hits none.
bool closed_form()
{
    return emit_info.info.z > 0.0 && pc.frame.y > 0.0;
}

#endif
