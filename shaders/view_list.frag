// view, linked-list output (Yang et al. 2010; seed 000, B.2): every fragment of the view, front
// and back faces, appended to its pixel's list. A fragment that finds the node pool full writes
// nothing and is counted, so the overflow is reported, never silent. Each node carries the
// surface's material (rb_material_pack). Perspective and orthographic views.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"
#include "view.glsl"
#include "material.glsl"

layout(std430, binding = RB_VIEW_BIND_VIEWS) readonly buffer Views { rb_gpu_view views[]; };
layout(std430, binding = RB_VIEW_BIND_MATERIALS) readonly buffer Materials
{
    rb_gpu_material materials[];
};
layout(binding = RB_VIEW_BIND_SRGB_TEXTURES) uniform sampler2DArray srgb_textures;
layout(binding = RB_VIEW_BIND_LINEAR_TEXTURES) uniform sampler2DArray linear_textures;
layout(binding = RB_VIEW_BIND_HEADS, r32ui) uniform coherent uimage2DArray heads;
layout(std430, binding = RB_VIEW_BIND_NODES) writeonly buffer Nodes { rb_gpu_list_node nodes[]; };
layout(std430, binding = RB_VIEW_BIND_COUNTER) coherent buffer Counter
{
    rb_gpu_list_counter counter;
};
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 0) in vec3 i_pos;
layout(location = 1) in vec3 i_normal;
layout(location = 2) in vec2 i_uv;
layout(location = 3) flat in uint i_material;

void main()
{
    // Texels no search will read (RB_VIEW_LIST_SKIP) take no nodes: most of a bdpt bundle's.
    ivec3 texel = ivec3(ivec2(gl_FragCoord.xy), int(pc.index.y));
    if (imageLoad(heads, texel).r == RB_VIEW_LIST_SKIP)
        return;
    // Alpha-masked texels are holes for bundles as for the camera; single-sided faces seen from
    // behind are kept, since a bundle ray meets them from either side.
    rb_gpu_material m = materials[i_material];
    rb_surface s = rb_material_eval(m, i_uv, srgb_textures, linear_textures);
    if (m.params.z > 0.0 && s.alpha < m.params.z)
        return;
    uint index = atomicAdd(counter.requested, 1u);
    if (index >= pc.index.w) {
        atomicAdd(counter.dropped, 1u);
        return;
    }
    float depth = abs(rb_view_depth(views[pc.index.x], pc.index.z, i_pos));
    uint next = imageAtomicExchange(heads, texel, index);
    nodes[index].depth = gl_FrontFacing ? depth : -depth;
    nodes[index].normal = rb_view_polar_encode(normalize(i_normal));
    uvec2 mat = rb_material_pack(s.c_diff, s.f0, s.roughness, s.emission);
    nodes[index].albedo = mat.x;
    nodes[index].gloss = mat.y;
    nodes[index].next = next;
}
