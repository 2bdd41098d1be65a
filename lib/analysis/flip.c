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
 * edges), so that the error maps agree to float rounding. Both passes of every filter run along
 * whole rows (a row of taps at a time), which the compiler vectorises; a 1080p LDR-FLIP then
 * takes under a second on one core (each HDR exposure as much). Pooling sorts the map (a radix sort
 * on the float bits) for the weighted percentiles, which sum in double where the reference sums in
 * float. What this file does not do: threads, colour-mapped error images, the reference tool's
 * histogram plot. */
#include "analysis/flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

/* Everything one evaluation needs, in one allocation. */
struct work {
    uint32_t w, h;
    size_t n;        /* w * h */
    int sr, fr, pad; /* spatial and feature radii, the larger */
    float *spatial[4];
    float *feature[3];
    float *gray[2];  /* per image: Y / Yw, for the feature filters */
    float *plane[8]; /* the horizontal pass's results */
    float *acc[8];   /* the vertical pass's sums, one row each */
    float *row[3];   /* one input row, padded by pad on both sides */
    float cmax, pccmax;
    float *block;
};

static void work_release(struct work *k)
{
    free(k->block);
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
    size_t padded = (size_t)w + 2 * (size_t)k->pad;
    /* 10 planes, 8 rows, 3 padded rows and the taps: overflow-checked in that order. */
    if (k->n > (SIZE_MAX / sizeof(float) - 4 * st - 3 * ft - 8 * (size_t)w - 3 * padded) / 10)
        return rb_errf(err, RB_E_NOMEM, "FLIP: a %ux%u image is too large", w, h);
    size_t total = 10 * k->n + 8 * (size_t)w + 3 * padded + 4 * st + 3 * ft;
    k->block = malloc(total * sizeof(float));
    if (!k->block)
        return rb_errf(err, RB_E_NOMEM, "FLIP: cannot allocate %zu MiB for a %ux%u image",
                       total * sizeof(float) >> 20, w, h);
    float *p = k->block;
    for (int i = 0; i < 2; i++, p += k->n)
        k->gray[i] = p;
    for (int i = 0; i < 8; i++, p += k->n)
        k->plane[i] = p;
    for (int i = 0; i < 8; i++, p += w)
        k->acc[i] = p;
    for (int i = 0; i < 3; i++, p += padded)
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

/* acc[x] += wt * src[x]: a tap of a filter over a whole row. */
static void axpy(float *restrict acc, const float *restrict src, float wt, uint32_t n)
{
    for (uint32_t x = 0; x < n; x++)
        acc[x] += wt * src[x];
}

/* Repeats the edge values of a row padded by pad on both sides (the reference clamps its
 * coordinates). */
static void pad_row(float *row, uint32_t w, int pad)
{
    for (int i = 0; i < pad; i++) {
        row[i] = row[pad];
        row[pad + w + (uint32_t)i] = row[pad + w - 1];
    }
}

static uint32_t clamp_row(long y, uint32_t h)
{
    return y < 0 ? 0 : y >= (long)h ? h - 1 : (uint32_t)y;
}

/* Image img's rows into YCxCz, its gray plane, and the horizontal pass of the CSF filters into
 * plane[4 img .. 4 img + 3]. */
static void spatial_horizontal(struct work *k, int img, const float *rgb, const struct xform *t)
{
    const uint32_t w = k->w;
    const int r = k->sr, pad = k->pad;
    float **out = k->plane + 4 * img;
    for (uint32_t y = 0; y < k->h; y++) {
        const float *in = rgb + (size_t)y * w * 3;
        float *gray = k->gray[img] + (size_t)y * w;
        for (uint32_t x = 0; x < w; x++) {
            float lin[3], xyz[3];
            to_display_linear(t, in + 3 * (size_t)x, lin);
            rgb_to_xyz(lin, xyz);
            for (int i = 0; i < 3; i++)
                xyz[i] *= inv_white[i];
            float yc = 116.0f * xyz[1] - 16.0f;
            k->row[0][pad + x] = yc;
            k->row[1][pad + x] = 500.0f * (xyz[0] - xyz[1]);
            k->row[2][pad + x] = 200.0f * (xyz[1] - xyz[2]);
            gray[x] = yc * (1.0f / 116.0f) + 16.0f / 116.0f;
        }
        for (int i = 0; i < 3; i++)
            pad_row(k->row[i], w, pad);
        float *o[4];
        for (int i = 0; i < 4; i++) {
            o[i] = out[i] + (size_t)y * w;
            memset(o[i], 0, w * sizeof(float));
        }
        for (int j = 0; j < 2 * r + 1; j++) {
            size_t off = (size_t)(pad - r + j);
            axpy(o[0], k->row[0] + off, k->spatial[0][j], w);
            axpy(o[1], k->row[1] + off, k->spatial[1][j], w);
            axpy(o[2], k->row[2] + off, k->spatial[2][j], w);
            axpy(o[3], k->row[2] + off, k->spatial[3][j], w);
        }
    }
}

/* The vertical pass of the CSF filters on both images, then the colour error into dst. */
static void spatial_vertical_color(struct work *k, float *dst)
{
    const uint32_t w = k->w;
    const int r = k->sr;
    for (uint32_t y = 0; y < k->h; y++) {
        for (int i = 0; i < 8; i++)
            memset(k->acc[i], 0, w * sizeof(float));
        for (int j = 0; j < 2 * r + 1; j++) {
            size_t off = (size_t)clamp_row((long)y - r + j, k->h) * w;
            for (int img = 0; img < 2; img++)
                for (int i = 0; i < 4; i++)
                    axpy(k->acc[4 * img + i], k->plane[4 * img + i] + off, k->spatial[i][j], w);
        }
        float *d = dst + (size_t)y * w;
        for (uint32_t x = 0; x < w; x++) {
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
    }
}

/* The feature filters' horizontal pass on image img's gray plane: along x the first derivative,
 * the second and the Gaussian, into plane[3 img .. 3 img + 2]. */
static void feature_horizontal(struct work *k, int img)
{
    const uint32_t w = k->w;
    const int r = k->fr, pad = k->pad;
    float *row = k->row[0];
    for (uint32_t y = 0; y < k->h; y++) {
        memcpy(row + pad, k->gray[img] + (size_t)y * w, w * sizeof(float));
        pad_row(row, w, pad);
        float *o[3];
        for (int i = 0; i < 3; i++) {
            o[i] = k->plane[3 * img + i] + (size_t)y * w;
            memset(o[i], 0, w * sizeof(float));
        }
        for (int j = 0; j < 2 * r + 1; j++) {
            const float *src = row + (pad - r + j);
            axpy(o[0], src, k->feature[1][j], w);
            axpy(o[1], src, k->feature[2][j], w);
            axpy(o[2], src, k->feature[0][j], w);
        }
    }
}

/* The vertical pass (the Gaussian on the x derivatives, the derivatives on the x Gaussian), the
 * feature error, and the final error: dst holds the colour error and receives FLIP's. */
static void feature_vertical_final(struct work *k, float *dst)
{
    const uint32_t w = k->w;
    const int r = k->fr;
    const float norm = 1.0f / sqrtf(2.0f);
    for (uint32_t y = 0; y < k->h; y++) {
        for (int i = 0; i < 8; i++)
            memset(k->acc[i], 0, w * sizeof(float));
        for (int j = 0; j < 2 * r + 1; j++) {
            size_t off = (size_t)clamp_row((long)y - r + j, k->h) * w;
            for (int img = 0; img < 2; img++) {
                float **a = k->acc + 4 * img, **p = k->plane + 3 * img;
                axpy(a[0], p[0] + off, k->feature[0][j], w); /* dx */
                axpy(a[1], p[1] + off, k->feature[0][j], w); /* ddx */
                axpy(a[2], p[2] + off, k->feature[1][j], w); /* dy */
                axpy(a[3], p[2] + off, k->feature[2][j], w); /* ddy */
            }
        }
        float *d = dst + (size_t)y * w;
        for (uint32_t x = 0; x < w; x++) {
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
}

/* LDR-FLIP of one pair under t into dst (w * h). */
static void evaluate(struct work *k, const float *test_rgb, const float *ref_rgb,
                     const struct xform *t, float *dst)
{
    spatial_horizontal(k, IMG_REF, ref_rgb, t);
    spatial_horizontal(k, IMG_TEST, test_rgb, t);
    spatial_vertical_color(k, dst);
    feature_horizontal(k, IMG_REF);
    feature_horizontal(k, IMG_TEST);
    feature_vertical_final(k, dst);
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
