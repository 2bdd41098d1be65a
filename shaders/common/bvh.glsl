// Ray casting through the BVH of lib/bvh (layout: bvh_shared.h), for the rays the hybrid
// integrator cannot finish in screen space (seed 003). The including shader declares, first:
//   layout(std430, binding = ...) readonly buffer BvhNodes { rb_gpu_bvh_node bvh_nodes[]; };
//   layout(std430, binding = ...) readonly buffer BvhTris { rb_gpu_bvh_triangle bvh_tris[]; };
// Traversal: a fixed stack of RB_BVH_STACK_SIZE (the builder keeps every leaf shallower), both
// children's boxes per visit, the nearer first; both faces hit. The closest hit is the least
// (t, triangle id), so a tie goes to the lower id whatever the order of the visits. An includer
// may define RB_BVH_FILTER(id, bary) first: a hit it returns false for is passed through (the
// hybrid's alpha mask).
#ifndef RB_BVH_GLSL
#define RB_BVH_GLSL

#include "bvh_shared.h"

struct rb_bvh_hit {
    float t;
    uint triangle; // global triangle id
    vec2 bary;     // weights of the triangle's second and third vertices
    uint extra;    // the triangle's v2.w, as bits (the hybrid's bake word)
};

// Möller-Trumbore, with the barycentrics let past the edges by a hair so that a ray through an
// edge shared by two triangles cannot slip between them (both then hit, and the tie rule picks).
bool rb_bvh_triangle(vec3 o, vec3 d, rb_gpu_bvh_triangle tri, out float t, out vec2 bary)
{
    const float edge = 1.0 / 1048576.0;
    vec3 e1 = tri.v1.xyz - tri.v0.xyz, e2 = tri.v2.xyz - tri.v0.xyz;
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    t = 0.0;
    bary = vec2(0.0);
    if (det == 0.0)
        return false;
    float inv = 1.0 / det;
    vec3 s = o - tri.v0.xyz;
    float u = dot(s, p) * inv;
    if (u < -edge || u > 1.0 + edge)
        return false;
    vec3 q = cross(s, e1);
    float v = dot(d, q) * inv;
    if (v < -edge || u + v > 1.0 + edge)
        return false;
    t = dot(e2, q) * inv;
    bary = vec2(u, v);
    return true;
}

// The entry distance of the ray into the box [lo, hi] within [tmin, tmax], or a miss. The far
// distance is widened by 2 gamma(3) (Ize, "Robust BVH Ray Traversal", 2013) so that rounding
// does not cut off a hit on a box face.
bool rb_bvh_box(vec3 lo, vec3 hi, vec3 o, vec3 inv_d, float tmin, float tmax, out float tnear)
{
    vec3 a = (lo - o) * inv_d, b = (hi - o) * inv_d;
    vec3 n = min(a, b), f = max(a, b);
    tnear = max(max(n.x, n.y), max(n.z, tmin));
    float tfar = min(min(f.x, f.y), min(f.z, tmax)) * 1.0000004;
    return tnear <= tfar;
}

// 1 / d with each component kept finite: a zero (or denormal) component becomes 1e-20, so that
// the slab test never multiplies zero by infinity (boxes are padded, so an origin is never
// exactly on a face of a flat box).
vec3 rb_bvh_inv_dir(vec3 d)
{
    vec3 m = mix(d, vec3(1e-20), lessThan(abs(d), vec3(1e-20)));
    return 1.0 / m;
}

// The closest hit or, with any_hit, the first found. Shared by both entry points below.
bool rb_bvh_trace(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, out rb_bvh_hit hit)
{
    vec3 inv_d = rb_bvh_inv_dir(d);
    uint stack_node[RB_BVH_STACK_SIZE];
    float stack_t[RB_BVH_STACK_SIZE];
    uint sp = 0u, node = 0u;
    bool found = false;
    hit.t = tmax;
    hit.triangle = RB_NONE;
    hit.bary = vec2(0.0);
    hit.extra = 0u;
    for (;;) {
        rb_gpu_bvh_node n = bvh_nodes[node];
        uint word[2] = uint[2](floatBitsToUint(n.box0_min.w), floatBitsToUint(n.box1_min.w));
        uint leaf[2] = uint[2](floatBitsToUint(n.box0_max.w), floatBitsToUint(n.box1_max.w));
        float tn[2];
        bool enter[2];
        enter[0] = rb_bvh_box(n.box0_min.xyz, n.box0_max.xyz, o, inv_d, tmin, hit.t, tn[0]);
        enter[1] = rb_bvh_box(n.box1_min.xyz, n.box1_max.xyz, o, inv_d, tmin, hit.t, tn[1]);
        for (int c = 0; c < 2; c++) {
            if (!enter[c] || leaf[c] == 0u)
                continue;
            enter[c] = false;
            uint end = word[c] + (leaf[c] & ~RB_BVH_LEAF_BIT);
            for (uint i = word[c]; i < end; i++) {
                rb_gpu_bvh_triangle tri = bvh_tris[i];
                uint id = floatBitsToUint(tri.v0.w);
                float t;
                vec2 bary;
                if (!rb_bvh_triangle(o, d, tri, t, bary) || !(t > tmin) || !(t < tmax))
                    continue;
                if (found && (t > hit.t || (t == hit.t && id >= hit.triangle)))
                    continue;
#ifdef RB_BVH_FILTER
                if (!RB_BVH_FILTER(id, bary))
                    continue;
#endif
                found = true;
                hit.t = t;
                hit.triangle = id;
                hit.bary = bary;
                hit.extra = floatBitsToUint(tri.v2.w);
                if (any_hit)
                    return true;
            }
        }
        // Boxes entered beyond a hit found in this node's leaves are passed by.
        enter[0] = enter[0] && tn[0] <= hit.t;
        enter[1] = enter[1] && tn[1] <= hit.t;
        if (enter[0] && enter[1]) {
            int near = tn[1] < tn[0] ? 1 : 0;
            stack_node[sp] = word[1 - near];
            stack_t[sp] = tn[1 - near];
            sp++;
            node = word[near];
        } else if (enter[0] || enter[1]) {
            node = word[enter[0] ? 0 : 1];
        } else {
            // Pop the next subtree still nearer than the closest hit.
            bool next = false;
            while (sp > 0u) {
                sp--;
                if (stack_t[sp] <= hit.t) {
                    node = stack_node[sp];
                    next = true;
                    break;
                }
            }
            if (!next)
                break;
        }
    }
    return found;
}

bool rb_bvh_intersect(vec3 o, vec3 d, float tmin, float tmax, out rb_bvh_hit hit)
{
    return rb_bvh_trace(o, d, tmin, tmax, false, hit);
}

bool rb_bvh_occluded(vec3 o, vec3 d, float tmin, float tmax)
{
    rb_bvh_hit hit;
    return rb_bvh_trace(o, d, tmin, tmax, true, hit);
}

#endif
