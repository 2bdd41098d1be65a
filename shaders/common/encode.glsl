// Compact encodings shared by passes.
#ifndef RB_ENCODE_GLSL
#define RB_ENCODE_GLSL

// Octahedral unit-vector encoding (Cigolle et al. 2014), in [-1, 1]^2.
vec2 rb_oct_encode(vec3 n)
{
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 p = n.xy;
    if (n.z < 0.0)
        p = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return p;
}

vec3 rb_oct_decode(vec2 p)
{
    vec3 n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    if (n.z < 0.0)
        n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

// A unit vector in one float, exactly: its octahedral coordinates at 12 bits each, an integer
// below 2^24 (every one of which a 32-bit float holds), so no NaN or denormal pattern can arise
// and any image format of 32-bit floats keeps it.
float rb_normal_pack(vec3 n)
{
    uvec2 q = uvec2(round((rb_oct_encode(n) * 0.5 + 0.5) * 4095.0));
    return float(q.x * 4096u + q.y);
}

vec3 rb_normal_unpack(float v)
{
    uint u = uint(v);
    return rb_oct_decode(vec2(u >> 12u, u & 4095u) / 4095.0 * 2.0 - 1.0);
}

#endif
