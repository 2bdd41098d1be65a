/* The BVH of the hybrid integrator (seed 003): rays that fail in screen space are traced on the
 * GPU through a BVH over the world-space triangles (shaders/common/bvh.glsl), since lavapipe has
 * no ray queries. Built on the CPU by Embree's rtcBuildBVH, then flattened into the layout of
 * shaders/common/bvh_shared.h in a canonical order, so that the bytes do not depend on Embree's
 * threads. Not for the reference, which traces Embree's own scene. */
#ifndef RB_BVH_BVH_H
#define RB_BVH_BVH_H

#include <stdatomic.h>

#include "core/core.h"

#include "bvh_shared.h" /* shaders/common, on the include path */

_Static_assert(sizeof(struct rb_gpu_bvh_node) == 64, "rb_gpu_bvh_node is std430");
_Static_assert(sizeof(struct rb_gpu_bvh_triangle) == 48, "rb_gpu_bvh_triangle is std430");
_Static_assert(sizeof(struct rb_gpu_bvh_ray) == 32, "rb_gpu_bvh_ray is std430");
_Static_assert(sizeof(struct rb_gpu_bvh_trace_hit) == 32, "rb_gpu_bvh_trace_hit is std430");
_Static_assert(RB_BVH_STACK_SIZE > RB_BVH_MAX_DEPTH + 8, "the stack outgrows Embree's depth");

/* A world-space triangle soup as the renderer lays it out (lib/integrators/frame.c). */
struct rb_bvh_mesh {
    const float *positions;  /* xyz of vertex i at positions[i * stride_floats] */
    size_t stride_floats;    /* at least 3 */
    uint32_t vertex_count;   /* every index is below it */
    const uint32_t *indices; /* global triangle t is indices[3t], [3t + 1], [3t + 2] */
    uint32_t triangle_count;
};

/* One instance's triangles, contiguous in the global list, and optionally a coarser version of
 * them (seed 003's LOD: a simplified mesh over the same vertices, elsewhere in the list), which
 * enters in its place when the whole object does not fit. Objects should not overlap. */
struct rb_bvh_object {
    uint32_t first_triangle, triangle_count;
    uint32_t lod_first, lod_count; /* lod_count 0: none */
};

/* How objects are scored for the budget (rb_bvh_select). */
enum rb_bvh_score {
    RB_BVH_SCORE_DEFAULT = 0, /* RELEVANCE */
    RB_BVH_SCORE_RELEVANCE,   /* projected size from the eye over triangles, with shares */
    RB_BVH_SCORE_AREA,        /* world area over triangles, the same from anywhere */
};

/* What became of an object. */
enum rb_bvh_choice {
    RB_BVH_LEFT_OUT = 0,
    RB_BVH_WHOLE,
    RB_BVH_COARSER, /* by its coarser version */
};

struct rb_bvh_desc {
    const struct rb_bvh_mesh *mesh;
    const struct rb_bvh_object *objects; /* NULL with object_count 0: the whole mesh, one object */
    uint32_t object_count;
    uint64_t triangle_budget; /* the most triangles the BVH holds; 0: every object */
    enum rb_bvh_score score;
    float eye[3];              /* RELEVANCE: the camera's position, where relevance is seen from */
    uint32_t thread_count;     /* Embree's build threads; 0: one per core. The output is the same
                                * whatever the count. */
    const atomic_bool *cancel; /* NULL, or a flag another thread may set: once it is true the
                                * build stops early with RB_E_INTERRUPTED */
};

/* What rb_bvh_build makes: the two arrays of bvh_shared.h, ready to upload. */
struct rb_bvh {
    struct rb_gpu_bvh_node *nodes; /* node_count >= 1; node 0 is the root */
    uint32_t node_count;
    struct rb_gpu_bvh_triangle *triangles;
    uint32_t triangle_count;
    uint32_t object_count, objects_included;
    uint8_t *choice;               /* object_count of them: enum rb_bvh_choice */
    uint32_t objects_simplified;   /* of those included, by their coarser version */
    uint64_t triangles_left_out;   /* of the objects left out by the budget (degenerate ones not
                                    * counted) */
    uint64_t triangles_degenerate; /* zero area or not finite: never in the BVH */
    uint32_t depth;                /* of the deepest leaf, the root's children at 1 */
    float bounds_min[3], bounds_max[3]; /* of the triangles included; min > max when none */
};

/* Chooses the objects of desc->mesh the BVH holds under desc->triangle_budget (seed 003: "a
 * score for each object based on its occlusion relevance vs traversal cost; include the best
 * objects until maximum BVH size is reached"), writing choice[i] (enum rb_bvh_choice) for each
 * of desc's objects. When every object fits, every object is whole. Otherwise, by desc->score:
 * RELEVANCE: an object's relevance is its world area over (d^2 + r^2), d the distance from
 * desc->eye to its bounds' centre and r their half diagonal (about four times the solid angle
 * it covers from the eye: what it can occlude there, behind the camera too); its share of the
 * budget is in proportion to its relevance, and one over its share takes its coarser version
 * (if it has one with fewer triangles); its score is its relevance over the triangles of the
 * version it takes. AREA: its area over its triangles, the same from anywhere. The best score
 * first (ties to the lower index), greedily: an object that no longer fits enters by its
 * coarser version if that fits, or is left out, and later ones are still tried. RELEVANCE then
 * spends what is left making coarser objects whole again, the most relevant first. Degenerate
 * triangles (zero area, a coordinate not finite) count for nothing. A pure function of the
 * vertices, objects, budget and eye. Fails as rb_bvh_build does on bad input. */
enum rb_status rb_bvh_select(const struct rb_bvh_desc *desc, uint8_t *choice, struct rb_err *err);

/* Builds the BVH of the objects rb_bvh_select chooses (out->choice says which). Degenerate
 * triangles are left out and not counted against the budget. No triangles gives a valid BVH
 * that nothing hits. The result depends only on the input, not on Embree's threads or
 * scheduling. *out (released with rb_bvh_release) is written only on success. Fails with
 * RB_E_INVALID for an object or index out of range, RB_E_NOMEM, RB_E_EXTERNAL when Embree fails
 * (its error named), or RB_E_INTERRUPTED once *desc->cancel is true. Thread-safe: each call has its
 * own Embree device. */
enum rb_status rb_bvh_build(const struct rb_bvh_desc *desc, struct rb_bvh *out, struct rb_err *err);

/* Frees what rb_bvh_build allocated and zeroes *bvh; accepts a zeroed struct. */
void rb_bvh_release(struct rb_bvh *bvh);

#endif
