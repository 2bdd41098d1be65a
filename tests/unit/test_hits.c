/* Hit-ratio sidecars: the summary (mean in pixel order, nearest-rank percentiles) against values
 * worked out by hand, the timing sidecar's "hits" object written and read back (and its absence
 * tolerated), and the writer of lib/render fed synthetic frame results: NAME.####.hits.exr with
 * its one channel and metadata, nothing of the kind for a frame without hit ratios, the space
 * check counting the file, and --resume's verdict for bdpt needing it. The writer's renderers are
 * created on lavapipe (no frame is rendered); files go under one mkdtemp directory. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "io/io.h"
#include "render/render.h"
#include "testutil.h"

#define W 20
#define H 10
#define N (W * H)

static char tmpdir[512];

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "hits");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

/* A path under the test's directory, in one of four buffers used in turn. */
static const char *tpath(const char *name)
{
    static char buf[4][1024];
    static int i;
    i = (i + 1) % 4;
    snprintf(buf[i], sizeof(buf[i]), "%s/%s", tmpdir, name);
    return buf[i];
}

/* The ramp 0/256, 1/256, ..., 199/256 (exact in float), stored in the order i * 7 mod 200 so
 * that only a sort finds the ranks. By hand: the mean is (199 * 200 / 2) / 200 / 256 = 99.5 / 256;
 * the nearest ranks of 200 values are ceil(5 * 200 / 100) = 10, 100 and 190, the values 9/256,
 * 99/256 and 189/256. */
static void ramp(float *out)
{
    for (int i = 0; i < N; i++)
        out[i] = (float)(i * 7 % N) / 256.0f;
}

static struct rb_io_hits summary(const float *v, size_t n)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_io_hits h;
    if (rb_io_hits_summarize(v, n, &h, &err))
        fail_msg("summary: %s", err.msg);
    return h;
}

static void test_summary(void **state)
{
    (void)state;
    float v[N + 2];
    ramp(v);
    struct rb_io_hits h = summary(v, N);
    assert_double_equal(h.mean, 99.5 / 256.0, 0.0);
    assert_double_equal(h.p5, 9.0 / 256.0, 0.0);
    assert_double_equal(h.p50, 99.0 / 256.0, 0.0);
    assert_double_equal(h.p95, 189.0 / 256.0, 0.0);
    /* The rank rounds up: of 21 values 1..21, p5 is the ceil(1.05) = 2nd, p50 the ceil(10.5) =
     * 11th, p95 the ceil(19.95) = 20th. */
    for (int i = 0; i < 21; i++)
        v[i] = (float)(21 - i);
    h = summary(v, 21);
    assert_double_equal(h.p5, 2.0, 0.0);
    assert_double_equal(h.p50, 11.0, 0.0);
    assert_double_equal(h.p95, 20.0, 0.0);
    assert_double_equal(h.mean, 11.0, 0.0);
    /* One value is every percentile; values that are not finite are left out. */
    v[0] = 0.75f;
    v[1] = NAN;
    v[2] = INFINITY;
    h = summary(v, 3);
    assert_double_equal(h.mean, 0.75, 0.0);
    assert_double_equal(h.p5, 0.75, 0.0);
    assert_double_equal(h.p95, 0.75, 0.0);
    h = summary(v + 1, 2);
    assert_true(isnan(h.mean) && isnan(h.p5) && isnan(h.p50) && isnan(h.p95));
    /* The mean is the double sum in pixel order: 1 + 2^-30 + ... is not float's 1. */
    float tiny[4] = {1.0f, 0x1p-30f, 0x1p-30f, 0x1p-30f};
    h = summary(tiny, 4);
    assert_double_equal(h.mean, (1.0 + 3.0 * 0x1p-30) / 4.0, 0.0);
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    static char buf[16384];
    size_t n = fread(buf, 1, sizeof(buf) - 1, f);
    fclose(f);
    buf[n] = '\0';
    return buf;
}

static void test_timing_hits(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    const struct rb_io_hits hits = {.mean = 99.5 / 256.0, .p5 = 0.03515625, .p50 = 1, .p95 = 1};
    struct rb_io_timing t = {.frame = 7,
                             .device = "d",
                             .driver = "v",
                             .job_hash = "0123456789abcdef",
                             .integrator = "bdpt"};
    struct rb_io_timing_file back = {0};
    t.hits = &hits;
    assert_int_equal(rb_io_timing_write(tpath("a.timing.json"), &t, &err), RB_OK);
    assert_non_null(strstr(slurp(tpath("a.timing.json")), "\"job_hash\": \"0123456789abcdef\""));
    assert_non_null(strstr(slurp(tpath("a.timing.json")),
                           "\"hits\": {\"mean\": 0.388671875, \"p5\": 0.03515625, \"p50\": 1, "
                           "\"p95\": 1}"));
    assert_int_equal(rb_io_timing_read(tpath("a.timing.json"), &back, &err), RB_OK);
    assert_true(back.has_hits);
    assert_string_equal(back.job_hash, "0123456789abcdef");
    assert_double_equal(back.hits.mean, hits.mean, 0.0);
    assert_double_equal(back.hits.p5, hits.p5, 0.0);
    assert_double_equal(back.hits.p50, 1.0, 0.0);
    assert_double_equal(back.hits.p95, 1.0, 0.0);
    rb_io_timing_file_release(&back);

    /* No hit ratios, no object; no job hash, no key; the reader takes a sidecar without them. */
    t.hits = NULL;
    t.job_hash = NULL;
    assert_int_equal(rb_io_timing_write(tpath("b.timing.json"), &t, &err), RB_OK);
    assert_null(strstr(slurp(tpath("b.timing.json")), "hits"));
    assert_null(strstr(slurp(tpath("b.timing.json")), "job_hash"));
    assert_int_equal(rb_io_timing_read(tpath("b.timing.json"), &back, &err), RB_OK);
    assert_false(back.has_hits);
    assert_string_equal(back.job_hash, "");
    rb_io_timing_file_release(&back);

    /* null (no finite hit ratio) reads as NaN; a malformed object is an error naming it. */
    static const char head[] = "{\"frame\": 1, \"wall_ms\": 2, \"device\": \"d\", \"driver\": "
                               "\"v\", \"passes\": [], \"hits\": ";
    const struct {
        const char *hits, *error;
    } cases[] = {
        {"{\"mean\": null, \"p5\": null, \"p50\": null, \"p95\": null}}", NULL},
        {"3}", "'hits' is not an object"},
        {"{\"mean\": 1, \"p5\": 1, \"p50\": 1}}", "no 'hits.p95'"},
        {"{\"mean\": 1, \"p5\": \"x\", \"p50\": 1, \"p95\": 1}}",
         "'hits.p5' is not a finite number"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        char text[512];
        snprintf(text, sizeof(text), "%s%s", head, cases[i].hits);
        enum rb_status st = rb_io_timing_parse("t.json", text, strlen(text), &back, &err);
        if (!cases[i].error) {
            assert_int_equal(st, RB_OK);
            assert_true(back.has_hits);
            assert_true(isnan(back.hits.mean) && isnan(back.hits.p95));
        } else {
            assert_int_equal(st, RB_E_PARSE);
            if (!strstr(err.msg, cases[i].error))
                fail_msg("case %zu: '%s' does not say '%s'", i, err.msg, cases[i].error);
        }
        rb_io_timing_file_release(&back);
    }
}

/* ---- the writer --------------------------------------------------------------------------- */

struct fixture {
    struct rb_job *job;
    struct rb_scene *scene;
    struct rb_scene_setup setup;
    struct rb_render *render;
    char hash[17];
};

static void make_render(struct fixture *f, const char *integrator)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_job_override o[] = {{"resolution", "[20, 10]", NULL},
                                  {"integrator.name", integrator, NULL}};
    if (rb_job_load("jobs/demo.yaml", o, 2, &f->job, &err) ||
        rb_scene_load(f->job->scene_path, 0, &f->scene, &err) ||
        rb_scene_setup_init(f->job, f->scene, NULL, 0, 0, &f->setup, &err) ||
        rb_render_create(
            &(struct rb_render_desc){
                .job = f->job, .scene = f->scene, .setup = &f->setup, .validate = true},
            &f->render, &err))
        fail_msg("%s render: %s", integrator, err.msg);
    snprintf(f->hash, sizeof(f->hash), "%016llx", (unsigned long long)f->setup.job_hash);
}

static void free_render(struct fixture *f)
{
    rb_render_destroy(f->render);
    rb_scene_destroy(f->scene);
    rb_job_destroy(f->job);
}

/* A frame of the job's size and layers, its beauty a ramp; hits may be NULL. */
static void write_frame(struct fixture *f, int frame, const char *path, const float *hits,
                        float *hits_after)
{
    struct rb_err err = RB_ERR_INIT;
    uint32_t stride = rb_layer_stride(f->job->layer_mask);
    float *px = calloc((size_t)N * stride, sizeof(float));
    assert_non_null(px);
    for (int i = 0; i < N; i++)
        px[(size_t)i * stride] = (float)i;
    struct rb_frame_result r = {.frame = frame,
                                .time_s = frame / 24.0,
                                .width_px = W,
                                .height_px = H,
                                .pixels = px,
                                .floats_per_pixel = stride,
                                .layer_mask = f->job->layer_mask,
                                .hits = hits};
    if (rb_render_write(f->render, path, &r, 1.0, &err))
        fail_msg("write: %s", err.msg);
    /* The next frame reuses the renderer's buffers at once: the writer has its own copies. */
    memset(px, 0xff, (size_t)N * stride * sizeof(float));
    if (hits_after)
        memset(hits_after, 0xff, N * sizeof(float));
    free(px);
    if (rb_render_flush(f->render, &err))
        fail_msg("flush: %s", err.msg);
}

static bool exists(const char *path)
{
    return access(path, F_OK) == 0;
}

static void test_writer_bdpt(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    struct fixture f = {0};
    make_render(&f, "bdpt");
    float hits[N];
    ramp(hits);
    char exr[1024], side[1024];
    snprintf(exr, sizeof(exr), "%s", tpath("bdpt/frame.0003.exr"));
    snprintf(side, sizeof(side), "%s", tpath("bdpt/frame.0003.hits.exr"));
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_NEW);
    write_frame(&f, 3, exr, hits, hits);
    ramp(hits);

    /* The image: one channel Y, the values exactly; the frame's metadata. */
    struct rb_io_image img = {0};
    assert_int_equal(rb_io_image_read(side, &img, &err), RB_OK);
    assert_int_equal(img.width_px, W);
    assert_int_equal(img.height_px, H);
    assert_int_equal(img.channel_count, 1);
    assert_string_equal(img.channel_names[0], "Y");
    assert_memory_equal(img.pixels, hits, sizeof(hits));
    rb_io_image_release(&img);
    char v[256];
    assert_true(rb_io_image_attr(side, "raybundle:integrator", v, sizeof(v)));
    assert_string_equal(v, "bdpt");
    assert_true(rb_io_image_attr(side, "raybundle:jobHash", v, sizeof(v)));
    assert_string_equal(v, f.hash);
    assert_true(rb_io_image_attr(side, "raybundle:frame", v, sizeof(v)));
    assert_string_equal(v, "3");
    assert_true(rb_io_image_attr(side, "ImageDescription", v, sizeof(v)));
    assert_non_null(strstr(v, "hit ratio"));

    /* The timing sidecar's summary: the hand-worked numbers of ramp(). */
    struct rb_io_timing_file t = {0};
    assert_int_equal(rb_io_timing_read(tpath("bdpt/frame.0003.timing.json"), &t, &err), RB_OK);
    assert_true(t.has_hits);
    assert_double_equal(t.hits.mean, 99.5 / 256.0, 0.0);
    assert_double_equal(t.hits.p5, 9.0 / 256.0, 0.0);
    assert_double_equal(t.hits.p50, 99.0 / 256.0, 0.0);
    assert_double_equal(t.hits.p95, 189.0 / 256.0, 0.0);
    rb_io_timing_file_release(&t);

    /* The space check counts the hit ratios: its message gives the size of a frame. */
    struct stat sb;
    uint64_t bytes = 0;
    const char *files[] = {exr, tpath("bdpt/frame.0003.timing.json"), side};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(stat(files[i], &sb), 0);
        bytes += (uint64_t)sb.st_size;
    }
    char want[64];
    snprintf(want, sizeof(want), "at %.0f KB a frame", bytes / 1e3);
    assert_int_equal(rb_render_check_space(exr, false, INT32_MAX, &err), RB_E_IO);
    if (!strstr(err.msg, want))
        fail_msg("'%s' does not say '%s'", err.msg, want);
    /* Each figure in a unit that shows it: never "0.0 GB" (a frame of a few KB). */
    if (strstr(err.msg, " 0.0 ") || strstr(err.msg, " 0 "))
        fail_msg("'%s' prints a figure as zero", err.msg);

    /* --resume keeps the frame only with its hit ratios complete. */
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_KEEP);
    assert_int_equal(rename(side, tpath("bdpt/saved.exr")), 0);
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_NEW);
    FILE *cut = fopen(side, "wb"); /* a file cut short, as a killed copy leaves it */
    assert_non_null(cut);
    fputs("v/1\001", cut);
    fclose(cut);
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_NEW);
    assert_int_equal(rename(tpath("bdpt/saved.exr"), side), 0);
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_KEEP);

    /* A bdpt frame without hit ratios: no file, no object; --resume renders it again. */
    snprintf(exr, sizeof(exr), "%s", tpath("bdpt/frame.0004.exr"));
    write_frame(&f, 4, exr, NULL, NULL);
    assert_true(exists(exr));
    assert_false(exists(tpath("bdpt/frame.0004.hits.exr")));
    assert_null(strstr(slurp(tpath("bdpt/frame.0004.timing.json")), "\"hits\""));
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_NEW);

    /* A frame that is not the job's size is refused. */
    struct rb_frame_result wrong = {.width_px = W + 1, .height_px = H, .pixels = hits};
    assert_int_equal(rb_render_write(f.render, tpath("bdpt/frame.0005.exr"), &wrong, 0.0, &err),
                     RB_E_INVALID);
    free_render(&f);
}

/* The direct integrator makes no hit ratios: its files and its verdict are as before. */
static void test_writer_direct(void **state)
{
    (void)state;
    struct fixture f = {0};
    make_render(&f, "direct");
    const char *exr = tpath("direct/frame.0002.exr");
    write_frame(&f, 2, exr, NULL, NULL);
    assert_false(exists(tpath("direct/frame.0002.hits.exr")));
    assert_null(strstr(slurp(tpath("direct/frame.0002.timing.json")), "\"hits\""));
    assert_int_equal(rb_render_resume_verdict(f.render, exr), RB_RENDER_KEEP);
    free_render(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_summary),
        cmocka_unit_test(test_timing_hits),
        cmocka_unit_test(test_writer_bdpt),
        cmocka_unit_test(test_writer_direct),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
