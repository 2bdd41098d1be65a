// bdpt, connect (seed 000, B.3; BDPT.md "Strategies"): iteration k of the frame's loop, over
// the camera vertices x1 of one sub-image of the split G-buffer. With VPL k (a light subpath
// light -> z) and bundle k (a direction d, its per-pixel lists):
//   (a) z -> x1 through z's paraboloid shadow map: paths light -> z -> x1 (one bounce);
//   (b) x1 -> z1, the nearest surface facing x1 along +-d (Program 1's search in x1's texel of
//       the bundle), then z1 -> each light through its shadow map (the same one-bounce paths,
//       from the other end), the environment when the ray escapes, z1's emission when it glows
//       (light reaching x1 after one scattering: direct light);
//   (c) z -> z1 through z's map, z1 -> x1 along the bundle: light -> z -> z1 -> x1 (two bounces).
// (a) and (b)'s light connections make the same paths and are combined with the balance
// heuristic over the sub-image's n_a VPLs and n_b bundles; (c) is the only strategy for its
// paths. Emitters: VPL k may be a point y0 on an emitter; its (a) is direct light, which the
// emitters' dispatch (below) makes at every pixel instead, from all the frame's emitter points,
// weighed against (b)'s emission hits; its (c), one bounce, every bundle makes with all the
// frame's emitter points too (emitters_at); its bounce VPL y1 (K_v + k, found by its probe)
// makes those one-bounce paths again through (a), and the two are weighed over the n_c pairs
// (counted twice) and n_a VPLs with p(y1 | y0) (y0's density is both sides' and cancels); the
// bounce VPL's (c) is the emitter's second bounce, the only strategy for it. What reaches x1
// is split into its BRDF's diffuse and specular parts (rb_brdf_parts)
// and added, in k order and without atomics, to x1's own texel of four accumulators.
// The emitters' dispatch (bounce.w = 1), once a frame over the whole split image: for each pixel
// the direct light of every emitter point among the frame's K_v VPLs, (a) with all of them, not
// the sub-image's share, written in image order to two images of its own that the filter adds
// after its kernels. A sub-image's one or two points, spread over the interleave block by the
// direct light's box, blurred every shadow edge of an area light over the block (the Cornell
// box's contact shadows, 2 pixels each way); at every pixel the points draw it sharp, and their
// count, K_v against the sub-image's n_a, enters the balance heuristic against the bundles.
#version 460
#extension GL_GOOGLE_include_directive : require
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
layout(push_constant) uniform Push { rb_gpu_bdpt_connect_push pc; };

#define RB_BDPT_LEAST_ROUGHNESS pc.frame.x
#include "bdpt_vpl.glsl"

#include "shadow.glsl"
#include "bundle_search.glsl"

// Whether VPL k sees p (geometric normal ng) through its paraboloid map: p is lifted off its
// surface by a texel's footprint along ng (at most 4 / size radians at the distance), but never
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
    float lift = length(from_eye) * 4.0 / size;
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

// The same, shadowed (times V) and without spread.
vec3 from_vpl(uint k, vec3 p, vec3 n, vec3 ng, bool clamp_g, out vec3 l, out float r2)
{
    float vis;
    vec3 x = from_vpl_unshadowed(k, p, n, ng, clamp_g, 0.0, l, r2, vis);
    return vis > 0.0 ? x : vec3(0.0);
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

// (a) for VPL j: its light at x1, weighed by MIS against the bundle strategy that makes the same
// paths (n_o of its samples in this sub-image: bundles for punctual and emitter VPLs, with the
// balance heuristic; pairs for bounce VPLs, against their parent's (c), with the power
// heuristic), into the direct (an emitter's point) or indirect accumulators. Indirect light is
// reflected at x1 with the least roughness, as the bundles reflect it: MIS weighs two estimates
// of one integrand. With the material's own lobe here, a glossy face seen edge-on (the top of
// the demo's column in frame 23 at 320x180, n.v = 0.016) took a VPL near its mirror direction:
// indirect 27.6 under MIS before the filter (92.5 with VPLs alone), 13.8 in the image, where the
// reference has 0.8.
void from_vpl_at_x1(uint j, vec3 x1, vec3 n1, vec3 ng1, vec3 v1, vec3 f0, float f90, float rough,
                    float n_o, inout vec3 dd, inout vec3 ds, inout vec3 id, inout vec3 is)
{
    uint strategies = pc.index.w;
    float n_a = pc.counts.x;
    vec3 l;
    float r2;
    vec3 x = from_vpl(j, x1, n1, ng1, strategies == RB_BDPT_VPL, l, r2);
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
        add(id, is, n1, v1, l, f0, f90, max(rough, RB_BDPT_LEAST_ROUGHNESS), x * (w / n_a));
}

// The light VPL j sends to the bundle's hit z1 (normal nz, reached along dir from x1, cos_in
// there), reflected at z1 towards x1, and in w its weight: with mis, the power heuristic against
// VPL j's bounce finding z1 through (a), p(z1 | z) against the bundle's density of z1 (its count
// n_c times count): where z1 is near z, the bounce's density grows as the 1/r^2 of G does, and
// takes those paths over; nothing is clamped.
vec3 at_bundle_hit(uint j, vec3 z1, vec3 nz, vec3 dir, rb_bundle_hit h, float cos_in, bool mis,
                   float count, out float w)
{
    vec3 l;
    float r2;
    w = 1.0;
    vec3 x = from_vpl(j, z1, nz, nz, false, l, r2);
    if (!any(greaterThan(x, vec3(0.0))))
        return vec3(0.0);
    x *= surface_brdf(nz, -dir, l, h.m);
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

// How much of the punctual lights' light reaches x1 (normal n1), as a luminance (irradiance /
// pi): through their shadow maps, one texel, hard. The filter's guide: its kernel stops where this
// changes by more than a factor, at a shadow's edge, which a contact shadow shares with the
// indirect light it cuts off (bdpt_filter.comp). The emitters' points are left out: a cache sees
// K_v of them, and their light's noise in a penumbra cut the kernel into bands that the Cornell
// box's indirect light then showed (beauty 0.0107 -> 0.0128 at 128x128).
float direct_guide(vec3 x1, vec3 n1)
{
    float sum = 0.0;
    for (uint j = 0u; j < g.size.z; j++) {
        rb_gpu_light L = lights[j];
        uint kind = uint(L.position.w);
        vec3 l;
        float atten, dist2;
        toward_light(L, x1, l, atten, dist2);
        float cos1 = dot(n1, l);
        if (cos1 <= 0.0 || atten <= 0.0)
            continue;
        int first = int(L.color.w);
        float vis = 1.0;
        if (first >= 0)
            vis = shadow_lookup(uint(first) + (kind == RB_KIND_POINT ? rb_cube_face(-l) : 0u),
                                x1, n1, cos1, false);
        sum += vis * rb_luminance(L.color.rgb) * atten * cos1 / RB_PI;
    }
    return sum;
}

// atan(y / x) for y >= 0, in [0, pi], from arithmetic alone: Abramowitz and Stegun 4.4.49 on
// [0, 1] (error under 2e-8), folded. The drivers' own atan differs in its last bits from one Mesa
// to the next, and the tarball must render another's bits exactly (check-dist).
float angle_of(float y, float x)
{
    float ax = abs(x), hi = max(ax, y);
    float t = hi > 0.0 ? min(ax, y) / hi : 0.0, s = t * t;
    float r = t * (1.0 + s * (-0.3333314528 + s * (0.1999355085 + s * (-0.1420889944 +
                   s * (0.1065626393 + s * (-0.0752896400 + s * (0.0429096138 +
                   s * (-0.0161657367 + s * 0.0028662257))))))));
    if (y > ax)
        r = 0.5 * RB_PI - r;
    return x < 0.0 ? RB_PI - r : r;
}

// The irradiance at x (normal n) from the frame's emissive triangles, unshadowed, in closed form
// (emit_info.tris, both sides emitting): each triangle clipped to x's upper half-space, then
// Lambert's sum over its edges, E = L / 2 |sum theta_k n . (v_k x v_k+1) / |v_k x v_k+1||.
vec3 closed_form_irradiance(vec3 x, vec3 n)
{
    vec3 sum = vec3(0.0);
    uint count = uint(emit_info.info.z);
    for (uint e = 0u; e < count; e++) {
        vec3 p[3] = vec3[3](emit_info.tris[4u * e].xyz, emit_info.tris[4u * e + 1u].xyz,
                            emit_info.tris[4u * e + 2u].xyz);
        // Sutherland-Hodgman against the plane n . (q - x) = 0: at most 4 corners.
        vec3 c[4];
        int m = 0;
        for (int k = 0; k < 3; k++) {
            vec3 a = p[k], b = p[(k + 1) % 3];
            float da = dot(n, a - x), db = dot(n, b - x);
            if (da > 0.0)
                c[m++] = a;
            if ((da > 0.0) != (db > 0.0))
                c[m++] = a + (b - a) * (da / (da - db));
        }
        if (m < 3)
            continue;
        float s = 0.0;
        for (int k = 0; k < m; k++) {
            vec3 a = normalize(c[k] - x), b = normalize(c[(k + 1) % m] - x);
            vec3 g = cross(a, b);
            float len = length(g);
            if (len > 1e-12)
                s += angle_of(len, dot(a, b)) * dot(n, g) / len;
        }
        sum += emit_info.tris[4u * e + 3u].rgb * (0.5 * abs(s));
    }
    return sum;
}

// The point of x's surface (normal n) at the centre of x's pixel px, where x is the cache's sample
// (the centre plus pc.offset.xy): along each axis, moved toward the centre by the offset's share
// of the way to the neighbouring sample on that side, where that sample lies on x's plane (within
// a thousandth of its distance; normal within 0.999); not moved along an axis where it does not,
// nor beyond the image. At the edge of a surface the centre may see another (the Cornell box's
// light quad in front of the ceiling behind it), and x's plane there is hidden from the camera.
vec3 at_pixel_centre(vec3 x, vec3 n, ivec2 px, ivec2 sub, int grid)
{
    vec3 c = x;
    for (int axis = 0; axis < 2; axis++) {
        float o = pc.offset[axis];
        if (o == 0.0)
            continue;
        ivec2 q = px;
        q[axis] += o > 0.0 ? -1 : 1;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, imageSize(e_diffuse))))
            continue;
        ivec2 sq = (q % grid) * sub + q / grid;
        vec4 pq = imageLoad(s_position, sq);
        vec3 d = pq.xyz - x;
        if (!(pq.w > 0.0) || abs(dot(n, d)) > 1e-3 * length(d) ||
            dot(imageLoad(s_normal, sq).xyz, n) < 0.999)
            continue;
        c += abs(o) * d;
    }
    return c;
}

// Whether the emitters' diffuse light is in closed form this frame (bdpt_generate.comp found few
// untextured emissive triangles, and the frame has points to shadow it with): then the emitters'
// dispatch makes all of it, and the bundles' emission hits keep their specular part.
bool closed_form()
{
    return emit_info.info.z > 0.0 && pc.frame.y > 0.0;
}

// The emitters' dispatch for split texel sp: the direct light of each of the frame's K_v VPLs
// that is a point on an emitter, at the pixel sp holds, weighed against the n_b bundles of the
// pixel's sub-image that find the emitter (rb_bdpt_balance with counts K_v and n_b). Where the
// frame's emitters are few untextured triangles (emit_info.info.z), the diffuse part is their
// closed-form irradiance times the points' shadowed share of theirs (the ratio estimator of
// Heitz et al. 2018), all of it, the bundles' emission hits keeping their specular part: the
// points' irradiance near an emitter is a spot per point (the Cornell box's ceiling beside the
// light quad, lit by its back 0.9 units below), and the closed form draws the emitter's shape;
// the points keep only the shadows' say. The closed form is taken at the pixel's centre
// (at_pixel_centre), where the reference and the G-buffer take the pixel, not at the cache's
// subpixel sample: behind the light quad's far edge it changes by orders of magnitude within a
// pixel (the bench's classic view at 128x128: relMSE 0.0189 at the samples, 0.0087 at the
// centres). A point
// stands for a = 1 / (K_v p) of the emitter's area (p its density) and lights as a disk of that
// area would: cos cos / (r^2 + a / pi), which near the emitter stays below the emitter's own
// radiance, as an area light's does, where a point's 1 / r^2 threw a bright dot on a surface
// just beside it (the Cornell box's ceiling around the quad that hangs 0.9 units below it).
void emitters(ivec2 sp)
{
    ivec2 sub = ivec2(pc.region.zw);
    int n = int(pc.frame.w);
    ivec2 px = (sp % sub) * n + sp / sub;
    if (any(greaterThanEqual(px, imageSize(e_diffuse))))
        return;
    vec3 dd = vec3(0.0), ds = vec3(0.0);
    vec4 pos = imageLoad(s_position, sp);
    uint strategies = pc.index.w;
    if (pos.w > 0.0 && strategies != RB_BDPT_BUNDLE) {
        vec3 x1 = pos.xyz;
        vec4 nr = imageLoad(s_normal, sp);
        vec4 fr = imageLoad(s_fresnel, sp);
        vec3 n1 = nr.xyz, f0 = fr.rgb, v1 = normalize(g.camera_pos.xyz - x1);
        vec3 ng1 = rb_oct_decode(imageLoad(s_geometric, sp).xy);
        float rough = nr.w, f90 = fr.a;
        uint k_v = uint(pc.frame.y), k_b = uint(pc.frame.z), count = uint(n * n);
        uint s = uint((sp.y / sub.y) * n + sp.x / sub.x);
        float n_b = float(rb_bdpt_share(k_b, s, count)), n_a = pc.frame.y;
        bool closed = closed_form();
        vec3 shadowed = vec3(0.0), unshadowed = vec3(0.0);
        for (uint j = 0u; j < k_v; j++) {
            if (!(vpls[j].position.w > 0.0) || uint(vpls[j].from.w) != RB_BDPT_VPL_EMITTER)
                continue;
            vec3 l;
            float r2, vis;
            float spread = pc.frame.y > 0.0 && vpls[j].normal.w > 0.0
                               ? 1.0 / (RB_PI * n_a * vpls[j].normal.w)
                               : 0.0;
            vec3 x = from_vpl_unshadowed(j, x1, n1, ng1, strategies == RB_BDPT_VPL, spread, l, r2,
                                         vis);
            if (!any(greaterThan(x, vec3(0.0))))
                continue;
            if (closed)
                unshadowed += x;
            if (!(vis > 0.0))
                continue;
            float w = 1.0;
            if (strategies == RB_BDPT_MIS) {
                float pdf_bundle = rb_bdpt_bundle_density(-dot(vpls[j].normal.xyz, l), r2);
                w = rb_bdpt_balance(n_a, vpls[j].normal.w, n_b, pdf_bundle);
            }
            if (closed) {
                vec3 kd, ks;
                rb_brdf_parts(n1, v1, l, f0, f90, rough, kd, ks);
                shadowed += kd * x;
                ds += ks * x * (w / n_a);
            } else {
                add(dd, ds, n1, v1, l, f0, f90, rough, x * (w / n_a));
            }
        }
        if (closed) {
            vec3 e = closed_form_irradiance(at_pixel_centre(x1, n1, px, sub, n), n1);
            dd = mix(vec3(0.0), shadowed / max(unshadowed, vec3(1e-30)) * e,
                     greaterThan(unshadowed, vec3(0.0)));
        }
    }
    // The filter's guide rides in the alpha.
    float guide = pos.w > 0.0 ? direct_guide(pos.xyz, imageLoad(s_normal, sp).xyz) : 0.0;
    imageStore(e_diffuse, px, vec4(dd, guide));
    imageStore(e_specular, px, vec4(ds, 0.0));
}

void main()
{
    if (pc.bounce.w != 0u) {
        ivec2 sp = ivec2(gl_GlobalInvocationID.xy);
        if (all(lessThan(sp, imageSize(s_position))))
            emitters(sp);
        return;
    }
    uvec2 local = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(local, pc.region.zw)))
        return;
    ivec2 sp = ivec2(pc.region.xy + local);
    vec4 pos = imageLoad(s_position, sp);
    if (pos.w <= 0.0)
        return;
    vec3 x1 = pos.xyz;
    vec4 nr = imageLoad(s_normal, sp);
    vec4 fr = imageLoad(s_fresnel, sp);
    vec3 n1 = nr.xyz, f0 = fr.rgb, v1 = normalize(g.camera_pos.xyz - x1);
    vec3 ng1 = rb_oct_decode(imageLoad(s_geometric, sp).xy);
    float rough = nr.w, f90 = fr.a;
    uint k = pc.index.x, strategies = pc.index.w;
    bool has_vpl = pc.index.y != 0u && vpls[k].position.w > 0.0, has_bundle = pc.index.z != 0u;
    bool has_bounce = pc.bounce.x != RB_NONE && vpls[pc.bounce.x].position.w > 0.0;
    bool has_bounce2 = pc.bounce.y != RB_NONE && vpls[pc.bounce.y].position.w > 0.0;
    float n_a = pc.counts.x, n_b = pc.counts.y, n_c = pc.counts.z;
    vec3 dd = vec3(0.0), ds = vec3(0.0), id = vec3(0.0), is = vec3(0.0);

    // (a) VPL k -> x1: light reflected once before x1 (an emitter's point, direct light, is the
    // emitters' dispatch's); then the same for VPL k's bounce, light reflected once, weighed
    // against (c) of emitter VPLs.
    if (strategies != RB_BDPT_BUNDLE) {
        if (has_vpl && uint(vpls[k].from.w) != RB_BDPT_VPL_EMITTER)
            from_vpl_at_x1(k, x1, n1, ng1, v1, f0, f90, rough, n_b, dd, ds, id, is);
        // (the emitter paths' bundles count emitter_bundle_count times, a punctual VPL's once)
        if (has_bounce) {
            bool emitted = uint(vpls[pc.bounce.x].from.w) == RB_BDPT_VPL_BOUNCE;
            from_vpl_at_x1(pc.bounce.x, x1, n1, ng1, v1, f0, f90, rough,
                           n_c * (emitted ? emitter_bundle_count : 1.0), dd, ds, id, is);
        }
        if (has_bounce2)
            from_vpl_at_x1(pc.bounce.y, x1, n1, ng1, v1, f0, f90, rough,
                           n_c * emitter_bundle_count, dd, ds, id, is);
    }

    // (b) and (c) along bundle k: the direction leaves x1 on its geometric front side, uniform
    // over that hemisphere (pdf 1 / 2 pi).
    if (has_bundle) {
        vec3 d = bundle_views[k].axis.xyz;
        float s = dot(ng1, d) >= 0.0 ? 1.0 : -1.0;
        vec3 dir = s * d;
        float cos1 = dot(n1, dir);
        if (cos1 > 0.0) {
            rb_bundle_hit h =
                rb_bundle_search(bundle_views[k], int(pc.params.z), uint(pc.params.w), x1, s);
            float scale = cos1 * 2.0 * RB_PI;
            if (!h.found) {
                add(dd, ds, n1, v1, dir, f0, f90, rough, environment(dir) * (scale / n_b));
            } else {
                vec3 z1 = x1 + dir * h.t, nz = h.n;
                if (dot(nz, dir) > 0.0)
                    nz = -nz;
                float cos_in = -dot(nz, dir);
                if (any(greaterThan(h.m.emission, vec3(0.0))) && strategies != RB_BDPT_VPL) {
                    // Weighed against the emitters' points (a), all K_v of the frame's VPLs at
                    // every pixel; alone when it is the only strategy or the scene's emitters
                    // have no points (zero density).
                    float w = 1.0;
                    if (strategies == RB_BDPT_MIS) {
                        float lum = rb_luminance(h.m.emission);
                        float pdf_bundle = rb_bdpt_bundle_density(abs(cos_in), h.t * h.t);
                        w = rb_bdpt_balance(n_b, pdf_bundle, pc.frame.y, emit_info.info.y * lum);
                    }
                    // Its diffuse part is the emitters' dispatch's alone where the emitters are
                    // in closed form there.
                    vec3 diffuse = vec3(0.0);
                    add(diffuse, ds, n1, v1, dir, f0, f90, rough, h.m.emission * (w * scale / n_b));
                    if (!(closed_form() && strategies == RB_BDPT_MIS))
                        dd += diffuse;
                }
                if (strategies != RB_BDPT_VPL && cos_in > 0.0) {
                    float pdf_bundle = rb_bdpt_bundle_density(cos_in, h.t * h.t);
                    vec3 x = from_lights(z1, nz, -dir, h.m, pdf_bundle);
                    // x1's lobe at its least roughness (bdpt_vpl.glsl): a bundle's direction is
                    // uniform, a few a pixel, and a glossy lobe seen at a grazing angle turned
                    // the one near its peak into a bright fringe down the demo column's edge.
                    add(id, is, n1, v1, dir, f0, f90, max(rough, RB_BDPT_LEAST_ROUGHNESS),
                        x * (scale / n_b));
                }
                if (strategies != RB_BDPT_VPL && cos_in > 0.0) {
                    // (c) of the emitters' points, all of them (emitters_at), as (b) does.
                    vec3 x = emitters_at(z1, nz, dir, h, cos_in, strategies == RB_BDPT_MIS);
                    add(id, is, n1, v1, dir, f0, f90, max(rough, RB_BDPT_LEAST_ROUGHNESS),
                        x * (scale / n_b));
                }
                if (n_c > 0.0) {
                    // (c): VPL k -> z1 -> x1: two bounces from a punctual light's VPL (an
                    // emitter's point is all the points' above); and from an emitter's bounce,
                    // two bounces. Each time the VPL's own bounce makes the same paths through
                    // (a): weighed against it under mis, left to it under vpl. A punctual VPL's
                    // bounce, and an emitter's bounce's bounce, have no (c): it would be a
                    // third bounce.
                    bool mis = strategies == RB_BDPT_MIS;
                    if (has_vpl && strategies != RB_BDPT_VPL &&
                        uint(vpls[k].from.w) != RB_BDPT_VPL_EMITTER)
                        via_bundle(k, z1, nz, dir, h, cos_in, n1, v1, f0, f90, rough,
                                   scale / n_c, mis, 1.0, id, is);
                    if (has_bounce && strategies != RB_BDPT_VPL &&
                        uint(vpls[pc.bounce.x].from.w) == RB_BDPT_VPL_BOUNCE)
                        via_bundle(pc.bounce.x, z1, nz, dir, h, cos_in, n1, v1, f0, f90, rough,
                                   scale / n_c, mis, emitter_bundle_count, id, is);
                }
            }
        }
    }

    imageStore(a_direct_diffuse, sp, imageLoad(a_direct_diffuse, sp) + vec4(dd, 0.0));
    imageStore(a_direct_specular, sp, imageLoad(a_direct_specular, sp) + vec4(ds, 0.0));
    imageStore(a_indirect_diffuse, sp, vec4(imageLoad(a_indirect_diffuse, sp).rgb + id, 1.0));
    imageStore(a_indirect_specular, sp, imageLoad(a_indirect_specular, sp) + vec4(is, 0.0));
}
