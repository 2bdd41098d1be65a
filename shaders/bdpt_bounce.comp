// bdpt, bounce (BDPT.md "Two bounces"): VPL src + i (a point y0 on an emitter, the surface z of
// a punctual light's VPL, or an emitter's bounce), probed along a cosine-distributed direction w
// for the first surface y1 its light reaches (its probe view's one texel, a reflective-shadow-
// map texel), becomes VPL dst + i, which reflects what VPL src + i sends it. Its power is what
// y1 receives over the pdf of the pair: from an emitter's point, Le cos_y0 cos_y1 / r^2 /
// (p_A(y0) p(y1 | y0)) = pi Le / p_A(y0) = pi times VPL i's; from a reflecting VPL of power Phi
// and BRDF f, Phi f cos / (cos / pi) = pi f Phi. Each bounce makes its parent's bundle
// connections (c) again through (a), so that their short connections, where the parent's 1/r^2
// would spike, are weighed towards it. The first round (src 0, dst K_v) also aims the probes
// of the emitters' bounces for the second (src K_v, dst 2 K_v).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "brdf.glsl"
#include "view.glsl"
#include "bdpt_views.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPLS) buffer Vpls { rb_gpu_vpl vpls[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPL_VIEWS) writeonly buffer VplViews { rb_gpu_view vpl_views[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_PROBE_VIEWS) buffer ProbeViews { rb_gpu_view probe_views[]; };
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_POSITION, rgba32f) uniform readonly image2DArray probe_position;
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_NORMAL, rgba32f) uniform readonly image2DArray probe_normal;
layout(binding = RB_BIND_BDPT_BOUNCE_PROBE_MATERIAL, rg32ui) uniform readonly uimage2DArray probe_material;
layout(std430, binding = RB_BIND_BDPT_BOUNCE_VPL_DRAWS) writeonly buffer VplDraws { uint vpl_draws[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_SAMPLES) readonly buffer Samples { rb_gpu_bdpt_sample samples[]; };
layout(std430, binding = RB_BIND_BDPT_BOUNCE_PROBE_DRAWS) writeonly buffer ProbeDraws { uint probe_draws[]; };
layout(push_constant) uniform Push { rb_gpu_bdpt_bounce_push pc; };

#define RB_BDPT_LEAST_ROUGHNESS pc.brdf.x
#include "bdpt_vpl.glsl"

void main()
{
    uint i = gl_GlobalInvocationID.x, count = pc.counts.x, dst = pc.counts.z + i;
    if (i >= count)
        return;
    rb_gpu_vpl y0 = vpls[pc.counts.y + i];
    rb_gpu_vpl o = no_vpl(vec4(y0.position.xyz, float(RB_BDPT_VPL_BOUNCE)), 0xffffffffu);
    vec4 p = imageLoad(probe_position, ivec3(0, 0, int(i)));
    uint kind = uint(y0.from.w);
    bool emitter = kind == RB_BDPT_VPL_EMITTER;
    bool reflects = kind == RB_BDPT_VPL_BOUNCE || (kind >= RB_KIND_POINT && kind <= RB_KIND_DIRECTIONAL);
    if ((emitter || reflects) && y0.position.w > 0.0 && p.w > 0.0) {
        vec3 w = probe_views[i].axis.xyz;
        vec3 n = imageLoad(probe_normal, ivec3(0, 0, int(i))).xyz; // faces y0
        vec3 d = p.xyz - y0.position.xyz;
        float r2 = dot(d, d), cos0 = dot(y0.normal.xyz, w), cos1 = -dot(n, w);
        // A surface nearer y0's than twice the lift (a panel just under a ceiling: the ceiling
        // above it) has no bounce: its lifted eye would pass y0's surface and light what that
        // surface hides. What such a gap traps barely leaves it.
        if (cos0 > 0.0 && cos1 > 0.0 && sqrt(r2) * cos1 > 2.0 * vpl_lift(pc.scene.w)) {
            vec3 power = RB_PI * y0.power.rgb;
            if (reflects)
                power *= vpl_brdf(y0, w);
            o.from.w = float(emitter ? RB_BDPT_VPL_BOUNCE : RB_BDPT_VPL_SECOND);
            o.position = vec4(p.xyz, 1.0);
            o.normal = vec4(n, rb_bdpt_bounce_density(cos0, cos1, r2));
            o.power = vec4(power, 0.0);
            o.material.xy = imageLoad(probe_material, ivec3(0, 0, int(i))).xy;
        }
    }
    vpls[dst] = o;
    vpl_draws[dst * RB_BDPT_DRAW_UINTS + RB_BDPT_DRAW_INSTANCES] = o.position.w > 0.0 ? 1u : 0u;
    vpl_views[dst] = vpl_view(o.position.xyz, o.normal.xyz, pc.scene.w);
    if (pc.counts.w != 0u) {
        bool probes = uint(o.from.w) == RB_BDPT_VPL_BOUNCE && o.position.w > 0.0;
        probe_draws[i * RB_BDPT_DRAW_UINTS + RB_BDPT_DRAW_INSTANCES] = probes ? 1u : 0u;
        probe_views[i] = bounce_probe(probes, o.position.xyz, o.normal.xyz, samples[i].v.zw,
                                      pc.scene.w);
    }
}
