/* lib/analysis flicker: synthetic sequences written with the project's EXR writer, whose
 * temporal stability has a closed form computed here in double: a constant image with a known
 * offset per frame and a checkerboard whose noise flips every frame (warped error and static
 * variance), ramps that translate with matching, missing and reversed motion vectors (which pins
 * the motion layer's direction), a square that uncovers the background (the depth test), and a
 * reference differing by a known amount per frame (the excess); then gaps, the pattern form of a
 * sequence, and each bad input refused with the file named. Files go under one mkdtemp
 * directory. */
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

#define W 24
#define H 12
#define EPS RB_ANALYSIS_FLICKER_LOG_EPSILON
/* The issue's tolerance for a known value. */
#define REL 0.02

static char tmpdir[512];

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "flicker");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

static const char *tpath(const char *name)
{
    static char buf[2][1024];
    static int k;
    k = (k + 1) % 2;
    snprintf(buf[k], sizeof(buf[k]), "%s/%s", tmpdir, name);
    return buf[k];
}

/* One synthetic frame: luminance (written as R = G = B, so it is the Rec.709 luminance), motion
 * (2 a pixel) and depth, w x h. */
struct synth {
    uint32_t w, h;
    float *lum, *motion, *depth;
};

static struct synth synth_make(uint32_t w, uint32_t h)
{
    struct synth s = {.w = w,
                      .h = h,
                      .lum = calloc((size_t)w * h, sizeof(float)),
                      .motion = calloc((size_t)w * h * 2, sizeof(float)),
                      .depth = calloc((size_t)w * h, sizeof(float))};
    assert_true(s.lum && s.motion && s.depth);
    return s;
}

static void synth_free(struct synth *s)
{
    free(s->lum);
    free(s->motion);
    free(s->depth);
}

/* Writes dir/NAME.NNNN.exr (NAME "frame" unless given) with the beauty and, has_motion, the
 * motion layer, and the depth layer. */
static void synth_write_as(const struct synth *s, const char *dir, const char *name, int frame,
                           bool has_motion)
{
    struct rb_err err = RB_ERR_INIT;
    size_t n = (size_t)s->w * s->h;
    float *rgba = malloc(n * 4 * sizeof(float));
    assert_non_null(rgba);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 4; c++)
            rgba[i * 4 + c] = c < 3 ? s->lum[i] : 1.0f;
    static const char *const rgba_names[] = {"R", "G", "B", "A"};
    static const char *const xy[] = {"X", "Y"};
    static const char *const z[] = {"Z"};
    struct rb_io_layer layers[3] = {
        {.channel_count = 4, .channel_names = rgba_names, .pixels = rgba},
        {.name = "depth", .channel_count = 1, .channel_names = z, .pixels = s->depth},
        {.name = "motion", .channel_count = 2, .channel_names = xy, .pixels = s->motion},
    };
    mkdir(dir, 0777);
    char path[1400];
    snprintf(path, sizeof(path), "%s/%s.%04d.exr", dir, name, frame);
    assert_int_equal(rb_io_exr_write(path, s->w, s->h, layers, has_motion ? 3 : 2, NULL, 0, &err),
                     RB_OK);
    free(rgba);
}

static void synth_write(const struct synth *s, const char *dir, int frame)
{
    synth_write_as(s, dir, "frame", frame, true);
}

static struct rb_analysis_flicker *flicker(const char *seq, const char *ref)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_flicker *f = NULL;
    struct rb_analysis_flicker_desc d = {.seq = seq, .reference = ref};
    if (rb_analysis_flicker_create(&d, &f, &err))
        fail_msg("flicker of '%s': %s", seq, err.msg);
    assert_non_null(f);
    return f;
}

static enum rb_status flicker_fails(const char *seq, const char *ref, struct rb_err *err)
{
    struct rb_analysis_flicker *f = NULL;
    struct rb_analysis_flicker_desc d = {.seq = seq, .reference = ref};
    enum rb_status st = rb_analysis_flicker_create(&d, &f, err);
    assert_null(f);
    return st;
}

/* Within REL of want (or within abs of it, for a want near 0). */
static void assert_near(double got, double want, double abs, const char *what, int frame)
{
    if (!(fabs(got - want) <= fmax(REL * fabs(want), abs)))
        fail_msg("%s of frame %d is %.9g, want %.9g", what, frame, got, want);
}

static double ll(double y)
{
    return log(y + EPS);
}

/* ---- known per-frame noise ------------------------------------------------------------------ */

/* A constant image plus a known offset a frame: every pixel is static, the warped error of frame
 * t is |l(c + o_t) - l(c + o_{t-1})|, and the static variance is the variance of l(c + o_t). */
static void test_offset(void **state)
{
    (void)state;
    const double c = 0.5, offset[] = {0.0, 0.05, -0.03, 0.08, 0.0, -0.1};
    const int count = (int)(sizeof(offset) / sizeof(offset[0]));
    struct synth s = synth_make(W, H);
    for (int t = 0; t < count; t++) {
        for (size_t i = 0; i < W * H; i++) {
            s.lum[i] = (float)(c + offset[t]);
            s.depth[i] = 2.0f;
        }
        synth_write(&s, tpath("offset"), t);
    }
    synth_free(&s);

    double mean = 0.0, var = 0.0;
    for (int t = 0; t < count; t++)
        mean += ll(c + offset[t]) / count;
    for (int t = 0; t < count; t++)
        var += (ll(c + offset[t]) - mean) * (ll(c + offset[t]) - mean) / count;

    struct rb_analysis_flicker *f = flicker(tpath("offset"), NULL);
    assert_int_equal(f->seq.frame_count, count);
    assert_int_equal(f->width_px, W);
    assert_false(f->has_reference);
    assert_true(isnan(f->frames[0].seq.warped_error));
    double sum = 0.0, max = 0.0;
    for (int t = 1; t < count; t++) {
        const struct rb_analysis_flicker_frame *fr = &f->frames[t];
        double want = fabs(ll(c + offset[t]) - ll(c + offset[t - 1]));
        assert_int_equal(fr->frame, t);
        assert_near(fr->seq.warped_error, want, 0.0, "warped error", t);
        assert_int_equal(fr->seq.compared_count, W * H);
        assert_int_equal(fr->seq.disoccluded_count, 0);
        assert_int_equal(fr->seq.offscreen_count, 0);
        assert_true(isnan(fr->excess_error));
        assert_true(isnan(fr->ref.warped_error));
        sum += want;
        max = fmax(max, want);
    }
    for (int t = 0; t < count; t++) {
        double d = ll(c + offset[t]) - mean;
        assert_near(f->frames[t].seq.static_deviation, d * d, 1e-9, "static deviation", t);
    }
    assert_near(f->summary.warped_error, sum / (count - 1), 0.0, "mean warped error", -1);
    assert_near(f->summary.warped_error_max, max, 0.0, "largest warped error", -1);
    assert_int_equal(f->summary.static_count, W * H);
    assert_near(f->summary.static_variance, var, 0.0, "static variance", -1);
    assert_true(isnan(f->excess_error));
    rb_analysis_flicker_destroy(f);
}

/* Per-pixel noise of known size: a checkerboard of c (1 +- a) whose signs flip every frame.
 * Every pixel changes by the same amount in log luminance, and over an even number of frames
 * each pixel's variance is a quarter of its square. */
static void test_noise(void **state)
{
    (void)state;
    const double c = 0.3, a = 0.2;
    struct synth s = synth_make(W, H);
    for (int t = 0; t < 4; t++) {
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++) {
                bool is_up = (x + y + (uint32_t)t) % 2 == 0;
                s.lum[y * W + x] = (float)(c * (is_up ? 1.0 + a : 1.0 - a));
                s.depth[y * W + x] = 1.0f + 0.01f * (float)x; /* a slanted wall */
            }
        synth_write(&s, tpath("noise"), t);
    }
    synth_free(&s);

    double step = ll(c * (1.0 + a)) - ll(c * (1.0 - a));
    struct rb_analysis_flicker *f = flicker(tpath("noise"), NULL);
    for (int t = 1; t < 4; t++)
        assert_near(f->frames[t].seq.warped_error, step, 0.0, "warped error", t);
    for (int t = 0; t < 4; t++)
        assert_near(f->frames[t].seq.static_deviation, step * step / 4, 0.0, "static deviation", t);
    assert_int_equal(f->summary.static_count, W * H);
    assert_near(f->summary.static_variance, step * step / 4, 0.0, "static variance", -1);
    rb_analysis_flicker_destroy(f);
}

/* ---- motion --------------------------------------------------------------------------------- */

/* A ramp of log luminance l = kx x + ky y that moves by (vx, vy) pixels a frame, written with
 * motion m * (-vx, -vy): m = 1 is the layer's convention (the previous position minus this one),
 * 0 no motion, -1 the reverse. */
static void write_ramp(const char *dir, double m)
{
    const double kx = 0.1, ky = 0.05, vx = 1.75, vy = 0.75;
    struct synth s = synth_make(W, H);
    for (int t = 0; t < 4; t++) {
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++) {
                size_t i = (size_t)y * W + x;
                double l = kx * (x + 0.5 - vx * t) + ky * (y + 0.5 - vy * t);
                s.lum[i] = (float)(exp(l) - EPS);
                s.motion[2 * i] = (float)(-m * vx);
                s.motion[2 * i + 1] = (float)(-m * vy);
                s.depth[i] = 3.0f;
            }
        synth_write(&s, dir, t);
    }
    synth_free(&s);
}

static void test_translation(void **state)
{
    (void)state;
    const double kx = 0.1, ky = 0.05, vx = 1.75, vy = 0.75;
    const double shift = kx * vx + ky * vy; /* |l_t(p) - l_{t-1}(p)| */
    write_ramp(tpath("ramp"), 1.0);
    write_ramp(tpath("ramp-still"), 0.0);
    write_ramp(tpath("ramp-reversed"), -1.0);

    /* Matching motion: the previous frame warped is this frame (bilinear is exact on a linear
     * ramp). The two left columns and the top row come from off the image. */
    struct rb_analysis_flicker *f = flicker(tpath("ramp"), NULL);
    uint64_t offscreen = 2 * H + (W - 2);
    for (int t = 1; t < 4; t++) {
        const struct rb_analysis_flicker_stats *s = &f->frames[t].seq;
        if (!(fabs(s->warped_error) < 1e-5))
            fail_msg("frame %d: warped error %.9g with matching motion, want ~0", t,
                     s->warped_error);
        assert_int_equal(s->offscreen_count, offscreen);
        assert_int_equal(s->compared_count, W * H - offscreen);
        assert_int_equal(s->disoccluded_count, 0);
    }
    assert_int_equal(f->summary.static_count, 0); /* everything moves */
    assert_true(isnan(f->summary.static_variance));
    assert_true(isnan(f->frames[2].seq.static_deviation));
    rb_analysis_flicker_destroy(f);

    /* No motion: every pixel differs by the shift. */
    f = flicker(tpath("ramp-still"), NULL);
    for (int t = 1; t < 4; t++) {
        assert_near(f->frames[t].seq.warped_error, shift, 0.0, "warped error, no motion", t);
        assert_int_equal(f->frames[t].seq.compared_count, W * H);
    }
    rb_analysis_flicker_destroy(f);

    /* Reversed motion reads twice as far the wrong way: 2 shifts (a little less where the
     * sample is clamped to the last column's centre). */
    f = flicker(tpath("ramp-reversed"), NULL);
    for (int t = 1; t < 4; t++) {
        const struct rb_analysis_flicker_stats *s = &f->frames[t].seq;
        assert_int_equal(s->offscreen_count, 2 * H + (W - 2));
        if (!(s->warped_error > 1.5 * shift))
            fail_msg("frame %d: warped error %.9g with reversed motion, want about %.9g", t,
                     s->warped_error, 2 * shift);
    }
    rb_analysis_flicker_destroy(f);
}

/* A 4x4 square in front (depth 1) moving right 2 pixels a frame over a wall (depth 4): the
 * columns it uncovers were the square one frame earlier, so they fail the depth test; what is
 * compared is the same surface at the same luminance. */
static void test_disocclusion(void **state)
{
    (void)state;
    const uint32_t side = 4, x0 = 3, y0 = 5, step = 2;
    const float bg = 0.2f, fg = 0.8f;
    struct synth s = synth_make(W, H);
    for (int t = 0; t < 4; t++) {
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++) {
                size_t i = (size_t)y * W + x;
                uint32_t left = x0 + step * (uint32_t)t;
                bool is_fg = x >= left && x < left + side && y >= y0 && y < y0 + side;
                s.lum[i] = is_fg ? fg : bg;
                s.depth[i] = is_fg ? 1.0f : 4.0f;
                s.motion[2 * i] = is_fg ? -(float)step : 0.0f;
                s.motion[2 * i + 1] = 0.0f;
            }
        synth_write(&s, tpath("square"), t);
    }
    synth_free(&s);

    struct rb_analysis_flicker *f = flicker(tpath("square"), NULL);
    for (int t = 1; t < 4; t++) {
        const struct rb_analysis_flicker_stats *st = &f->frames[t].seq;
        assert_int_equal(st->disoccluded_count, step * side);
        assert_int_equal(st->offscreen_count, 0);
        assert_int_equal(st->compared_count, W * H - step * side);
        assert_double_equal(st->warped_error, 0.0, 1e-12);
    }
    /* Static: the wall where the square never was. */
    uint32_t swept = side * (side + 3 * step);
    assert_int_equal(f->summary.static_count, W * H - swept);
    assert_double_equal(f->summary.static_variance, 0.0, 1e-12);

    /* A tolerance wide enough to take the square for the wall compares those pixels too. */
    struct rb_err err = RB_ERR_INIT;
    rb_analysis_flicker_destroy(f);
    f = NULL;
    struct rb_analysis_flicker_desc d = {.seq = tpath("square"), .depth_tolerance = 4.0};
    assert_int_equal(rb_analysis_flicker_create(&d, &f, &err), RB_OK);
    double want = step * side * fabs(ll(bg) - ll(fg)) / (W * H);
    assert_near(f->frames[1].seq.warped_error, want, 0.0, "warped error, wide tolerance", 1);
    assert_double_equal(f->desc.depth_tolerance, 4.0, 0.0);
    assert_double_equal(f->desc.log_epsilon, EPS, 0.0);
    rb_analysis_flicker_destroy(f);
}

/* ---- the reference ----------------------------------------------------------------------------
 */

/* The reference is a constant c_t a frame; the sequence adds a known error n_t to it. Then
 * (I_t - I_{t-1}) - (R_t - R_{t-1}) = n_t - n_{t-1} at every pixel. The reference has more
 * frames than the sequence, which has a gap (no frame 4). */
static void test_reference(void **state)
{
    (void)state;
    const double ref[] = {0.4, 0.45, 0.42, 0.5, 0.47, 0.44, 0.41};
    const double noise[] = {0.0, 0.02, -0.01, 0.03, 0.0, 0.05, -0.02};
    const int frames[] = {0, 1, 2, 3, 5, 6};
    struct synth s = synth_make(W, H);
    for (size_t i = 0; i < W * H; i++)
        s.depth[i] = 2.0f;
    for (int t = 0; t < 7; t++) {
        for (size_t i = 0; i < W * H; i++)
            s.lum[i] = (float)ref[t];
        synth_write(&s, tpath("ref"), t);
    }
    for (size_t k = 0; k < 6; k++) {
        int t = frames[k];
        for (size_t i = 0; i < W * H; i++)
            s.lum[i] = (float)(ref[t] + noise[t]);
        synth_write(&s, tpath("seq"), t);
    }
    synth_free(&s);

    struct rb_analysis_flicker *f = flicker(tpath("seq"), tpath("ref"));
    assert_true(f->has_reference);
    assert_int_equal(f->seq.frame_count, 6);
    double sum = 0.0;
    int count = 0;
    for (size_t k = 0; k < 6; k++) {
        const struct rb_analysis_flicker_frame *fr = &f->frames[k];
        int t = frames[k];
        assert_int_equal(fr->frame, t);
        if (t == 0 || t == 5) { /* a first frame, and one after the gap */
            assert_true(isnan(fr->excess_error));
            assert_true(isnan(fr->seq.warped_error));
            assert_true(isnan(fr->ref.warped_error));
            continue;
        }
        double want = fabs(noise[t] - noise[t - 1]);
        assert_near(fr->excess_error, want, 1e-6, "excess error", t);
        assert_near(fr->ref.warped_error, fabs(ll(ref[t]) - ll(ref[t - 1])), 0.0,
                    "the reference's warped error", t);
        assert_near(fr->seq.warped_error,
                    fabs(ll(ref[t] + noise[t]) - ll(ref[t - 1] + noise[t - 1])), 0.0,
                    "warped error", t);
        sum += want;
        count++;
    }
    assert_near(f->excess_error, sum / count, 1e-6, "mean excess error", -1);
    /* The reference's metrics are over the sequence's frames only. */
    double mean = 0.0, var = 0.0;
    for (size_t k = 0; k < 6; k++)
        mean += ll(ref[frames[k]]) / 6;
    for (size_t k = 0; k < 6; k++)
        var += (ll(ref[frames[k]]) - mean) * (ll(ref[frames[k]]) - mean) / 6;
    assert_int_equal(f->reference_summary.static_count, W * H);
    assert_near(f->reference_summary.static_variance, var, 0.0, "the reference's variance", -1);

    /* The same files give the same bits. */
    struct rb_analysis_flicker *again = flicker(tpath("seq"), tpath("ref"));
    for (size_t k = 0; k < 6; k++) {
        const struct rb_analysis_flicker_frame *a = &f->frames[k], *b = &again->frames[k];
        const double va[] = {a->seq.warped_error, a->seq.static_deviation, a->ref.warped_error,
                             a->ref.static_deviation, a->excess_error};
        const double vb[] = {b->seq.warped_error, b->seq.static_deviation, b->ref.warped_error,
                             b->ref.static_deviation, b->excess_error};
        assert_memory_equal(va, vb, sizeof(va));
    }
    rb_analysis_flicker_destroy(again);
    rb_analysis_flicker_destroy(f);
}

/* ---- sequences and bad input ---------------------------------------------------------------- */

static void test_pattern(void **state)
{
    (void)state;
    struct synth s = synth_make(W, H);
    for (size_t i = 0; i < W * H; i++) {
        s.lum[i] = 0.5f;
        s.depth[i] = 1.0f;
    }
    for (int t = 7; t <= 9; t++) {
        synth_write_as(&s, tpath("two"), "shot", t, true);
        synth_write_as(&s, tpath("two"), "take", t - 5, true);
    }
    synth_free(&s);
    struct rb_err err = RB_ERR_INIT;
    /* A directory of two sequences is ambiguous; a pattern picks one. */
    assert_int_equal(flicker_fails(tpath("two"), NULL, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "holds frames of two sequences"));
    struct rb_analysis_flicker *f = flicker(tpath("two/shot.####.exr"), NULL);
    assert_string_equal(f->seq.stem, "shot");
    assert_string_equal(f->seq.dir, tpath("two"));
    assert_int_equal(f->seq.frame_count, 3);
    assert_int_equal(f->frames[0].frame, 7); /* the sequence's own numbers */
    assert_int_equal(f->frames[2].frame, 9);
    assert_double_equal(f->frames[1].seq.warped_error, 0.0, 0.0);
    rb_analysis_flicker_destroy(f);
    f = flicker(tpath("two/take.#.exr"), NULL);
    assert_int_equal(f->frames[0].frame, 2);
    rb_analysis_flicker_destroy(f);

    char want[2200];
    assert_int_equal(flicker_fails(tpath("two/none.####.exr"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "no frames match '%s'", tpath("two/none.####.exr"));
    assert_string_equal(err.msg, want);
    assert_int_equal(flicker_fails(tpath("two/shot.##.#.exr"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "'%s' is neither a directory nor a pattern DIR/NAME.####.exr",
             tpath("two/shot.##.#.exr"));
    assert_string_equal(err.msg, want);
}

static void test_errors(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    char want[2200];
    struct synth s = synth_make(W, H), small = synth_make(W / 2, H);
    for (size_t i = 0; i < W * H; i++) {
        s.lum[i] = 0.5f;
        s.depth[i] = 1.0f;
    }
    for (int t = 0; t < 3; t++)
        synth_write(&s, tpath("good"), t);

    assert_int_equal(flicker_fails(tpath("nowhere"), NULL, &err), RB_E_IO);
    snprintf(want, sizeof(want), "cannot open '%s'", tpath("nowhere"));
    assert_non_null(strstr(err.msg, want));

    /* A frame of another size, in the sequence and in the reference. */
    synth_write(&s, tpath("sizes"), 0);
    synth_write(&small, tpath("sizes"), 1);
    assert_int_equal(flicker_fails(tpath("sizes"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want),
             "size mismatch: '%s/frame.0001.exr' is %ux%u, '%s/frame.0000.exr' is %ux%u",
             tpath("sizes"), W / 2, H, tpath("sizes"), W, H);
    assert_string_equal(err.msg, want);
    for (int t = 0; t < 3; t++)
        synth_write(&small, tpath("small"), t);
    assert_int_equal(flicker_fails(tpath("good"), tpath("small"), &err), RB_E_INVALID);
    snprintf(want, sizeof(want),
             "size mismatch: '%s/frame.0000.exr' is %ux%u, '%s/frame.0000.exr' is %ux%u",
             tpath("small"), W / 2, H, tpath("good"), W, H);
    assert_string_equal(err.msg, want);

    /* No motion layer. */
    synth_write(&s, tpath("nomotion"), 0);
    synth_write_as(&s, tpath("nomotion"), "frame", 1, false);
    assert_int_equal(flicker_fails(tpath("nomotion"), NULL, &err), RB_E_INVALID);
    snprintf(want, sizeof(want),
             "'%s/frame.0001.exr' has no layer 'motion'; its layers: beauty, depth",
             tpath("nomotion"));
    assert_string_equal(err.msg, want);

    /* A reference without one of the sequence's frames. */
    synth_write(&s, tpath("short"), 0);
    synth_write(&s, tpath("short"), 2);
    assert_int_equal(flicker_fails(tpath("good"), tpath("short"), &err), RB_E_INVALID);
    snprintf(want, sizeof(want), "the reference '%s' has no frame 1 (for '%s/frame.0001.exr')",
             tpath("short"), tpath("good"));
    assert_string_equal(err.msg, want);

    /* A bad desc. */
    struct rb_analysis_flicker *f = NULL;
    struct rb_analysis_flicker_desc d = {.seq = tpath("good"), .log_epsilon = -1.0};
    assert_int_equal(rb_analysis_flicker_create(&d, &f, &err), RB_E_INVALID);
    d = (struct rb_analysis_flicker_desc){.seq = tpath("good"), .depth_tolerance = NAN};
    assert_int_equal(rb_analysis_flicker_create(&d, &f, &err), RB_E_INVALID);
    d = (struct rb_analysis_flicker_desc){0};
    assert_int_equal(rb_analysis_flicker_create(&d, &f, &err), RB_E_INVALID);
    assert_null(f);
    synth_free(&s);
    synth_free(&small);
}

/* A normal number from a fixed LCG (Box-Muller), so the test is the same every run. */
static double normal(uint64_t *state)
{
    double u[2];
    for (int k = 0; k < 2; k++) {
        *state = *state * 6364136223846793005ull + 1442695040888963407ull;
        u[k] = ((double)(*state >> 11) + 0.5) / 9007199254740992.0;
    }
    return sqrt(-2.0 * log(u[0])) * cos(6.283185307179586 * u[1]);
}

/* The excess less the reference's noise: a sequence whose change is off the truth's by a known
 * normal a (sd 0.1) against a reference whose two frames carry independent normal noise of
 * known, per-pixel variances (5 times a's on average): the RMS finds a's sd within 3%, while the
 * plain RMS and mean count the noise; without variances nothing is subtracted; the noise never
 * takes the RMS below 0; no finite pixel gives NaN. */
static void test_excess_noise(void **state)
{
    (void)state;
    enum { N = 200000 };
    double *cur = calloc(N, sizeof(double)), *prev = calloc(N, sizeof(double));
    double *ref = calloc(N, sizeof(double)), *ref_prev = calloc(N, sizeof(double));
    float *var = calloc(N, sizeof(float)), *var_prev = calloc(N, sizeof(float));
    assert_true(cur && prev && ref && ref_prev && var && var_prev);
    uint64_t rng = 42;
    double sd = 0.1, noise = 0.0, sum_abs = 0.0;
    for (size_t i = 0; i < N; i++) {
        var[i] = (float)(0.004 * (double)((1 + i % 5) * (1 + i % 5)));
        var_prev[i] = (float)(0.005 * (double)(1 + i % 3));
        double truth = 0.5 + 0.001 * (double)(i % 97); /* the true change, in both */
        cur[i] = 1.0 + truth + sd * normal(&rng);
        prev[i] = 1.0;
        ref[i] = 2.0 + truth + sqrt((double)var[i]) * normal(&rng);
        ref_prev[i] = 2.0 + sqrt((double)var_prev[i]) * normal(&rng);
        noise += (double)var[i] + (double)var_prev[i];
        sum_abs += fabs((cur[i] - prev[i]) - (ref[i] - ref_prev[i]));
    }
    struct rb_analysis_flicker_excess x =
        rb_analysis_flicker_excess(cur, prev, ref, ref_prev, var, var_prev, N);
    assert_int_equal(x.count, N);
    assert_true(fabs(x.sum_noise - noise) <= 1e-12 * noise);
    assert_true(fabs(x.error - sum_abs / N) <= 1e-12 * x.error);
    if (!(fabs(x.rms - sd) <= 0.03 * sd))
        fail_msg("the RMS less the noise is %.9g, want %.9g within 3%%", x.rms, sd);
    assert_true(sqrt(x.sum_sq / N) > 2.0 * sd); /* the noise dominates the plain RMS */
    struct rb_analysis_flicker_excess plain =
        rb_analysis_flicker_excess(cur, prev, ref, ref_prev, NULL, NULL, N);
    assert_true(plain.sum_noise == 0.0);
    assert_true(plain.error == x.error);
    assert_true(fabs(plain.rms - sqrt(x.sum_sq / N)) <= 1e-12 * plain.rms);
    /* more noise than squares: 0, not NaN */
    assert_true(rb_analysis_flicker_excess_rms(1.0, 2.0, 10) == 0.0);
    assert_true(rb_analysis_flicker_excess_rms(4.0, 0.0, 1) == 2.0);
    assert_true(isnan(rb_analysis_flicker_excess_rms(0.0, 0.0, 0)));
    cur[0] = NAN;
    struct rb_analysis_flicker_excess one =
        rb_analysis_flicker_excess(cur, prev, ref, ref_prev, var, var_prev, 1);
    assert_int_equal(one.count, 0);
    assert_true(isnan(one.error) && isnan(one.rms));
    free(cur);
    free(prev);
    free(ref);
    free(ref_prev);
    free(var);
    free(var_prev);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_offset),      cmocka_unit_test(test_noise),
        cmocka_unit_test(test_translation), cmocka_unit_test(test_disocclusion),
        cmocka_unit_test(test_reference),   cmocka_unit_test(test_pattern),
        cmocka_unit_test(test_errors),      cmocka_unit_test(test_excess_noise),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
