// bdpt, bounce (BDPT.md "As implemented", emitters' bounce): VPL i, a point y0 on an emitter,
// probed along a cosine-distributed direction w for the first surface y1 its emission reaches
// (its probe view's one texel, a reflective-shadow-map texel). y1 becomes VPL K_v + i: it
// reflects what y0 sends it, and with a bundle it gives the emitter's second bounce, as a
// punctual light's VPL gives that light's. Its power is what y1 receives over the pdf of the
// pair: Le cos_y0 cos_y1 / r^2 / (p_A(y0) p(y1 | y0)) = pi Le / p_A(y0) = pi times VPL i's.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "brdf.glsl"
#include "bdpt_views.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPLS) buffer Vpls { rb_gpu_vpl vpls[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPL_VIEWS) writeonly buffer VplViews { rb_gpu_view vpl_views[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_PROBE_VIEWS) readonly buffer ProbeViews { rb_gpu_view probe_views[]; };
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_POSITION, rgba32f) uniform readonly image2DArray probe_position;
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_NORMAL, rgba32f) uniform readonly image2DArray probe_normal;
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_MATERIAL, rg32ui) uniform readonly uimage2DArray probe_material;
layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPL_DRAWS) writeonly buffer VplDraws { uint vpl_draws[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_bounce_push pc; };

void main()
{
    uint i = gl_GlobalInvocationID.x, count = pc.counts.x;
    if (i >= count)
        return;
    rb_gpu_vpl y0 = vpls[i];
    rb_gpu_vpl o = no_vpl(vec4(y0.position.xyz, float(RB_BDPT_VPL_BOUNCE)), 0xffffffffu);
    vec4 p = imageLoad(probe_position, ivec3(0, 0, int(i)));
    if (uint(y0.from.w) == RB_BDPT_VPL_EMITTER && y0.position.w > 0.0 && p.w > 0.0) {
        vec3 w = probe_views[i].axis.xyz;
        vec3 n = imageLoad(probe_normal, ivec3(0, 0, int(i))).xyz; // faces y0
        vec3 d = p.xyz - y0.position.xyz;
        float r2 = dot(d, d), cos0 = dot(y0.normal.xyz, w), cos1 = -dot(n, w);
        // A surface nearer y0's than twice the lift (a panel just under a ceiling: the ceiling
        // above it) has no bounce: its lifted eye would pass y0's surface and light what that
        // surface hides. What such a gap traps barely leaves it.
        if (cos0 > 0.0 && cos1 > 0.0 && sqrt(r2) * cos1 > 2.0 * vpl_lift(pc.scene.w)) {
            o.position = vec4(p.xyz, 1.0);
            o.normal = vec4(n, rb_bdpt_bounce_density(cos0, cos1, r2));
            o.power = vec4(RB_PI * y0.power.rgb, 0.0);
            o.material.xy = imageLoad(probe_material, ivec3(0, 0, int(i))).xy;
        }
    }
    vpls[count + i] = o;
    vpl_draws[(count + i) * RB_BDPT_DRAW_UINTS + RB_BDPT_DRAW_INSTANCES] = o.position.w > 0.0 ? 1u : 0u;
    vpl_views[count + i] = vpl_view(o.position.xyz, o.normal.xyz, pc.scene.w);
}
