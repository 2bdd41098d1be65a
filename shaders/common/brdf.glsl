// The glTF metallic-roughness BRDF (glTF 2.0 spec, appendix B), with KHR_materials_specular's
// weight: Lambert diffuse, GGX with Smith height-correlated visibility, Schlick Fresnel.
// The CPU reference evaluates the same model; a test holds the two to each other.
#ifndef RB_BRDF_GLSL
#define RB_BRDF_GLSL

const float RB_PI = 3.14159265358979323846;

// The gray specular map of a surface with Fresnel f0 (seed 000's "gray scale specular maps"): what
// bdpt's specular light is divided by where it is gathered and multiplied by in the output.
float rb_spec_map(vec3 f0)
{
    return max((f0.r + f0.g + f0.b) / 3.0, 1e-3);
}

// The GGX lobe's Fresnel F, distribution D and Smith height-correlated visibility V, shared by
// rb_brdf and rb_brdf_parts; false where nothing is reflected (alpha = roughness^2).
bool rb_ggx(vec3 n, vec3 v, vec3 l, vec3 f0, float f90, float roughness, out vec3 F, out float D,
            out float V)
{
    F = vec3(0.0);
    D = 0.0;
    V = 0.0;
    float ndl = max(dot(n, l), 0.0);
    float ndv = max(dot(n, v), 1e-4);
    if (ndl <= 0.0)
        return false;
    // l == -v: the half vector does not exist (normalize would give NaN), and there is no light.
    vec3 lv = l + v;
    if (!(dot(lv, lv) > 0.0))
        return false;
    vec3 h = normalize(lv);
    float ndh = max(dot(n, h), 0.0);
    // Clamped above too: with l close to v, rounding puts dot(v, h) a few ulps over 1, and
    // 1 - vdh would go negative (a light on the line from the camera to the point).
    float vdh = clamp(dot(v, h), 0.0, 1.0);
    float a = max(roughness * roughness, 1e-4);
    float a2 = a * a;
    // (1 - vdh)^5 by multiplication, as the reference's rb_ref_pow5: the driver's pow is an
    // exp2 of a log2, which cost the connect and emitter_direct passes 6-8% of their time.
    float m = 1.0 - vdh, m2 = m * m;
    F = f0 + (vec3(f90) - f0) * (m2 * m2 * m);
    float d = ndh * ndh * (a2 - 1.0) + 1.0;
    D = a2 / (RB_PI * d * d);
    float vis_den = ndl * sqrt(ndv * ndv * (1.0 - a2) + a2) + ndv * sqrt(ndl * ndl * (1.0 - a2) + a2);
    V = vis_den > 0.0 ? 0.5 / vis_den : 0.0;
    return true;
}

// c_diff: diffuse albedo; f0, f90: Fresnel at normal and grazing incidence.
vec3 rb_brdf(vec3 n, vec3 v, vec3 l, vec3 c_diff, vec3 f0, float f90, float roughness)
{
    vec3 F;
    float D, V;
    if (!rb_ggx(n, v, l, f0, f90, roughness, F, D, V))
        return vec3(0.0);
    return (vec3(1.0) - F) * c_diff / RB_PI + F * D * V;
}

// The two parts of rb_brdf for a camera vertex whose diffuse albedo is applied later (bdpt
// gathers light untextured and textures it in the output pass): kd = (1 - F) / pi, the factor of
// c_diff, and ks = F D V / spec_map, the specular part divided by the gray specular map.
void rb_brdf_parts(vec3 n, vec3 v, vec3 l, vec3 f0, float f90, float roughness, out vec3 kd,
                   out vec3 ks)
{
    kd = vec3(0.0);
    ks = vec3(0.0);
    vec3 F;
    float D, V;
    if (!rb_ggx(n, v, l, f0, f90, roughness, F, D, V))
        return;
    kd = (vec3(1.0) - F) / RB_PI;
    ks = F * D * V / rb_spec_map(f0);
}

#endif
