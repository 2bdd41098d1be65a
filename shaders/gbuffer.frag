// gbuffer: materials and textures to the G-buffer (full precision): position and view depth,
// shading normal and face, diffuse albedo and triangle, specular F0 and roughness, emission and
// F90, motion vector and geometric normal.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "encode.glsl"
#include "material.glsl"

layout(std140, binding = RB_BIND_GBUFFER_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std430, binding = RB_BIND_GBUFFER_MATERIALS) readonly buffer Materials { rb_gpu_material materials[]; };
layout(binding = RB_BIND_GBUFFER_SRGB_TEXTURES) uniform sampler2DArray srgb_textures;
layout(binding = RB_BIND_GBUFFER_LINEAR_TEXTURES) uniform sampler2DArray linear_textures;

layout(location = 0) in vec3 i_pos;
layout(location = 1) in vec3 i_normal;
layout(location = 2) in vec4 i_tangent;
layout(location = 3) in vec2 i_uv;
layout(location = 4) flat in uint i_material;
layout(location = 5) in vec4 i_clip;
layout(location = 6) in vec4 i_prev_clip;

layout(location = 0) out vec4 o_position; // world xyz, view depth
layout(location = 1) out vec4 o_normal;   // shading normal, face (+1 front, -1 back)
layout(location = 2) out vec4 o_albedo;   // diffuse albedo, global triangle index
layout(location = 3) out vec4 o_specular; // F0, roughness
layout(location = 4) out vec4 o_emission; // emitted radiance, F90
layout(location = 5) out vec4 o_motion;   // previous minus current pixel position, octahedral Ng

void main()
{
    rb_gpu_material m = materials[i_material];
    if (m.params.z < 0.0)
        discard; // blended: the transparency pass draws it, after the deferred passes
    vec4 base = m.base_color;
    if (m.textures.x >= 0)
        base *= texture(srgb_textures, vec3(i_uv, float(m.textures.x)));
    if (m.params.z > 0.0 && base.a < m.params.z)
        discard;
    bool double_sided = m.specular_color.w > 0.5;
    if (!gl_FrontFacing && !double_sided)
        discard;

    float metallic = m.params.x, roughness = m.params.y;
    if (m.textures.y >= 0) {
        vec4 mr = texture(linear_textures, vec3(i_uv, float(m.textures.y)));
        roughness *= mr.g;
        metallic *= mr.b;
    }
    metallic = clamp(metallic, 0.0, 1.0);
    roughness = clamp(roughness, 0.0, 1.0);

    vec3 ng = normalize(cross(dFdx(i_pos), dFdy(i_pos)));
    vec3 n = normalize(i_normal);
    float face = gl_FrontFacing ? 1.0 : -1.0;
    if (!gl_FrontFacing)
        n = -n;
    // Make the geometric normal face the same side as the interpolated one.
    if (dot(ng, n) < 0.0)
        ng = -ng;
    if (m.textures.z >= 0)
        n = rb_normal_map(n, i_tangent,
                          texture(linear_textures, vec3(i_uv, float(m.textures.z))).xyz * 2.0 - 1.0,
                          m.emissive.w);

    vec3 emission = m.emissive.rgb;
    if (m.textures.w >= 0)
        emission *= texture(srgb_textures, vec3(i_uv, float(m.textures.w))).rgb;

    float spec = m.params.w;
    vec3 f0_dielectric = min(vec3(0.04) * m.specular_color.rgb, vec3(1.0)) * spec;
    vec3 f0 = mix(f0_dielectric, base.rgb, metallic);
    float f90 = mix(spec, 1.0, metallic);
    vec3 c_diff = mix(base.rgb, vec3(0.0), metallic);

    vec4 view_pos = g.view * vec4(i_pos, 1.0);
    vec2 size = vec2(g.size.xy);
    vec2 cur = (i_clip.xy / i_clip.w * 0.5 + 0.5) * size;
    vec2 prev = (i_prev_clip.xy / i_prev_clip.w * 0.5 + 0.5) * size;

    o_position = vec4(i_pos, -view_pos.z);
    o_normal = vec4(n, face);
    // The frame draws its whole index buffer at once: the primitive is the global triangle, whose
    // index a float holds exactly below 2^24 (the hybrid's screen hits look up its baked light).
    o_albedo = vec4(c_diff, float(gl_PrimitiveID));
    o_specular = vec4(f0, roughness);
    o_emission = vec4(emission, f90);
    o_motion = vec4(prev - cur, rb_oct_encode(ng));
}
