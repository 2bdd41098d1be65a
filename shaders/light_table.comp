// light_table: evaluates the light model of shaders/common/lights.glsl over a table of lights and
// shading points and a table of environment directions, so a test can hold it to the CPU
// reference's (tests/unit/test_light_parity.c). Not a pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "brdf.glsl"
#include "lights.glsl"

layout(local_size_x = 64) in;

// Entry i of the first part: light i lighting point i. Of the second part: the environment map
// seen along a direction, with a rotation (radians) and an intensity.
layout(std430, binding = RB_BIND_LIGHT_TABLE_LIGHTS) readonly buffer Lights { rb_gpu_light lights[]; };
layout(std430, binding = RB_BIND_LIGHT_TABLE_POINTS) readonly buffer Points { vec4 points[]; };  // xyz
layout(std430, binding = RB_BIND_LIGHT_TABLE_DIRS) readonly buffer Dirs { vec4 dirs[]; };      // xyz, rotation
layout(binding = RB_BIND_LIGHT_TABLE_ENV_MAP) uniform sampler2D env_map;
// Two vec4 per entry. A light: l.xyz, attenuation; falloff, spot factor, distance, unused. Then
// the environment: rgb, unused; the map coordinates u, v, unused, unused.
layout(std430, binding = RB_BIND_LIGHT_TABLE_OUT) writeonly buffer Out { vec4 outputs[]; };
layout(push_constant) uniform Push { uint light_count, env_count; float env_intensity; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.light_count) {
        // The light's direction and attenuation at p, as direct.comp's light loop computes them.
        rb_gpu_light L = lights[i];
        vec3 p = points[i].xyz;
        uint kind = uint(L.position.w);
        vec3 l;
        float dist = 0.0, falloff = 1.0, spot = 1.0;
        if (kind == RB_KIND_DIRECTIONAL) {
            l = -L.direction.xyz;
        } else {
            vec3 d = L.position.xyz - p;
            dist = length(d);
            l = d / max(dist, 1e-8);
            falloff = rb_light_falloff(dist, L.direction.w);
            if (kind == RB_KIND_SPOT)
                spot = rb_spot_factor(L.direction.xyz, -l, L.cone.xy);
        }
        outputs[2 * i + 0] = vec4(l, falloff * spot);
        outputs[2 * i + 1] = vec4(falloff, spot, dist, 0.0);
        return;
    }
    uint j = i - pc.light_count;
    if (j >= pc.env_count)
        return;
    // The environment as direct.comp looks it up where no geometry is.
    vec4 d = dirs[j];
    vec2 uv = rb_equirect_uv(d.xyz, d.w);
    vec3 env = textureLod(env_map, uv, 0.0).rgb;
    outputs[2 * (pc.light_count + j) + 0] = vec4(env * pc.env_intensity, 0.0);
    outputs[2 * (pc.light_count + j) + 1] = vec4(uv, 0.0, 0.0);
}
