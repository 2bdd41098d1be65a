// Program 1 of seed 000 (B.3): from a point x1, the nearest surface facing it along a ray-bundle,
// found in x1's texel of the bundle's per-pixel lists (view_list.frag). One definition for
// bdpt_connect.comp and bundle_probe.comp, through which tests/unit/test_bundle_search.c holds
// it to Embree. Needs view_shared.h and view.glsl, and the includer's declarations of the lists
// under these names: `heads` (r32ui uimage2DArray, the bundle in layer 0) and `nodes`
// (rb_gpu_list_node[]).
#ifndef RB_BUNDLE_SEARCH_GLSL
#define RB_BUNDLE_SEARCH_GLSL

// The surface a bundle ray meets.
struct rb_bundle_hit {
    bool found;
    float t;        // distance from x1
    vec3 n;         // shading normal, facing x1
    rb_material m;
    uint node;      // the node's index in nodes[]
};

// Whether node a comes before node b in the search's total order: nearer first, then by the
// node's words, so that the order the nodes were appended in (which varies from run to run)
// never changes the pick.
bool rb_bundle_before(rb_gpu_list_node a, rb_gpu_list_node b)
{
    if (a.depth != b.depth)
        return a.depth < b.depth;
    if (a.normal != b.normal)
        return a.normal < b.normal;
    if (a.albedo != b.albedo)
        return a.albedo < b.albedo;
    return a.gloss < b.gloss;
}

// The nearest surface facing x1 along the bundle v (an orthographic view, size x size texels,
// its lists in at most capacity nodes) from x1, in either direction. A node's depth carries its
// face in its sign (+ front: facing against the bundle's direction d). Going along s d (s = +-1)
// from view depth z1, the surfaces that face x1 are the nodes whose depth has the sign s, and
// they lie ahead where depth > s z1: the nearest is the least such depth. x1's own surface faces
// the other way and is never picked.
rb_bundle_hit rb_bundle_search(rb_gpu_view v, int size, uint capacity, vec3 x1, float s)
{
    rb_bundle_hit h;
    h.found = false;
    ivec2 t = rb_bundle_texel(v, size, x1);
    if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(size))))
        return h; // outside the fitted grid: cannot happen for a visible x1 (generate)
    float key = s * rb_view_depth(v, RB_VIEW_ORTHOGRAPHIC, x1);
    float eps = 0.5 * v.axis.w; // half a texel: the nodes' depths are taken at texel centres
    uint i = imageLoad(heads, ivec3(t, 0)).r;
    uint best = RB_NONE;
    rb_gpu_list_node b;
    for (uint step = 0u; i != RB_NONE && i < capacity && step < capacity; step++) {
        rb_gpu_list_node n = nodes[i];
        if (n.depth * s > 0.0 && n.depth > key + eps &&
            (best == RB_NONE || rb_bundle_before(n, b))) {
            best = i;
            b = n;
        }
        i = n.next;
    }
    if (best == RB_NONE)
        return h;
    h.found = true;
    h.t = b.depth - key;
    h.n = rb_view_polar_decode(b.normal);
    h.m = rb_material_unpack(uvec2(b.albedo, b.gloss));
    h.node = best;
    return h;
}

// The distance along x1's own line to the surface of the hit that the search found for x1
// along bundle v (size texels) on side s: the search takes the node's depth, which the
// rasterizer sampled at its texel's centre, up to half a texel's diagonal beside x1's line; on a
// surface at a slant to the bundle that depth is off by that times the slant, and z1, half the
// time behind its surface, was shadowed from the lights it faces. Here the node's plane (its
// normal through the centre's sample) meets x1's line: delta from the centre's depth, at most two
// texels (a plane nearly along the bundle), and no nearer than the search starts (half a
// texel). The one-bounce light that the bundles alone carry (strategies bundle, 512 of them, the
// demo room at 128x72, bundle_size 256) was 7.7% under the reference, 0.2% over with the plane;
// at bundle_size 1024 without it, 0.2% under: the texels' size, not the estimator.
// tests/unit/test_bundle_search.c holds it to Embree along x1's own line.
float rb_bundle_on_own_line(rb_gpu_view v, int size, vec3 x1, float s, rb_bundle_hit h)
{
    vec2 ndc = (v.transform * vec4(x1, 1.0)).xy;
    vec2 centre = (vec2(rb_bundle_texel(v, size, x1)) + 0.5) / float(size) * 2.0 - 1.0;
    vec2 off = ndc - centre;
    // The grid's rows in world space (the view's right and up over its half size).
    vec3 r0 = vec3(v.transform[0].x, v.transform[1].x, v.transform[2].x);
    vec3 r1 = vec3(v.transform[0].y, v.transform[1].y, v.transform[2].y);
    vec3 aside = off.x * r0 / dot(r0, r0) + off.y * r1 / dot(r1, r1);
    float nd = dot(h.n, v.axis.xyz), texel = v.axis.w;
    float delta = abs(nd) > 1e-4 ? clamp(-dot(h.n, aside) / nd, -2.0 * texel, 2.0 * texel) : 0.0;
    return max(h.t + s * delta, 0.5 * texel);
}

#endif
