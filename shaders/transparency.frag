// transparency: a fragment of a blended material (glTF alphaMode BLEND), lit as direct.comp
// lights a G-buffer pixel (emission, and the frame's punctual lights with their shadow maps:
// with the direct integrator, the emitters' point samples among them; with bdpt and hybrid,
// those samples and the environment's directions as the layer lights), premultiplied by its
// alpha (base colour factor x texture alpha). The pipeline blends it over what the fragments
// drawn before it left: rgb' = rgb_src + (1 - a) rgb, a' = (1 - a) a, from (0, 0, 0, 1), so the
// target ends as the light the blended layers add (rgb) and the fraction of the light behind
// them that passes (a); the output pass composites the frame under it.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "brdf.glsl"
#include "lights.glsl"
#include "material.glsl"

layout(std140, binding = RB_BIND_TRANSPARENCY_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std430, binding = RB_BIND_TRANSPARENCY_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(binding = RB_BIND_TRANSPARENCY_SRGB_TEXTURES) uniform sampler2DArray srgb_textures;
layout(binding = RB_BIND_TRANSPARENCY_LINEAR_TEXTURES) uniform sampler2DArray linear_textures;
layout(std430, binding = RB_BIND_TRANSPARENCY_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_TRANSPARENCY_SHADOW_VIEWS) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(binding = RB_BIND_TRANSPARENCY_SHADOW_MAPS) uniform sampler2DArray shadow_maps;

#include "shadow.glsl"
// The frame's lights and the layer lights after them: with bdpt and hybrid, the emitters' point
// samples and the environment's directions, which their own passes leave out.
#define RB_PUNCTUAL_LIGHT_COUNT (g.size.z + uint(g.shadow.w))
#include "punctual.glsl"

layout(location = 0) in vec3 i_pos;
layout(location = 1) in vec3 i_normal;
layout(location = 2) in vec4 i_tangent;
layout(location = 3) in vec2 i_uv;
layout(location = 4) flat in uint i_material;

layout(location = 0) out vec4 o_light; // premultiplied radiance, alpha

void main()
{
    rb_gpu_material m = materials[i_material];
    rb_surface s = rb_material_eval(m, i_uv, srgb_textures, linear_textures);
    // Single-sided materials show their front faces alone, as in the G-buffer.
    if (!gl_FrontFacing && m.specular_color.w <= 0.5)
        discard;
    float alpha = clamp(s.alpha, 0.0, 1.0);
    if (alpha <= 0.0)
        discard;

    // The shading frame as gbuffer.frag builds it.
    vec3 ng = normalize(cross(dFdx(i_pos), dFdy(i_pos)));
    vec3 n = normalize(i_normal);
    if (!gl_FrontFacing)
        n = -n;
    if (dot(ng, n) < 0.0)
        ng = -ng;
    if (m.textures.z >= 0)
        n = rb_normal_map(n, i_tangent,
                          texture(linear_textures, vec3(i_uv, float(m.textures.z))).xyz * 2.0 - 1.0,
                          m.emissive.w);
    vec3 v = normalize(g.camera_pos.xyz - i_pos);
    vec3 radiance = rb_punctual_light(s.emission, i_pos, n, ng, v, s.c_diff, s.f0, s.f90,
                                      s.roughness);
    o_light = vec4(radiance * alpha, alpha);
}
