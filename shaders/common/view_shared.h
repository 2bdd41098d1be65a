/* The raster views' layouts, shared by C (lib/passes/view.c) and GLSL (shaders/view.*): view
 * kinds, binding numbers, push constants, the per-view record and the linked-list node. C checks
 * each size with _Static_assert in lib/passes/passes.h. */
#ifndef RB_SHADERS_VIEW_SHARED_H
#define RB_SHADERS_VIEW_SHARED_H

#include "shared.h"

#ifdef VULKAN
#define RB_FLOAT(n) float n
#define RB_UINT(n) uint n
#else
#define RB_FLOAT(n) float n
#define RB_UINT(n) uint32_t n
#endif

/* View kinds, as in enum rb_view_kind. */
#define RB_VIEW_PERSPECTIVE 1
#define RB_VIEW_ORTHOGRAPHIC 2
#define RB_VIEW_PARABOLOID 3

/* The view pass's one descriptor set (push descriptors): each output binds what it reads. */
#define RB_VIEW_BIND_VERTICES 0        /* the slot's geometry record (all) */
#define RB_VIEW_BIND_VIEWS 1           /* rb_gpu_view (all) */
#define RB_VIEW_BIND_MATERIALS 2       /* rb_gpu_material (all: blended ones are in no view) */
#define RB_VIEW_BIND_SRGB_TEXTURES 3   /* sampler2DArray (rsm, list) */
#define RB_VIEW_BIND_LINEAR_TEXTURES 4 /* sampler2DArray (rsm, list) */
#define RB_VIEW_BIND_HEADS 5           /* r32ui image2DArray, a layer per view (list) */
#define RB_VIEW_BIND_NODES 6           /* rb_gpu_list_node (list) */
#define RB_VIEW_BIND_COUNTER 7         /* rb_gpu_list_counter (list) */
#define RB_VIEW_BIND_COUNT 8

/* A list head that takes no fragments: a batch whose caller cleared the heads to this and marked
 * the texels it reads RB_NONE (struct rb_view_batch's has_marked_heads) lists those alone. */
#define RB_VIEW_LIST_SKIP 0xfffffffeu

/* Paraboloid views tessellate each triangle so that no projected sub-edge is longer than this
 * many texels (while the level stays under RB_VIEW_TESS_MAX_LEVEL); view.c derives the edge
 * error this leaves: C^2 / (2 size), 2 texels of a 256^2 map (and why not less). */
#define RB_VIEW_TESS_CHORD_PX 32.0
#define RB_VIEW_TESS_MAX_LEVEL 64.0
/* Paraboloid views draw nothing nearer than this fraction of their far distance. */
#define RB_VIEW_PARABOLOID_NEAR 1e-4

/* One view: where it looks from and how it projects. rb_view_perspective, _orthographic and
 * _paraboloid fill it. The layout is struct rb_gpu_shadow_view's, so the shadow maps' views
 * are views of this kind as they are. */
struct rb_gpu_view {
    RB_MAT4(transform); /* perspective, orthographic: world to clip; paraboloid: world to the
                         * view's frame (x right, y down the map, z the axis), scaled by 1/far */
    RB_VEC4(origin);    /* xyz: the eye (perspective, paraboloid) or the near plane's centre
                         * (orthographic); w: not read (the shadow maps keep the light kind) */
    RB_VEC4(axis);      /* xyz: the unit view direction (orthographic depth runs along it;
                         * paraboloid: the hemisphere's axis); w: not read (texel size) */
};

/* Push constants of one view. */
struct rb_gpu_view_push {
    RB_UVEC4(index);    /* view (into the views buffer), target layer, kind, list capacity */
    RB_VEC4(intensity); /* rsm: rgb radiant intensity in W/sr (perspective), or irradiance in
                         * W/m^2 across the beam (orthographic); w unused */
    RB_VEC4(size);      /* target width, height in pixels, and their reciprocals */
};

/* A fragment of a linked-list view: seed 000's struct Node (B.2), 20 bytes. */
struct rb_gpu_list_node {
    RB_FLOAT(depth); /* the view depth, as the depth output stores it; its sign is the face:
                      * + front, - back */
    RB_UINT(normal); /* the interpolated vertex normal in polar angles, 16 bits each: theta in
                      * [0, pi] low, phi in [-pi, pi] high (rb_view_polar_encode) */
    RB_UINT(albedo); /* diffuse RGB and gray specular F0, 8 bits each (rb_material_pack) */
    RB_UINT(gloss);  /* roughness, 8 bits, low; emitted radiance in the 24 bits above it */
    RB_UINT(next);   /* the pixel's next node, RB_NONE at the end of its list */
};

/* The node pool's counters, reset by each list batch. */
struct rb_gpu_list_counter {
    RB_UINT(requested); /* fragments that asked for a node, whether or not they got one */
    RB_UINT(dropped);   /* of them, those that found the pool full and wrote nothing */
    RB_UINT(pad0);
    RB_UINT(pad1);
};

#endif
