// What a VPL or a bundle's node reflects, shared by bdpt_connect.comp (its connections) and
// bdpt_bounce.comp (the power a bounce carries). Needs shared.h, bdpt_shared.h, brdf.glsl and
// view.glsl (rb_material), and RB_BDPT_LEAST_ROUGHNESS defined by the includer (the job's
// integrator.bdpt.min_roughness, from its push constants).
#ifndef RB_BDPT_VPL_GLSL
#define RB_BDPT_VPL_GLSL

// A node's or VPL's BRDF: its diffuse colour and gray F0, F90 = 1 (rb_material_pack), its
// roughness at least RB_BDPT_LEAST_ROUGHNESS. These are the vertices past the camera's (a VPL, a
// bundle's hit), where nothing samples a glossy lobe: a VPL on a glossy surface throws its
// lobe's peak onto one small patch, a bright spot that moves with the VPL from frame to frame.
// Roughening them there (path regularization) trades that spot for a bias that the man page
// measures; the camera's vertex keeps its own roughness.
vec3 surface_brdf(vec3 n, vec3 v, vec3 l, rb_material m)
{
    return rb_brdf(n, v, l, m.c_diff, vec3(m.spec), 1.0,
                   max(m.roughness, RB_BDPT_LEAST_ROUGHNESS));
}

// The BRDF through which a reflecting VPL z (not an emitter's point) sends towards dir the
// light that reaches it: from its light's position (point, spot, or its parent VPL's for a
// bounce) or along its light's direction (directional).
vec3 vpl_brdf(rb_gpu_vpl z, vec3 dir)
{
    vec3 to_light = uint(z.from.w) == RB_KIND_DIRECTIONAL
                        ? z.from.xyz
                        : normalize(z.from.xyz - z.position.xyz);
    return surface_brdf(z.normal.xyz, dir, to_light, rb_material_unpack(z.material.xy));
}

#endif
