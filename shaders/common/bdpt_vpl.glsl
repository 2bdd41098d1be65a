// What a VPL or a bundle's node reflects, shared by bdpt_connect.comp (its connections) and
// bdpt_bounce.comp (the power a bounce carries). Needs shared.h, bdpt_shared.h, brdf.glsl and
// view.glsl (rb_material).
#ifndef RB_BDPT_VPL_GLSL
#define RB_BDPT_VPL_GLSL

// A node's or VPL's BRDF: its diffuse colour and gray F0, F90 = 1 (rb_material_pack).
vec3 surface_brdf(vec3 n, vec3 v, vec3 l, rb_material m)
{
    return rb_brdf(n, v, l, m.c_diff, vec3(m.spec), 1.0, m.roughness);
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
