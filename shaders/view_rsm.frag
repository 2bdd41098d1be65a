// view, reflective-shadow-map output (Dachsbacher and Stamminger 2005; DESIGN.md "bdpt", rsm):
// what the light sees at each texel -- world position, normal, the flux the texel's patch
// reflects, and its material as a bundle node stores it (for VPLs). Materials as in gbuffer.frag: alpha cutoff, single-sided faces seen from behind are
// not there. Perspective and orthographic views.
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
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 0) in vec3 i_pos;
layout(location = 1) in vec3 i_normal;
layout(location = 2) in vec2 i_uv;
layout(location = 3) flat in uint i_material;

layout(location = 0) out vec4 o_position; // world xyz; w = 1 (0 where nothing was drawn)
layout(location = 1) out vec4 o_normal;   // unit normal on the view's side; w = face (+1, -1)
layout(location = 2) out vec4 o_flux;     // reflected flux in W (rgb); w = the view depth
layout(location = 3) out uvec2 o_material; // rb_material_pack: a bundle node's albedo and gloss

// What one texel covers at the pixel centre: its solid angle in sr (perspective), or its area
// across the beam in m^2 (orthographic). With rows R0, R1, R3 of the view's transform, clip
// x, y and w of the direction d from the eye are R0.d, R1.d and R3.d (the eye projects to clip
// (0, 0, z, 0)); so d = M^-1 (x, y, 1) for NDC (x, y), and the solid angle per unit of NDC area
// is |det M^-1| / |d|^3. An orthographic view maps the plane across the beam linearly with rows
// R0, R1: a unit of NDC area is 1 / |R0 x R1| of it.
float texel_measure(rb_gpu_view v, uint kind)
{
    vec2 ndc = gl_FragCoord.xy * pc.size.zw * 2.0 - 1.0;
    float ndc_area = 4.0 * pc.size.z * pc.size.w;
    mat4 t = v.transform;
    vec3 r0 = vec3(t[0][0], t[1][0], t[2][0]);
    vec3 r1 = vec3(t[0][1], t[1][1], t[2][1]);
    if (kind == RB_VIEW_ORTHOGRAPHIC)
        return ndc_area / length(cross(r0, r1));
    vec3 r3 = vec3(t[0][3], t[1][3], t[2][3]);
    mat3 inv = inverse(transpose(mat3(r0, r1, r3)));
    vec3 d = inv * vec3(ndc, 1.0);
    float len = length(d);
    return ndc_area * abs(determinant(inv)) / (len * len * len);
}

void main()
{
    rb_gpu_material m = materials[i_material];
    rb_surface s = rb_material_eval(m, i_uv, srgb_textures, linear_textures);
    if (rb_material_discards(m, s, gl_FrontFacing))
        discard;
    rb_gpu_view v = views[pc.index.x];
    uint kind = pc.index.z;
    vec3 n = normalize(i_normal);
    if (!gl_FrontFacing)
        n = -n;
    o_position = vec4(i_pos, 1.0);
    o_normal = vec4(n, gl_FrontFacing ? 1.0 : -1.0);
    o_flux = vec4(s.c_diff * pc.intensity.rgb * texel_measure(v, kind), rb_view_depth(v, kind, i_pos));
    o_material = rb_material_pack(s.c_diff, s.f0, s.roughness, s.emission);
}
