/* The bdpt integrator's buffers and push constants, shared by C (lib/passes/bdpt.c,
 * lib/integrators/bdpt.c) and GLSL (shaders/bdpt_*.comp); C checks each size with
 * _Static_assert in lib/passes/passes.h. DESIGN.md "bdpt" and BDPT.md say what they hold. */
#ifndef RB_SHADERS_BDPT_SHARED_H
#define RB_SHADERS_BDPT_SHARED_H

#include "shared.h"

/* One virtual point light: the first surface z a light's RSM sees along a sampled direction
 * (BDPT.md "VPL"). Written by bdpt_generate.comp, read by bdpt_connect.comp. */
struct rb_gpu_vpl {
    RB_VEC4(position); /* xyz: z; w: 1 for a VPL, 0 where the direction found no surface */
    RB_VEC4(normal);   /* xyz: z's unit normal, on the side the light arrives from; w: p_A^L(z),
                        * the area density of z under the light's sampling, light choice
                        * included (for MIS) */
    RB_VEC4(power);    /* rgb: I(w) window(|y0 - z|) / (P(light) p(w)), or E A / P(light) for a
                        * directional light: what z receives, divided by its pdf (W); w: unused */
    RB_VEC4(from);     /* xyz: the light's position (point, spot) or the direction towards it
                        * (directional); w: the light kind */
    RB_UVEC4(material); /* x: albedo word, y: gloss word (rb_material_pack, the bundle node's);
                         * z: the light's index; w: unused */
};

/* A VPL's from.w when it is a point on an emissive triangle (BDPT.md "As implemented",
 * emitters): it sends its emission, not a reflection, and its map covers the side it emits
 * from. */
#define RB_BDPT_VPL_EMITTER 4

/* A VPL's from.w when it is the first surface y1 a point y0 on an emitter sees along a cosine-
 * distributed direction (BDPT.md "As implemented", emitters' bounce): VPL K_v + i, the bounce
 * of emitter VPL i, found by i's probe view. It reflects what y0 sends it; from.xyz is y0; its
 * normal.w is p(y1 | y0), y1's area density given y0 (rb_bdpt_bounce_density). */
#define RB_BDPT_VPL_BOUNCE 5

/* A VPL's from.w when it is the first surface z' that a reflecting VPL z (a punctual light's,
 * or an emitter's bounce) sees along a cosine-distributed direction (BDPT.md "Two bounces"):
 * VPL K_v + i, the bounce of punctual VPL i, or 2 K_v + i, the bounce of emitter VPL i's
 * bounce. It reflects what z reflects towards it; from.xyz is z; normal.w is p(z' | z). It
 * lights the camera's points through (a) only (its bundle connection would be a third bounce).
 */
#define RB_BDPT_VPL_SECOND 6

/* One emissive triangle, listed once when the integrator starts (a triangle of the scene whose
 * material's emissive factor is above zero). */
struct rb_gpu_bdpt_emitter {
    RB_UVEC4(tri); /* xyz: its corners' indices into the frame's world vertices; w: material */
};

/* At most this many emissive triangles are also integrated in closed form (bdpt_connect.comp's
 * emitters' dispatch); a scene with more lights by its points alone. */
#define RB_BDPT_ANALYTIC_MAX 16

/* The specular lobe's linearly transformed cosines (tools/ltcfit.c, lib/passes/ltc_ggx.inc): a
 * table of RB_LTC_SIZE rows (sqrt(1 - n.v)) by RB_LTC_SIZE columns (roughness), a vec4 an entry:
 * the inverse transform's m00 m02 m20 m22 (m11 = 1). */
#define RB_LTC_SIZE 64

/* What the frame's emitters come to, written by bdpt_generate.comp for bdpt_connect.comp. */
struct rb_gpu_bdpt_emit_info {
    RB_VEC4(info); /* x: P_e, the chance a VPL is a point on an emitter rather than a VPL of a
                    * punctual light; y: P_e / (2 S), S the sum of area x luminance of the
                    * emissive factor over the emitters: an emitter point's area density per
                    * unit of that luminance (both sides); z: how many triangles tris holds, the
                    * frame's emitters (0: none, more than RB_BDPT_ANALYTIC_MAX, or a textured
                    * one); w: unused */
    RB_VEC4(tris[4 * RB_BDPT_ANALYTIC_MAX]); /* per emissive triangle, 4 in a row: its corners
                                              * in the frame's world space (xyz), then its
                                              * emissive factor (rgb, both sides) */
};

/* Per light, what sampling it needs beyond struct rb_gpu_light (host-written each frame). */
struct rb_gpu_bdpt_light {
    RB_VEC4(choice); /* x: P(light), the chance a VPL picks it (by power); y: the CDF through it;
                      * z: the density of its sampled direction (1 / 4 pi, a point light; one
                      * over the cone's solid angle, a spot) or of its beam point (1 / A,
                      * directional); w: cos of the spot's outer angle */
};

/* The sampling table: scene-independent quasi-random numbers, one row per VPL and per bundle,
 * generated once (lib/integrators/bdpt.c). */
struct rb_gpu_bdpt_sample {
    RB_VEC4(u); /* VPL: light choice, two for the direction or beam point; bundle: two for the
                 * direction; w unused */
    RB_VEC4(v); /* VPL: two for the direction of its bounce, two for its bounce's (emitters) */
};

/* The draw commands of the VPL maps and probes are VkDrawIndexedIndirectCommand, five uints;
 * generate and bounce set the instance count, 1 for a view that sees something and 0 for one
 * whose VPL has no surface (or whose probe has no emitter), so that it costs its clear alone.
 * RB_BDPT_DRAW_INSTANCES: the instance count's uint in a command. */
#define RB_BDPT_DRAW_UINTS 5
#define RB_BDPT_DRAW_INSTANCES 1

/* Push constants of bdpt_generate.comp. */
struct rb_gpu_bdpt_generate_push {
    RB_UVEC4(counts);  /* VPLs, bundles, light count, RSM size in texels */
    RB_VEC4(scene);    /* xyz: the centre of the job's bounds; w: their radius */
    RB_VEC4(sizes);    /* bundle grid size, VPL map size, the punctual lights' summed power
                        * (W, as write_lights weighs them), the emissive triangles' count */
};

/* The pixels across one workgroup of bdpt_bounds.comp (8 x 8 invocations, 4 x 4 pixels each). */
#define RB_BDPT_BOUNDS_TILE_PX 32

/* Push constants of bdpt_mark.comp: bundle k and its sub-image. */
struct rb_gpu_bdpt_mark_push {
    RB_UVEC4(index);  /* bundle k, the bundle grid size, 0, 0 */
    RB_UVEC4(region); /* the sub-image's first texel in the split images (x, y), its size */
};

/* Push constants of bdpt_connect.comp (one iteration of the loop, over one sub-image) and
 * bdpt_emitter_direct.comp (the whole split image). */
struct rb_gpu_bdpt_connect_push {
    RB_UVEC4(index);   /* iteration k, whether VPL k exists (0/1), whether bundle k does, the
                        * strategies (RB_BDPT_MIS, _VPL, _BUNDLE) */
    RB_UVEC4(region);  /* the sub-image's first texel in the split images (x, y), its size */
    RB_VEC4(counts);   /* samples of the sub-image: VPLs n_a, bundles n_b, pairs n_c (as
                        * floats); the G clamp (0: none) */
    RB_VEC4(params);   /* VPL bias, VPL map size, bundle grid size, node capacity */
    RB_UVEC4(bounce);  /* x: the index of VPL k's bounce (K_v + k), or RB_NONE where the frame
                        * has none; y: its bounce's (2 K_v + k), or RB_NONE; z: the bounce
                        * VPLs' map size (the corner of their layers they fill); w: unused */
    RB_VEC4(frame);    /* x: the least roughness of a VPL's or a bundle hit's BRDF; y: K_v, the
                        * frame's VPLs; z: K_b, its bundles; w: n x n, its sub-images (floats) */
    RB_VEC4(offset);   /* xy: the cache's subpixel offset (pixels: its G-buffer's sample of a
                        * pixel lies at the pixel's centre plus this; emitter_direct); z: a
                        * VPL's disk, in the areas it stands for (connect's (a) and (c));
                        * w: unused */
};

/* Push constants of bdpt_emitters.comp. */
struct rb_gpu_bdpt_emitters_push {
    RB_UVEC4(counts); /* the emissive triangles, unused, unused, unused */
};

/* Push constants of bdpt_bounce.comp. */
struct rb_gpu_bdpt_bounce_push {
    RB_UVEC4(counts); /* K_v; src, the first VPL probed (0 or K_v); dst, where its bounces go
                       * (K_v or 2 K_v); whether the emitters' bounces probe for a next round */
    RB_VEC4(scene);   /* xyz: the centre of the job's bounds; w: their radius */
    RB_VEC4(brdf);    /* x: the least roughness of a VPL's BRDF; yzw: unused */
};

/* Spatial interleaving (seed 000, A.1): at most this many sub-images along each axis, and a
 * filter radius of at most this many pixels (the job's bounds on interleave and filter_radius;
 * the indirect tent's half-width, the radius rounded to a multiple of the interleave, is at most
 * 16 too, since a larger multiple is never nearer). */
#define RB_BDPT_MAX_INTERLEAVE 8
#define RB_BDPT_MAX_FILTER 16

/* The temporal caches (seed 000, section A; DESIGN.md "Temporal interleaved sampling"): at most
 * this many, one reprojection target each. */
#define RB_BDPT_MAX_CACHES 8

/* What the reprojection and reconstruction passes know of the caches, by age a: the cache
 * written a frames ago (frame f - a), which is slot (f - a) mod l. Host-written each frame. */
struct rb_gpu_bdpt_history {
    RB_MAT4(view_proj[RB_BDPT_MAX_CACHES]); /* frame f - a's camera, unjittered */
    RB_VEC4(depth_row[RB_BDPT_MAX_CACHES]); /* its view depth: dot(depth_row, (x, 1)) */
    RB_VEC4(offset[RB_BDPT_MAX_CACHES]);    /* by slot: xy, its samples' offset from the pixel
                                             * centres, in pixels; zw unused */
    RB_UVEC4(info);  /* l; which ages hold a cache (bit a); the hit test (RB_BDPT_HIT_*); the
                      * slot this frame writes, f mod l */
    RB_VEC4(params); /* 2 sigma^2 of the gaussian test; epsilon of the binary one; the
                      * least cosine between a pixel's normal and a cache sample's (the
                      * filter's normal threshold); unused */
};

/* info.z: the hit test, as enum rb_bdpt_hit_test. */
#define RB_BDPT_HIT_TEST_GAUSSIAN 1u
#define RB_BDPT_HIT_TEST_BINARY 2u

/* Push constants of the split, gather and filter passes. */
struct rb_gpu_bdpt_image_push {
    RB_UVEC4(split);  /* n, sub-image width, height, the filter's tent half-width h for
                       * indirect light (a multiple of n; 1: no filter) */
    RB_VEC4(stops);   /* depth threshold, normal threshold, the box radius for direct light
                       * (n / 2, one interleave block; 0: no filter), the sub-images that saw
                       * samples (the first min(n^2, max(K_v, K_b))) */
    RB_VEC4(light);   /* the filter's light stop: the least ratio of two pixels' direct light
                       * (0: none) */
};

/* ---- the MIS weights (BDPT.md "As implemented"), one definition for GLSL and C: the connect
 * shader uses them and tests/unit/test_bdpt.c holds them to their properties. */
#ifdef VULKAN
#define RB_BDPT_FN
#define RB_BDPT_UINT uint
#else
#define RB_BDPT_FN static inline
#define RB_BDPT_UINT uint32_t
#endif

/* How many of the iterations k < limit land on sub-image s of count (n x n): those with
 * k mod count == s. The host's counts of a connect iteration and the emitters' dispatch's
 * bundles of a pixel's sub-image. */
RB_BDPT_FN RB_BDPT_UINT rb_bdpt_share(RB_BDPT_UINT limit, RB_BDPT_UINT s, RB_BDPT_UINT count)
{
    return limit > s ? (limit - s + count - 1u) / count : 0u;
}

/* The area density at z of a bundle ray from x: a direction uniform over x's hemisphere
 * (1 / 2 pi) seen from z at cos_z, dist2 away. */
RB_BDPT_FN float rb_bdpt_bundle_density(float cos_z, float dist2)
{
    return cos_z / (2.0f * 3.14159265358979f * dist2);
}

/* The area density at z of a VPL: the light's choice times its direction's (or beam point's)
 * density, pdf, over the sphere of radius dist (1 for a directional light), at cos_in. */
RB_BDPT_FN float rb_bdpt_vpl_density(float pdf, float cos_in, float dist2)
{
    return pdf * cos_in / dist2;
}

/* The area density at y1 of the bounce of an emitter's point y0: a cosine-distributed
 * direction from y0 (cos_y0 / pi) seen from y1 at cos_y1, dist2 away. */
RB_BDPT_FN float rb_bdpt_bounce_density(float cos_y0, float cos_y1, float dist2)
{
    return cos_y0 * cos_y1 / (3.14159265358979f * dist2);
}

/* The balance heuristic over a pixel's samples: the weight of a strategy drawn n_s times that
 * finds z with area density p_s, against the other's n_o draws at density p_o. The weights of
 * the two strategies of a path sum to one. */
RB_BDPT_FN float rb_bdpt_balance(float n_s, float p_s, float n_o, float p_o)
{
    float s = n_s * p_s, o = n_o * p_o;
    return s > 0.0f ? s / (s + o) : 0.0f;
}

/* The power heuristic (exponent 2) over the same counts and densities: the weight a VPL and its
 * bounce take for the paths they both make (BDPT.md "Two bounces"). Neither samples the BRDFs
 * the connection passes through, so where both densities are moderate the balance heuristic
 * keeps half of a bounce that lands beside a glossy surface and lights a patch of floor through
 * it; squaring hands each path more firmly to the strategy with the larger density. */
RB_BDPT_FN float rb_bdpt_power(float n_s, float p_s, float n_o, float p_o)
{
    float s = n_s * p_s, o = n_o * p_o;
    if (!(s > 0.0f))
        return 0.0f;
    float t = o / s; /* as a ratio, so that squaring a density near a singularity cannot overflow */
    return 1.0f / (1.0f + t * t);
}

/* Strategies, as enum rb_bdpt_strategies. */
#define RB_BDPT_MIS 1
#define RB_BDPT_VPL 2
#define RB_BDPT_BUNDLE 3

/* The light the bdpt passes gather, four images: diffuse and specular parts of what reaches
 * the camera vertex after one scattering there from bundle directions (the environment and
 * emitters: direct light) and after more (indirect light). */
#define RB_BDPT_DIRECT_DIFFUSE 0
#define RB_BDPT_DIRECT_SPECULAR 1
#define RB_BDPT_INDIRECT_DIFFUSE 2
#define RB_BDPT_INDIRECT_SPECULAR 3
#define RB_BDPT_LIGHT_COUNT 4

/* The direct light of the emitters' points at every pixel (the emitters' dispatch of connect,
 * in image order, added after the filter): diffuse and specular parts. */
#define RB_BDPT_EMITTED_COUNT 2

#endif
