/* lib/analysis report: the value axis against its rule over many magnitudes, the plot's
 * geometry, finding a sequence's frames among other files, and a report of small sequences
 * written here (constant EXRs, timing sidecars, hit-ratio images) whose numbers have closed forms:
 * relMSE, the frame-to-frame RMSE, the passes in order of appearance, gaps, and every mismatch
 * refused with the file named; then the page: no script, its sections, a bar where the layout
 * puts it. Files go under one mkdtemp directory. */
#include "analysis/analysis.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "testutil.h"

#define W 8
#define H 4
#define CONFIG "share/ocio/config.ocio"

static char tmpdir[512];

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "report");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

/* ---- the axis and the plot ---------------------------------------------------------------- */

static void test_axis(void **state)
{
    (void)state;
    const struct {
        double data, max, step;
    } cases[] = {
        {45.2, 50, 10}, {100, 100, 20}, {0.37, 0.4, 0.1},   {1, 1, 0.2},
        {7, 8, 2},      {86, 100, 20},  {3e-5, 3e-5, 1e-5},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        struct rb_analysis_axis a = rb_analysis_axis_fit(cases[i].data);
        assert_double_equal(a.max, cases[i].max, 1e-12 * cases[i].max);
        assert_double_equal(a.step, cases[i].step, 1e-12 * cases[i].step);
    }
    const double none[] = {0.0, -1.0, NAN, INFINITY};
    for (size_t i = 0; i < sizeof(none) / sizeof(none[0]); i++) {
        struct rb_analysis_axis a = rb_analysis_axis_fit(none[i]);
        assert_double_equal(a.max, 1.0, 0.0);
        assert_double_equal(a.step, 0.2, 0.0);
    }
    /* The rule, over 13 decades: the top covers the data (to rounding) and one step less does
     * not; at most 5 steps; the step is 1, 2 or 5 times a power of ten. */
    for (double v = 1.234e-6; v < 1e7; v *= 1.37) {
        struct rb_analysis_axis a = rb_analysis_axis_fit(v);
        double steps = a.max / a.step, mant = a.step / pow(10.0, floor(log10(a.step) + 1e-9));
        if (!(a.max >= v * (1 - 1e-9) && a.max - a.step < v && steps <= 5.0 + 1e-9 &&
              (fabs(mant - 1) < 1e-9 || fabs(mant - 2) < 1e-9 || fabs(mant - 5) < 1e-9)))
            fail_msg("axis of %.17g: max %.17g, step %.17g", v, a.max, a.step);
    }
}

static void test_plot(void **state)
{
    (void)state;
    struct rb_analysis_plot p = {.x_px = 72,
                                 .y_px = 202,
                                 .width_px = 640,
                                 .height_px = 176,
                                 .slot_count = 4,
                                 .axis = {.max = 50, .step = 10}};
    assert_double_equal(rb_analysis_plot_x(&p, 0), 152.0, 1e-12);
    assert_double_equal(rb_analysis_plot_x(&p, 3), 632.0, 1e-12);
    assert_double_equal(rb_analysis_plot_y(&p, 0), 378.0, 1e-12);
    assert_double_equal(rb_analysis_plot_y(&p, 50), 202.0, 1e-12);
    assert_double_equal(rb_analysis_plot_y(&p, 25), 290.0, 1e-12);
    assert_double_equal(rb_analysis_plot_bar_width(&p), 112.0, 1e-12);
    p.slot_count = 1000;
    assert_double_equal(rb_analysis_plot_bar_width(&p), 1.0, 0.0);
}

/* The filmstrip's frames against the rule computed in double: every frame up to max_count,
 * otherwise max_count distinct ascending indices, the first and the last among them, each the
 * nearest to its k (n - 1) / (max - 1) (ties, which the integers round up, at most half off). */
static void test_filmstrip_pick(void **state)
{
    (void)state;
    size_t out[64];
    assert_int_equal(rb_analysis_filmstrip_pick(0, 24, out), 0);
    assert_int_equal(rb_analysis_filmstrip_pick(1, 2, out), 1);
    assert_int_equal(out[0], 0);
    assert_int_equal(rb_analysis_filmstrip_pick(6, 3, out), 3);
    assert_int_equal(out[0], 0);
    assert_int_equal(out[1], 3); /* 2.5, rounded up */
    assert_int_equal(out[2], 5);
    for (size_t n = 1; n <= 200; n++) {
        for (size_t max = 2; max <= 64; max++) {
            size_t count = rb_analysis_filmstrip_pick(n, max, out);
            assert_int_equal(count, n < max ? n : max);
            assert_int_equal(out[0], 0);
            assert_int_equal(out[count - 1], n - 1);
            for (size_t k = 0; k < count; k++) {
                if (k > 0)
                    assert_true(out[k] > out[k - 1]);
                double want = n <= max ? (double)k : (double)k * (n - 1) / (double)(max - 1);
                assert_true(fabs((double)out[k] - want) <= 0.5 + 1e-9);
            }
        }
    }
}

/* ---- sequences ---------------------------------------------------------------------------- */

static const char *tpath(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static const char *tpath(const char *fmt, ...)
{
    static char buf[4][1024];
    static int k;
    char rel[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(rel, sizeof(rel), fmt, ap);
    va_end(ap);
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof(buf[k]), "%s/%s", tmpdir, rel);
    return buf[k];
}

static void touch(const char *path)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fclose(f);
}

static void test_scan(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_sequence s;
    mkdir(tpath("scan"), 0777);
    const char *names[] = {
        "frame.0002.exr",      "frame.0000.exr", "frame.0010.exr", "frame.0001.timing.json",
        "frame.0002.hits.exr", "frame.exr",      "notes.txt",      ".0003.exr"};
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++)
        touch(tpath("scan/%s", names[i]));
    assert_int_equal(rb_analysis_sequence_scan(tpath("scan/"), &s, &err), RB_OK);
    assert_string_equal(s.stem, "frame");
    assert_string_equal(s.dir, tpath("scan"));
    assert_int_equal(s.frame_count, 3);
    const int want[] = {0, 2, 10};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(s.frames[i], want[i]);
        assert_string_equal(s.paths[i], tpath("scan/frame.%04d.exr", want[i]));
    }
    rb_analysis_sequence_release(&s);

    touch(tpath("scan/frame.2.exr"));
    assert_int_equal(rb_analysis_sequence_scan(tpath("scan"), &s, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "are both frame 2"));
    rb_analysis_sequence_release(&s);
    remove(tpath("scan/frame.2.exr"));

    touch(tpath("scan/beauty.0001.exr"));
    touch(tpath("scan/zz.0001.exr"));
    assert_int_equal(rb_analysis_sequence_scan(tpath("scan"), &s, &err), RB_E_INVALID);
    char msg[1200];
    snprintf(msg, sizeof(msg),
             "'%s' holds frames of two sequences, 'beauty.####.exr' and 'frame.####.exr'",
             tpath("scan"));
    assert_string_equal(err.msg, msg);
    rb_analysis_sequence_release(&s);

    mkdir(tpath("scan-empty"), 0777);
    touch(tpath("scan-empty/frame.0001.timing.json"));
    assert_int_equal(rb_analysis_sequence_scan(tpath("scan-empty"), &s, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "holds no frames"));
    rb_analysis_sequence_release(&s);
    assert_int_equal(rb_analysis_sequence_scan(tpath("nowhere"), &s, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, "cannot open"));
    rb_analysis_sequence_release(&s);
}

/* ---- reports ------------------------------------------------------------------------------ */

/* A constant W x H frame (beauty R = G = B = v, A = 1; size w x h) with its sidecar: pass
 * "gbuffer" takes 1 + frame ms, "shadow" 2 ms, and "late" 0.5 ms from frame 2 on. */
static void write_frame(const char *dir, int frame, float v, uint32_t w, uint32_t h)
{
    struct rb_err err = RB_ERR_INIT;
    float *px = malloc((size_t)w * h * 4 * sizeof(float));
    assert_non_null(px);
    for (size_t i = 0; i < (size_t)w * h; i++)
        for (int c = 0; c < 4; c++)
            px[i * 4 + c] = c < 3 ? v : 1.0f;
    static const char *const rgba[] = {"R", "G", "B", "A"};
    struct rb_io_layer layer = {.channel_count = 4, .channel_names = rgba, .pixels = px};
    mkdir(dir, 0777);
    char path[1100];
    snprintf(path, sizeof(path), "%s/frame.%04d.exr", dir, frame);
    assert_int_equal(rb_io_exr_write(path, w, h, &layer, 1, NULL, 0, &err), RB_OK);
    free(px);
    struct rb_pass_time p[3] = {{.name = "gbuffer", .gpu_ms = 1.0 + frame, .count = 1},
                                {.name = "shadow", .gpu_ms = 2.0, .count = 1},
                                {.name = "late", .gpu_ms = 0.5, .count = 1}};
    snprintf(path, sizeof(path), "%s/frame.%04d.timing.json", dir, frame);
    struct rb_io_timing t = {.frame = frame,
                             .passes = p,
                             .pass_count = frame >= 2 ? 3 : 2,
                             .wall_ms = 10.0 + frame,
                             .device = "test device",
                             .driver = "test driver",
                             .integrator = "direct",
                             .width_px = w,
                             .height_px = h};
    assert_int_equal(rb_io_timing_write(path, &t, &err), RB_OK);
}

static void write_hits(const char *dir, int frame, float v)
{
    struct rb_err err = RB_ERR_INIT;
    float px[W * H];
    for (int i = 0; i < W * H; i++)
        px[i] = v;
    static const char *const y[] = {"Y"};
    struct rb_io_layer layer = {.channel_count = 1, .channel_names = y, .pixels = px};
    char path[1100];
    snprintf(path, sizeof(path), "%s/frame.%04d.hits.exr", dir, frame);
    assert_int_equal(rb_io_exr_write(path, W, H, &layer, 1, NULL, 0, &err), RB_OK);
}

static const struct rb_io_color_desc color = {.config = CONFIG};

static struct rb_analysis_report *report(const char *dir, const char *ref)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_report *r = NULL;
    struct rb_analysis_report_desc d = {.dir = dir, .reference_dir = ref, .color = &color};
    if (rb_analysis_report_create(&d, &r, &err))
        fail_msg("report of '%s': %s", dir, err.msg);
    return r;
}

static enum rb_status report_fails(const char *dir, const char *ref, struct rb_err *err)
{
    struct rb_analysis_report *r = NULL;
    struct rb_analysis_report_desc d = {.dir = dir, .reference_dir = ref, .color = &color};
    enum rb_status st = rb_analysis_report_create(&d, &r, err);
    assert_null(r);
    return st;
}

/* Frames 0, 1, 2 and 4 of value 0.1 (f + 1); the reference 0.5 in frames 0 to 5. */
static float seq_value(int f)
{
    return 0.1f * (float)(f + 1);
}

static void write_sequences(void)
{
    const int frames[] = {0, 1, 2, 4};
    for (int i = 0; i < 4; i++)
        write_frame(tpath("seq"), frames[i], seq_value(frames[i]), W, H);
    for (int f = 0; f <= 5; f++)
        write_frame(tpath("ref"), f, 0.5f, W, H);
}

static void test_report_numbers(void **state)
{
    (void)state;
    write_sequences();
    struct rb_analysis_report *r = report(tpath("seq"), tpath("ref"));
    assert_int_equal(r->seq.frame_count, 4);
    assert_true(r->has_reference);
    assert_false(r->has_hits);
    assert_int_equal(r->width_px, W);
    assert_int_equal(r->height_px, H);
    assert_string_equal(r->device, "test device");
    assert_int_equal(r->pass_count, 3);
    assert_string_equal(r->pass_names[0], "gbuffer");
    assert_string_equal(r->pass_names[1], "shadow");
    assert_string_equal(r->pass_names[2], "late");
    for (size_t i = 0; i < 4; i++) {
        const struct rb_analysis_report_frame *f = &r->frames[i];
        double a = seq_value(f->frame), b = 0.5f;
        assert_double_equal(f->relmse, (a - b) * (a - b) / (b * b + RB_ANALYSIS_EPSILON), 1e-12);
        assert_double_equal(f->wall_ms, 10.0 + f->frame, 0.0);
        assert_double_equal(f->pass_ms[0], 1.0 + f->frame, 0.0);
        assert_double_equal(f->pass_ms[1], 2.0, 0.0);
        assert_double_equal(f->pass_ms[2], f->frame >= 2 ? 0.5 : 0.0, 0.0);
        assert_double_equal(f->pass_total_ms, 3.0 + f->frame + (f->frame >= 2 ? 0.5 : 0.0), 1e-12);
        assert_true(isnan(f->hit_ratio));
        assert_non_null(f->thumb);
        assert_non_null(f->reference_thumb);
        assert_null(f->hits_thumb);
        /* A PNG begins with 89 50 4e 47 0d 0a 1a 0a, "iVBORw0KGgo" in base64. */
        assert_true(strncmp(f->thumb, "data:image/png;base64,iVBORw0KGgo", 33) == 0);
        if (f->frame == 0 || f->frame == 4) { /* a first frame, and one after a gap */
            assert_true(isnan(f->temporal_rmse));
            assert_true(isnan(f->reference_temporal_rmse));
        } else {
            double d = (double)seq_value(f->frame) - (double)seq_value(f->frame - 1);
            assert_double_equal(f->temporal_rmse, fabs(d), 1e-12);
            assert_double_equal(f->reference_temporal_rmse, 0.0, 0.0);
        }
    }
    rb_analysis_report_destroy(r);

    r = report(tpath("seq"), NULL);
    assert_false(r->has_reference);
    assert_true(isnan(r->frames[1].relmse));
    assert_null(r->frames[1].reference_thumb);
    rb_analysis_report_destroy(r);

    for (int f = 0; f <= 4; f++)
        write_hits(tpath("ref"), f, 0.25f * (float)(f % 3));
    write_hits(tpath("ref"), 5, NAN); /* a non-finite pixel does not count */
    r = report(tpath("ref"), NULL);
    assert_true(r->has_hits);
    for (size_t i = 0; i < 5; i++) {
        assert_double_equal(r->frames[i].hit_ratio, 0.25 * (double)(i % 3), 0.0);
        assert_non_null(r->frames[i].hits_thumb);
    }
    assert_true(isnan(r->frames[5].hit_ratio));
    rb_analysis_report_destroy(r);
}

static void test_report_errors(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    char want[2048];
    write_sequences();

    /* The reference lacks frame 4 of the sequence. */
    for (int f = 0; f <= 2; f++)
        write_frame(tpath("ref-short"), f, 0.5f, W, H);
    assert_int_equal(report_fails(tpath("seq"), tpath("ref-short"), &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "the reference '%s' has no frame 4 (for '%s')", tpath("ref-short"),
             tpath("seq/frame.0004.exr"));
    assert_string_equal(err.msg, want);

    /* A frame of the reference at another size. */
    write_frame(tpath("ref-size"), 0, 0.5f, W, H);
    write_frame(tpath("ref-size"), 1, 0.5f, W / 2, H);
    assert_int_equal(report_fails(tpath("ref-size"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "size mismatch: '%s' is 4x4, '%s' is 8x4",
             tpath("ref-size/frame.0001.exr"), tpath("ref-size/frame.0000.exr"));
    assert_string_equal(err.msg, want);
    assert_int_equal(report_fails(tpath("seq"), tpath("ref-size"), &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "size mismatch"));

    /* A missing sidecar, and a sidecar of another frame. */
    write_frame(tpath("no-timing"), 0, 0.5f, W, H);
    write_frame(tpath("no-timing"), 1, 0.5f, W, H);
    remove(tpath("no-timing/frame.0001.timing.json"));
    assert_int_equal(report_fails(tpath("no-timing"), NULL, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, tpath("no-timing/frame.0001.timing.json")));
    rename(tpath("no-timing/frame.0000.timing.json"), tpath("no-timing/frame.0001.timing.json"));
    write_frame(tpath("no-timing"), 0, 0.5f, W, H);
    assert_int_equal(report_fails(tpath("no-timing"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "'%s' is the sidecar of frame 0, not of frame 1",
             tpath("no-timing/frame.0001.timing.json"));
    assert_string_equal(err.msg, want);

    /* Hit-ratio images in some frames only, either way round. */
    write_frame(tpath("some-hits"), 0, 0.5f, W, H);
    write_frame(tpath("some-hits"), 1, 0.5f, W, H);
    write_hits(tpath("some-hits"), 1, 0.5f);
    assert_int_equal(report_fails(tpath("some-hits"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "'%s' is there, but '%s' has none",
             tpath("some-hits/frame.0001.hits.exr"), tpath("some-hits/frame.0000.exr"));
    assert_string_equal(err.msg, want);
    write_hits(tpath("some-hits"), 0, 0.5f);
    remove(tpath("some-hits/frame.0001.hits.exr"));
    assert_int_equal(report_fails(tpath("some-hits"), NULL, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "frame.0001.hits.exr' is missing"));

    struct rb_analysis_report *r = NULL;
    assert_int_equal(rb_analysis_report_create(&(struct rb_analysis_report_desc){0}, &r, &err),
                     RB_E_INVALID);
    assert_null(r);
}

static void test_report_page(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    write_sequences();
    struct rb_analysis_report *r = report(tpath("seq"), NULL);
    const char *path = tpath("page.html");
    assert_int_equal(rb_analysis_report_write(r, path, &err), RB_OK);
    rb_analysis_report_destroy(r);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char page[1 << 20];
    size_t n = fread(page, 1, sizeof(page) - 1, f);
    fclose(f);
    page[n] = '\0';
    assert_true(n > 1000 && n < sizeof(page) - 1);
    assert_null(strstr(page, "<script"));
    assert_null(strstr(page, "http"));
    const char *ids[] = {"passes", "frame-time",      "hit-ratio", "temporal",
                         "warped", "reference-error", "filmstrip"};
    for (size_t i = 0; i < sizeof(ids) / sizeof(ids[0]); i++) {
        char want[64];
        snprintf(want, sizeof(want), "<section id=\"%s\"", ids[i]);
        assert_non_null(strstr(page, want));
    }
    assert_non_null(strstr(page, "No hit-ratio images"));
    assert_non_null(strstr(page, "No reference given"));
    /* These frames have no motion layer: the flicker chart says what is missing. */
    assert_non_null(strstr(page, "<p class=\"none\">Not computed: &#39;"));
    assert_non_null(strstr(page, "has no layer &#39;motion&#39;"));
    /* The pass chart, worked from the layout: its plot area starts 160 + 30 + 12 = 202 down and
     * 72 across, 640 x 176. The tallest bar is frame 4's 3 + 4 + 0.5 = 7.5 ms, so the axis runs
     * to 8 ms in steps of 2. Frame 4 is the 4th of 4 slots, each 160 wide: centre 72 + 3.5 160 =
     * 632, bar 112 wide from 576. Its "shadow" segment (the second pass, orange) stacks on
     * gbuffer's 5 ms: from 5 to 7 ms, y = 378 - 7 / 8 176 = 224 to 378 - 5 / 8 176 = 268. */
    assert_non_null(strstr(page, "data-plot=\"72 202 640 176 8 4\""));
    assert_non_null(strstr(page, "<rect x=\"576.00\" y=\"224.00\" width=\"112.00\" "
                                 "height=\"44.00\" fill=\"#f28e2b\""));
    assert_non_null(strstr(page, "fill=\"#f28e2b\" data-series=\"shadow\""));
    /* Frame 0 has no "late" pass: its bar has two segments. */
    const char *g = strstr(page, "<g><title>frame 0:");
    assert_non_null(g);
    const char *end = strstr(g, "</g>");
    size_t rects = 0;
    for (const char *p = strstr(g, "<rect"); p && p < end; p = strstr(p + 1, "<rect"))
        rects++;
    assert_int_equal(rects, 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_axis),           cmocka_unit_test(test_plot),
        cmocka_unit_test(test_filmstrip_pick), cmocka_unit_test(test_scan),
        cmocka_unit_test(test_report_numbers), cmocka_unit_test(test_report_errors),
        cmocka_unit_test(test_report_page),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
