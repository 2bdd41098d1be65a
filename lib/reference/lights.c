/* Lights for the reference: the punctual falloff and spot cone of shaders/common/lights.glsl, and
 * the environment (a uniform colour, or an equirectangular map looked up like the GPU's linear
 * sampler and importance-sampled by luminance x sin(theta) through a 2D CDF). */
#include "reference/reference_int.h"

#include <math.h>
#include <stdlib.h>

float rb_ref_light_falloff(float dist, float range)
{
    float inv_sq = 1.0f / rb_ref_maxf(dist * dist, 1e-8f);
    if (range <= 0.0f)
        return inv_sq;
    float r = dist / range;
    return rb_clampf(1.0f - r * r * r * r, 0.0f, 1.0f) * inv_sq;
}

float rb_ref_spot_factor(const float spot_dir[3], const float to_surface[3], float cos_inner,
                         float cos_outer)
{
    float cd = rb_f3_dot(spot_dir, to_surface);
    float scale = 1.0f / rb_ref_maxf(1e-3f, cos_inner - cos_outer);
    float t = rb_clampf((cd - cos_outer) * scale, 0.0f, 1.0f);
    return t * t;
}

/* ---- the environment ------------------------------------------------------------------------ */

/* rb_equirect_uv of lights.glsl: u from atan(x, -z) (-Z is the map's centre), v from the polar
 * angle (v = 0 is +Y); rotation turns the map about +Y. */
void rb_ref_equirect_uv(const float d_in[3], float rotation, float *u, float *v)
{
    float c = cosf(-rotation), s = sinf(-rotation);
    float d[3] = {c * d_in[0] + s * d_in[2], d_in[1], -s * d_in[0] + c * d_in[2]};
    *u = atan2f(d[0], -d[2]) / (2.0f * RB_PI) + 0.5f;
    *v = acosf(rb_clampf(d[1], -1.0f, 1.0f)) / RB_PI;
}

/* The inverse: the direction of map coordinates (u, v); also sin(theta). */
static float equirect_dir(float u, float v, float rotation, float d[3])
{
    float theta = v * RB_PI, phi = (u - 0.5f) * 2.0f * RB_PI;
    float st = sinf(theta);
    float m[3] = {st * sinf(phi), cosf(theta), -st * cosf(phi)};
    float c = cosf(-rotation), s = sinf(-rotation);
    /* undo the rotation of equirect_uv (its transpose) */
    d[0] = c * m[0] - s * m[2];
    d[1] = m[1];
    d[2] = s * m[0] + c * m[2];
    return st;
}

static const float *texel(const struct rb_ref_env *env, int64_t x, int64_t y)
{
    int64_t w = env->width_px, h = env->height_px;
    /* u repeats (the map wraps around the azimuth); v clamps to the poles' rows */
    x %= w;
    if (x < 0)
        x += w;
    y = y < 0 ? 0 : (y >= h ? h - 1 : y);
    return env->rgba + ((size_t)y * (size_t)w + (size_t)x) * 4;
}

/* Bilinear at the map's own resolution, texel centres at half-integers, as a linear sampler
 * reads a level-0 texture. */
static void map_lookup(const struct rb_ref_env *env, float u, float v, float out[3])
{
    float x = u * (float)env->width_px - 0.5f, y = v * (float)env->height_px - 0.5f;
    float fx = floorf(x), fy = floorf(y);
    float ax = x - fx, ay = y - fy;
    int64_t ix = (int64_t)fx, iy = (int64_t)fy;
    const float *t00 = texel(env, ix, iy), *t10 = texel(env, ix + 1, iy);
    const float *t01 = texel(env, ix, iy + 1), *t11 = texel(env, ix + 1, iy + 1);
    for (int i = 0; i < 3; i++) {
        float top = t00[i] + (t10[i] - t00[i]) * ax;
        float bot = t01[i] + (t11[i] - t01[i]) * ax;
        out[i] = top + (bot - top) * ay;
    }
}

void rb_ref_env_eval(const struct rb_ref_env *env, const float d[3], float out[3])
{
    if (!env->rgba) {
        for (int i = 0; i < 3; i++)
            out[i] = env->color[i];
        return;
    }
    float u, v;
    rb_ref_equirect_uv(d, env->rotation_rad, &u, &v);
    if (!(u == u) || !(v == v)) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    map_lookup(env, u, v, out);
    for (int i = 0; i < 3; i++)
        out[i] *= env->intensity;
}

static float texel_luminance(const struct rb_ref_env *env, int64_t x, int64_t y)
{
    const float *t = texel(env, x, y);
    float c[3] = {rb_ref_maxf(t[0], 0.0f), rb_ref_maxf(t[1], 0.0f), rb_ref_maxf(t[2], 0.0f)};
    float lum = rb_ref_luminance(c);
    return lum == lum && lum < INFINITY ? lum : 0.0f;
}

/* The importance table of env's map into marginal (h + 1), conditional (h rows of w + 1) and
 * texel_pdf (w h); returns the sum of the texels' weights (0: no light). row_sum: h doubles of
 * scratch. */
static double env_table(const struct rb_ref_env *env, float *marginal, float *conditional,
                        float *texel_pdf, double *row_sum)
{
    uint32_t w = env->width_px, h = env->height_px;
    /* A texel's weight is the largest luminance of its 3x3 neighbourhood, so that every
     * direction the bilinear lookup gives light to has a non-zero pdf, times sin(theta) for
     * the equirectangular area. */
    double total = 0.0;
    for (uint32_t y = 0; y < h; y++) {
        float st = sinf(RB_PI * ((float)y + 0.5f) / (float)h);
        double sum = 0.0;
        float *cdf = conditional + (size_t)y * (w + 1);
        cdf[0] = 0.0f;
        for (uint32_t x = 0; x < w; x++) {
            float m = 0.0f;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++)
                    m = rb_ref_maxf(m, texel_luminance(env, (int64_t)x + dx, (int64_t)y + dy));
            float wgt = m * st;
            texel_pdf[(size_t)y * w + x] = wgt;
            sum += wgt;
            cdf[x + 1] = (float)sum;
        }
        for (uint32_t x = 1; x <= w; x++)
            cdf[x] = sum > 0.0 ? (float)(cdf[x] / sum) : (float)x / (float)w;
        cdf[w] = 1.0f;
        row_sum[y] = sum;
        total += sum;
    }
    double acc = 0.0;
    marginal[0] = 0.0f;
    for (uint32_t y = 0; y < h; y++) {
        acc += row_sum[y];
        marginal[y + 1] = total > 0.0 ? (float)(acc / total) : 0.0f;
    }
    marginal[h] = 1.0f;
    for (size_t i = 0; i < (size_t)w * h; i++)
        texel_pdf[i] = total > 0.0 ? (float)(texel_pdf[i] / total) : 0.0f;
    return total;
}

enum rb_status rb_ref_env_init(struct rb_ref_env *env, struct rb_err *err)
{
    env->is_black = false;
    if (!env->rgba) {
        env->is_black = !(env->color[0] > 0.0f || env->color[1] > 0.0f || env->color[2] > 0.0f);
        return RB_OK;
    }
    uint32_t w = env->width_px, h = env->height_px;
    if (w == 0 || h == 0)
        return rb_errf(err, RB_E_INVALID, "environment map of %ux%u pixels", w, h);
    env->marginal = malloc((h + 1) * sizeof(float));
    env->conditional = malloc((size_t)h * (w + 1) * sizeof(float));
    env->texel_pdf = malloc((size_t)w * h * sizeof(float));
    double *row_sum = malloc(h * sizeof(double));
    if (!env->marginal || !env->conditional || !env->texel_pdf || !row_sum) {
        free(row_sum);
        return rb_errf(err, RB_E_NOMEM, "out of memory for the environment's importance table");
    }
    double total = env_table(env, env->marginal, env->conditional, env->texel_pdf, row_sum);
    free(row_sum);
    env->is_black = !(total > 0.0) || !(env->intensity > 0.0f);
    return RB_OK;
}

size_t rb_reference_env_table_floats(uint32_t width_px, uint32_t height_px)
{
    return (size_t)(height_px + 1) + (size_t)height_px * (width_px + 1) +
           (size_t)width_px * height_px;
}

enum rb_status rb_reference_env_table(const float *rgba, uint32_t width_px, uint32_t height_px,
                                      float *out, struct rb_err *err)
{
    if (width_px == 0 || height_px == 0)
        return rb_errf(err, RB_E_INVALID, "environment map of %ux%u pixels", width_px, height_px);
    double *row_sum = malloc(height_px * sizeof(double));
    if (!row_sum)
        return rb_errf(err, RB_E_NOMEM, "out of memory for the environment's importance table");
    struct rb_ref_env env = {.rgba = rgba, .width_px = width_px, .height_px = height_px};
    float *conditional = out + height_px + 1;
    env_table(&env, out, conditional, conditional + (size_t)height_px * (width_px + 1), row_sum);
    free(row_sum);
    return RB_OK;
}

void rb_ref_env_release(struct rb_ref_env *env)
{
    free(env->marginal);
    free(env->conditional);
    free(env->texel_pdf);
    env->marginal = env->conditional = env->texel_pdf = NULL;
}

/* The last index i in [0, n) with cdf[i] <= u (cdf has n + 1 entries, cdf[0] = 0), skipping
 * empty intervals. */
static uint32_t search(const float *cdf, uint32_t n, float u)
{
    uint32_t lo = 0, hi = n;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    while (lo + 1 < n && !(cdf[lo + 1] > cdf[lo]))
        lo++;
    return lo;
}

float rb_ref_env_sample(const struct rb_ref_env *env, const float n[3], float u0, float u1,
                        float d[3])
{
    if (env->is_black)
        return 0.0f;
    if (!env->rgba) {
        /* A uniform environment: cosine-weighted around the shading normal. */
        float t[3], b[3];
        rb_ref_basis(n, t, b);
        float r = sqrtf(u0), phi = 2.0f * RB_PI * u1;
        float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(rb_ref_maxf(1.0f - u0, 0.0f));
        for (int i = 0; i < 3; i++)
            d[i] = x * t[i] + y * b[i] + z * n[i];
        float len = sqrtf(rb_f3_dot(d, d));
        for (int i = 0; i < 3; i++)
            d[i] /= len;
        return rb_ref_env_pdf(env, n, d);
    }
    uint32_t w = env->width_px, h = env->height_px;
    uint32_t y = search(env->marginal, h, u0);
    float r0 = env->marginal[y], r1 = env->marginal[y + 1];
    float fy = r1 > r0 ? (u0 - r0) / (r1 - r0) : 0.5f;
    const float *cdf = env->conditional + (size_t)y * (w + 1);
    uint32_t x = search(cdf, w, u1);
    float c0 = cdf[x], c1 = cdf[x + 1];
    float fx = c1 > c0 ? (u1 - c0) / (c1 - c0) : 0.5f;
    float u = ((float)x + rb_clampf(fx, 0.0f, 1.0f)) / (float)w;
    float v = ((float)y + rb_clampf(fy, 0.0f, 1.0f)) / (float)h;
    float st = equirect_dir(u, v, env->rotation_rad, d);
    if (!(st > 0.0f))
        return 0.0f;
    return rb_ref_env_pdf(env, n, d);
}

float rb_ref_env_pdf(const struct rb_ref_env *env, const float n[3], const float d[3])
{
    if (env->is_black)
        return 0.0f;
    if (!env->rgba)
        return rb_ref_maxf(rb_f3_dot(n, d), 0.0f) / RB_PI;
    float u, v;
    rb_ref_equirect_uv(d, env->rotation_rad, &u, &v);
    if (!(u == u) || !(v == v))
        return 0.0f;
    uint32_t w = env->width_px, h = env->height_px;
    float fx = floorf(u * (float)w), fy = floorf(v * (float)h);
    uint32_t x = fx < 0.0f ? 0 : (fx >= (float)w ? w - 1 : (uint32_t)fx);
    uint32_t y = fy < 0.0f ? 0 : (fy >= (float)h ? h - 1 : (uint32_t)fy);
    float st = sinf(v * RB_PI);
    if (!(st > 0.0f))
        return 0.0f;
    /* density over the unit (u, v) square, then over solid angle: du dv = dw / (2 pi^2 sin) */
    float p_uv = env->texel_pdf[(size_t)y * w + x] * (float)w * (float)h;
    return p_uv / (2.0f * RB_PI * RB_PI * st);
}
