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
// emitters' dispatch (bdpt_emitter_direct.comp) makes at every pixel instead, from all the
// frame's emitter points, weighed against (b)'s emission hits or, where the emitters are in
// closed form, alone; its (c), one bounce, every bundle makes with all the
// frame's emitter points too (emitters_at); its bounce VPL y1 (K_v + k, found by its probe)
// makes those one-bounce paths again through (a), and the two are weighed over the n_c pairs
// (counted twice) and n_a VPLs with p(y1 | y0) (y0's density is both sides' and cancels); the
// bounce VPL's (c) is the emitter's second bounce, the only strategy for it. What reaches x1
// is split into its BRDF's diffuse and specular parts (rb_brdf_parts)
// and added, in k order and without atomics, to x1's own texel of four accumulators.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bdpt_connect.glsl"

void main()
{
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
            if (h.found)
                h.t = rb_bundle_on_own_line(bundle_views[k], int(pc.params.z), x1, s, h);
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
                    // It is the emitters' dispatch's alone where the emitters are in closed form
                    // there.
                    if (!(closed_form() && strategies == RB_BDPT_MIS))
                        add(dd, ds, n1, v1, dir, f0, f90, rough, h.m.emission * (w * scale / n_b));
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
