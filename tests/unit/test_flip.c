/* lib/analysis/flip.c: LDR- and HDR-FLIP against the figures NVIDIA's reference tool gives for
 * the image pairs in $RB_SHARED/flip (default ../shared; skipped when absent), and on synthetic
 * images whose answers follow from the definition: identical images, one changed pixel (error
 * only within the filters' reach), symmetry, the pooled percentiles, the exposure range. */
#include "analysis/flip.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "testutil.h"

/* The figures must agree within this fraction of the expected value. */
#define REL_TOL 0.01

static float *image_new(uint32_t w, uint32_t h, float v)
{
    float *p = malloc((size_t)w * h * 3 * sizeof(float));
    assert_non_null(p);
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        p[i] = v;
    return p;
}

/* ---- the shared pairs ------------------------------------------------------------------- */

/* $RB_SHARED/flip (default ../shared/flip) into buf; 0 when its expected.tsv is readable. */
static int shared_dir(char *buf, size_t size)
{
    const char *dir = getenv("RB_SHARED");
    snprintf(buf, size, "%s/flip", dir && *dir ? dir : "../shared");
    char tsv[4200];
    snprintf(tsv, sizeof(tsv), "%s/expected.tsv", buf);
    return access(tsv, R_OK) == 0 ? 0 : -1;
}

/* Reads dir/name's R, G, B channels interleaved into a new array. */
static float *read_rgb(const char *dir, const char *name, uint32_t *w, uint32_t *h)
{
    char path[4400];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(path, &img, &err))
        fail_msg("%s", err.msg);
    int ch[3] = {rb_io_image_channel(&img, "R"), rb_io_image_channel(&img, "G"),
                 rb_io_image_channel(&img, "B")};
    if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0)
        fail_msg("%s: no R, G, B channels", path);
    size_t n = (size_t)img.width_px * img.height_px;
    float *rgb = malloc(n * 3 * sizeof(float));
    assert_non_null(rgb);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = img.pixels[i * img.channel_count + (size_t)ch[c]];
    *w = img.width_px;
    *h = img.height_px;
    rb_io_image_release(&img);
    return rgb;
}

static bool near_rel(double got, double want)
{
    return fabs(got - want) <= REL_TOL * fabs(want);
}

/* Runs every row of expected.tsv of kind ("ldr" or "hdr"), prints the measured figures beside
 * the expected ones, and fails after the last row if any figure is off. */
static void check_reference_rows(const char *kind)
{
    char dir[4096];
    if (shared_dir(dir, sizeof(dir))) {
        print_message("# skipped: %s/expected.tsv is absent (set RB_SHARED)\n", dir);
        skip(); /* a checkout without the shared test images */
    }
    char tsv[4200];
    snprintf(tsv, sizeof(tsv), "%s/expected.tsv", dir);
    FILE *f = fopen(tsv, "r");
    assert_non_null(f);
    char line[1024];
    int rows = 0, bad = 0;
    while (fgets(line, sizeof(line), f)) {
        char ref[256], test[256], k[16], start_s[32], stop_s[32], count_s[32];
        double want[5];
        if (sscanf(line,
                   "%255[^\t]\t%255[^\t]\t%15[^\t]\t%lf\t%lf\t%lf\t%lf\t%lf\t%31[^\t]\t%31["
                   "^\t]\t%31s",
                   ref, test, k, &want[0], &want[1], &want[2], &want[3], &want[4], start_s, stop_s,
                   count_s) != 11 ||
            strcmp(k, kind))
            continue; /* the header, or the other kind */
        uint32_t rw, rh, tw, th;
        float *r = read_rgb(dir, ref, &rw, &rh);
        float *t = read_rgb(dir, test, &tw, &th);
        assert_true(rw == tw && rh == th);
        struct rb_analysis_flip_stats s;
        struct rb_analysis_flip_exposures e = {0};
        struct rb_err err = RB_ERR_INIT;
        enum rb_status st = !strcmp(kind, "hdr")
                                ? rb_analysis_flip_hdr(t, r, rw, rh, NULL, NULL, &s, &e, &err)
                                : rb_analysis_flip_ldr(t, r, rw, rh, NULL, NULL, &s, &err);
        if (st)
            fail_msg("%s vs %s: %s", test, ref, err.msg);
        const double got[5] = {s.mean, s.weighted_median, s.weighted_q1, s.weighted_q3, s.max};
        static const char *const names[5] = {"mean", "weighted median", "q1", "q3", "max"};
        print_message("# %s vs %s (%s):\n", test, ref, kind);
        for (int i = 0; i < 5; i++) {
            bool ok = near_rel(got[i], want[i]);
            bad += !ok;
            print_message("#   %-16s %.6f, expected %.6f (%+.3f%%)%s\n", names[i], got[i], want[i],
                          100.0 * (got[i] - want[i]) / want[i], ok ? "" : "  OFF");
        }
        if (!strcmp(kind, "hdr")) {
            double start = atof(start_s), stop = atof(stop_s);
            unsigned count = (unsigned)atoi(count_s);
            /* The table gives four decimals. */
            bool ok =
                fabs(e.start - start) <= 5e-4 && fabs(e.stop - stop) <= 5e-4 && e.count == count;
            bad += !ok;
            print_message("#   exposures        %.4f to %.4f, %u; expected %.4f to %.4f, %u%s\n",
                          e.start, e.stop, e.count, start, stop, count, ok ? "" : "  OFF");
        }
        free(r);
        free(t);
        rows++;
    }
    fclose(f);
    if (!rows)
        fail_msg("%s has no %s rows", tsv, kind);
    if (bad)
        fail_msg("%d figure(s) differ from the reference tool's by more than %g%%", bad,
                 100.0 * REL_TOL);
}

static void test_expected_ldr(void **state)
{
    (void)state;
    check_reference_rows("ldr");
}

static void test_expected_hdr(void **state)
{
    (void)state;
    check_reference_rows("hdr");
}

/* ---- synthetic images ------------------------------------------------------------------- */

#define W 48
#define H 40

/* A smooth colour gradient with a few steps, in [0,1] (sRGB-encoded for LDR). */
static float *pattern(float scale)
{
    float *p = image_new(W, H, 0.0f);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            float *c = p + 3 * ((size_t)y * W + x);
            c[0] = scale * (0.1f + 0.8f * (float)x / W);
            c[1] = scale * (0.2f + 0.6f * (float)y / H);
            c[2] = scale * (x > W / 2 ? 0.7f : 0.3f);
        }
    return p;
}

static void test_identical(void **state)
{
    (void)state;
    float *a = pattern(1.0f), *b = pattern(1.0f);
    float *map = image_new(W, H, -1.0f);
    struct rb_analysis_flip_stats s;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_ldr(a, b, W, H, NULL, map, &s, &err), RB_OK);
    for (size_t i = 0; i < (size_t)W * H; i++)
        assert_true(map[i] == 0.0f);
    assert_true(s.mean == 0.0 && s.max == 0.0 && s.min == 0.0);
    assert_true(s.weighted_median == 0.0 && s.weighted_q1 == 0.0 && s.weighted_q3 == 0.0);

    /* HDR: scene-linear values above 1 too. */
    free(a);
    free(b);
    a = pattern(6.0f);
    b = pattern(6.0f);
    struct rb_analysis_flip_exposures e;
    assert_int_equal(rb_analysis_flip_hdr(a, b, W, H, NULL, map, &s, &e, &err), RB_OK);
    for (size_t i = 0; i < (size_t)W * H; i++)
        assert_true(map[i] == 0.0f);
    assert_true(s.max == 0.0 && s.weighted_median == 0.0);
    assert_true(e.count >= 2);
    free(a);
    free(b);
    free(map);
}

/* The colour error reaches as far as the CSF filters, the feature error as far as the
 * Gaussian derivatives; at the default 67 PPD those radii are 10 and 9 pixels. */
static void test_one_pixel(void **state)
{
    (void)state;
    const uint32_t px = 30, py = 17;
    const long reach = 10;
    float *ref = image_new(W, H, 0.5f), *test = image_new(W, H, 0.5f);
    float *map = image_new(W, H, -1.0f);
    float *c = test + 3 * ((size_t)py * W + px);
    c[0] = 1.0f;
    c[1] = 0.1f;
    struct rb_analysis_flip_stats s;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_ldr(test, ref, W, H, NULL, map, &s, &err), RB_OK);
    size_t nonzero = 0;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            float v = map[(size_t)y * W + x];
            long dx = labs((long)x - (long)px), dy = labs((long)y - (long)py);
            assert_true(v >= 0.0f && v <= 1.0f);
            if (dx > reach || dy > reach) {
                if (v != 0.0f)
                    fail_msg("error %g at (%u, %u), beyond the filters' reach", (double)v, x, y);
            } else {
                nonzero += v > 0.0f;
            }
        }
    assert_true(nonzero > 0);
    assert_true(map[(size_t)py * W + px] > 0.0f);
    /* The largest error is at the changed pixel. */
    assert_int_equal(s.max_x, px);
    assert_int_equal(s.max_y, py);
    free(ref);
    free(test);
    free(map);
}

/* Both the colour error (HyAB) and the feature error (|edge_ref - edge_test|, likewise points)
 * treat the two images alike: LDR-FLIP(a, b) == LDR-FLIP(b, a), to the bit. */
static void test_symmetric(void **state)
{
    (void)state;
    float *a = pattern(1.0f), *b = pattern(0.8f);
    b[3 * (5 * W + 7)] = 0.0f;
    float *ab = image_new(W, H, 0.0f), *ba = image_new(W, H, 0.0f);
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_ldr(a, b, W, H, NULL, ab, NULL, &err), RB_OK);
    assert_int_equal(rb_analysis_flip_ldr(b, a, W, H, NULL, ba, NULL, &err), RB_OK);
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        assert_true(ab[i] == ba[i]);
        sum += ab[i];
    }
    assert_true(sum > 0.0);

    /* Mirroring both images mirrors the error map (the filters are even, the edges clamped),
     * up to the order the taps are summed in. */
    float *ma = image_new(W, H, 0.0f), *mb = image_new(W, H, 0.0f), *mab = image_new(W, H, 0.0f);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++)
            for (int c = 0; c < 3; c++) {
                size_t from = 3 * ((size_t)y * W + x) + (size_t)c;
                size_t to = 3 * ((size_t)y * W + (W - 1 - x)) + (size_t)c;
                ma[to] = a[from];
                mb[to] = b[from];
            }
    assert_int_equal(rb_analysis_flip_ldr(ma, mb, W, H, NULL, mab, NULL, &err), RB_OK);
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++)
            assert_double_equal(mab[(size_t)y * W + (W - 1 - x)], ab[(size_t)y * W + x], 1e-5);
    free(a);
    free(b);
    free(ab);
    free(ba);
    free(ma);
    free(mb);
    free(mab);
}

/* The reference tool's weighted percentiles: values sorted ascending, the first whose running
 * sum exceeds the fraction of the total. 0.1 + 0.2 + 0.3 + 0.4 = 1: the running sums are
 * 0.1, 0.3, 0.6 and 1, so q1 is 0.2, the median 0.3 and q3 0.4. */
static void test_pool(void **state)
{
    (void)state;
    const float map[6] = {0.3f, 0.1f, 0.0f, 0.4f, 0.2f, 0.0f};
    struct rb_analysis_flip_stats s;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_pool(map, 3, 2, &s, &err), RB_OK);
    assert_double_equal(s.mean, 1.0 / 6.0, 1e-7);
    assert_double_equal(s.weighted_q1, 0.2, 1e-7);
    assert_double_equal(s.weighted_median, 0.3, 1e-7);
    assert_double_equal(s.weighted_q3, 0.4, 1e-7);
    assert_double_equal(s.min, 0.0, 0.0);
    assert_double_equal(s.max, 0.4, 1e-7);
    assert_int_equal(s.max_x, 0);
    assert_int_equal(s.max_y, 1);

    const float bad[2] = {0.5f, -0.25f};
    assert_int_equal(rb_analysis_flip_pool(bad, 2, 1, &s, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "(1, 0)"));
}

/* Where the ACES fit (applied to 0.6 x) reaches 0.85, by bisection in double. */
static double aces_x85(void)
{
    double lo = 0.0, hi = 100.0;
    for (int i = 0; i < 200; i++) {
        double m = 0.5 * (lo + hi), x = 0.6 * m;
        double y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
        if (y < 0.85)
            lo = m;
        else
            hi = m;
    }
    return 0.5 * (lo + hi);
}

/* Grey pixels, so the luminance is the value: largest 4, median (the upper middle of 8) 0.3. */
static void test_exposures(void **state)
{
    (void)state;
    const float v[8] = {0.01f, 0.1f, 0.2f, 0.2f, 0.3f, 1.0f, 2.0f, 4.0f};
    float *ref = image_new(4, 2, 0.0f);
    for (int i = 0; i < 8; i++)
        ref[3 * i] = ref[3 * i + 1] = ref[3 * i + 2] = v[7 - i];
    struct rb_analysis_flip_exposures e;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_exposures_compute(ref, 4, 2, 0, &e, &err), RB_OK);
    double x85 = aces_x85();
    assert_double_equal(e.start, log2(x85 / 4.0), 1e-4);
    assert_double_equal(e.stop, log2(x85 / 0.3), 1e-4);
    assert_int_equal(e.count, 4);

    /* HDR-FLIP reports the range it used, and takes one given in the desc. */
    float *test = image_new(4, 2, 0.3f);
    struct rb_analysis_flip_exposures used;
    assert_int_equal(rb_analysis_flip_hdr(test, ref, 4, 2, NULL, NULL, NULL, &used, &err), RB_OK);
    assert_true(used.start == e.start && used.stop == e.stop && used.count == e.count);
    struct rb_analysis_flip_desc d = {.has_start_exposure = true,
                                      .start_exposure = -1.0,
                                      .has_stop_exposure = true,
                                      .stop_exposure = 2.0,
                                      .exposure_count = 7};
    assert_int_equal(rb_analysis_flip_hdr(test, ref, 4, 2, &d, NULL, NULL, &used, &err), RB_OK);
    assert_true(used.start == -1.0 && used.stop == 2.0 && used.count == 7);

    /* A black reference leaves nothing to choose the exposures from. */
    float *black = image_new(4, 2, 0.0f);
    assert_int_equal(rb_analysis_flip_hdr(test, black, 4, 2, NULL, NULL, NULL, NULL, &err),
                     RB_E_INVALID);
    d.start_exposure = 3.0;
    assert_int_equal(rb_analysis_flip_hdr(test, ref, 4, 2, &d, NULL, NULL, NULL, &err),
                     RB_E_INVALID);
    free(ref);
    free(test);
    free(black);
}

static void test_invalid(void **state)
{
    (void)state;
    float *a = image_new(4, 3, 0.5f), *b = image_new(4, 3, 0.5f);
    struct rb_analysis_flip_stats s;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_ldr(a, b, 0, 3, NULL, NULL, &s, &err), RB_E_INVALID);
    assert_int_equal(rb_analysis_flip_ldr(NULL, b, 4, 3, NULL, NULL, &s, &err), RB_E_INVALID);
    b[3 * (2 * 4 + 1) + 2] = NAN;
    assert_int_equal(rb_analysis_flip_ldr(a, b, 4, 3, NULL, NULL, &s, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "reference image pixel (1, 2) channel 2"));
    b[3 * (2 * 4 + 1) + 2] = 0.5f;
    assert_int_equal(rb_analysis_flip_ldr(a, b, 4, 3,
                                          &(struct rb_analysis_flip_desc){.pixels_per_degree = -1},
                                          NULL, &s, &err),
                     RB_E_INVALID);
    /* Tiny images are fine: the filters clamp at the edges. */
    assert_int_equal(rb_analysis_flip_ldr(a, b, 1, 1, NULL, NULL, &s, &err), RB_OK);
    free(a);
    free(b);
}

static void test_defaults(void **state)
{
    (void)state;
    struct rb_analysis_flip_desc d = rb_analysis_flip_desc_resolve(NULL);
    /* 0.7 * 3840 / 0.7 * pi / 180 */
    assert_double_equal(d.pixels_per_degree, 67.0206432, 1e-4);
    assert_int_equal(d.tonemapper, RB_ANALYSIS_FLIP_TONEMAPPER_ACES);
    assert_false(d.has_start_exposure || d.has_stop_exposure);
}

/* The colour map: magma's ends, its nearest entry, and what lies outside [0, 1]. */
static void test_color(void **state)
{
    (void)state;
    uint8_t c[3];
    rb_analysis_flip_color(0.0f, c);
    assert_true(c[0] == 0 && c[1] == 0 && c[2] == 4);
    rb_analysis_flip_color(1.0f, c);
    assert_true(c[0] == 252 && c[1] == 253 && c[2] == 191);
    rb_analysis_flip_color(0.5f, c); /* entry 128 */
    assert_true(c[0] == 183 && c[1] == 55 && c[2] == 121);
    rb_analysis_flip_color(-1.0f, c);
    assert_true(c[0] == 0 && c[1] == 0 && c[2] == 4);
    rb_analysis_flip_color(NAN, c);
    assert_true(c[0] == 0 && c[1] == 0 && c[2] == 4);
    rb_analysis_flip_color(2.0f, c);
    assert_true(c[0] == 252 && c[1] == 253 && c[2] == 191);
    /* Brighter (in luma) as the error grows, step by step of an eighth. */
    int prev = -1;
    for (int i = 0; i <= 8; i++) {
        rb_analysis_flip_color((float)i / 8.0f, c);
        int luma = 2126 * c[0] + 7152 * c[1] + 722 * c[2];
        assert_true(luma > prev);
        prev = luma;
    }
}

/* Images wider than one strip and not a multiple of the filters' blocks wide: the map of the
 * mirrored images is the map mirrored, FLIP's filters being symmetric (to rounding, the sums
 * running in another order), so no strip or block edge shows. */
static void test_mirror(void **state)
{
    (void)state;
    enum { MW = 301, MH = 23 };
    float *a = malloc(MW * MH * 3 * sizeof(float)), *b = malloc(MW * MH * 3 * sizeof(float));
    float *ma = malloc(MW * MH * 3 * sizeof(float)), *mb = malloc(MW * MH * 3 * sizeof(float));
    float *map = malloc(MW * MH * sizeof(float)), *mmap = malloc(MW * MH * sizeof(float));
    assert_non_null(a && b && ma && mb && map && mmap);
    for (int y = 0; y < MH; y++)
        for (int x = 0; x < MW; x++)
            for (int c = 0; c < 3; c++) {
                size_t i = ((size_t)y * MW + (size_t)x) * 3 + (size_t)c;
                size_t m = ((size_t)y * MW + (size_t)(MW - 1 - x)) * 3 + (size_t)c;
                a[i] = ma[m] = 0.5f + 0.4f * sinf(0.05f * (float)(x * (c + 1) + 3 * y));
                b[i] = mb[m] = 0.5f + 0.4f * sinf(0.05f * (float)(x * (c + 1) + 3 * y) + 0.3f);
            }
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_analysis_flip_hdr(a, b, MW, MH, NULL, map, NULL, NULL, &err), RB_OK);
    assert_int_equal(rb_analysis_flip_hdr(ma, mb, MW, MH, NULL, mmap, NULL, NULL, &err), RB_OK);
    double sum = 0.0;
    for (int y = 0; y < MH; y++)
        for (int x = 0; x < MW; x++) {
            float v = map[(size_t)y * MW + (size_t)x];
            assert_float_equal(v, mmap[(size_t)y * MW + (size_t)(MW - 1 - x)], 1e-5f);
            sum += v;
        }
    assert_true(sum > 0.0);
    free(a);
    free(b);
    free(ma);
    free(mb);
    free(map);
    free(mmap);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),     cmocka_unit_test(test_identical),
        cmocka_unit_test(test_one_pixel),    cmocka_unit_test(test_symmetric),
        cmocka_unit_test(test_pool),         cmocka_unit_test(test_exposures),
        cmocka_unit_test(test_invalid),      cmocka_unit_test(test_expected_ldr),
        cmocka_unit_test(test_expected_hdr), cmocka_unit_test(test_color),
        cmocka_unit_test(test_mirror),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
