/* The hybrid integrator's buffers and push constants, shared by C (lib/passes/hybrid.c,
 * lib/integrators/hybrid.c) and GLSL (shaders/hybrid_*.comp); C checks each size with
 * _Static_assert in lib/passes/passes.h. DESIGN.md "hybrid" and man/raybundle-job.5 say what
 * the passes do. */
#ifndef RB_SHADERS_HYBRID_SHARED_H
#define RB_SHADERS_HYBRID_SHARED_H

#include "shared.h"

/* The two lobes a pixel samples separately, each with its own rays, counts and filter. */
#define RB_HYBRID_DIFFUSE 0u
#define RB_HYBRID_SPECULAR 1u

/* A ray slot's state (the w of its first vec4). A slot is (lobe, ray, pixel): slot index
 * ((lobe * rays + ray) * height + y) * width + x, so every ray has one place whatever order
 * the passes find it in. */
#define RB_HYBRID_NONE 0u    /* not requested */
#define RB_HYBRID_SCREEN 1u  /* hit in screen space, shaded */
#define RB_HYBRID_QUEUED 2u  /* left the screen or passed behind unknown depth: for the BVH */
#define RB_HYBRID_BVH 3u     /* hit in the BVH, shaded */
#define RB_HYBRID_MISS 4u    /* hit nothing: the environment */
#define RB_HYBRID_DROPPED 5u /* queued when the queue was full: not a sample */
#define RB_HYBRID_ABSORBED 6u /* sampled below the surface: a sample of nothing */

/* One ray slot, 32 bytes (at 1920x1080 a ray a lobe's fit lavapipe's 128 MiB storage range).
 * While the ray waits for the BVH: a.xyz its direction, b.rgb the estimator's weight (BRDF x
 * cosine / pdf, untextured as the output pass expects), b.w the lobe's pdf of the direction (for
 * the MIS weight of an emitter it hits); its origin is its pixel's, recomputed
 * (rb_hybrid_origin). Once shaded, what it brings the pixel, weighted, split as the layers are:
 * a.rgb the emission or environment it found, MIS-weighted, plus the light pass's light sample
 * (direct light of the camera vertex), b.rgb the light its hit reflects (the indirect light). */
struct rb_gpu_hybrid_slot {
    RB_VEC4(a); /* w: state, float bits of RB_HYBRID_* */
    RB_VEC4(b);
};

/* Layers of an accumulator image: two sets (A, B) of four, then the frame's geometry. Set s's
 * layer 4s + RB_HYBRID_ACC_*: rgb sums of the lobe's direct and indirect light; w of the direct
 * layer: samples; w of the indirect layer: sum of the squared luminance of the samples. */
#define RB_HYBRID_ACC_DIFFUSE_DIRECT 0u
#define RB_HYBRID_ACC_DIFFUSE_INDIRECT 1u
#define RB_HYBRID_ACC_SPECULAR_DIRECT 2u
#define RB_HYBRID_ACC_SPECULAR_INDIRECT 3u
#define RB_HYBRID_ACC_GEOMETRY 8u /* shading normal xyz, depth (0: no surface) */
#define RB_HYBRID_ACC_LAYERS 9u

/* Ray counts of a frame (integer atomics: the totals do not depend on the order), then the
 * BVH pass's indirect dispatch. */
struct rb_gpu_hybrid_counters {
    RB_UVEC4(rays);     /* requested, screen hits, queued, BVH hits */
    RB_UVEC4(more);     /* misses, dropped (queue full), queue length, unused */
    RB_UVEC4(check);    /* check_screen: screen hits traced again, those the BVH agrees with */
    RB_UVEC4(dispatch); /* x, y, z workgroups of the BVH pass */
};

/* The emitter table of next-event estimation (seed 003 has none; DESIGN.md "hybrid", rays):
 * the pc.bake.w emissive triangles' global indices in `indices` from uint pc.scene.z (written
 * once), and their running sums of emitted power (area x luminance of the emissive factor, as
 * the reference and bdpt weigh them), as float bits in `blocks` after the queue's blocks, the
 * total last: hybrid_emitters.comp writes them each frame from the frame's vertices. */

/* Workgroup size of the queue's passes (a block of slots each) and of the BVH pass. */
#define RB_HYBRID_QUEUE_GROUP 256u
#define RB_HYBRID_BVH_GROUP 64u

/* Side of the noise tiles (seed 003: variance over 16 x 16 tiles). */
#define RB_HYBRID_TILE 16u

/* The baked light of a BVH triangle (seed 003: "bake direct artificial light"), in the word its
 * v2.w carries: 0 for none, else bits 0-3 its resolution R (1 to 15), bit 4 set when its back
 * is baked too (a double-sided material), bits 5-31 the index of its first point, in vec4s from
 * the start of the BVH's triangle buffer. That buffer holds the triangles' room, then each
 * global triangle's word (0 for one the BVH left out), from uint push.bake.z, for screen hits,
 * which know their triangle from the G-buffer, then the points. Its (R + 1)(R + 2) / 2 points sit at barycentrics (i / R, j / R) of its second and
 * third vertices, shrunk toward the centroid by RB_HYBRID_BAKE_SHRINK (so no point sits on an
 * edge, where a neighbour's surface would shadow half of it), row j after row j - 1; the back's
 * points follow the front's. Each holds irradiance / pi (what a white Lambertian surface
 * reflects) in rgb, interpolated linearly across the lattice's small triangles. */
#define RB_HYBRID_BAKE_MAX_RES 15u
#define RB_HYBRID_BAKE_BACK 16u
#define RB_HYBRID_BAKE_SHIFT 5u
#define RB_HYBRID_BAKE_SHRINK 0.02

/* Push constants of every hybrid pass: the one layout keeps the record code simple. */
struct rb_gpu_hybrid_push {
    RB_UVEC4(frame);   /* frame index, rays a lobe, lobe of this dispatch, slots per lobe */
    RB_UVEC4(history); /* reset A, reset B (0/1), output set (0: A, 1: B) | 2 with feedback
                        * (max_bounces unlimited, rb_hybrid_feedback) | max_bounces << 2
                        * otherwise (rb_hybrid_max_bounces), younger set */
    RB_UVEC4(sizes);   /* spp aimed for, screen steps, queue capacity, hiz levels */
    RB_UVEC4(level);   /* hiz: level written, its width, height, offset; queue: phase */
    RB_UVEC4(more);    /* hiz: offset of the level read, its width, height; light_rays: x, the
                        * shadow rays march the screen too (1); filter radius */
    RB_VEC4(params);   /* noise target, thickness, filter depth stop, filter normal stop */
    RB_VEC4(scene);    /* scene diagonal, ray offset (fraction of depth), first uint of the
                        * emitter list in `indices` (uint bits), check_screen (0/1) */
    RB_UVEC4(bake);    /* baked light (0/1), screen hits find their triangle by the G-buffer's
                        * index (1) or by a short BVH ray (0), first uint of the per-triangle
                        * bake words, emissive triangles (the emitter table's length) */
};

#endif
