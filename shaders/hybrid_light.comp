// hybrid_light: next-event estimation at the camera vertex (DESIGN.md "hybrid", rays). For each
// ray of the pixel traced this frame (a sample the accumulators will count; ray r of both lobes
// shares its light samples, each lobe weighing them by its own pdf), one light sample of the
// emitters: an emissive triangle chosen by emitted power (the emitter table), a
// point uniformly on it; and one of the environment: a direction by its importance table (or
// cosine-weighted without a map, as the reference's). Each has its visibility by a shadow ray
// through the BVH, and brings the lobe's BRDF (untextured, as the ray's weight is) x cosine x
// its light over its pdf, weighted against the BRDF rays that find the same light by the power
// heuristic (the reference's); added to what the ray found directly. Where the BVH's budget left
// surfaces out, the shadow ray also marches the screen (the BRDF rays' march), and a surface it
// meets there that the BVH does not hold blocks the sample too (a union with the BVH's answer,
// which alone decides for its own triangles, exactly, so that the march's thickness guess never
// shadows what it holds; an object held by its coarser version is both). Their random numbers are
// the pixel's own R3 sequence (rb_hybrid_u3) and a rotation of its R2 sequence apart from the
// rays'.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "hybrid.glsl"
#include "hybrid_screen.glsl"

// Whether the screen shows a surface the BVH does not hold (a triangle without a bake word: left
// out by the budget, or held by its coarser version) on the way from o along l, nearer than
// dist. Only where the frame's BVH leaves objects out (pc.more.x), and where screen hits know
// their triangle (the G-buffer's index and the bake words).
bool screen_occluded(vec3 o, vec3 l, float dist)
{
    if (pc.more.x == 0u || pc.sizes.y == 0u || pc.bake.x == 0u || pc.bake.y == 0u)
        return false;
    ivec2 hit = screen_trace(o, l, pc.params.y, pc.sizes.y);
    if (hit.x < 0)
        return false;
    vec3 p = imageLoad(gb_position, hit).xyz;
    if (!(dot(p - o, l) < dist))
        return false;
    uint t = uint(imageLoad(gb_albedo, hit).w);
    return bake_word(pc.bake.z + t) == 0u;
}

// The first emitter whose running sum is over x (one of positive power).
uint pick_emitter(float x)
{
    uint base = rb_hybrid_cdf_base(), lo = 0u, hi = pc.bake.w - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (uintBitsToFloat(blocks[base + mid]) > x)
            hi = mid;
        else
            lo = mid + 1u;
    }
    return lo;
}

// The light a sample brings each lobe that wants it (lit.x: diffuse, lit.y: specular), from
// direction l with pdf pdf and light le: the lobe's BRDF (untextured) x cosine x le / pdf, by the
// power heuristic against the lobe's own rays.
void add_lobes(bvec2 lit, vec3 n, vec3 v, vec4 spec, float f90, vec3 l, float pdf, vec3 le,
               inout vec3 c[2])
{
    vec3 kd, ks;
    rb_brdf_parts(n, v, l, spec.rgb, f90, spec.a, kd, ks);
    float ndl = dot(n, l);
    if (lit.x)
        c[0] += kd * le * (ndl * rb_hybrid_mis(pdf, rb_hybrid_pdf(0u, n, v, l, spec.a)) / pdf);
    if (lit.y)
        c[1] += ks * le * (ndl * rb_hybrid_mis(pdf, rb_hybrid_pdf(1u, n, v, l, spec.a)) / pdf);
}

// One light sample of the emitters (o: the rays' origin), with random numbers u (the point) and
// pick (the emitter).
void light_sample(bvec2 lit, vec3 o, vec3 n, vec3 ng, vec3 v, vec4 spec, float f90, vec2 u,
                  float pick, inout vec3 c[2])
{
    float total = rb_hybrid_emit_total();
    if (!(total > 0.0))
        return;
    uint t = index_at(floatBitsToUint(pc.scene.z) + pick_emitter(min(pick, 0.99999994) * total));
    rb_gpu_vertex v0 = vertex_at(index_at(3u * t)), v1 = vertex_at(index_at(3u * t + 1u)),
                  v2 = vertex_at(index_at(3u * t + 2u));
    float su = sqrt(u.x), b1 = su * (1.0 - u.y), b2 = su * u.y;
    vec3 q = (1.0 - b1 - b2) * v0.position.xyz + b1 * v1.position.xyz + b2 * v2.position.xyz;
    vec3 d = q - o;
    float dist = length(d);
    if (!(dist > 0.0))
        return;
    vec3 l = d / dist;
    if (dot(ng, l) <= 0.0 || dot(n, l) <= 0.0)
        return;
    vec3 ne = cross(v1.position.xyz - v0.position.xyz, v2.position.xyz - v0.position.xyz);
    float cos_l = abs(dot(normalize(ne), l));
    rb_gpu_material m = materials[floatBitsToUint(v0.uv.z)];
    float pdf = rb_hybrid_light_pdf(m, dist, cos_l);
    if (!(pdf > 0.0) || !(pdf < 1e30))
        return;
    vec2 uv = (1.0 - b1 - b2) * v0.uv.xy + b1 * v1.uv.xy + b2 * v2.uv.xy;
    vec3 le = rb_material_eval(m, uv, srgb_textures, linear_textures).emission;
    if (!(max(le.r, max(le.g, le.b)) > 0.0))
        return;
    // The shadow ray stops short of the emitter, so that it cannot find the emitter itself.
    if (rb_bvh_occluded(o, l, 0.0, dist * (1.0 - 1e-3)) ||
        screen_occluded(o, l, dist * (1.0 - 1e-3)))
        return;
    add_lobes(lit, n, v, spec, f90, l, pdf, le, c);
}

// One light sample of the environment, with random numbers u.
void env_sample(bvec2 lit, vec3 o, vec3 n, vec3 ng, vec3 v, vec4 spec, float f90, vec2 u,
                inout vec3 c[2])
{
    vec3 l;
    float pdf = rb_hybrid_env_sample(n, u, l);
    if (!(pdf > 0.0) || !(pdf < 1e30) || dot(ng, l) <= 0.0 || dot(n, l) <= 0.0)
        return;
    vec3 le = rb_hybrid_env(l);
    if (!(max(le.r, max(le.g, le.b)) > 0.0) || rb_bvh_occluded(o, l, 0.0, 1e30) ||
        screen_occluded(o, l, 1e30))
        return;
    add_lobes(lit, n, v, spec, f90, l, pdf, le, c);
}

// Whether a slot's ray is a sample the accumulators count.
bool counted(uint slot)
{
    uint state = floatBitsToUint(slots[slot].a.w);
    return state == RB_HYBRID_SCREEN || state == RB_HYBRID_BVH || state == RB_HYBRID_MISS ||
           state == RB_HYBRID_ABSORBED;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    bool env = rb_hybrid_env_lit();
    if (any(greaterThanEqual(uvec2(px), g.size.xy)) || (pc.bake.w == 0u && !env))
        return;
    vec4 pos = imageLoad(gb_position, px);
    if (!(pos.w > 0.0))
        return;
    vec3 n = imageLoad(gb_normal, px).xyz;
    vec3 ng = rb_oct_decode(imageLoad(gb_motion, px).zw);
    vec3 v = normalize(g.camera_pos.xyz - pos.xyz);
    vec4 spec = imageLoad(gb_specular, px);
    float f90 = imageLoad(gb_emission, px).w;
    vec3 o = rb_hybrid_origin(px);
    if (pc.more.x != 0u)
        hiz_levels();
    uint rays = pc.frame.y;
    for (uint r = 0u; r < rays; r++) {
        uint slot_d = rb_hybrid_slot(RB_HYBRID_DIFFUSE, r, px);
        uint slot_s = rb_hybrid_slot(RB_HYBRID_SPECULAR, r, px);
        bvec2 lit = bvec2(counted(slot_d), counted(slot_s));
        if (!any(lit))
            continue;
        uint k = pc.frame.x * rays + r;
        vec3 c[2] = vec3[2](vec3(0.0), vec3(0.0));
        if (pc.bake.w > 0u) {
            vec3 u = rb_hybrid_u3(k, px, 0u);
            light_sample(lit, o, n, ng, v, spec, f90, u.xy, u.z, c);
        }
        if (env)
            env_sample(lit, o, n, ng, v, spec, f90, rb_hybrid_u(k, px, 8u), c);
        if (lit.x && max(c[0].r, max(c[0].g, c[0].b)) > 0.0)
            slots[slot_d].a.rgb += c[0];
        if (lit.y && max(c[1].r, max(c[1].g, c[1].b)) > 0.0)
            slots[slot_s].a.rgb += c[1];
    }
}
