/* lib/analysis: the comparison metrics on hand-made images with known answers (identical
 * images, a constant offset, one outlier, masks, relMSE's epsilon, NaN), accumulation over
 * frames, edge exclusion on synthetic depth and alpha steps, layer channels, and the error
 * image read back. Files go under one mkdtemp directory. */
#include "analysis/analysis.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "testutil.h"

#define W 8
#define H 6
#define N (W * H)

static char tmpdir[512];

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "compare");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

static void fill(float *px, size_t count, float v)
{
    for (size_t i = 0; i < count; i++)
        px[i] = v;
}

/* Compares a against b (W x H, nc channels) and expects success. */
static struct rb_analysis_metrics run(const float *a, const float *b, uint32_t nc,
                                      const uint8_t *mask, double eps)
{
    struct rb_analysis_metrics m;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_analysis_compare(&(struct rb_analysis_compare_desc){.width_px = W,
                                                                               .height_px = H,
                                                                               .channel_count = nc,
                                                                               .a = a,
                                                                               .b = b,
                                                                               .mask = mask,
                                                                               .epsilon = eps},
                                            &m, &err);
    if (st)
        fail_msg("rb_analysis_compare: %s", err.msg);
    return m;
}

/* ---- metrics ---------------------------------------------------------------------------- */

static void test_identical(void **state)
{
    (void)state;
    float a[N * 3];
    for (int i = 0; i < N * 3; i++)
        a[i] = 0.1f * (float)(i % 7);
    struct rb_analysis_metrics m = run(a, a, 3, NULL, 0.0);
    assert_int_equal(m.pixel_count, N);
    assert_int_equal(m.value_count, N * 3);
    assert_true(m.rmse == 0.0 && m.relmse == 0.0 && m.mae == 0.0 && m.max_error == 0.0);
    assert_true(isinf(m.psnr) && m.psnr > 0);
    assert_int_equal(m.max_error_x, 0);
    assert_int_equal(m.max_error_y, 0);
    assert_int_equal(m.nonfinite_count, 0);
    assert_double_equal(m.max_b, 0.6f, 1e-7); /* the largest value, 0.1 * 6 */
    assert_double_equal(m.peak, 1.0, 0);      /* PSNR's peak is RB_ANALYSIS_PEAK, not max_b */
}

static void test_constant_offset(void **state)
{
    (void)state;
    float a[N * 3], b[N * 3];
    fill(b, N * 3, 0.5f);
    fill(a, N * 3, 0.75f); /* exact in binary, so the answers are exact too */
    struct rb_analysis_metrics m = run(a, b, 3, NULL, 0.0);
    assert_double_equal(m.rmse, 0.25, 1e-12);
    assert_double_equal(m.mae, 0.25, 1e-12);
    assert_double_equal(m.mse, 0.0625, 1e-12);
    assert_double_equal(m.relmse, 0.0625 / (0.25 + 0.01), 1e-12);
    assert_double_equal(m.peak, 1.0, 0);
    assert_double_equal(m.psnr, 10.0 * log10(1.0 / 0.0625), 1e-9);
    assert_double_equal(m.max_error, 0.25, 0);
    /* Every value ties: the first pixel in row order is reported. */
    assert_int_equal(m.max_error_x, 0);
    assert_int_equal(m.max_error_y, 0);
}

static void test_outlier(void **state)
{
    (void)state;
    float a[N * 3], b[N * 3];
    fill(a, N * 3, 0.25f);
    fill(b, N * 3, 0.25f);
    size_t px = 4 * W + 5; /* x 5, y 4 */
    a[px * 3 + 1] = 2.25f; /* green off by 2 */
    a[2 * 3] = 0.5f;       /* a smaller error earlier in row order */
    struct rb_analysis_metrics m = run(a, b, 3, NULL, 0.0);
    assert_double_equal(m.max_error, 2.0, 0);
    assert_int_equal(m.max_error_x, 5);
    assert_int_equal(m.max_error_y, 4);
    double sq = 4.0 + 0.0625;
    assert_double_equal(m.rmse, sqrt(sq / (N * 3)), 1e-12);
    assert_double_equal(m.mae, 2.25 / (N * 3), 1e-12);
    assert_double_equal(m.relmse, sq / (0.0625 + 0.01) / (N * 3), 1e-12);
}

static void test_mask(void **state)
{
    (void)state;
    float a[N], b[N];
    uint8_t mask[N];
    fill(a, N, 1.0f);
    fill(b, N, 1.0f);
    memset(mask, 1, sizeof(mask));
    a[10] = 5.0f;
    mask[10] = 0;
    mask[11] = 0;
    b[20] = 100.0f; /* a masked-out reference value is not the largest compared */
    a[20] = 100.0f;
    mask[20] = 0;
    struct rb_analysis_metrics m = run(a, b, 1, mask, 0.0);
    assert_int_equal(m.pixel_count, N - 3);
    assert_true(m.rmse == 0.0 && m.max_error == 0.0 && isinf(m.psnr));
    assert_double_equal(m.max_b, 1.0, 0);
    /* Without the mask the outlier counts. */
    m = run(a, b, 1, NULL, 0.0);
    assert_int_equal(m.pixel_count, N);
    assert_double_equal(m.max_error, 4.0, 0);
    assert_int_equal(m.max_error_x, 10 % W);
    assert_int_equal(m.max_error_y, 10 / W);
    assert_double_equal(m.max_b, 100.0, 0);
    assert_double_equal(m.peak, 1.0, 0); /* the peak does not follow the reference */
}

static void test_mask_and(void **state)
{
    (void)state;
    uint8_t mask[4] = {1, 1, 1, 0};
    /* Two channels per pixel; the first is read. */
    const float v[8] = {0.9f, 0.0f, 0.5f, 1.0f, NAN, 1.0f, 1.0f, 1.0f};
    rb_analysis_mask_and(mask, 4, v, 2);
    assert_int_equal(mask[0], 1);
    assert_int_equal(mask[1], 0); /* 0.5 is not above the threshold */
    assert_int_equal(mask[2], 0); /* NaN excludes */
    assert_int_equal(mask[3], 0); /* stays excluded */
}

static void test_relmse_epsilon(void **state)
{
    (void)state;
    float a[N], b[N];
    fill(a, N, 0.1f);
    fill(b, N, 0.0f);
    double d2 = (double)0.1f * (double)0.1f;
    struct rb_analysis_metrics m = run(a, b, 1, NULL, 0.0);
    assert_double_equal(m.relmse, d2 / 1e-2, 1e-12); /* the default epsilon */
    m = run(a, b, 1, NULL, 1e-2);
    assert_double_equal(m.relmse, d2 / 1e-2, 1e-12);
    m = run(a, b, 1, NULL, 1.0);
    assert_double_equal(m.relmse, d2, 1e-12);
    /* A black reference: the peak is still 1. */
    assert_double_equal(m.peak, 1.0, 0);
    assert_double_equal(m.psnr, 10.0 * log10(1.0 / d2), 1e-9);
}

static void test_negative_reference_peak(void **state)
{
    (void)state;
    float a[N * 2], b[N * 2];
    fill(b, N * 2, -3.0f); /* motion vectors can be all negative */
    fill(a, N * 2, -2.0f);
    struct rb_analysis_metrics m = run(a, b, 2, NULL, 0.0);
    assert_double_equal(m.max_b, -3.0, 0);
    assert_double_equal(m.peak, 1.0, 0);
    assert_double_equal(m.psnr, 0.0, 1e-12);
}

/* PSNR's peak: 1 unless the desc gives one, whatever the reference holds; kept over frames;
 * a negative or infinite one is refused. */
static void test_peak(void **state)
{
    (void)state;
    float a[N * 3], b[N * 3];
    fill(b, N * 3, 0.5f);
    fill(a, N * 3, 0.75f);
    b[7] = 38.0f; /* an emitter's value in the reference */
    a[7] = 38.0f;
    struct rb_analysis_compare_desc d = {
        .width_px = W, .height_px = H, .channel_count = 3, .a = a, .b = b};
    struct rb_analysis_metrics m;
    struct rb_err err = RB_ERR_INIT;
    double mse = 0.0625 * (N * 3 - 1) / (N * 3);
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_OK);
    assert_double_equal(m.mse, mse, 1e-12);
    assert_double_equal(m.max_b, 38.0, 0);
    assert_double_equal(m.peak, RB_ANALYSIS_PEAK, 0);
    assert_double_equal(m.psnr, 10.0 * log10(1.0 / mse), 1e-9);
    d.peak = 38.0;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_OK);
    assert_double_equal(m.peak, 38.0, 0);
    assert_double_equal(m.psnr, 10.0 * log10(38.0 * 38.0 / mse), 1e-9);

    /* Two frames with peak 2 add up with peak 2. */
    d.peak = 2.0;
    struct rb_analysis_metrics total = {0};
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_OK);
    rb_analysis_metrics_add(&total, &m, 0);
    rb_analysis_metrics_add(&total, &m, 1);
    assert_double_equal(total.peak, 2.0, 0);
    assert_double_equal(total.psnr, 10.0 * log10(4.0 / mse), 1e-9);

    d.peak = -1.0;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "peak -1"));
    d.peak = INFINITY;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
    d.peak = NAN;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
}

static void test_nonfinite(void **state)
{
    (void)state;
    float a[N * 3], b[N * 3];
    fill(a, N * 3, 0.5f);
    fill(b, N * 3, 0.5f);
    a[3 * 3 + 2] = NAN;
    b[7 * 3] = INFINITY;
    a[9 * 3 + 1] = -INFINITY;
    struct rb_analysis_metrics m = run(a, b, 3, NULL, 0.0);
    assert_int_equal(m.nonfinite_count, 3);
    assert_int_equal(m.pixel_count, N - 3);
    assert_true(m.rmse == 0.0 && isfinite(m.relmse));
}

static void test_error_buffers(void **state)
{
    (void)state;
    float a[N * 2], b[N * 2], abs_error[N * 2], rel_error[N];
    uint8_t mask[N];
    fill(a, N * 2, 1.0f);
    fill(b, N * 2, 1.0f);
    fill(abs_error, N * 2, -1.0f);
    fill(rel_error, N, -1.0f);
    memset(mask, 1, sizeof(mask));
    a[5 * 2] = 1.5f;
    a[5 * 2 + 1] = 0.0f;
    a[6 * 2] = 9.0f;
    mask[6] = 0;
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_metrics m;
    assert_int_equal(rb_analysis_compare(&(struct rb_analysis_compare_desc){.width_px = W,
                                                                            .height_px = H,
                                                                            .channel_count = 2,
                                                                            .a = a,
                                                                            .b = b,
                                                                            .mask = mask,
                                                                            .epsilon = 1.0,
                                                                            .abs_error = abs_error,
                                                                            .rel_error = rel_error},
                                         &m, &err),
                     RB_OK);
    assert_double_equal(abs_error[5 * 2], 0.5, 1e-7);
    assert_double_equal(abs_error[5 * 2 + 1], 1.0, 1e-7);
    assert_double_equal(rel_error[5], (0.25 / 2.0 + 1.0 / 2.0) / 2.0, 1e-7);
    /* Excluded and equal pixels are 0. */
    assert_true(abs_error[6 * 2] == 0.0f && abs_error[6 * 2 + 1] == 0.0f && rel_error[6] == 0.0f);
    assert_true(abs_error[0] == 0.0f && rel_error[0] == 0.0f);
}

static void test_invalid(void **state)
{
    (void)state;
    float a[N];
    fill(a, N, 0.0f);
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_metrics m;
    struct rb_analysis_compare_desc d = {
        .width_px = W, .height_px = H, .channel_count = 5, .a = a, .b = a};
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "5 channels"));
    d.channel_count = 1;
    d.epsilon = -1.0;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
    d.epsilon = 0.0;
    d.b = NULL;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
    d.b = a;
    d.height_px = 0;
    assert_int_equal(rb_analysis_compare(&d, &m, &err), RB_E_INVALID);
}

/* Two frames accumulate to the metrics of the two side by side. */
static void test_accumulate(void **state)
{
    (void)state;
    float a0[N], b0[N], a1[N], b1[N];
    for (int i = 0; i < N; i++) {
        b0[i] = 0.1f * (float)(i % 5);
        a0[i] = b0[i] + 0.01f * (float)(i % 3);
        b1[i] = 0.2f * (float)(i % 4);
        a1[i] = b1[i] - 0.02f * (float)(i % 7);
    }
    a1[3 * W + 2] = 7.0f; /* the largest error: frame 11, pixel (2, 3) */
    a0[4] = 6.0f;
    struct rb_analysis_metrics f0 = run(a0, b0, 1, NULL, 0.0);
    struct rb_analysis_metrics f1 = run(a1, b1, 1, NULL, 0.0);
    struct rb_analysis_metrics total = {0};
    rb_analysis_metrics_add(&total, &f0, 10);
    rb_analysis_metrics_add(&total, &f1, 11);

    /* The same pixels as one image twice as tall. */
    float a[2 * N], b[2 * N];
    memcpy(a, a0, sizeof(a0));
    memcpy(a + N, a1, sizeof(a1));
    memcpy(b, b0, sizeof(b0));
    memcpy(b + N, b1, sizeof(b1));
    struct rb_analysis_metrics both;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_compare(
                         &(struct rb_analysis_compare_desc){
                             .width_px = W, .height_px = 2 * H, .channel_count = 1, .a = a, .b = b},
                         &both, &err),
                     RB_OK);
    assert_int_equal(total.pixel_count, 2 * N);
    assert_double_equal(total.rmse, both.rmse, 1e-12);
    assert_double_equal(total.relmse, both.relmse, 1e-12);
    assert_double_equal(total.mae, both.mae, 1e-12);
    assert_double_equal(total.psnr, both.psnr, 1e-9);
    assert_double_equal(total.peak, both.peak, 0);
    assert_double_equal(total.max_error, both.max_error, 0);
    assert_int_equal(total.max_error_frame, 11);
    assert_int_equal(total.max_error_x, 2);
    assert_int_equal(total.max_error_y, 3);

    /* An empty frame changes nothing; a tie keeps the earlier frame. */
    struct rb_analysis_metrics empty = {0}, before = total;
    rb_analysis_metrics_add(&total, &empty, 12);
    assert_int_equal(total.pixel_count, before.pixel_count);
    assert_true(total.sum_sq_error == before.sum_sq_error && total.rmse == before.rmse &&
                total.relmse == before.relmse && total.peak == before.peak);
    assert_int_equal(total.max_error_frame, 11);
    rb_analysis_metrics_add(&total, &f1, 13);
    assert_int_equal(total.max_error_frame, 11);
}

/* ---- edges ------------------------------------------------------------------------------ */

#define EW 12
#define EH 5

/* Prints a mask row by row when a test fails, to see which pixels went. */
static void assert_columns_excluded(const uint8_t *mask, int lo, int hi)
{
    for (int y = 0; y < EH; y++)
        for (int x = 0; x < EW; x++) {
            bool excluded = x >= lo && x <= hi;
            if (mask[y * EW + x] != !excluded)
                fail_msg("pixel (%d, %d) is %s, want columns %d..%d excluded", x, y,
                         mask[y * EW + x] ? "included" : "excluded", lo, hi);
        }
}

static void test_edges_depth_step(void **state)
{
    (void)state;
    float depth[EW * EH];
    uint8_t mask[EW * EH];
    struct rb_err err = RB_ERR_INIT;
    /* Depth 2 left of x = 6, 3 from there on: one discontinuity between columns 5 and 6. A
     * gentle 1% slope inside each side is not an edge. */
    for (int y = 0; y < EH; y++)
        for (int x = 0; x < EW; x++)
            depth[y * EW + x] = (x < 6 ? 2.0f : 3.0f) * (1.0f + 0.01f * (float)x);
    struct rb_analysis_edge_desc d = {.width_px = EW, .height_px = EH, .depth = depth};

    memset(mask, 1, sizeof(mask));
    d.radius_px = 0;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    assert_columns_excluded(mask, 100, 100); /* radius 0: nothing */

    d.radius_px = 1;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    assert_columns_excluded(mask, 5, 6);

    memset(mask, 1, sizeof(mask));
    d.radius_px = 3;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    assert_columns_excluded(mask, 3, 8);

    /* 5% is of the larger depth (symmetric in p and q): 1 to 1.0515 is not an edge, 1 to 1.06
     * is. */
    for (int i = 0; i < EW * EH; i++)
        depth[i] = (i % EW) < 6 ? 1.0f : 1.0515f;
    memset(mask, 1, sizeof(mask));
    d.radius_px = 1;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    assert_columns_excluded(mask, 100, 100);
    for (int i = 0; i < EW * EH; i++)
        depth[i] = (i % EW) < 6 ? 1.0f : 1.06f;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    assert_columns_excluded(mask, 5, 6);
}

static void test_edges_background_and_alpha(void **state)
{
    (void)state;
    /* Interleaved depth and alpha (stride 2): geometry at depth 4 in a box, background 0. */
    float px[EW * EH * 2];
    uint8_t mask[EW * EH];
    struct rb_err err = RB_ERR_INIT;
    for (int y = 0; y < EH; y++)
        for (int x = 0; x < EW; x++) {
            bool inside = x >= 4 && x <= 7 && y >= 1 && y <= 3;
            px[(y * EW + x) * 2] = inside ? 4.0f : 0.0f;
            px[(y * EW + x) * 2 + 1] = 1.0f;
        }
    memset(mask, 1, sizeof(mask));
    struct rb_analysis_edge_desc d = {.width_px = EW,
                                      .height_px = EH,
                                      .depth = px,
                                      .depth_stride = 2,
                                      .alpha = px + 1,
                                      .alpha_stride = 2,
                                      .radius_px = 1};
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    int excluded = 0;
    for (int i = 0; i < EW * EH; i++)
        excluded += !mask[i];
    /* The box's border (4x3 minus its 2x1 core) and the 4-neighbours outside it. */
    assert_int_equal(excluded, (12 - 2) + (2 * 4 + 2 * 3));
    assert_int_equal(mask[2 * EW + 5], 1); /* inside, away from the edge */
    assert_int_equal(mask[1 * EW + 4], 0); /* the box's corner */
    assert_int_equal(mask[0 * EW + 3], 1); /* diagonal neighbour outside: not a 4-neighbour */
    assert_int_equal(mask[0 * EW + 4], 0);

    /* Flat depth, an alpha step between rows 1 and 2. */
    for (int i = 0; i < EW * EH; i++) {
        px[i * 2] = 1.0f;
        px[i * 2 + 1] = i / EW >= 2 ? 1.0f : 0.5f;
    }
    memset(mask, 1, sizeof(mask));
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    for (int i = 0; i < EW * EH; i++)
        assert_int_equal(mask[i], i / EW == 1 || i / EW == 2 ? 0 : 1);
    /* Without alpha, no edge. */
    memset(mask, 1, sizeof(mask));
    d.alpha = NULL;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    for (int i = 0; i < EW * EH; i++)
        assert_int_equal(mask[i], 1);
}

/* A large radius covers the whole image without reading past it. */
static void test_edges_large_radius(void **state)
{
    (void)state;
    float depth[EW * EH];
    uint8_t mask[EW * EH];
    struct rb_err err = RB_ERR_INIT;
    for (int i = 0; i < EW * EH; i++)
        depth[i] = i == 0 ? 9.0f : 1.0f;
    memset(mask, 1, sizeof(mask));
    struct rb_analysis_edge_desc d = {
        .width_px = EW, .height_px = EH, .depth = depth, .radius_px = 1000};
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_OK);
    for (int i = 0; i < EW * EH; i++)
        assert_int_equal(mask[i], 0);
    d.depth = NULL;
    assert_int_equal(rb_analysis_exclude_edges(&d, mask, &err), RB_E_INVALID);
}

/* ---- layers ----------------------------------------------------------------------------- */

static void test_layer_resolve(void **state)
{
    (void)state;
    struct rb_analysis_layer l;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_layer_resolve(NULL, &l, &err), RB_OK);
    assert_string_equal(l.name, "beauty");
    assert_int_equal(l.channel_count, 3);
    assert_string_equal(l.channels[0], "R");
    assert_string_equal(l.channels[2], "B");
    assert_int_equal(rb_analysis_layer_resolve("direct", &l, &err), RB_OK);
    assert_int_equal(l.channel_count, 3);
    assert_string_equal(l.channels[1], "direct.G");
    assert_int_equal(rb_analysis_layer_resolve("normal", &l, &err), RB_OK);
    assert_string_equal(l.channels[2], "normal.Z");
    assert_int_equal(rb_analysis_layer_resolve("depth", &l, &err), RB_OK);
    assert_int_equal(l.channel_count, 1);
    assert_string_equal(l.channels[0], "depth.Z");
    assert_int_equal(rb_analysis_layer_resolve("motion", &l, &err), RB_OK);
    assert_int_equal(l.channel_count, 2);
    assert_string_equal(l.channels[1], "motion.Y");
    /* the hybrid's counts: a channel a lobe, named as the renderer writes them */
    assert_int_equal(rb_analysis_layer_resolve("samples", &l, &err), RB_OK);
    assert_int_equal(l.channel_count, 2);
    assert_string_equal(l.channels[0], "samples.diffuse");
    assert_string_equal(l.channels[1], "samples.specular");
    assert_int_equal(rb_analysis_layer_resolve("tiles", &l, &err), RB_OK);
    assert_string_equal(l.channels[1], "tiles.specular");
    /* a name the renderer does not write is read as RGB */
    assert_int_equal(rb_analysis_layer_resolve("hits", &l, &err), RB_OK);
    assert_int_equal(l.channel_count, 3);
    assert_string_equal(l.channels[0], "hits.R");
    assert_int_equal(rb_analysis_layer_resolve("direct.R", &l, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "'direct.R'"));
    /* the renderer's layers in any case, spelt as it writes them; others as asked */
    assert_int_equal(rb_analysis_layer_resolve("Normal", &l, &err), RB_OK);
    assert_string_equal(l.name, "normal");
    assert_int_equal(l.channel_count, 3);
    assert_string_equal(l.channels[0], "normal.X");
    assert_int_equal(rb_analysis_layer_resolve("DEPTH", &l, &err), RB_OK);
    assert_string_equal(l.channels[0], "depth.Z");
    assert_int_equal(rb_analysis_layer_resolve("Beauty", &l, &err), RB_OK);
    assert_string_equal(l.name, "beauty");
    assert_string_equal(l.channels[0], "R");
    assert_int_equal(rb_analysis_layer_resolve("Hits", &l, &err), RB_OK);
    assert_string_equal(l.channels[0], "Hits.R");
}

static void test_layer_extract(void **state)
{
    (void)state;
    char *names[] = {"R", "G", "B", "A", "depth.Z"};
    float px[2 * 5] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    struct rb_io_image img = {
        .width_px = 2, .height_px = 1, .channel_count = 5, .channel_names = names, .pixels = px};
    struct rb_analysis_layer l;
    struct rb_err err = RB_ERR_INIT;
    float *out = NULL;

    assert_int_equal(rb_analysis_layer_resolve("depth", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_OK);
    assert_true(out[0] == 5.0f && out[1] == 10.0f);
    free(out);
    out = NULL;
    assert_int_equal(rb_analysis_layer_resolve("beauty", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_OK);
    assert_true(out[0] == 1.0f && out[2] == 3.0f && out[3] == 6.0f && out[5] == 8.0f);
    free(out);
    out = NULL;
    assert_int_equal(rb_analysis_layer_resolve("albedo", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_E_INVALID);
    assert_null(out);
    /* A missing layer is named with the layers the file has. */
    assert_string_equal(err.msg, "'x.exr' has no layer 'albedo'; its layers: beauty, depth");
}

/* A layer's name matches the file's whatever the case (the exact name first); a layer that is
 * there in part is named with its missing channel. */
static void test_layer_extract_case(void **state)
{
    (void)state;
    char *names[] = {"R",        "Diffuse.R", "Diffuse.G", "Diffuse.B",
                     "NORMAL.X", "normal.X",  "motion.X",  "Custom.b"};
    float px[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    struct rb_io_image img = {
        .width_px = 1, .height_px = 1, .channel_count = 8, .channel_names = names, .pixels = px};
    struct rb_analysis_layer l;
    struct rb_err err = RB_ERR_INIT;
    float *out = NULL;

    assert_int_equal(rb_analysis_layer_resolve("diffuse", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_OK);
    assert_true(out[0] == 2.0f && out[1] == 3.0f && out[2] == 4.0f);
    free(out);
    out = NULL;
    /* "normal.X" is there as it is spelt: it wins over "NORMAL.X"; Y and Z are not there. */
    assert_int_equal(rb_analysis_layer_resolve("Normal", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_E_INVALID);
    assert_null(out);
    assert_string_equal(err.msg, "'x.exr' has no layer 'normal': channel 'normal.Y' is missing "
                                 "(the layer is normal.X, normal.Y, normal.Z)");
    /* The channel's own name is not matched without case: "Custom.b" is not "custom.B". */
    assert_int_equal(rb_analysis_layer_resolve("custom", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "'x.exr' has no layer 'custom': channel 'custom.R' is missing "
                                 "(the layer is custom.R, custom.G, custom.B)");
    /* The layers are listed as the file spells them: the beauty, raybundle's in their order,
     * then the others in the order of the channels. */
    assert_int_equal(rb_analysis_layer_resolve("foo", &l, &err), RB_OK);
    assert_int_equal(rb_analysis_layer_extract(&l, &img, "x.exr", &out, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "'x.exr' has no layer 'foo'; its layers: beauty, normal, "
                                 "motion, Diffuse, NORMAL, Custom");
}

/* ---- error image ------------------------------------------------------------------------ */

static void test_error_image(void **state)
{
    (void)state;
    float abs_error[N], rel_error[N];
    for (int i = 0; i < N; i++) {
        abs_error[i] = 0.5f * (float)i;
        rel_error[i] = 0.25f * (float)i;
    }
    char path[1024];
    snprintf(path, sizeof(path), "%s/err.exr", tmpdir);
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_error_write(path, W, H, 1, abs_error, rel_error, &err), RB_OK);

    struct rb_io_image img = {0};
    assert_int_equal(rb_io_image_read(path, &img, &err), RB_OK);
    assert_int_equal(img.width_px, W);
    assert_int_equal(img.height_px, H);
    assert_int_equal(img.channel_count, 4);
    int r = rb_io_image_channel(&img, "R"), g = rb_io_image_channel(&img, "G");
    int b = rb_io_image_channel(&img, "B"), y = rb_io_image_channel(&img, "relmse.Y");
    assert_true(r >= 0 && g >= 0 && b >= 0 && y >= 0);
    for (int i = 0; i < N; i++) {
        const float *p = img.pixels + (size_t)i * img.channel_count;
        assert_true(p[r] == abs_error[i] && p[g] == abs_error[i] && p[b] == abs_error[i]);
        assert_true(p[y] == rel_error[i]);
    }
    rb_io_image_release(&img);
    /* No temporary file is left beside it. */
    char tmp[1100];
    snprintf(tmp, sizeof(tmp), "%s/err.exr.tmp.%d", tmpdir, (int)getpid());
    assert_int_not_equal(access(tmp, F_OK), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_identical),
        cmocka_unit_test(test_constant_offset),
        cmocka_unit_test(test_outlier),
        cmocka_unit_test(test_mask),
        cmocka_unit_test(test_mask_and),
        cmocka_unit_test(test_relmse_epsilon),
        cmocka_unit_test(test_negative_reference_peak),
        cmocka_unit_test(test_peak),
        cmocka_unit_test(test_nonfinite),
        cmocka_unit_test(test_error_buffers),
        cmocka_unit_test(test_invalid),
        cmocka_unit_test(test_accumulate),
        cmocka_unit_test(test_edges_depth_step),
        cmocka_unit_test(test_edges_background_and_alpha),
        cmocka_unit_test(test_edges_large_radius),
        cmocka_unit_test(test_layer_resolve),
        cmocka_unit_test(test_layer_extract),
        cmocka_unit_test(test_layer_extract_case),
        cmocka_unit_test(test_error_image),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
