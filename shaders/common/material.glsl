// A glTF metallic-roughness material at a texture coordinate, as gbuffer.frag evaluates it
// (without the normal map, which the small views do not need): the raster views' RSM and list
// outputs use it. Needs rb_gpu_material (shared.h).
#ifndef RB_MATERIAL_GLSL
#define RB_MATERIAL_GLSL

struct rb_surface {
    float alpha; // base color alpha, for the cutoff
    vec3 c_diff;
    vec3 f0;
    float f90;
    float roughness;
    vec3 emission;
};

rb_surface rb_material_eval(rb_gpu_material m, vec2 uv, sampler2DArray srgb_textures,
                            sampler2DArray linear_textures)
{
    vec4 base = m.base_color;
    if (m.textures.x >= 0)
        base *= texture(srgb_textures, vec3(uv, float(m.textures.x)));
    float metallic = m.params.x, roughness = m.params.y;
    if (m.textures.y >= 0) {
        vec4 mr = texture(linear_textures, vec3(uv, float(m.textures.y)));
        roughness *= mr.g;
        metallic *= mr.b;
    }
    metallic = clamp(metallic, 0.0, 1.0);
    rb_surface s;
    s.alpha = base.a;
    s.roughness = clamp(roughness, 0.0, 1.0);
    s.emission = m.emissive.rgb;
    if (m.textures.w >= 0)
        s.emission *= texture(srgb_textures, vec3(uv, float(m.textures.w))).rgb;
    float spec = m.params.w;
    vec3 f0_dielectric = min(vec3(0.04) * m.specular_color.rgb, vec3(1.0)) * spec;
    s.f0 = mix(f0_dielectric, base.rgb, metallic);
    s.f90 = mix(spec, 1.0, metallic);
    s.c_diff = mix(base.rgb, vec3(0.0), metallic);
    return s;
}

// The shading normal n (unit, on the side being shaded) bent by a tangent-space normal map's
// texel tn (already mapped to [-1, 1]) at the given scale, in the frame of the interpolated
// tangent (xyz, w: handedness); n unchanged where the tangent is parallel to it.
vec3 rb_normal_map(vec3 n, vec4 tangent, vec3 tn, float scale)
{
    vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
    if (!(dot(t, t) > 1e-12))
        return n;
    t = normalize(t);
    vec3 b = cross(n, t) * (tangent.w < 0.0 ? -1.0 : 1.0);
    tn.xy *= scale;
    return normalize(t * tn.x + b * tn.y + n * tn.z);
}

// Whether the fragment is not there: alpha below the cutoff, or a single-sided face from behind.
bool rb_material_discards(rb_gpu_material m, rb_surface s, bool front)
{
    return (m.params.z > 0.0 && s.alpha < m.params.z) || (!front && m.specular_color.w <= 0.5);
}

#endif
