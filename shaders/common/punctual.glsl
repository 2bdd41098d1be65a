// Direct light of the punctual lights at a surface point, shadow-mapped (16-tap PCF), toward v:
// what direct.comp computes at a G-buffer pixel and the hybrid integrator at its rays' hits.
// The including shader declares `g` (rb_gpu_globals), `lights` (rb_gpu_light[]), `views` and
// `shadow_maps` (for shadow.glsl) and includes brdf.glsl, lights.glsl and shadow.glsl first.
#ifndef RB_PUNCTUAL_GLSL
#define RB_PUNCTUAL_GLSL

// The lights it sums: the frame's (size.z); the transparency pass adds the layer lights.
#ifndef RB_PUNCTUAL_LIGHT_COUNT
#define RB_PUNCTUAL_LIGHT_COUNT g.size.z
#endif

// acc plus each light's reflected radiance, added in light order (n: shading normal, ng:
// geometric normal, both on v's side).
vec3 rb_punctual_light(vec3 acc, vec3 p, vec3 n, vec3 ng, vec3 v, vec3 c_diff, vec3 f0, float f90,
                       float roughness)
{
    vec3 radiance = acc;
    for (uint i = 0; i < RB_PUNCTUAL_LIGHT_COUNT; i++) {
        rb_gpu_light L = lights[i];
        uint kind = uint(L.position.w);
        vec3 l;
        float dist, atten;
        if (kind == RB_KIND_DIRECTIONAL) {
            l = -L.direction.xyz;
            dist = 0.0;
            atten = 1.0;
        } else {
            vec3 d = L.position.xyz - p;
            dist = length(d);
            l = d / max(dist, 1e-8);
            atten = rb_light_falloff(dist, L.direction.w);
            if (kind == RB_KIND_SPOT)
                atten *= rb_spot_factor(L.direction.xyz, -l, L.cone.xy);
            else if (kind == RB_KIND_EMITTER)
                atten *= abs(dot(L.direction.xyz, l)); // emission leaves both sides
        }
        float ndl = dot(n, l);
        if (ndl <= 0.0 || atten <= 0.0 || dot(ng, l) <= 0.0)
            continue;
        float vis = 1.0;
        int first = int(L.color.w);
        if (first >= 0) {
            float cos_g = max(dot(ng, l), 0.0);
            bool cube = kind == RB_KIND_POINT || kind == RB_KIND_EMITTER;
            uint layer = uint(first) + (cube ? rb_cube_face(-l) : 0u);
            vis = shadow_visibility(layer, p, ng, cos_g);
        }
        if (vis <= 0.0)
            continue;
        vec3 f = rb_brdf(n, v, l, c_diff, f0, f90, roughness);
        radiance += f * L.color.rgb * atten * ndl * vis;
    }
    return radiance;
}

#endif
