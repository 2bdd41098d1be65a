// Punctual lights as KHR_lights_punctual defines them (intensity in candela or lux, range
// window, smooth spot cone), shadow-map lookups with 16-tap PCF, and the environment map.
#ifndef RB_LIGHTS_GLSL
#define RB_LIGHTS_GLSL

// KHR_lights_punctual's recommended range window, times inverse-square falloff.
float rb_light_falloff(float dist, float range)
{
    float inv_sq = 1.0 / max(dist * dist, 1e-8);
    if (range <= 0.0)
        return inv_sq;
    float r = dist / range;
    return clamp(1.0 - r * r * r * r, 0.0, 1.0) * inv_sq;
}

float rb_spot_factor(vec3 spot_dir, vec3 to_surface, vec2 cos_cone)
{
    float cd = dot(spot_dir, to_surface);
    float scale = 1.0 / max(1e-3, cos_cone.x - cos_cone.y);
    float t = clamp((cd - cos_cone.y) * scale, 0.0, 1.0);
    return t * t;
}

// Which cube face of a point light's six (+X, -X, +Y, -Y, +Z, -Z) sees direction d.
uint rb_cube_face(vec3 d)
{
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z)
        return d.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z)
        return d.y >= 0.0 ? 2u : 3u;
    return d.z >= 0.0 ? 4u : 5u;
}

// Equirectangular lookup: u from the azimuth (atan(x, -z), so -Z is the map's centre), v from
// the polar angle (v = 0 is +Y). rotation turns the map about +Y.
vec2 rb_equirect_uv(vec3 d, float rotation)
{
    float c = cos(-rotation), s = sin(-rotation);
    d = vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
    float u = atan(d.x, -d.z) / (2.0 * RB_PI) + 0.5;
    float v = acos(clamp(d.y, -1.0, 1.0)) / RB_PI;
    return vec2(u, v);
}

#endif
