/* FLIP and HDR-FLIP, written from the papers (Andersson et al., HPG 2020; Ray Tracing Gems II,
 * 2021; Eurographics 2021) to give the figures of NVIDIA's reference tool, NVlabs/flip 1.6.
 *
 * LDR-FLIP, per pixel of two display-referred images:
 *  1. decode sRGB, clamp to [0,1], go to YCxCz (linear RGB -> XYZ -> the opponent space of
 *     Zhang and Wandell, against the D65 white);
 *  2. filter each channel with its contrast sensitivity function, a sum of Gaussians in
 *     a sqrt(pi/b) exp(-pi^2 x^2 / b) form (x in degrees: 1/PPD a pixel), radius
 *     ceil(3 sqrt(b_max / (2 pi^2)) PPD): one Gaussian for Y and Cx, which separate; two for Cz,
 *     filtered as two separable products with the square roots of the weights (the reference's
 *     separatedConvolutions note), the sum normalised to 1 by 1 / sqrt(S1^2 + S2^2) per axis;
 *  3. back to linear RGB clamped to [0,1], then CIELAB with the Hunt effect (a and b scaled by
 *     L / 100), and HyAB: |dL| + sqrt(da^2 + db^2);
 *  4. colour error dEc: HyAB^qc (qc = 0.7) compressed to [0,1]: below pc cmax (pc = 0.4, cmax
 *     the HyAB^qc between Hunt-adjusted green and blue) it maps linearly to [0, pt] (pt = 0.95),
 *     above, linearly to [pt, 1];
 *  5. feature error dEf on the luminance Y / 116 + 16 / 116 (that is Y / Yw): Gaussian
 *     derivative filters with sigma = 0.5 w PPD (w = 0.082), radius ceil(3 sigma), the first
 *     derivative for edges and the second for points, each normalised so that its positive
 *     weights sum to 1 and its negative ones to -1, applied separably (derivative along one
 *     axis, the Gaussian along the other); dEf = (max(|edge diff|, |point diff|) / sqrt 2)^qf,
 *     qf = 0.5;
 *  6. dE = dEc^(1 - dEf).
 * HDR-FLIP exposes both scene-linear images by 2^e for count exposures e evenly spaced from start
 * to stop, tone-maps them (ACES by default) and clamps them to [0,1], runs LDR-FLIP from step 1's
 * YCxCz (no sRGB round trip, as the reference does) and keeps each pixel's largest error. start
 * and stop come from the reference: the tone mapper reaches 0.85 at x85, start = log2(x85 /
 * Ymax), stop = log2(x85 / Ymedian).
 *
 * Arithmetic is float and in the reference's order (its constants, its sums in tap order, clamped
 * edges), so that the error maps agree to float rounding. Every filter is separable and runs as
 * a horizontal then a vertical pass; the image goes in strips of 256 columns, top to bottom, the
 * horizontal passes of the rows a vertical pass needs kept in a ring of 2 r + 1 rows, so the
 * work stays in a core's cache. The passes sum 64 pixels at a time in vector registers (GNU C
 * vectors; on x86-64 also built for AVX2 and picked at load time) and the colour arithmetic
 * runs 4 pixels at a time, powf and sqrtf lane by lane: every pixel gets the same operations in
 * the same order as one at a time, so the bits do not depend on the processor. A 1920x1080
 * HDR-FLIP (13 exposures) takes about 2 s on one core (make bench). Pooling sorts the map (a
 * radix sort on the float bits) for the weighted percentiles, which sum in double where the
 * reference sums in float. Error maps are drawn with the tool's colour map, magma, as a table.
 * What this file does not do: threads, the reference tool's histogram plot. */
#include "analysis/flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/io.h"

#define PI_F 3.14159265358979f

/* The papers' constants (HPG 2020). */
#define FLIP_QC 0.7f
#define FLIP_PC 0.4f
#define FLIP_PT 0.95f
#define FLIP_W 0.082f
#define FLIP_QF 0.5f

/* The contrast sensitivity functions as sums of two Gaussians, a1 g(b1) + a2 g(b2), for Y, Cx
 * and Cz (HPG 2020; the b's in squared degrees). */
static const float csf_a1[3] = {1.0f, 1.0f, 34.1f};
static const float csf_b1[3] = {0.0047f, 0.0053f, 0.04f};
static const float csf_a2[3] = {0.0f, 0.0f, 13.5f};
static const float csf_b2[3] = {1.0e-5f, 1.0e-5f, 0.025f};

/* D65, the XYZ of linear RGB (1, 1, 1), and its inverse. */
static const float white[3] = {0.950428545f, 1.000000000f, 1.088900371f};
static const float inv_white[3] = {1.052156925f, 1.000000000f, 0.918357670f};

/* Tone mappers as (k0 x^2 + k1 x + k2) / (k3 x^2 + k4 x + k5); Reinhard's row only serves the
 * exposure range, its curve divides by the luminance instead. */
static const float tonemap_k[][6] = {
    [RB_ANALYSIS_FLIP_TONEMAPPER_ACES] = {0.6f * 0.6f * 2.51f, 0.6f * 0.03f, 0.0f,
                                          0.6f * 0.6f * 2.43f, 0.6f * 0.59f, 0.14f},
    [RB_ANALYSIS_FLIP_TONEMAPPER_REINHARD] = {0.0f, 1.0f, 0.0f, 0.0f, 1.0f, 1.0f},
    [RB_ANALYSIS_FLIP_TONEMAPPER_HABLE] = {0.231683f, 0.013791f, 0.0f, 0.18f, 0.3f, 0.018f},
};

/* ---- colour ----------------------------------------------------------------------------- */

static float clamp01(float v)
{
    v = v > 0.0f ? v : 0.0f; /* NaN becomes 0, as in the reference */
    return v > 1.0f ? 1.0f : v;
}

static float srgb_to_linear(float s)
{
    return s <= 0.04045f ? s / 12.92f : powf((s + 0.055f) / 1.055f, 2.4f);
}

static float luminance(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

/* sRGB primaries, D65 (the reference's exact fractions). */
static void rgb_to_xyz(const float c[3], float o[3])
{
    static const float m[9] = {
        10135552.0f / 24577794.0f, 8788810.0f / 24577794.0f, 4435075.0f / 24577794.0f,
        2613072.0f / 12288897.0f,  8788810.0f / 12288897.0f, 887015.0f / 12288897.0f,
        1425312.0f / 73733382.0f,  8788810.0f / 73733382.0f, 70074185.0f / 73733382.0f,
    };
    o[0] = m[0] * c[0] + m[1] * c[1] + m[2] * c[2];
    o[1] = m[3] * c[0] + m[4] * c[1] + m[5] * c[2];
    o[2] = m[6] * c[0] + m[7] * c[1] + m[8] * c[2];
}

static void xyz_to_rgb(const float c[3], float o[3])
{
    static const float m[9] = {
        3.241003275f, -1.537398934f, -0.498615861f, -0.969224334f, 1.875930071f,
        0.041554224f, 0.055639423f,  -0.204011202f, 1.057148933f,
    };
    o[0] = m[0] * c[0] + m[1] * c[1] + m[2] * c[2];
    o[1] = m[3] * c[0] + m[4] * c[1] + m[5] * c[2];
    o[2] = m[6] * c[0] + m[7] * c[1] + m[8] * c[2];
}

static void xyz_to_lab(const float xyz[3], float lab[3])
{
    const float delta = 6.0f / 29.0f;
    const float delta2 = delta * delta;
    const float delta3 = delta * delta2;
    const float factor = 1.0f / (3.0f * delta2);
    const float term = 4.0f / 29.0f;
    float f[3];
    for (int i = 0; i < 3; i++) {
        float t = xyz[i] * inv_white[i];
        f[i] = t > delta3 ? powf(t, 1.0f / 3.0f) : factor * t + term;
    }
    lab[0] = 116.0f * f[1] - 16.0f;
    lab[1] = 500.0f * (f[0] - f[1]);
    lab[2] = 200.0f * (f[1] - f[2]);
}

/* CIELAB with the Hunt effect: chroma fades with lightness (HPG 2020). */
static void lab_hunt(float lab[3])
{
    lab[1] = 0.01f * lab[0] * lab[1];
    lab[2] = 0.01f * lab[0] * lab[2];
}

static float hyab(const float a[3], const float b[3])
{
    float da = a[1] - b[1], db = a[2] - b[2];
    return fabsf(a[0] - b[0]) + sqrtf(da * da + db * db);
}

/* A filtered YCxCz back to linear RGB, clamped to the gamut, then to Hunt-adjusted CIELAB. */
static void ycxcz_to_lab_hunt(float y, float cx, float cz, float lab[3])
{
    float yy = (y + 16.0f) / 116.0f;
    float xyz[3] = {(yy + cx / 500.0f) * white[0], yy * white[1], (yy - cz / 200.0f) * white[2]};
    float rgb[3];
    xyz_to_rgb(xyz, rgb);
    for (int i = 0; i < 3; i++)
        rgb[i] = clamp01(rgb[i]);
    rgb_to_xyz(rgb, xyz);
    xyz_to_lab(xyz, lab);
    lab_hunt(lab);
}

/* HyAB^qc between Hunt-adjusted green and blue: the largest colour difference, which maps to 1. */
static float max_color_distance(void)
{
    const float green[3] = {0.0f, 1.0f, 0.0f}, blue[3] = {0.0f, 0.0f, 1.0f};
    float xyz[3], g[3], b[3];
    rgb_to_xyz(green, xyz);
    xyz_to_lab(xyz, g);
    lab_hunt(g);
    rgb_to_xyz(blue, xyz);
    xyz_to_lab(xyz, b);
    lab_hunt(b);
    return powf(hyab(g, b), FLIP_QC);
}

/* ---- the same, four pixels at a time ----------------------------------------------------- */

/* Four floats, and four lanes of a comparison (all ones where true): GNU C vector types, one SSE
 * register on x86-64. Every function here does what its one-pixel namesake does, operation for
 * operation, so the bits are the same; what has no vector form (powf, sqrtf) runs lane by lane. */
typedef float vec4 __attribute__((vector_size(16)));
typedef int32_t mask4 __attribute__((vector_size(16)));

static vec4 splat4(float v)
{
    return (vec4){v, v, v, v};
}

/* m ? a : b, lane by lane. */
static vec4 select4(mask4 m, vec4 a, vec4 b)
{
    return (vec4)((m & (mask4)a) | (~m & (mask4)b));
}

static vec4 clamp01_4(vec4 v)
{
    v = select4(v > splat4(0.0f), v, splat4(0.0f)); /* NaN becomes 0 */
    return select4(v > splat4(1.0f), splat4(1.0f), v);
}

static void rgb_to_xyz4(const vec4 c[3], vec4 o[3])
{
    static const float m[9] = {
        10135552.0f / 24577794.0f, 8788810.0f / 24577794.0f, 4435075.0f / 24577794.0f,
        2613072.0f / 12288897.0f,  8788810.0f / 12288897.0f, 887015.0f / 12288897.0f,
        1425312.0f / 73733382.0f,  8788810.0f / 73733382.0f, 70074185.0f / 73733382.0f,
    };
    for (int i = 0; i < 3; i++)
        o[i] = m[3 * i] * c[0] + m[3 * i + 1] * c[1] + m[3 * i + 2] * c[2];
}

static void ycxcz_to_lab_hunt4(vec4 y, vec4 cx, vec4 cz, vec4 lab[3])
{
    static const float m[9] = {
        3.241003275f, -1.537398934f, -0.498615861f, -0.969224334f, 1.875930071f,
        0.041554224f, 0.055639423f,  -0.204011202f, 1.057148933f,
    };
    const float delta = 6.0f / 29.0f;
    const float delta2 = delta * delta;
    const float delta3 = delta * delta2;
    const float factor = 1.0f / (3.0f * delta2);
    const float term = 4.0f / 29.0f;
    vec4 yy = (y + 16.0f) / 116.0f;
    vec4 xyz[3] = {(yy + cx / 500.0f) * white[0], yy * white[1], (yy - cz / 200.0f) * white[2]};
    vec4 rgb[3], f[3];
    for (int i = 0; i < 3; i++)
        rgb[i] = clamp01_4(m[3 * i] * xyz[0] + m[3 * i + 1] * xyz[1] + m[3 * i + 2] * xyz[2]);
    rgb_to_xyz4(rgb, xyz);
    for (int i = 0; i < 3; i++) {
        vec4 t = xyz[i] * inv_white[i];
        for (int l = 0; l < 4; l++)
            f[i][l] = t[l] > delta3 ? powf(t[l], 1.0f / 3.0f) : factor * t[l] + term;
    }
    lab[0] = 116.0f * f[1] - 16.0f;
    lab[1] = 500.0f * (f[0] - f[1]);
    lab[2] = 200.0f * (f[1] - f[2]);
    lab[1] = 0.01f * lab[0] * lab[1];
    lab[2] = 0.01f * lab[0] * lab[2];
}

static vec4 hyab4(const vec4 a[3], const vec4 b[3])
{
    vec4 da = a[1] - b[1], db = a[2] - b[2], dl = a[0] - b[0];
    vec4 h = da * da + db * db;
    for (int l = 0; l < 4; l++)
        h[l] = sqrtf(h[l]);
    return (vec4)((mask4)dl & 0x7fffffff) + h;
}

/* ---- how an input pixel becomes display linear RGB -------------------------------------- */

struct xform {
    bool is_hdr;
    enum rb_analysis_flip_tonemapper tonemapper; /* resolved */
    float scale;                                 /* 2^exposure */
};

static float tonemap_channel(const float *k, float c)
{
    /* Beyond 1e18, c * c would overflow to inf / inf (NaN, then black); divide through by c^2. */
    if (c > 1e18f)
        return (k[0] + k[1] / c + k[2] / (c * c)) / (k[3] + k[4] / c + k[5] / (c * c));
    return ((c * c) * k[0] + c * k[1] + k[2]) / ((c * c) * k[3] + c * k[4] + k[5]);
}

static void to_display_linear(const struct xform *t, const float in[3], float out[3])
{
    if (!t->is_hdr) {
        for (int i = 0; i < 3; i++)
            out[i] = clamp01(srgb_to_linear(in[i]));
        return;
    }
    float c[3] = {in[0] * t->scale, in[1] * t->scale, in[2] * t->scale};
    if (t->tonemapper == RB_ANALYSIS_FLIP_TONEMAPPER_REINHARD) {
        float f = 1.0f / (1.0f + luminance(c[0], c[1], c[2]));
        for (int i = 0; i < 3; i++)
            out[i] = clamp01(c[i] * f);
        return;
    }
    for (int i = 0; i < 3; i++)
        out[i] = clamp01(tonemap_channel(tonemap_k[t->tonemapper], c[i]));
}

/* to_display_linear of four pixels of an HDR image (c: their R, G and B, exposed). */
static void to_display_linear4(const struct xform *t, vec4 c[3])
{
    if (t->tonemapper == RB_ANALYSIS_FLIP_TONEMAPPER_REINHARD) {
        vec4 f = 1.0f / (1.0f + (0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]));
        for (int i = 0; i < 3; i++)
            c[i] = clamp01_4(c[i] * f);
        return;
    }
    const float *k = tonemap_k[t->tonemapper];
    for (int i = 0; i < 3; i++) {
        vec4 x = c[i], x2 = x * x;
        vec4 near = (x2 * k[0] + x * k[1] + k[2]) / (x2 * k[3] + x * k[4] + k[5]);
        vec4 far = (k[0] + k[1] / x + k[2] / x2) / (k[3] + k[4] / x + k[5] / x2);
        c[i] = clamp01_4(select4(x > splat4(1e18f), far, near));
    }
}

/* ---- filters ---------------------------------------------------------------------------- */

static float gauss_ab(float x2, float a, float b)
{
    const float pi_sq = PI_F * PI_F;
    return a * sqrtf(PI_F / b) * expf(-pi_sq * x2 / b);
}

/* The square root of gauss_ab's weight: its product along x and y is the 2D Gaussian. */
static float gauss_ab_sqrt(float x2, float a, float b)
{
    const float pi_sq = PI_F * PI_F;
    return sqrtf(a * sqrtf(PI_F / b)) * expf(-pi_sq * x2 / b);
}

static int spatial_radius(float ppd)
{
    const float pi_sq = PI_F * PI_F;
    float b_max = 0.0f;
    for (int c = 0; c < 3; c++)
        b_max = fmaxf(b_max, fmaxf(csf_b1[c], csf_b2[c]));
    return (int)ceilf(3.0f * sqrtf(b_max / (2.0f * pi_sq)) * ppd);
}

static float feature_sigma(float ppd)
{
    return 0.5f * FLIP_W * ppd;
}

/* s[0..3]: Y, Cx, the first and second Cz Gaussians; each 2r + 1 taps. */
static void spatial_filters(float ppd, int r, float *s[4])
{
    float dx = 1.0f / ppd;
    float sum[4] = {0};
    int n = 2 * r + 1;
    for (int i = 0; i < n; i++) {
        float x = (float)(i - r) * dx;
        float x2 = x * x;
        s[0][i] = gauss_ab(x2, csf_a1[0], csf_b1[0]);
        s[1][i] = gauss_ab(x2, csf_a1[1], csf_b1[1]);
        s[2][i] = gauss_ab_sqrt(x2, csf_a1[2], csf_b1[2]);
        s[3][i] = gauss_ab_sqrt(x2, csf_a2[2], csf_b2[2]);
        for (int k = 0; k < 4; k++)
            sum[k] += s[k][i];
    }
    float norm_y = 1.0f / sum[0], norm_cx = 1.0f / sum[1];
    float norm_cz = 1.0f / sqrtf(sum[2] * sum[2] + sum[3] * sum[3]);
    for (int i = 0; i < n; i++) {
        s[0][i] *= norm_y;
        s[1][i] *= norm_cx;
        s[2][i] *= norm_cz;
        s[3][i] *= norm_cz;
    }
}

/* f[0..2]: the Gaussian, its first and its second derivative; each 2r + 1 taps. */
static void feature_filters(float ppd, int r, float *f[3])
{
    float sd = feature_sigma(ppd);
    float g_sum = 0.0f, dg_pos = 0.0f, dg_neg = 0.0f, ddg_pos = 0.0f, ddg_neg = 0.0f;
    int n = 2 * r + 1;
    for (int i = 0; i < n; i++) {
        float x = (float)(i - r);
        float g = expf(-(x * x) / (2.0f * sd * sd));
        float dg = -x * g;
        float ddg = (x * x / (sd * sd) - 1.0f) * g;
        g_sum += g;
        if (dg > 0.0f)
            dg_pos += dg;
        else
            dg_neg -= dg;
        if (ddg > 0.0f)
            ddg_pos += ddg;
        else
            ddg_neg -= ddg;
        f[0][i] = g;
        f[1][i] = dg;
        f[2][i] = ddg;
    }
    for (int i = 0; i < n; i++) {
        f[0][i] /= g_sum;
        f[1][i] /= f[1][i] > 0.0f ? dg_pos : dg_neg;
        f[2][i] /= f[2][i] > 0.0f ? ddg_pos : ddg_neg;
    }
}

/* ---- the evaluator ---------------------------------------------------------------------- */

enum { IMG_REF, IMG_TEST };

/* A row's horizontal passes, per image: the CSF filters' four (Y, Cx, and Cz's two Gaussians)
 * at RING_SPATIAL + 4 img, the feature filters' three (along x the first derivative, the second,
 * the Gaussian) at RING_FEATURE + 3 img. */
enum { RING_SPATIAL = 0, RING_FEATURE = 8, RING_PLANES = 14 };

/* The width of the strips the image is evaluated in, so that the ring stays in a core's cache. */
#define STRIP_PX 256

/* Everything one evaluation needs, in one allocation. The image is evaluated in strips of at
 * most STRIP_PX columns, top to bottom; the horizontal passes of the rows the vertical passes
 * need (pad above and below the row they make) live in a ring of 2 pad + 1 rows of the strip,
 * small enough for the cache, and nothing the size of the image is written but the error
 * map. */
struct work {
    uint32_t w, h;
    size_t n;           /* w * h */
    int sr, fr, pad;    /* spatial and feature radii, the larger */
    uint32_t strip_w;   /* the widest strip: min(w, STRIP_PX) */
    uint32_t ring_rows; /* 2 pad + 1 */
    float *spatial[4];
    float *feature[3];
    float *ring; /* ring_rows rows of RING_PLANES planes of strip_w: row y in slot y % ring_rows */
    float *acc[8]; /* the vertical pass's sums, one strip row each */
    float *row[4]; /* one strip row's Y, Cx, Cz and gray, padded by pad on both sides */
    float cmax, pccmax;
    float *block;
    const float **taps; /* 2 pad + 1 row pointers, a filter's inputs (convolve) */
};

static void work_release(struct work *k)
{
    free(k->block);
    free(k->taps);
    memset(k, 0, sizeof(*k));
}

static enum rb_status work_init(struct work *k, uint32_t w, uint32_t h, float ppd,
                                struct rb_err *err)
{
    memset(k, 0, sizeof(*k));
    k->w = w;
    k->h = h;
    k->n = (size_t)w * h;
    k->sr = spatial_radius(ppd);
    k->fr = (int)ceilf(3.0f * feature_sigma(ppd));
    k->pad = k->sr > k->fr ? k->sr : k->fr;
    size_t st = 2 * (size_t)k->sr + 1, ft = 2 * (size_t)k->fr + 1;
    k->strip_w = w < STRIP_PX ? w : STRIP_PX;
    size_t sw = k->strip_w, padded = sw + 2 * (size_t)k->pad;
    k->ring_rows = 2 * (uint32_t)k->pad + 1;
    /* The ring, 8 rows, 4 padded rows and the taps: pad is at most a few thousand. */
    size_t total = (size_t)k->ring_rows * RING_PLANES * sw + 8 * sw + 4 * padded + 4 * st + 3 * ft;
    k->block = malloc(total * sizeof(float));
    k->taps = malloc((2 * (size_t)k->pad + 1) * sizeof(*k->taps));
    if (!k->block || !k->taps)
        return rb_errf(err, RB_E_NOMEM, "FLIP: cannot allocate %zu MiB for a %ux%u image",
                       total * sizeof(float) >> 20, w, h);
    float *p = k->block;
    k->ring = p;
    p += (size_t)k->ring_rows * RING_PLANES * sw;
    for (int i = 0; i < 8; i++, p += sw)
        k->acc[i] = p;
    for (int i = 0; i < 4; i++, p += padded)
        k->row[i] = p;
    for (int i = 0; i < 4; i++, p += st)
        k->spatial[i] = p;
    for (int i = 0; i < 3; i++, p += ft)
        k->feature[i] = p;
    spatial_filters(ppd, k->sr, k->spatial);
    feature_filters(ppd, k->fr, k->feature);
    k->cmax = max_color_distance();
    k->pccmax = FLIP_PC * k->cmax;
    return RB_OK;
}

/* A convolution's partial sums: CONV_VECS vectors of 8 floats, which stay in registers over
 * all the taps (a GNU C vector type, lowered to what the target has: two SSE registers each on
 * plain x86-64). Eight of them keep enough additions in flight to hide their latency. */
typedef float vec8 __attribute__((vector_size(32)));
#define CONV_VECS 8
#define CONV_BLOCK (8 * CONV_VECS)

/* On x86-64, convolve is built twice, for AVX2 and for the baseline, and the loader picks the
 * one the processor runs. Both do the same multiplications and additions in the same order (no
 * fused multiply-add: -ffp-contract=off), so they give the same bits. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CONV_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CONV_CLONES
#endif

/* dst[x] = the sum over j of wt[j] * src[j][x], for x < n: a filter of taps taps along the
 * rows src[0 .. taps - 1] (the rows above and below for a vertical pass, a row shifted by one
 * pixel a tap for a horizontal one). Each sum starts at 0 and adds its taps in order, so the
 * result is the same bits whatever the block size. */
CONV_CLONES static void convolve(float *restrict dst, const float *const *src, const float *wt,
                                 int taps, uint32_t n)
{
    uint32_t x = 0;
    for (; x + CONV_BLOCK <= n; x += CONV_BLOCK) {
        vec8 s[CONV_VECS];
#pragma GCC unroll 8
        for (int i = 0; i < CONV_VECS; i++)
            s[i] = (vec8){0};
        for (int j = 0; j < taps; j++) {
            const float *p = src[j] + x;
            const vec8 wj = {wt[j], wt[j], wt[j], wt[j], wt[j], wt[j], wt[j], wt[j]};
#pragma GCC unroll 8
            for (int i = 0; i < CONV_VECS; i++) {
                vec8 v;
                memcpy(&v, p + 8 * i, sizeof(v));
                s[i] += wj * v;
            }
        }
        memcpy(dst + x, s, sizeof(s));
    }
    for (; x + 8 <= n; x += 8) {
        vec8 s = {0};
        for (int j = 0; j < taps; j++) {
            const vec8 wj = {wt[j], wt[j], wt[j], wt[j], wt[j], wt[j], wt[j], wt[j]};
            vec8 v;
            memcpy(&v, src[j] + x, sizeof(v));
            s += wj * v;
        }
        memcpy(dst + x, &s, sizeof(s));
    }
    for (; x < n; x++) {
        float s = 0.0f;
        for (int j = 0; j < taps; j++)
            s += wt[j] * src[j][x];
        dst[x] = s;
    }
}

/* The taps of a horizontal pass of radius r over a row padded by pad: the row shifted. */
static void row_taps(const float *row, int pad, int r, const float **taps)
{
    for (int j = 0; j < 2 * r + 1; j++)
        taps[j] = row + (pad - r + j);
}

static uint32_t clamp_row(long y, uint32_t h)
{
    return y < 0 ? 0 : y >= (long)h ? h - 1 : (uint32_t)y;
}

static float *ring_row(const struct work *k, uint32_t y, int plane)
{
    return k->ring + ((size_t)(y % k->ring_rows) * RING_PLANES + (size_t)plane) * k->strip_w;
}

/* w pixels of RGB in into YCxCz (o[0..2]) and gray (o[3]: Y / Yw, for the feature filters). */
static void to_ycxcz(const struct xform *t, const float *in, uint32_t w, float *const o[4])
{
    float *gray = o[3];
    uint32_t x = 0;
    for (; t->is_hdr && x + 4 <= w; x += 4) {
        const float *p = in + 3 * (size_t)x;
        vec4 c[3], xyz[3];
        for (int i = 0; i < 3; i++)
            c[i] = (vec4){p[i], p[3 + i], p[6 + i], p[9 + i]} * t->scale;
        to_display_linear4(t, c);
        rgb_to_xyz4(c, xyz);
        for (int i = 0; i < 3; i++)
            xyz[i] *= inv_white[i];
        vec4 yc = 116.0f * xyz[1] - 16.0f, cx = 500.0f * (xyz[0] - xyz[1]);
        vec4 cz = 200.0f * (xyz[1] - xyz[2]), g = yc * (1.0f / 116.0f) + 16.0f / 116.0f;
        memcpy(o[0] + x, &yc, sizeof(yc));
        memcpy(o[1] + x, &cx, sizeof(cx));
        memcpy(o[2] + x, &cz, sizeof(cz));
        memcpy(gray + x, &g, sizeof(g));
    }
    for (; x < w; x++) {
        float lin[3], xyz[3];
        to_display_linear(t, in + 3 * (size_t)x, lin);
        rgb_to_xyz(lin, xyz);
        for (int i = 0; i < 3; i++)
            xyz[i] *= inv_white[i];
        float yc = 116.0f * xyz[1] - 16.0f;
        o[0][x] = yc;
        o[1][x] = 500.0f * (xyz[0] - xyz[1]);
        o[2][x] = 200.0f * (xyz[1] - xyz[2]);
        gray[x] = yc * (1.0f / 116.0f) + 16.0f / 116.0f;
    }
}

/* Row y of image img in the strip of sw columns from x0: the columns the filters reach into
 * YCxCz and gray, the image's edges repeated (the reference clamps its coordinates), then the
 * horizontal passes of the CSF and feature filters into its slot of the ring. */
static void horizontal(struct work *k, uint32_t y, int img, const float *rgb, const struct xform *t,
                       uint32_t x0, uint32_t sw)
{
    const int pad = k->pad;
    uint32_t lo = x0 > (uint32_t)pad ? x0 - (uint32_t)pad : 0;
    uint32_t hi = k->w - x0 - sw > (uint32_t)pad ? x0 + sw + (uint32_t)pad : k->w;
    size_t first = (size_t)pad - (x0 - lo), last = first + (hi - lo); /* in the padded row */
    float *o[4];
    for (int i = 0; i < 4; i++)
        o[i] = k->row[i] + first;
    to_ycxcz(t, rgb + ((size_t)y * k->w + lo) * 3, hi - lo, o);
    for (int i = 0; i < 4; i++) {
        float *row = k->row[i];
        for (size_t x = 0; x < first; x++)
            row[x] = row[first];
        for (size_t x = last; x < sw + 2 * (size_t)pad; x++)
            row[x] = row[last - 1];
    }
    /* Y, Cx, and Cz twice: its two Gaussians. */
    for (int i = 0; i < 4; i++) {
        row_taps(k->row[i < 3 ? i : 2], pad, k->sr, k->taps);
        convolve(ring_row(k, y, RING_SPATIAL + 4 * img + i), k->taps, k->spatial[i], 2 * k->sr + 1,
                 sw);
    }
    /* Along x: the first derivative, the second, the Gaussian. */
    static const int filter[3] = {1, 2, 0};
    row_taps(k->row[3], pad, k->fr, k->taps);
    for (int i = 0; i < 3; i++)
        convolve(ring_row(k, y, RING_FEATURE + 3 * img + i), k->taps, k->feature[filter[i]],
                 2 * k->fr + 1, sw);
}

/* The vertical pass of the plane's rows around y (radius r) with the filter wt into the sw
 * values of dst. */
static void vertical(struct work *k, uint32_t y, int plane, int r, const float *wt, uint32_t sw,
                     float *dst)
{
    for (int j = 0; j < 2 * r + 1; j++)
        k->taps[j] = ring_row(k, clamp_row((long)y - r + j, k->h), plane);
    convolve(dst, k->taps, wt, 2 * r + 1, sw);
}

/* Row y of the strip, w values, into d: the CSF filters' vertical pass on both images and the
 * colour error, then the feature filters' (the Gaussian along y on the x derivatives, the
 * derivatives along y on the x Gaussian), the feature error, and FLIP's. */
static void error_row(struct work *k, uint32_t y, uint32_t w, float *d)
{
    const float norm = 1.0f / sqrtf(2.0f);
    for (int i = 0; i < 8; i++)
        vertical(k, y, RING_SPATIAL + i, k->sr, k->spatial[i % 4], w, k->acc[i]);
    uint32_t x = 0;
    for (; x + 4 <= w; x += 4) {
        vec4 a[8], ref[3], test[3];
        for (int i = 0; i < 8; i++)
            memcpy(&a[i], k->acc[i] + x, sizeof(a[i]));
        ycxcz_to_lab_hunt4(a[0], a[1], a[2] + a[3], ref);
        ycxcz_to_lab_hunt4(a[4], a[5], a[6] + a[7], test);
        vec4 e = hyab4(ref, test);
        for (int l = 0; l < 4; l++) /* 0 where the colours agree, as powf gives */
            e[l] = e[l] > 0.0f ? powf(e[l], FLIP_QC) : 0.0f;
        vec4 lo = e * (FLIP_PT / k->pccmax);
        vec4 hi = FLIP_PT + ((e - k->pccmax) / (k->cmax - k->pccmax)) * (1.0f - FLIP_PT);
        e = select4(e < splat4(k->pccmax), lo, hi);
        memcpy(d + x, &e, sizeof(e));
    }
    for (; x < w; x++) {
        float ref[3], test[3];
        ycxcz_to_lab_hunt(k->acc[0][x], k->acc[1][x], k->acc[2][x] + k->acc[3][x], ref);
        ycxcz_to_lab_hunt(k->acc[4][x], k->acc[5][x], k->acc[6][x] + k->acc[7][x], test);
        float e = powf(hyab(ref, test), FLIP_QC);
        if (e < k->pccmax)
            e *= FLIP_PT / k->pccmax;
        else
            e = FLIP_PT + ((e - k->pccmax) / (k->cmax - k->pccmax)) * (1.0f - FLIP_PT);
        d[x] = e;
    }
    /* Per image: dx, ddx, dy, ddy. */
    static const int plane[4] = {0, 1, 2, 2}, filter[4] = {0, 0, 1, 2};
    for (int i = 0; i < 8; i++)
        vertical(k, y, RING_FEATURE + 3 * (i / 4) + plane[i % 4], k->fr, k->feature[filter[i % 4]],
                 w, k->acc[i]);
    x = 0;
    for (; x + 4 <= w; x += 4) {
        vec4 a[8], v[4], e;
        for (int i = 0; i < 8; i++)
            memcpy(&a[i], k->acc[i] + x, sizeof(a[i]));
        /* edge and point, of the reference and of the test */
        v[0] = a[0] * a[0] + a[2] * a[2];
        v[1] = a[4] * a[4] + a[6] * a[6];
        v[2] = a[1] * a[1] + a[3] * a[3];
        v[3] = a[5] * a[5] + a[7] * a[7];
        for (int i = 0; i < 4; i++)
            for (int l = 0; l < 4; l++)
                v[i][l] = sqrtf(v[i][l]);
        vec4 de = (vec4)((mask4)(v[0] - v[1]) & 0x7fffffff);
        vec4 dp = (vec4)((mask4)(v[2] - v[3]) & 0x7fffffff);
        vec4 m = norm * select4(de > dp, de, dp);
        memcpy(&e, d + x, sizeof(e));
        for (int l = 0; l < 4; l++) {
            float q = 1.0f - sqrtf(m[l]); /* powf's own results where it is skipped */
            e[l] = q == 1.0f || (e[l] == 0.0f && q > 0.0f) ? e[l] : powf(e[l], q);
        }
        memcpy(d + x, &e, sizeof(e));
    }
    for (; x < w; x++) {
        float *const *a = k->acc;
        float edge_ref = sqrtf(a[0][x] * a[0][x] + a[2][x] * a[2][x]);
        float edge_test = sqrtf(a[4][x] * a[4][x] + a[6][x] * a[6][x]);
        float point_ref = sqrtf(a[1][x] * a[1][x] + a[3][x] * a[3][x]);
        float point_test = sqrtf(a[5][x] * a[5][x] + a[7][x] * a[7][x]);
        float de = fabsf(edge_ref - edge_test), dp = fabsf(point_ref - point_test);
        /* qf is 1/2: the reference's pow(v, 0.5f) is sqrtf(v). */
        float feature = sqrtf(norm * (de > dp ? de : dp));
        d[x] = powf(d[x], 1.0f - feature);
    }
}

/* LDR-FLIP of one pair under t into dst (w * h), strip by strip: each row of a strip once the
 * ring holds the horizontal passes of the rows it needs. */
static void evaluate(struct work *k, const float *test_rgb, const float *ref_rgb,
                     const struct xform *t, float *dst)
{
    for (uint32_t x0 = 0; x0 < k->w; x0 += k->strip_w) {
        uint32_t sw = k->w - x0 < k->strip_w ? k->w - x0 : k->strip_w;
        uint32_t next = 0; /* the next row into the ring */
        for (uint32_t y = 0; y < k->h; y++) {
            uint32_t last = y + (uint32_t)k->pad < k->h ? y + (uint32_t)k->pad : k->h - 1;
            for (; next <= last; next++) {
                horizontal(k, next, IMG_REF, ref_rgb, t, x0, sw);
                horizontal(k, next, IMG_TEST, test_rgb, t, x0, sw);
            }
            error_row(k, y, sw, dst + (size_t)y * k->w + x0);
        }
    }
}

/* ---- sorting (radix, on the float bits) ------------------------------------------------- */

static uint32_t float_key(float f)
{
    uint32_t u;
    if (f == 0.0f)
        f = 0.0f; /* -0 sorts as +0 */
    memcpy(&u, &f, sizeof(u));
    return u & 0x80000000u ? ~u : u | 0x80000000u;
}

static float key_float(uint32_t k)
{
    uint32_t u = k & 0x80000000u ? k & 0x7fffffffu : ~k;
    float f;
    memcpy(&f, &u, sizeof(f));
    return f;
}

/* Sorts n finite floats ascending into out; tmp holds n uint32_t as well as out's n. */
static void sort_floats(const float *in, size_t n, float *out, uint32_t *tmp, uint32_t *keys)
{
    for (size_t i = 0; i < n; i++)
        keys[i] = float_key(in[i]);
    uint32_t *src = keys, *dst = tmp;
    for (int shift = 0; shift < 32; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++)
            count[((src[i] >> shift) & 0xffu) + 1]++;
        for (int b = 0; b < 256; b++)
            count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 0xffu]++] = src[i];
        uint32_t *swap = src;
        src = dst;
        dst = swap;
    }
    for (size_t i = 0; i < n; i++)
        out[i] = key_float(src[i]); /* four passes: the result is back in keys */
}

/* ---- the colour map --------------------------------------------------------------------- */

/* magma's 256 colours (CC0: van der Walt and Smith, matplotlib's default colour maps), each of
 * its published [0, 1] sRGB values times 255, rounded. */
static const uint8_t magma[RB_ANALYSIS_FLIP_COLORMAP_SIZE][3] = {
    {0, 0, 4},       {1, 0, 5},       {1, 1, 6},       {1, 1, 8},       {2, 1, 9},
    {2, 2, 11},      {2, 2, 13},      {3, 3, 15},      {3, 3, 18},      {4, 4, 20},
    {5, 4, 22},      {6, 5, 24},      {6, 5, 26},      {7, 6, 28},      {8, 7, 30},
    {9, 7, 32},      {10, 8, 34},     {11, 9, 36},     {12, 9, 38},     {13, 10, 41},
    {14, 11, 43},    {16, 11, 45},    {17, 12, 47},    {18, 13, 49},    {19, 13, 52},
    {20, 14, 54},    {21, 14, 56},    {22, 15, 59},    {24, 15, 61},    {25, 16, 63},
    {26, 16, 66},    {28, 16, 68},    {29, 17, 71},    {30, 17, 73},    {32, 17, 75},
    {33, 17, 78},    {34, 17, 80},    {36, 18, 83},    {37, 18, 85},    {39, 18, 88},
    {41, 17, 90},    {42, 17, 92},    {44, 17, 95},    {45, 17, 97},    {47, 17, 99},
    {49, 17, 101},   {51, 16, 103},   {52, 16, 105},   {54, 16, 107},   {56, 16, 108},
    {57, 15, 110},   {59, 15, 112},   {61, 15, 113},   {63, 15, 114},   {64, 15, 116},
    {66, 15, 117},   {68, 15, 118},   {69, 16, 119},   {71, 16, 120},   {73, 16, 120},
    {74, 16, 121},   {76, 17, 122},   {78, 17, 123},   {79, 18, 123},   {81, 18, 124},
    {82, 19, 124},   {84, 19, 125},   {86, 20, 125},   {87, 21, 126},   {89, 21, 126},
    {90, 22, 126},   {92, 22, 127},   {93, 23, 127},   {95, 24, 127},   {96, 24, 128},
    {98, 25, 128},   {100, 26, 128},  {101, 26, 128},  {103, 27, 128},  {104, 28, 129},
    {106, 28, 129},  {107, 29, 129},  {109, 29, 129},  {110, 30, 129},  {112, 31, 129},
    {114, 31, 129},  {115, 32, 129},  {117, 33, 129},  {118, 33, 129},  {120, 34, 129},
    {121, 34, 130},  {123, 35, 130},  {124, 35, 130},  {126, 36, 130},  {128, 37, 130},
    {129, 37, 129},  {131, 38, 129},  {132, 38, 129},  {134, 39, 129},  {136, 39, 129},
    {137, 40, 129},  {139, 41, 129},  {140, 41, 129},  {142, 42, 129},  {144, 42, 129},
    {145, 43, 129},  {147, 43, 128},  {148, 44, 128},  {150, 44, 128},  {152, 45, 128},
    {153, 45, 128},  {155, 46, 127},  {156, 46, 127},  {158, 47, 127},  {160, 47, 127},
    {161, 48, 126},  {163, 48, 126},  {165, 49, 126},  {166, 49, 125},  {168, 50, 125},
    {170, 51, 125},  {171, 51, 124},  {173, 52, 124},  {174, 52, 123},  {176, 53, 123},
    {178, 53, 123},  {179, 54, 122},  {181, 54, 122},  {183, 55, 121},  {184, 55, 121},
    {186, 56, 120},  {188, 57, 120},  {189, 57, 119},  {191, 58, 119},  {192, 58, 118},
    {194, 59, 117},  {196, 60, 117},  {197, 60, 116},  {199, 61, 115},  {200, 62, 115},
    {202, 62, 114},  {204, 63, 113},  {205, 64, 113},  {207, 64, 112},  {208, 65, 111},
    {210, 66, 111},  {211, 67, 110},  {213, 68, 109},  {214, 69, 108},  {216, 69, 108},
    {217, 70, 107},  {219, 71, 106},  {220, 72, 105},  {222, 73, 104},  {223, 74, 104},
    {224, 76, 103},  {226, 77, 102},  {227, 78, 101},  {228, 79, 100},  {229, 80, 100},
    {231, 82, 99},   {232, 83, 98},   {233, 84, 98},   {234, 86, 97},   {235, 87, 96},
    {236, 88, 96},   {237, 90, 95},   {238, 91, 94},   {239, 93, 94},   {240, 95, 94},
    {241, 96, 93},   {242, 98, 93},   {242, 100, 92},  {243, 101, 92},  {244, 103, 92},
    {244, 105, 92},  {245, 107, 92},  {246, 108, 92},  {246, 110, 92},  {247, 112, 92},
    {247, 114, 92},  {248, 116, 92},  {248, 118, 92},  {249, 120, 93},  {249, 121, 93},
    {249, 123, 93},  {250, 125, 94},  {250, 127, 94},  {250, 129, 95},  {251, 131, 95},
    {251, 133, 96},  {251, 135, 97},  {252, 137, 97},  {252, 138, 98},  {252, 140, 99},
    {252, 142, 100}, {252, 144, 101}, {253, 146, 102}, {253, 148, 103}, {253, 150, 104},
    {253, 152, 105}, {253, 154, 106}, {253, 155, 107}, {254, 157, 108}, {254, 159, 109},
    {254, 161, 110}, {254, 163, 111}, {254, 165, 113}, {254, 167, 114}, {254, 169, 115},
    {254, 170, 116}, {254, 172, 118}, {254, 174, 119}, {254, 176, 120}, {254, 178, 122},
    {254, 180, 123}, {254, 182, 124}, {254, 183, 126}, {254, 185, 127}, {254, 187, 129},
    {254, 189, 130}, {254, 191, 132}, {254, 193, 133}, {254, 194, 135}, {254, 196, 136},
    {254, 198, 138}, {254, 200, 140}, {254, 202, 141}, {254, 204, 143}, {254, 205, 144},
    {254, 207, 146}, {254, 209, 148}, {254, 211, 149}, {254, 213, 151}, {254, 215, 153},
    {254, 216, 154}, {253, 218, 156}, {253, 220, 158}, {253, 222, 160}, {253, 224, 161},
    {253, 226, 163}, {253, 227, 165}, {253, 229, 167}, {253, 231, 169}, {253, 233, 170},
    {253, 235, 172}, {252, 236, 174}, {252, 238, 176}, {252, 240, 178}, {252, 242, 180},
    {252, 244, 182}, {252, 246, 184}, {252, 247, 185}, {252, 249, 187}, {252, 251, 189},
    {252, 253, 191},
};

void rb_analysis_flip_color(float error, uint8_t rgb[3])
{
    float v = clamp01(error) * (float)(RB_ANALYSIS_FLIP_COLORMAP_SIZE - 1) + 0.5f;
    memcpy(rgb, magma[(int)v], 3);
}

enum rb_status rb_analysis_flip_png_write(const char *path, const float *error_map,
                                          uint32_t width_px, uint32_t height_px, struct rb_err *err)
{
    size_t n = (size_t)width_px * height_px;
    uint8_t *rgba = malloc(n * 4);
    if (!rgba)
        return rb_errf(err, RB_E_NOMEM, "FLIP map '%s': out of memory for %ux%u", path, width_px,
                       height_px);
    for (size_t i = 0; i < n; i++) {
        rb_analysis_flip_color(error_map[i], rgba + 4 * i);
        rgba[4 * i + 3] = 255;
    }
    enum rb_status st = rb_io_png_write(path, width_px, height_px, rgba, err);
    free(rgba);
    return st;
}

/* ---- checks ----------------------------------------------------------------------------- */

static enum rb_status check_image(const float *rgb, const char *what, uint32_t w, uint32_t h,
                                  struct rb_err *err)
{
    if (!rgb)
        return rb_errf(err, RB_E_INVALID, "FLIP: no %s image", what);
    size_t n = (size_t)w * h * 3;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(rgb[i])) {
            size_t p = i / 3;
            return rb_errf(err, RB_E_INVALID, "FLIP: %s image pixel (%zu, %zu) channel %zu is %g",
                           what, p % w, p / w, i % 3, (double)rgb[i]);
        }
    return RB_OK;
}

static enum rb_status check_size(uint32_t w, uint32_t h, struct rb_err *err)
{
    if (!w || !h)
        return rb_errf(err, RB_E_INVALID, "FLIP: image size %ux%u is empty", w, h);
    if ((size_t)w * h > SIZE_MAX / (3 * sizeof(float)))
        return rb_errf(err, RB_E_INVALID, "FLIP: image size %ux%u is too large", w, h);
    return RB_OK;
}

static enum rb_status check_desc(const struct rb_analysis_flip_desc *d, struct rb_err *err)
{
    if (!(d->pixels_per_degree > 0.0) || !(d->pixels_per_degree <= RB_ANALYSIS_FLIP_MAX_PPD))
        return rb_errf(err, RB_E_INVALID, "FLIP: pixels per degree %g is not in (0, %g]",
                       d->pixels_per_degree, RB_ANALYSIS_FLIP_MAX_PPD);
    if (d->tonemapper < RB_ANALYSIS_FLIP_TONEMAPPER_ACES ||
        d->tonemapper > RB_ANALYSIS_FLIP_TONEMAPPER_HABLE)
        return rb_errf(err, RB_E_INVALID, "FLIP: unknown tone mapper %d", (int)d->tonemapper);
    if ((d->has_start_exposure && !isfinite(d->start_exposure)) ||
        (d->has_stop_exposure && !isfinite(d->stop_exposure)))
        return rb_errf(err, RB_E_INVALID, "FLIP: exposures must be finite");
    return RB_OK;
}

/* ---- public ----------------------------------------------------------------------------- */

double rb_analysis_flip_ppd(double distance_m, double width_m, double resolution_px)
{
    return (float)distance_m * ((float)resolution_px / (float)width_m) * (PI_F / 180.0f);
}

struct rb_analysis_flip_desc rb_analysis_flip_desc_resolve(const struct rb_analysis_flip_desc *in)
{
    struct rb_analysis_flip_desc d = in ? *in : (struct rb_analysis_flip_desc){0};
    if (d.pixels_per_degree == 0.0)
        d.pixels_per_degree =
            rb_analysis_flip_ppd(RB_ANALYSIS_FLIP_DISTANCE_M, RB_ANALYSIS_FLIP_DISPLAY_WIDTH_M,
                                 RB_ANALYSIS_FLIP_DISPLAY_WIDTH_PX);
    if (d.tonemapper == RB_ANALYSIS_FLIP_TONEMAPPER_DEFAULT)
        d.tonemapper = RB_ANALYSIS_FLIP_TONEMAPPER_ACES;
    return d;
}

enum rb_status rb_analysis_flip_pool(const float *error_map, uint32_t width_px, uint32_t height_px,
                                     struct rb_analysis_flip_stats *out, struct rb_err *err)
{
    enum rb_status st = check_size(width_px, height_px, err);
    if (st)
        return st;
    if (!error_map || !out)
        return rb_errf(err, RB_E_INVALID, "FLIP pooling: no error map or no output");
    size_t n = (size_t)width_px * height_px;
    struct rb_analysis_flip_stats s = {.min = INFINITY, .max = -INFINITY};
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        float v = error_map[i];
        if (!isfinite(v) || v < 0.0f)
            return rb_errf(err, RB_E_INVALID, "FLIP pooling: pixel (%zu, %zu) is %g", i % width_px,
                           i / width_px, (double)v);
        sum += v;
        if (v < s.min)
            s.min = v;
        if (v > s.max) {
            s.max = v;
            s.max_x = (uint32_t)(i % width_px);
            s.max_y = (uint32_t)(i / width_px);
        }
    }
    s.mean = sum / (double)n;

    float *sorted = malloc(n * sizeof(float));
    uint32_t *keys = malloc(2 * n * sizeof(uint32_t));
    if (!sorted || !keys) {
        free(sorted);
        free(keys);
        return rb_errf(err, RB_E_NOMEM, "FLIP pooling: cannot sort %zu values", n);
    }
    sort_floats(error_map, n, sorted, keys + n, keys);
    /* The reference tool's weighted percentile: the first value, ascending, at which the
     * running sum of values exceeds the fraction of their total. */
    const double frac[3] = {0.25, 0.5, 0.75};
    double *dst[3] = {&s.weighted_q1, &s.weighted_median, &s.weighted_q3};
    double running = 0.0;
    int q = 0;
    for (size_t i = 0; i < n && q < 3; i++) {
        running += sorted[i];
        while (q < 3 && running > frac[q] * sum)
            *dst[q++] = sorted[i];
    }
    free(sorted);
    free(keys);
    *out = s;
    return RB_OK;
}

enum rb_status rb_analysis_flip_exposures_compute(const float *ref_rgb, uint32_t width_px,
                                                  uint32_t height_px,
                                                  enum rb_analysis_flip_tonemapper tonemapper,
                                                  struct rb_analysis_flip_exposures *out,
                                                  struct rb_err *err)
{
    enum rb_status st = check_size(width_px, height_px, err);
    if (st)
        return st;
    if ((st = check_image(ref_rgb, "reference", width_px, height_px, err)))
        return st;
    if (!out)
        return rb_errf(err, RB_E_INVALID, "FLIP exposures: no output");
    if (tonemapper == RB_ANALYSIS_FLIP_TONEMAPPER_DEFAULT)
        tonemapper = RB_ANALYSIS_FLIP_TONEMAPPER_ACES;
    if (tonemapper < RB_ANALYSIS_FLIP_TONEMAPPER_ACES ||
        tonemapper > RB_ANALYSIS_FLIP_TONEMAPPER_HABLE)
        return rb_errf(err, RB_E_INVALID, "FLIP: unknown tone mapper %d", (int)tonemapper);

    /* x85: where the tone curve reaches 0.85, the larger root of (k0 - t k3) x^2 + (k1 - t k4) x
     * + (k2 - t k5) = 0. */
    const float *k = tonemap_k[tonemapper];
    const float t = 0.85f;
    float a = k[0] - t * k[3], b = k[1] - t * k[4], c = k[2] - t * k[5];
    float x85;
    if (a == 0.0f) {
        x85 = -c / b;
    } else {
        float d1 = -0.5f * (b / a);
        x85 = d1 + sqrtf(d1 * d1 - c / a);
    }

    size_t n = (size_t)width_px * height_px;
    float *lum = malloc(2 * n * sizeof(float));
    uint32_t *keys = malloc(2 * n * sizeof(uint32_t));
    if (!lum || !keys) {
        free(lum);
        free(keys);
        return rb_errf(err, RB_E_NOMEM, "FLIP exposures: cannot sort %zu luminances", n);
    }
    for (size_t i = 0; i < n; i++)
        lum[i] = luminance(ref_rgb[3 * i], ref_rgb[3 * i + 1], ref_rgb[3 * i + 2]);
    sort_floats(lum, n, lum + n, keys + n, keys);
    float y_max = lum[2 * n - 1], y_median = lum[n + n / 2];
    free(lum);
    free(keys);
    if (!(y_max > 0.0f) || !(y_median > 0.0f))
        return rb_errf(err, RB_E_INVALID,
                       "FLIP: the reference's luminance (largest %g, median %g) must be positive "
                       "to choose exposures; give start and stop exposures",
                       (double)y_max, (double)y_median);
    float start = log2f(x85 / y_max), stop = log2f(x85 / y_median);
    float count = ceilf(stop - start);
    out->start = start;
    out->stop = stop;
    out->count = count > 2.0f ? (uint32_t)count : 2;
    return RB_OK;
}

/* The finished error map to the caller: its pooled figures into out and a copy into error_map,
 * each when asked for. */
static enum rb_status hand_over(const float *map, uint32_t width_px, uint32_t height_px,
                                struct rb_analysis_flip_stats *out, float *error_map,
                                struct rb_err *err)
{
    if (out) {
        struct rb_analysis_flip_stats s;
        enum rb_status st = rb_analysis_flip_pool(map, width_px, height_px, &s, err);
        if (st)
            return st;
        *out = s;
    }
    if (error_map)
        memcpy(error_map, map, (size_t)width_px * height_px * sizeof(float));
    return RB_OK;
}

enum rb_status rb_analysis_flip_ldr(const float *test_rgb, const float *ref_rgb, uint32_t width_px,
                                    uint32_t height_px, const struct rb_analysis_flip_desc *desc,
                                    float *error_map, struct rb_analysis_flip_stats *out,
                                    struct rb_err *err)
{
    struct rb_analysis_flip_desc d = rb_analysis_flip_desc_resolve(desc);
    struct work k = {0};
    float *map = NULL;
    enum rb_status st = check_size(width_px, height_px, err);
    if (st || (st = check_desc(&d, err)) ||
        (st = check_image(test_rgb, "test", width_px, height_px, err)) ||
        (st = check_image(ref_rgb, "reference", width_px, height_px, err)))
        return st;
    if ((st = work_init(&k, width_px, height_px, (float)d.pixels_per_degree, err)))
        goto out;
    map = malloc(k.n * sizeof(float));
    if (!map) {
        st = rb_errf(err, RB_E_NOMEM, "FLIP: cannot allocate a %ux%u error map", width_px,
                     height_px);
        goto out;
    }
    evaluate(&k, test_rgb, ref_rgb, &(struct xform){.is_hdr = false}, map);
    st = hand_over(map, width_px, height_px, out, error_map, err);
out:
    free(map);
    work_release(&k);
    return st;
}

enum rb_status rb_analysis_flip_hdr(const float *test_rgb, const float *ref_rgb, uint32_t width_px,
                                    uint32_t height_px, const struct rb_analysis_flip_desc *desc,
                                    float *error_map, struct rb_analysis_flip_stats *out,
                                    struct rb_analysis_flip_exposures *exposures,
                                    struct rb_err *err)
{
    struct rb_analysis_flip_desc d = rb_analysis_flip_desc_resolve(desc);
    struct work k = {0};
    float *map = NULL, *tmp = NULL;
    enum rb_status st = check_size(width_px, height_px, err);
    if (st || (st = check_desc(&d, err)) ||
        (st = check_image(test_rgb, "test", width_px, height_px, err)) ||
        (st = check_image(ref_rgb, "reference", width_px, height_px, err)))
        return st;

    struct rb_analysis_flip_exposures e = {0};
    if (!d.has_start_exposure || !d.has_stop_exposure) {
        if ((st = rb_analysis_flip_exposures_compute(ref_rgb, width_px, height_px, d.tonemapper, &e,
                                                     err)))
            return st;
    }
    /* The reference keeps exposures in float. */
    if (d.has_start_exposure)
        e.start = (float)d.start_exposure;
    if (d.has_stop_exposure)
        e.stop = (float)d.stop_exposure;
    if (e.start > e.stop)
        return rb_errf(err, RB_E_INVALID, "FLIP: start exposure %g is above stop exposure %g",
                       e.start, e.stop);
    if (d.exposure_count)
        e.count = d.exposure_count;
    else {
        float c = ceilf((float)e.stop - (float)e.start);
        e.count = c > 2.0f ? (uint32_t)c : 2;
    }

    if ((st = work_init(&k, width_px, height_px, (float)d.pixels_per_degree, err)))
        goto out;
    map = calloc(k.n, sizeof(float));
    tmp = malloc(k.n * sizeof(float));
    if (!map || !tmp) {
        st =
            rb_errf(err, RB_E_NOMEM, "FLIP: cannot allocate %ux%u error maps", width_px, height_px);
        goto out;
    }
    float step = e.count > 1 ? ((float)e.stop - (float)e.start) / (float)(e.count - 1) : 0.0f;
    for (uint32_t i = 0; i < e.count; i++) {
        float exposure = (float)e.start + (float)i * step;
        struct xform t = {
            .is_hdr = true, .tonemapper = d.tonemapper, .scale = powf(2.0f, exposure)};
        evaluate(&k, test_rgb, ref_rgb, &t, tmp);
        for (size_t p = 0; p < k.n; p++)
            if (tmp[p] > map[p])
                map[p] = tmp[p];
    }
    if ((st = hand_over(map, width_px, height_px, out, error_map, err)))
        goto out;
    if (exposures)
        *exposures = e;
out:
    free(map);
    free(tmp);
    work_release(&k);
    return st;
}
