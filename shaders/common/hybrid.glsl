// The hybrid integrator's resources (one binding table for all its passes) and what its passes
// share: the quasi-random numbers of a ray, BRDF sampling of each lobe, shading at a hit,
// reprojection into the previous frame. The including shader defines its local size first.
#ifndef RB_HYBRID_GLSL
#define RB_HYBRID_GLSL

#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "hybrid_shared.h"
#include "bvh_shared.h"
#include "geometry_shared.h"
#include "brdf.glsl"
#include "encode.glsl"
#include "lights.glsl"
#include "material.glsl"

layout(std140, binding = RB_BIND_HYBRID_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(binding = RB_BIND_HYBRID_GB_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_HYBRID_GB_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_HYBRID_GB_ALBEDO, rgba32f) uniform readonly image2D gb_albedo;
layout(binding = RB_BIND_HYBRID_GB_SPECULAR, rgba32f) uniform readonly image2D gb_specular;
layout(binding = RB_BIND_HYBRID_GB_EMISSION, rgba32f) uniform readonly image2D gb_emission;
layout(binding = RB_BIND_HYBRID_GB_MOTION, rgba32f) uniform readonly image2D gb_motion;
layout(std430, binding = RB_BIND_HYBRID_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_HYBRID_SHADOW_VIEWS) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(binding = RB_BIND_HYBRID_SHADOW_MAPS) uniform sampler2DArray shadow_maps;
layout(binding = RB_BIND_HYBRID_ENV_MAP) uniform sampler2D env_map;
layout(binding = RB_BIND_HYBRID_DIRECT, rgba32f) uniform readonly image2D direct_light;
layout(std430, binding = RB_BIND_HYBRID_HIZ) buffer Hiz { vec2 hiz[]; };
layout(std430, binding = RB_BIND_HYBRID_SLOTS) buffer Slots { rb_gpu_hybrid_slot slots[]; };
layout(std430, binding = RB_BIND_HYBRID_COUNTERS) buffer Counters { rb_gpu_hybrid_counters counters; };
layout(std430, binding = RB_BIND_HYBRID_QUEUE) buffer Queue { uint queue[]; };
layout(std430, binding = RB_BIND_HYBRID_BLOCKS) buffer Blocks { uint blocks[]; };
layout(std430, binding = RB_BIND_HYBRID_BVH_NODES) readonly buffer BvhNodes { rb_gpu_bvh_node bvh_nodes[]; };
// Bound as far as the BVH's triangles; the baked points and words that follow them, which grow
// with the scene's triangles, are read by the buffer's address (table.bake, table.bake_words).
layout(std430, binding = RB_BIND_HYBRID_BVH_TRIS) readonly buffer BvhTris { rb_gpu_bvh_triangle bvh_tris[]; };
// The world vertices, the triangles' indices followed by the emitter and sky tables, and the
// bake, by their device addresses (geometry_shared.h: no binding's range bounds them):
// vertex_at, index_at, baked_point and bake_word below.
layout(std140, binding = RB_BIND_HYBRID_VERTICES) uniform Geometry { rb_gpu_geometry geo; };
layout(std140, binding = RB_BIND_HYBRID_INDICES) uniform Table { rb_gpu_hybrid_table table; };
layout(std430, binding = RB_BIND_HYBRID_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(binding = RB_BIND_HYBRID_SRGB_TEXTURES) uniform sampler2DArray srgb_textures;
layout(binding = RB_BIND_HYBRID_LINEAR_TEXTURES) uniform sampler2DArray linear_textures;
layout(binding = RB_BIND_HYBRID_ACC_PREV, rgba32f) uniform readonly image2DArray acc_prev;
layout(binding = RB_BIND_HYBRID_ACC, rgba32f) uniform image2DArray acc;
layout(std430, binding = RB_BIND_HYBRID_TILES) buffer Tiles { float tiles[]; };
layout(binding = RB_BIND_HYBRID_STATS, rgba32f) uniform image2D stats;
layout(binding = RB_BIND_HYBRID_LIGHT + RB_BDPT_DIRECT_DIFFUSE, rgba32f) uniform writeonly image2D o_direct_diffuse;
layout(binding = RB_BIND_HYBRID_LIGHT + RB_BDPT_DIRECT_SPECULAR, rgba32f) uniform writeonly image2D o_direct_specular;
layout(binding = RB_BIND_HYBRID_LIGHT + RB_BDPT_INDIRECT_DIFFUSE, rgba32f) uniform writeonly image2D o_indirect_diffuse;
layout(binding = RB_BIND_HYBRID_LIGHT + RB_BDPT_INDIRECT_SPECULAR, rgba32f) uniform writeonly image2D o_indirect_specular;

layout(push_constant) uniform Push { rb_gpu_hybrid_push pc; };

rb_gpu_vertex vertex_at(uint i)
{
    return geo.vertices.v[i];
}

uint index_at(uint i)
{
    return table.indices.u[i];
}

vec4 baked_point(uint i)
{
    return table.bake.v[i];
}

uint bake_word(uint i)
{
    return table.bake_words.u[i];
}

#include "shadow.glsl"
#include "punctual.glsl"

// The BVH passes through the texels of an alpha-masked material under its cutoff, as the
// G-buffer discards them and the reference's rays pass them, and through blended materials,
// which are no occluders (the transparency pass draws them over the frame).
bool rb_hybrid_bvh_filter(uint t, vec2 bary)
{
    rb_gpu_vertex v0 = vertex_at(index_at(3u * t));
    rb_gpu_material m = materials[floatBitsToUint(v0.uv.z)];
    if (m.params.z < 0.0)
        return false;
    if (!(m.params.z > 0.0))
        return true;
    float a = m.base_color.a;
    if (m.textures.x >= 0) {
        vec2 uv = (1.0 - bary.x - bary.y) * v0.uv.xy + bary.x * vertex_at(index_at(3u * t + 1u)).uv.xy +
                  bary.y * vertex_at(index_at(3u * t + 2u)).uv.xy;
        a *= textureLod(srgb_textures, vec3(uv, float(m.textures.x)), 0.0).a;
    }
    return a >= m.params.z;
}
#define RB_BVH_FILTER rb_hybrid_bvh_filter

#include "bvh.glsl"

uint rb_hybrid_slot(uint lobe, uint ray, ivec2 px)
{
    return ((lobe * pc.frame.y + ray) * g.size.y + uint(px.y)) * g.size.x + uint(px.x);
}

// The pixel of a slot.
ivec2 rb_hybrid_slot_pixel(uint slot)
{
    return ivec2(slot % g.size.x, (slot / g.size.x) % g.size.y);
}

// Where a pixel's rays start: its G-buffer point moved off the surface along the geometric
// normal, by a fraction of its depth. The trace and the BVH pass both compute it here, so a
// queued ray need not carry it.
vec3 rb_hybrid_origin(ivec2 px)
{
    vec4 pos = imageLoad(gb_position, px);
    return pos.xyz + rb_oct_decode(imageLoad(gb_motion, px).zw) * (pc.scene.y * pos.w);
}

// A 32-bit integer hash (Wang's), for each pixel's and lobe's rotation of the sequence.
uint rb_hash(uint x)
{
    x = (x ^ 61u) ^ (x >> 16);
    x *= 9u;
    x ^= x >> 4;
    x *= 0x27d4eb2du;
    x ^= x >> 15;
    return x;
}

// The two random numbers of sample k of a pixel's lobe: point k of the R2 sequence (Roberts'
// additive recurrence on the plastic number), shifted by the pixel's own rotation (Cranley-
// Patterson), all in 32-bit fixed point so every device computes the same bits. k counts the
// frame's rays from the frame index, so consecutive frames stratify each other.
vec2 rb_hybrid_u(uint k, ivec2 px, uint lobe)
{
    uint h = rb_hash(uint(px.x) * 0x9e3779b9u ^ rb_hash(uint(px.y) + 0x85ebca6bu * (lobe + 1u)));
    uvec2 r = uvec2(k * 3242174889u + h, k * 2447445414u + rb_hash(h));
    return vec2(r >> 8) * (1.0 / 16777216.0);
}

// The three random numbers of light sample k of a pixel's lobe: point k of the R3 sequence
// (Roberts' recurrence on the root of x^4 = x + 1), rotated by the pixel's own shift as
// rb_hybrid_u is, in 32-bit fixed point: the emitter's pick (z) stays independent of the point
// on it (xy), which two rotations of one 2D sequence would not be.
vec3 rb_hybrid_u3(uint k, ivec2 px, uint lobe)
{
    uint h = rb_hash(uint(px.y) * 0x9e3779b9u ^ rb_hash(uint(px.x) + 0x632be5abu * (lobe + 1u)));
    uvec3 r = uvec3(k * 3518319154u + h, k * 2882110344u + rb_hash(h),
                    k * 2360945575u + rb_hash(h ^ 0x5bd1e995u));
    return vec3(r >> 8) * (1.0 / 16777216.0);
}

// An orthonormal frame around n (Duff et al. 2017).
void rb_basis(vec3 n, out vec3 t, out vec3 b)
{
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// GGX visible-normal sampling (Heitz 2018) of the half vector for v, in the frame (t, b, n).
vec3 rb_sample_vndf(vec3 v, vec3 t, vec3 b, vec3 n, float alpha, vec2 u)
{
    vec3 vl = vec3(dot(v, t), dot(v, b), max(dot(v, n), 1e-4));
    vec3 vh = normalize(vec3(alpha * vl.x, alpha * vl.y, vl.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * RB_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    vec3 hl = normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
    return hl.x * t + hl.y * b + hl.z * n;
}

// Smith's G1 for GGX.
float rb_g1(float ndx, float alpha)
{
    float a2 = alpha * alpha;
    float c = max(ndx, 1e-4);
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

// Samples one lobe of the camera vertex's BRDF: the direction l and the weight BRDF-lobe x
// cos / pdf, untextured (diffuse: over c_diff; specular: over the gray specular map) as the
// output pass textures it. Returns false when the sample carries nothing.
bool rb_hybrid_sample(uint lobe, vec3 n, vec3 ng, vec3 v, vec3 f0, float f90, float roughness,
                      vec2 u, out vec3 l, out vec3 weight)
{
    vec3 t, b;
    rb_basis(n, t, b);
    weight = vec3(0.0);
    if (lobe == RB_HYBRID_DIFFUSE) {
        // Cosine-weighted: (1 - F) / pi x cos / (cos / pi) = 1 - F(v.h).
        float r = sqrt(u.x), phi = 2.0 * RB_PI * u.y;
        l = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(1.0 - u.x, 0.0)) * n);
        vec3 kd, ks;
        rb_brdf_parts(n, v, l, f0, f90, roughness, kd, ks);
        weight = kd * RB_PI;
    } else {
        float alpha = max(roughness * roughness, 1e-4);
        vec3 h = rb_sample_vndf(v, t, b, n, alpha, u);
        l = reflect(-v, h);
        float ndl = dot(n, l);
        if (ndl <= 0.0)
            return false;
        // pdf = G1(v) D (v.h) / (n.v) / (4 v.h), so F D V cos / pdf = F 4 V (n.v) cos / G1(v).
        vec3 F;
        float D, V;
        if (!rb_ggx(n, v, l, f0, f90, roughness, F, D, V))
            return false;
        float ndv = max(dot(n, v), 1e-4);
        weight = F * (4.0 * V * ndv * ndl / rb_g1(ndv, alpha)) / rb_spec_map(f0);
    }
    return dot(ng, l) > 0.0 && dot(n, l) > 0.0;
}

// The lobe's pdf (solid angle) of sampling direction l with rb_hybrid_sample: cos / pi for the
// diffuse lobe, GGX's visible normals' G1(v) D / (4 n.v) for the specular one. The MIS weights
// of a BRDF ray and of a light sample both use it, so they add up to one.
float rb_hybrid_pdf(uint lobe, vec3 n, vec3 v, vec3 l, float roughness)
{
    float ndl = dot(n, l);
    if (!(ndl > 0.0))
        return 0.0;
    if (lobe == RB_HYBRID_DIFFUSE)
        return ndl / RB_PI;
    vec3 lv = l + v;
    if (!(dot(lv, lv) > 0.0))
        return 0.0;
    vec3 h = normalize(lv);
    float alpha = max(roughness * roughness, 1e-4), a2 = alpha * alpha;
    float ndh = max(dot(n, h), 0.0);
    float dd = ndh * ndh * (a2 - 1.0) + 1.0;
    float ndv = max(dot(n, v), 1e-4);
    return rb_g1(ndv, alpha) * (a2 / (RB_PI * dd * dd)) / (4.0 * ndv);
}

// The power heuristic (beta = 2, as the reference's) of a technique with pdf a against one with
// pdf b, as a ratio so that a mirror's huge pdf neither overflows nor makes NaN.
float rb_hybrid_mis(float a, float b)
{
    a = min(a, 1e30);
    b = min(b, 1e30);
    if (!(a > 0.0))
        return 0.0;
    float r = b / a;
    return 1.0 / (1.0 + r * r);
}

// The emitter table (hybrid_shared.h): where its running sums start in `blocks`, its total.
uint rb_hybrid_cdf_base()
{
    return (2u * pc.frame.w + RB_HYBRID_QUEUE_GROUP - 1u) / RB_HYBRID_QUEUE_GROUP;
}

float rb_hybrid_emit_total()
{
    return pc.bake.w == 0u ? 0.0 : uintBitsToFloat(blocks[rb_hybrid_cdf_base() + pc.bake.w - 1u]);
}

// The light sample's pdf (solid angle, from the ray's origin) of a point of emissive material m
// at distance dist whose face is at cosine cos_l to the ray: the emitter chosen by power, the
// point uniformly on it, so per unit area the emissive factor's luminance over the total power.
float rb_hybrid_light_pdf(rb_gpu_material m, float dist, float cos_l)
{
    float total = rb_hybrid_emit_total();
    float p_area = total > 0.0 ? rb_luminance(max(m.emissive.rgb, vec3(0.0))) / total : 0.0;
    return cos_l > 0.0 ? p_area * dist * dist / cos_l : 1e30;
}

// The environment's light samples (DESIGN.md "hybrid", rays), as the reference takes them
// (lib/reference/lights.c): with a map, by the importance table of its texels (each the largest
// luminance of its 3 x 3 neighbourhood times sin(theta)), which lib/integrators/hybrid.c writes
// into the index table (index_at) after the emitter list: the marginal CDF over rows (h + 1), each row's CDF
// (w + 1 a row), then each texel's probability (w h), as float bits; without a map, cosine-
// weighted around the shading normal. None when the environment is black (rb_hybrid_env_lit).
bool rb_hybrid_env_lit()
{
    return g.env.x > 0.0 &&
           (g.env.z > 0.5 || max(g.env_color.r, max(g.env_color.g, g.env_color.b)) > 0.0);
}

uint rb_hybrid_env_table()
{
    return floatBitsToUint(pc.scene.z) + pc.bake.w;
}

float rb_hybrid_table(uint i)
{
    return uintBitsToFloat(index_at(i));
}

// The reference's search: the last i in [0, n) with cdf[i] <= u, skipping empty intervals.
uint rb_hybrid_search(uint base, uint n, float u)
{
    uint lo = 0u, hi = n;
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (rb_hybrid_table(base + mid) <= u)
            lo = mid;
        else
            hi = mid;
    }
    while (lo + 1u < n && !(rb_hybrid_table(base + lo + 1u) > rb_hybrid_table(base + lo)))
        lo++;
    return lo;
}

// The pdf (solid angle) of the environment's light sample of direction d at shading normal n.
float rb_hybrid_env_pdf(vec3 n, vec3 d)
{
    if (!rb_hybrid_env_lit())
        return 0.0;
    if (g.env.z <= 0.5)
        return max(dot(n, d), 0.0) / RB_PI;
    uvec2 size = uvec2(textureSize(env_map, 0));
    vec2 uv = rb_equirect_uv(d, g.env.y);
    if (any(isnan(uv)))
        return 0.0;
    uvec2 t = uvec2(clamp(floor(uv * vec2(size)), vec2(0.0), vec2(size) - 1.0));
    float st = sin(uv.y * RB_PI);
    if (!(st > 0.0))
        return 0.0;
    uint pdfs = rb_hybrid_env_table() + (size.y + 1u) + size.y * (size.x + 1u);
    float p_uv = rb_hybrid_table(pdfs + t.y * size.x + t.x) * float(size.x) * float(size.y);
    return p_uv / (2.0 * RB_PI * RB_PI * st);
}

// The environment's light sample of random numbers u at shading normal n: its direction d and
// pdf (0: none).
float rb_hybrid_env_sample(vec3 n, vec2 u, out vec3 d)
{
    d = n;
    if (!rb_hybrid_env_lit())
        return 0.0;
    if (g.env.z <= 0.5) {
        vec3 t, b;
        rb_basis(n, t, b);
        float r = sqrt(u.x), phi = 2.0 * RB_PI * u.y;
        d = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(1.0 - u.x, 0.0)) * n);
        return rb_hybrid_env_pdf(n, d);
    }
    uvec2 size = uvec2(textureSize(env_map, 0));
    uint marginal = rb_hybrid_env_table(), rows = marginal + size.y + 1u;
    uint y = rb_hybrid_search(marginal, size.y, u.x);
    float r0 = rb_hybrid_table(marginal + y), r1 = rb_hybrid_table(marginal + y + 1u);
    float fy = r1 > r0 ? (u.x - r0) / (r1 - r0) : 0.5;
    uint row = rows + y * (size.x + 1u);
    uint x = rb_hybrid_search(row, size.x, u.y);
    float c0 = rb_hybrid_table(row + x), c1 = rb_hybrid_table(row + x + 1u);
    float fx = c1 > c0 ? (u.y - c0) / (c1 - c0) : 0.5;
    float mu = (float(x) + clamp(fx, 0.0, 1.0)) / float(size.x);
    float mv = (float(y) + clamp(fy, 0.0, 1.0)) / float(size.y);
    // lights.c's equirect_dir: the direction of map coordinates (mu, mv), rotation undone
    float theta = mv * RB_PI, phi = (mu - 0.5) * 2.0 * RB_PI, st = sin(theta);
    vec3 m = vec3(st * sin(phi), cos(theta), -st * cos(phi));
    float c = cos(-g.env.y), sn = sin(-g.env.y);
    d = vec3(c * m.x - sn * m.z, m.y, sn * m.x + c * m.z);
    if (!(st > 0.0))
        return 0.0;
    return rb_hybrid_env_pdf(n, d);
}

// The MIS weight of emission a BRDF ray of pdf pdf_brdf found on global triangle t, at distance
// dist from its origin, along l: against the light sample that could have found the same point.
float rb_hybrid_emit_weight(uint t, vec3 l, float dist, float pdf_brdf)
{
    if (pc.bake.w == 0u)
        return 1.0;
    rb_gpu_vertex v0 = vertex_at(index_at(3u * t));
    rb_gpu_material m = materials[floatBitsToUint(v0.uv.z)];
    vec3 ne = cross(vertex_at(index_at(3u * t + 1u)).position.xyz - v0.position.xyz,
                    vertex_at(index_at(3u * t + 2u)).position.xyz - v0.position.xyz);
    float len = length(ne);
    float cos_l = len > 0.0 ? abs(dot(ne / len, l)) : 0.0;
    return rb_hybrid_mis(pdf_brdf, rb_hybrid_light_pdf(m, dist, cos_l));
}

vec3 rb_hybrid_env(vec3 d)
{
    vec3 env = g.env_color.rgb;
    if (g.env.z > 0.5)
        env = textureLod(env_map, rb_equirect_uv(d, g.env.y), 0.0).rgb;
    return env * g.env.x;
}

uint rb_bake_point(uint base, uint r, uint i, uint j)
{
    return base + j * (r + 1u) - (j * (j - 1u)) / 2u + i;
}

// The baked light (irradiance / pi) of a BVH triangle with bake word `word`, at barycentrics
// bary of its second and third vertices, on its back or its front (hybrid_shared.h's lattice).
vec3 rb_hybrid_baked(uint word, vec2 bary, bool back)
{
    uint r = word & RB_HYBRID_BAKE_MAX_RES;
    if (r == 0u || (back && (word & RB_HYBRID_BAKE_BACK) == 0u))
        return vec3(0.0);
    uint base = word >> RB_HYBRID_BAKE_SHIFT;
    if (back)
        base += (r + 1u) * (r + 2u) / 2u;
    // Undo the shrink, then find the lattice's small triangle the point is in.
    vec2 c = vec2(1.0 / 3.0);
    vec2 x = max(c + (bary - c) / (1.0 - RB_HYBRID_BAKE_SHRINK), vec2(0.0)) * float(r);
    float over = x.x + x.y - float(r);
    if (over > 0.0)
        x -= 0.5 * over;
    x = max(x, vec2(0.0));
    uvec2 i0 = uvec2(min(floor(x), vec2(float(r - 1u))));
    if (i0.x + i0.y > r - 1u) {
        if (i0.x > 0u)
            i0.x--;
        else
            i0.y--;
    }
    vec2 f = x - vec2(i0);
    if (f.x + f.y <= 1.0 || i0.x + i0.y + 2u > r) {
        vec3 w = max(vec3(1.0 - f.x - f.y, f.x, f.y), vec3(0.0));
        w /= max(w.x + w.y + w.z, 1e-6);
        return w.x * baked_point(rb_bake_point(base, r, i0.x, i0.y)).rgb +
               w.y * baked_point(rb_bake_point(base, r, i0.x + 1u, i0.y)).rgb +
               w.z * baked_point(rb_bake_point(base, r, i0.x, i0.y + 1u)).rgb;
    }
    return (f.x + f.y - 1.0) * baked_point(rb_bake_point(base, r, i0.x + 1u, i0.y + 1u)).rgb +
           (1.0 - f.x) * baked_point(rb_bake_point(base, r, i0.x, i0.y + 1u)).rgb +
           (1.0 - f.y) * baked_point(rb_bake_point(base, r, i0.x + 1u, i0.y)).rgb;
}

// The baked light at a surface point the camera sees (a screen hit): p is the G-buffer's point,
// ng its geometric normal (the side the camera sees), tri the G-buffer's triangle index, back
// whether the camera sees the triangle's back (the G-buffer's face: the bake's sides follow the
// winding, whatever the vertex normals say). The
// triangle's bake word and the point's barycentrics in this frame's vertices find the lattice;
// past 2^24 triangles, where the G-buffer's float cannot hold the index, a short BVH ray down
// ng, from a thousandth of the depth above to as far below, finds the triangle instead. None
// where the BVH does not hold the surface.
vec3 rb_hybrid_baked_at(vec3 p, vec3 ng, float depth, float tri, bool back)
{
    if (pc.bake.x == 0u)
        return vec3(0.0);
    if (pc.bake.y == 0u) {
        float e = 1e-3 * depth;
        rb_bvh_hit hit;
        if (!rb_bvh_intersect(p + ng * e, -ng, 0.0, 2.0 * e, hit))
            return vec3(0.0);
        return rb_hybrid_baked(hit.extra, hit.bary, back);
    }
    uint t = uint(tri);
    uint word = bake_word(pc.bake.z + t);
    if (word == 0u)
        return vec3(0.0);
    vec3 p0 = vertex_at(index_at(3u * t)).position.xyz, p1 = vertex_at(index_at(3u * t + 1u)).position.xyz,
         p2 = vertex_at(index_at(3u * t + 2u)).position.xyz;
    // Barycentrics of p's projection into the triangle's plane.
    vec3 e1 = p1 - p0, e2 = p2 - p0, q = p - p0;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float q1 = dot(q, e1), q2 = dot(q, e2), det = d11 * d22 - d12 * d12;
    if (!(det > 0.0))
        return vec3(0.0);
    vec2 bary = clamp(vec2(d22 * q1 - d12 * q2, d11 * q2 - d12 * q1) / det, 0.0, 1.0);
    return rb_hybrid_baked(word, bary, back);
}

// The light a surface point sends toward v, but its emission: the punctual lights' direct light
// through the shadow maps, and either what its pixel gathered of the rest (rb_hybrid_feedback,
// when `fed`: `baked` is that light) or the baked light of the emitters and the environment
// (irradiance / pi) through its diffuse albedo. (Shading at a hit, screen or BVH alike.)
vec3 rb_hybrid_shade(vec3 p, vec3 n, vec3 ng, vec3 v, vec3 c_diff, vec3 f0, float f90,
                     float roughness, vec3 baked, bool fed)
{
    return rb_punctual_light(vec3(0.0), p, n, ng, v, c_diff, f0, f90, roughness) +
           (fed ? baked : c_diff * baked);
}

// Where the pixel's surface was in the previous frame (its motion vector), or (-1, -1) when it
// was not there: off screen, or the previous frame saw another surface there (depth or normal
// too different: a disocclusion).
ivec2 rb_hybrid_reproject(ivec2 px, float depth, vec3 n)
{
    vec2 m = imageLoad(gb_motion, px).xy;
    ivec2 q = ivec2(floor(vec2(px) + 0.5 + m));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(g.size.xy))))
        return ivec2(-1);
    vec4 geo = imageLoad(acc_prev, ivec3(q, RB_HYBRID_ACC_GEOMETRY));
    if (!(geo.w > 0.0) || abs(geo.w - depth) > pc.params.z * 2.0 * depth ||
        dot(geo.xyz, n) < pc.params.w)
        return ivec2(-1);
    return q;
}

// Every bounce (DESIGN.md "hybrid", bvh trace): the light a hit at world point p (shading
// normal n, on the side the ray sees; diffuse albedo c_diff, F0 f0) reflects, after any number
// of bounces, as the pixel that saw p in the previous frame gathered it (seed 003's screen hits
// reading the lit result): that pixel's diffuse and specular light, direct and indirect, each
// over its samples, in this frame's younger accumulator, textured by the hit's own maps (the
// accumulators are untextured). It is the light the pixel sends toward the camera, taken as what
// the hit sends along the ray. Each frame's hits thus reflect one bounce more than the last
// frame's. False where the previous frame did not see p (off screen, or another surface there:
// the depth and normal tests), where the pixel has no diffuse samples yet, where that accumulator
// starts again this frame (so that what an accumulator holds depends on the frames since its
// start alone: the history contract of lib/integrators/hybrid.c), and with
// integrator.hybrid.max_bounces a count.
bool rb_hybrid_feedback(vec3 p, vec3 n, vec3 c_diff, vec3 f0, out vec3 light)
{
    light = vec3(0.0);
    uint set = pc.history.w;
    if ((pc.history.z & 2u) == 0u || (set == 0u ? pc.history.x : pc.history.y) != 0u)
        return false;
    vec4 c = g.prev_view_proj * vec4(p, 1.0);
    if (!(c.w > 0.0))
        return false;
    ivec2 q = ivec2(floor((c.xy / c.w * 0.5 + 0.5) * vec2(g.size.xy)));
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(g.size.xy))))
        return false;
    vec4 geo = imageLoad(acc_prev, ivec3(q, RB_HYBRID_ACC_GEOMETRY));
    if (!(geo.w > 0.0) || abs(geo.w - c.w) > pc.params.z * 2.0 * c.w ||
        dot(geo.xyz, n) < pc.params.w)
        return false;
    uint base = 4u * set;
    vec4 dd = imageLoad(acc_prev, ivec3(q, base + RB_HYBRID_ACC_DIFFUSE_DIRECT));
    if (!(dd.w > 0.0) && max(c_diff.r, max(c_diff.g, c_diff.b)) > 0.0)
        return false;
    vec4 di = imageLoad(acc_prev, ivec3(q, base + RB_HYBRID_ACC_DIFFUSE_INDIRECT));
    vec4 sd = imageLoad(acc_prev, ivec3(q, base + RB_HYBRID_ACC_SPECULAR_DIRECT));
    vec4 si = imageLoad(acc_prev, ivec3(q, base + RB_HYBRID_ACC_SPECULAR_INDIRECT));
    if (dd.w > 0.0)
        light += c_diff * (dd.rgb + di.rgb) / dd.w;
    if (sd.w > 0.0)
        light += rb_spec_map(f0) * (sd.rgb + si.rgb) / sd.w;
    return true;
}

// A BVH hit's surface: position, shading and geometric normals on the side the ray d arrives
// from (front: whether that is the triangle's front), and its material.
void rb_hybrid_bvh_surface(vec3 o, vec3 d, rb_bvh_hit hit, out vec3 p, out vec3 n, out vec3 ng,
                           out bool front, out rb_surface sf)
{
    uint t = hit.triangle;
    rb_gpu_vertex v0 = vertex_at(index_at(3u * t)), v1 = vertex_at(index_at(3u * t + 1u)),
                  v2 = vertex_at(index_at(3u * t + 2u));
    vec3 b = vec3(1.0 - hit.bary.x - hit.bary.y, hit.bary);
    ng = normalize(cross(v1.position.xyz - v0.position.xyz, v2.position.xyz - v0.position.xyz));
    n = normalize(b.x * v0.normal.xyz + b.y * v1.normal.xyz + b.z * v2.normal.xyz);
    vec2 uv = b.x * v0.uv.xy + b.y * v1.uv.xy + b.z * v2.uv.xy;
    rb_gpu_material m = materials[floatBitsToUint(v0.uv.z)];
    front = dot(ng, d) < 0.0;
    if (!front)
        ng = -ng;
    if (dot(n, ng) < 0.0)
        n = -n;
    if (m.textures.z >= 0) {
        vec4 tangent = b.x * v0.tangent + b.y * v1.tangent + b.z * v2.tangent;
        vec3 tn = textureLod(linear_textures, vec3(uv, float(m.textures.z)), 0.0).xyz;
        n = rb_normal_map(n, tangent, tn * 2.0 - 1.0, m.emissive.w);
    }
    sf = rb_material_eval(m, uv, srgb_textures, linear_textures);
    p = o + hit.t * d;
}

// Bounces past a hit (integrator.hybrid.max_bounces, as the reference counts them after the
// first surface hit): UINT_MAX for unlimited (rb_hybrid_feedback), else the count.
uint rb_hybrid_max_bounces()
{
    return (pc.history.z & 2u) != 0u ? 0xffffffffu : pc.history.z >> 2u;
}

// A counted path's further bounces from a hit (p, shading normal n, geometric normal ng, on the
// side the ray arrived from; v toward where the ray came from; its material): `count`
// cosine-weighted rays through the BVH, one from each hit the last one found, each hit lit as a
// hit of one bounce is (the punctual lights' shadow-mapped light and its baked light through its
// diffuse albedo), what each brings weighed by the BRDFs (both lobes) before it. The light the
// path sends from p toward v, but emission (the emitters' and the environment's light at each
// vertex is its bake's). Random numbers: sample k of the pixel's R2 sequence, a rotation of its
// own a bounce (the first one's is the hidden hit's secondary ray's, 6 + lobe).
vec3 rb_hybrid_chain(vec3 p, vec3 n, vec3 ng, vec3 v, vec3 c_diff, vec3 f0, float f90,
                     float roughness, uint count, uint k, ivec2 px, uint lobe)
{
    vec3 sum = vec3(0.0), beta = vec3(1.0);
    for (uint j = 0u; j < count; j++) {
        vec2 u = rb_hybrid_u(k, px, (j == 0u ? 6u : 8u + 2u * j) + lobe);
        vec3 t, b;
        rb_basis(n, t, b);
        float r = sqrt(u.x), phi = 2.0 * RB_PI * u.y;
        vec3 l = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(1.0 - u.x, 0.0)) * n);
        if (dot(ng, l) <= 0.0)
            break;
        // BRDF x cosine over the cosine-weighted pdf
        beta *= RB_PI * rb_brdf(n, v, l, c_diff, f0, f90, roughness);
        if (!(max(beta.r, max(beta.g, beta.b)) > 0.0))
            break;
        vec3 o = p + ng * (1e-4 * length(p - g.camera_pos.xyz) + 1e-6 * pc.scene.x);
        rb_bvh_hit hit;
        if (!rb_bvh_intersect(o, l, 0.0, 1e30, hit))
            break;
        bool front;
        rb_surface sf;
        rb_hybrid_bvh_surface(o, l, hit, p, n, ng, front, sf);
        vec3 baked = rb_hybrid_baked(hit.extra, hit.bary, !front);
        sum += beta * rb_hybrid_shade(p, n, ng, -l, sf.c_diff, sf.f0, sf.f90, sf.roughness, baked,
                                      false);
        v = -l;
        c_diff = sf.c_diff;
        f0 = sf.f0;
        f90 = sf.f90;
        roughness = sf.roughness;
    }
    return sum;
}

// The tile mask at a pixel, smoothed by a cubic B-spline across tiles (seed 003: "bicubic tile
// filtering for stenciling"): a lobe's rays stop where it is at least 0.5. `eroded` reads the
// mask eroded by one tile, the diffuse lobe's, whose filter is wide. hybrid_trace.comp's
// requests test it, and the filter writes it into the tiles layer.
float rb_hybrid_tile_done(ivec2 px, bool eroded)
{
    uvec2 tiles_n = (g.size.xy + RB_HYBRID_TILE - 1u) / RB_HYBRID_TILE;
    uint base = eroded ? tiles_n.x * tiles_n.y : 0u;
    vec2 tc = (vec2(px) + 0.5) / float(RB_HYBRID_TILE) - 0.5;
    vec2 i0 = floor(tc);
    vec2 f = tc - i0;
    vec4 wx = vec4(pow(1.0 - f.x, 3.0), 3.0 * pow(f.x, 3.0) - 6.0 * f.x * f.x + 4.0,
                   -3.0 * pow(f.x, 3.0) + 3.0 * f.x * f.x + 3.0 * f.x + 1.0, pow(f.x, 3.0)) / 6.0;
    vec4 wy = vec4(pow(1.0 - f.y, 3.0), 3.0 * pow(f.y, 3.0) - 6.0 * f.y * f.y + 4.0,
                   -3.0 * pow(f.y, 3.0) + 3.0 * f.y * f.y + 3.0 * f.y + 1.0, pow(f.y, 3.0)) / 6.0;
    float s = 0.0;
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            ivec2 t = clamp(ivec2(i0) + ivec2(x - 1, y - 1), ivec2(0), ivec2(tiles_n) - 1);
            s += wx[x] * wy[y] * tiles[base + uint(t.y) * tiles_n.x + uint(t.x)];
        }
    return s;
}

#endif
