/* The BVH the hybrid integrator traces in a compute shader (lavapipe has no ray queries; seed
 * 003), shared by C (lib/bvh) and GLSL (shaders/common/bvh.glsl); C checks the sizes with
 * _Static_assert in lib/bvh/bvh.h. Both arrays are std430.
 *
 * Nodes: a binary tree, node 0 the root, in depth-first order (a node, then its child 0's
 * subtree, then its child 1's). A node holds both children's boxes, so one visit tests two.
 * Each child is either an inner node (its index) or a leaf (a run of triangles): the w
 * components hold two words per child, as float bits (floatBitsToUint in GLSL):
 *   box0_min.w: child 0's node index (inner) or first triangle (leaf)
 *   box0_max.w: child 0's leaf word: 0 for an inner node, RB_BVH_LEAF_BIT | triangle count
 *   box1_min.w, box1_max.w: the same for child 1.
 * A leaf with no triangles (RB_BVH_LEAF_BIT alone) is empty: the root of a BVH with one leaf
 * or none has one. Boxes are padded outwards so that a flat box (an axis-aligned triangle) still
 * has a volume the slab test can enter.
 *
 * Triangles: world positions as given, in leaf order (each leaf's sorted by global id), with
 * the global triangle id (the index into the renderer's triangle list) in v0.w and the object
 * index (struct rb_bvh_object) in v1.w, both as float bits. lib/bvh leaves v2.w 0, for its user
 * to fill (the hybrid integrator's bake word, hybrid_shared.h); a hit carries it. */
#ifndef RB_SHADERS_BVH_SHARED_H
#define RB_SHADERS_BVH_SHARED_H

#include "shared.h"

/* Embree's maxDepth for the build, and the traversal stack, which must be deeper than any
 * leaf (lib/bvh/bvh.c checks the tree it flattens against it). */
#define RB_BVH_MAX_DEPTH 48
#define RB_BVH_STACK_SIZE 64
#define RB_BVH_MAX_LEAF_SIZE 4
#define RB_BVH_LEAF_BIT 0x80000000u

struct rb_gpu_bvh_node {
    RB_VEC4(box0_min); /* xyz: child 0's box; w: child 0's index word (see above) */
    RB_VEC4(box0_max); /* xyz; w: child 0's leaf word */
    RB_VEC4(box1_min); /* xyz: child 1's box; w: child 1's index word */
    RB_VEC4(box1_max); /* xyz; w: child 1's leaf word */
};

struct rb_gpu_bvh_triangle {
    RB_VEC4(v0); /* xyz: the first vertex, world space; w: global triangle id (float bits) */
    RB_VEC4(v1); /* xyz: the second; w: object index (float bits) */
    RB_VEC4(v2); /* xyz: the third; w: 0 from lib/bvh, the user's word */
};

/* bvh_trace.comp (tests/unit/test_bvh.c): one ray per invocation. */
#define RB_BIND_BVH_TRACE_NODES 0
#define RB_BIND_BVH_TRACE_TRIS 1
#define RB_BIND_BVH_TRACE_RAYS 2
#define RB_BIND_BVH_TRACE_HITS 3
#define RB_BIND_BVH_TRACE_COUNT 4

struct rb_gpu_bvh_ray {
    RB_VEC4(origin);    /* xyz; w: tmin */
    RB_VEC4(direction); /* xyz (any length); w: tmax */
};

struct rb_gpu_bvh_trace_hit {
    RB_VEC4(hit);      /* t (-1: none), triangle (float bits), barycentrics of vertices 1, 2 */
    RB_UVEC4(occluded); /* rb_bvh_occluded over (tmin, tmax), and over (tmin, t / 2) after a
                         * hit (0 when none); z, w: 0 */
};

#endif
