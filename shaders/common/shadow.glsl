// Shadow-map lookups of the direct light's maps, shared by direct.comp and bdpt_connect.comp.
// The including shader declares `g` (rb_gpu_globals), `views` (rb_gpu_shadow_view[]) and
// `shadow_maps` (sampler2DArray) first.
#ifndef RB_SHADOW_GLSL
#define RB_SHADOW_GLSL

// Fraction of the taps that see the light: with pcf, 16 taps (a 4x4 grid spanning the PCF
// radius); without, the one texel the point falls in (a hard shadow, a point light's true one).
// The lookup point is pushed off the surface along the geometric normal by the filter's
// footprint (normal-offset shadows), and the depth test gets a slope-scaled bias: together they
// keep grazing surfaces from shadowing themselves. The one-texel test keeps the filter's offset
// and bias: its points (bundle hits) lie off their surface by up to a bundle texel's depth.
float shadow_lookup(uint layer, vec3 p, vec3 ng, float cos_theta, bool pcf)
{
    rb_gpu_shadow_view v = views[layer];
    bool persp = uint(v.light.w) != RB_KIND_DIRECTIONAL;
    float radius = g.shadow.y;
    float d0 = persp ? length(p - v.light.xyz) : dot(p - v.light.xyz, v.axis.xyz);
    float footprint0 = v.axis.w * (persp ? d0 : 1.0);
    p += ng * footprint0 * (radius + 1.0) * sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    float dist = persp ? length(p - v.light.xyz) : dot(p - v.light.xyz, v.axis.xyz);
    vec4 clip = v.view_proj * vec4(p, 1.0);
    if (clip.w <= 0.0)
        return 1.0;
    vec2 ndc = clip.xy / clip.w;
    float size = g.shadow.z;
    vec2 texel = (ndc * 0.5 + 0.5) * size - 0.5;
    float tan_theta = min(sqrt(max(1.0 - cos_theta * cos_theta, 0.0)) / max(cos_theta, 1e-3), 10.0);
    float footprint = v.axis.w * (persp ? dist : 1.0);
    float bias = g.shadow.x * max(dist, 1e-3) + footprint * (radius + 1.0) * tan_theta;
    if (!pcf) {
        ivec2 t = clamp(ivec2(floor(texel + 0.5)), ivec2(0), ivec2(int(size) - 1));
        return dist - bias <= texelFetch(shadow_maps, ivec3(t, int(layer)), 0).r ? 1.0 : 0.0;
    }
    float step = radius / 1.5;
    float lit = 0.0;
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            vec2 o = (vec2(x, y) - 1.5) * step;
            ivec2 t = clamp(ivec2(floor(texel + o + 0.5)), ivec2(0), ivec2(int(size) - 1));
            float stored = texelFetch(shadow_maps, ivec3(t, int(layer)), 0).r;
            lit += dist - bias <= stored ? 1.0 : 0.0;
        }
    return lit / 16.0;
}

// The direct light's lookup: 16-tap PCF.
float shadow_visibility(uint layer, vec3 p, vec3 ng, float cos_theta)
{
    return shadow_lookup(layer, p, ng, cos_theta, true);
}

#endif
