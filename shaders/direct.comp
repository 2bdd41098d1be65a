// direct: light from punctual lights (shadow-mapped, 16-tap PCF; with the direct integrator, the
// emitters' point samples among them) and emission at every G-buffer pixel; the environment where
// no geometry is.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "brdf.glsl"
#include "encode.glsl"
#include "lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std140, binding = RB_BIND_DIRECT_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(binding = RB_BIND_DIRECT_GB_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_DIRECT_GB_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_DIRECT_GB_ALBEDO, rgba32f) uniform readonly image2D gb_albedo;
layout(binding = RB_BIND_DIRECT_GB_SPECULAR, rgba32f) uniform readonly image2D gb_specular;
layout(binding = RB_BIND_DIRECT_GB_EMISSION, rgba32f) uniform readonly image2D gb_emission;
layout(binding = RB_BIND_DIRECT_GB_MOTION, rgba32f) uniform readonly image2D gb_motion;
layout(std430, binding = RB_BIND_DIRECT_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_DIRECT_SHADOW_VIEWS) readonly buffer Views { rb_gpu_shadow_view views[]; };
layout(binding = RB_BIND_DIRECT_SHADOW_MAPS) uniform sampler2DArray shadow_maps;
layout(binding = RB_BIND_DIRECT_ENV_MAP) uniform sampler2D env_map;
layout(binding = RB_BIND_DIRECT_OUT, rgba32f) uniform writeonly image2D o_direct;

#include "shadow.glsl"
#include "punctual.glsl"

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), g.size.xy)))
        return;
    vec4 pos = imageLoad(gb_position, px);
    if (pos.w <= 0.0) {
        // No geometry: the environment, seen through the pixel centre.
        vec2 ndc = (vec2(px) + 0.5) / vec2(g.size.xy) * 2.0 - 1.0;
        vec4 far = g.inv_view_proj * vec4(ndc, 1.0, 1.0);
        vec3 dir = normalize(far.xyz / far.w - g.camera_pos.xyz);
        vec3 env = g.env_color.rgb;
        if (g.env.z > 0.5)
            env = textureLod(env_map, rb_equirect_uv(dir, g.env.y), 0.0).rgb;
        imageStore(o_direct, px, vec4(env * g.env.x, 0.0));
        return;
    }
    vec3 p = pos.xyz;
    vec3 n = imageLoad(gb_normal, px).xyz;
    vec3 c_diff = imageLoad(gb_albedo, px).rgb;
    vec4 spec = imageLoad(gb_specular, px);
    vec4 emission = imageLoad(gb_emission, px);
    vec3 ng = rb_oct_decode(imageLoad(gb_motion, px).zw);
    vec3 v = normalize(g.camera_pos.xyz - p);

    vec3 radiance = rb_punctual_light(emission.rgb, p, n, ng, v, c_diff, spec.rgb, emission.w, spec.a);
    imageStore(o_direct, px, vec4(radiance, 1.0));
}
