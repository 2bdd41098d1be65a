// The raster views' shared GLSL: the depth each kind stores and the list node's normal encoding.
// Needs rb_gpu_view (view_shared.h).
#ifndef RB_VIEW_GLSL
#define RB_VIEW_GLSL

// The depth a view stores for world point p: the distance from the eye (perspective) or from
// the near plane along the axis (orthographic). Paraboloid views store the distance from the
// eye too, computed per pixel in view_paraboloid.frag.
float rb_view_depth(rb_gpu_view v, uint kind, vec3 p)
{
    if (kind == RB_VIEW_ORTHOGRAPHIC)
        return dot(p - v.origin.xyz, v.axis.xyz);
    return length(p - v.origin.xyz);
}

// x1's texel of the size x size grid of bundle v (an orthographic view); outside the grid when
// x1 is. rb_bundle_search reads the texel this gives, and bdpt_mark.comp marks it beforehand:
// one function, so that both find the same texel.
ivec2 rb_bundle_texel(rb_gpu_view v, int size, vec3 x1)
{
    vec2 ndc = (v.transform * vec4(x1, 1.0)).xy;
    return ivec2(floor((ndc * 0.5 + 0.5) * float(size)));
}

// A unit vector as polar angles, 16 bits each (seed 000, B.2): theta = acos(z) in [0, pi] in the
// low half, phi = atan(y, x) in [-pi, pi] (0 at the poles) in the high half, both rounded to the
// nearest step.
uint rb_view_polar_encode(vec3 n)
{
    const float pi = 3.14159265358979;
    float theta = acos(clamp(n.z, -1.0, 1.0));
    float phi = n.x == 0.0 && n.y == 0.0 ? 0.0 : atan(n.y, n.x); // atan(0, 0) is undefined
    uint t = uint(round(theta / pi * 65535.0));
    uint f = uint(round((phi / (2.0 * pi) + 0.5) * 65535.0));
    return min(t, 65535u) | (min(f, 65535u) << 16);
}

// A unit vector back from rb_view_polar_encode.
vec3 rb_view_polar_decode(uint w)
{
    const float pi = 3.14159265358979;
    float theta = float(w & 0xffffu) / 65535.0 * pi;
    float phi = (float(w >> 16) / 65535.0 - 0.5) * 2.0 * pi;
    float s = sin(theta);
    return vec3(s * cos(phi), s * sin(phi), cos(theta));
}

// A surface's material in the two words of a bundle node (seed 000, B.2) and of an RSM texel:
// albedo = diffuse RGB and gray specular F0 (their mean), 8-bit unorm each; gloss = roughness
// (8-bit unorm) in the low byte and emitted radiance in the 24 bits the seed reserves for it: a
// shared exponent e (6 bits, 2^-31 .. 2^32) and three 6-bit mantissas, c = m / 63 * 2^e. F90 is
// taken as 1 (glTF's, without KHR_materials_specular).
uvec2 rb_material_pack(vec3 c_diff, vec3 f0, float roughness, vec3 emission)
{
    float spec = clamp((f0.r + f0.g + f0.b) / 3.0, 0.0, 1.0);
    uint albedo = packUnorm4x8(vec4(clamp(c_diff, 0.0, 1.0), spec));
    uint gloss = uint(round(clamp(roughness, 0.0, 1.0) * 255.0));
    float m = max(emission.r, max(emission.g, emission.b));
    if (m > 1e-9) {
        int e = clamp(int(floor(log2(m))) + 1, -31, 32);
        vec3 q = round(clamp(emission / exp2(float(e)), 0.0, 1.0) * 63.0);
        uvec3 u = uvec3(q);
        gloss |= (uint(e + 31) << 8) | (u.r << 14) | (u.g << 20) | (u.b << 26);
    }
    return uvec2(albedo, gloss);
}

struct rb_material {
    vec3 c_diff;
    float spec; // gray F0
    float roughness;
    vec3 emission;
};

rb_material rb_material_unpack(uvec2 w)
{
    rb_material m;
    vec4 a = unpackUnorm4x8(w.x);
    m.c_diff = a.rgb;
    m.spec = a.a;
    m.roughness = float(w.y & 0xffu) / 255.0;
    uint hi = w.y >> 8;
    if (hi == 0u) {
        m.emission = vec3(0.0);
    } else {
        float s = exp2(float(int(hi & 63u) - 31)) / 63.0;
        m.emission = vec3(float((hi >> 6) & 63u), float((hi >> 12) & 63u), float(hi >> 18)) * s;
    }
    return m;
}

#endif
