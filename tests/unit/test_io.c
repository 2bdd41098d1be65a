/* lib/io: frame and sidecar paths, atomic writes, the EXR round trip (channels, attributes,
 * byte-for-byte determinism), completeness checks, the OCIO preview, and the timing JSON.
 * Every file goes under one mkdtemp directory; run from the repository root (the preview
 * tests use share/ocio/config.ocio). */
#include "io/io.h"
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#define CONFIG "share/ocio/config.ocio"

static char tmpdir[512];

/* ---- helpers ---------------------------------------------------------------------------- */

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "io");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

/* A path under the test directory; each call returns a new static slot (8 in rotation). */
static const char *tpath(const char *name)
{
    static char slots[8][1024];
    static int next;
    char *p = slots[next++ % 8];
    snprintf(p, 1024, "%s/%s", tmpdir, name);
    return p;
}

static bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Number of entries in dir whose name contains needle. */
static int count_entries(const char *dir, const char *needle)
{
    int n = 0;
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, needle))
            n++;
    closedir(d);
    return n;
}

static char *slurp(const char *path, size_t *size)
{
    char *buf = NULL;
    size_t n = 0;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_read_file(path, &buf, &n, &err);
    if (st)
        fail_msg("%s", err.msg);
    if (size)
        *size = n;
    return buf;
}

static void spit(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* ---- paths ------------------------------------------------------------------------------ */

static void check_frame(const char *pattern, int frame, const char *want)
{
    char out[256];
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_io_frame_path(pattern, frame, out, sizeof(out), &err), RB_OK);
    assert_string_equal(out, want);
}

static void test_frame_path(void **state)
{
    (void)state;
    check_frame("out/shot.####.exr", 12, "out/shot.0012.exr");
    check_frame("out/shot.####.exr", 0, "out/shot.0000.exr");
    check_frame("a.#.exr", 7, "a.7.exr");
    check_frame("a.#.exr", 42, "a.42.exr");
    check_frame("x.####.exr", 12345, "x.12345.exr");
    check_frame("x.####.exr", -12, "x.-012.exr");
    check_frame("x.#.exr", -3, "x.-3.exr");
    /* Only the last run of '#' is replaced. */
    check_frame("a##/b.###.exr", 5, "a##/b.005.exr");
    /* No '#': ".####" goes before the extension, or at the end without one. */
    check_frame("a/b.exr", 12, "a/b.0012.exr");
    check_frame("a/b", 3, "a/b.0003");
    check_frame("a.d/b", 3, "a.d/b.0003");
    check_frame("a/.hidden", 3, "a/.hidden.0003");

    char small[8];
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_io_frame_path("out/shot.####.exr", 1, small, sizeof(small), &err),
                     RB_E_OVERFLOW);
    assert_non_null(strstr(err.msg, "'out/shot.####.exr'"));
    assert_int_equal(rb_io_frame_path("", 1, small, sizeof(small), &err), RB_E_INVALID);
}

static void test_sidecar_path(void **state)
{
    (void)state;
    char out[256];
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_io_sidecar_path("a/shot.0012.exr", ".timing.json", out, sizeof(out), &err),
                     RB_OK);
    assert_string_equal(out, "a/shot.0012.timing.json");
    assert_int_equal(rb_io_sidecar_path("a.b/shot", ".hits.exr", out, sizeof(out), &err), RB_OK);
    assert_string_equal(out, "a.b/shot.hits.exr");
    assert_int_equal(rb_io_sidecar_path("shot.0001.exr", ".png", out, sizeof(out), &err), RB_OK);
    assert_string_equal(out, "shot.0001.png");

    char small[10];
    assert_int_equal(
        rb_io_sidecar_path("a/shot.0012.exr", ".timing.json", small, sizeof(small), &err),
        RB_E_OVERFLOW);
    assert_non_null(strstr(err.msg, "'a/shot.0012.exr'"));
}

static void test_make_parent_dirs(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    const char *file = tpath("mk/x//y/z/frame.exr");
    assert_int_equal(rb_io_make_parent_dirs(file, &err), RB_OK);
    struct stat st;
    assert_int_equal(stat(tpath("mk/x/y/z"), &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    /* Existing directories are fine. */
    assert_int_equal(rb_io_make_parent_dirs(file, &err), RB_OK);
    /* A file where a directory should be is an error that names it. */
    spit(tpath("mk/plain"), "x", 1);
    assert_int_equal(rb_io_make_parent_dirs(tpath("mk/plain/sub/f.exr"), &err), RB_E_IO);
    assert_non_null(strstr(err.msg, "mk/plain'"));
    assert_non_null(strstr(err.msg, strerror(ENOTDIR)));
    /* No directory part: nothing to do. */
    assert_int_equal(rb_io_make_parent_dirs("frame.exr", &err), RB_OK);
}

static void test_write_atomic(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    const char *dir = tpath("atomic");
    assert_int_equal(mkdir(dir, 0777), 0);
    const char *file = tpath("atomic/a.txt");

    assert_int_equal(rb_io_write_atomic(file, "hello world", 11, &err), RB_OK);
    size_t n;
    char *s = slurp(file, &n);
    assert_int_equal(n, 11);
    assert_memory_equal(s, "hello world", 11);
    free(s);

    /* Replaces an existing file completely (shorter content, no leftover bytes). */
    assert_int_equal(rb_io_write_atomic(file, "bye", 3, &err), RB_OK);
    s = slurp(file, &n);
    assert_int_equal(n, 3);
    assert_memory_equal(s, "bye", 3);
    free(s);
    assert_int_equal(count_entries(dir, ".tmp."), 0);
    assert_int_equal(count_entries(dir, "a.txt"), 1);

    /* A missing directory: an error naming the path, and no temporary left behind. */
    const char *bad = tpath("atomic/missing/b.txt");
    assert_int_equal(rb_io_write_atomic(bad, "x", 1, &err), RB_E_IO);
    char want[1200];
    snprintf(want, sizeof(want), "cannot write '%s': %s", bad, strerror(ENOENT));
    assert_string_equal(err.msg, want);
    assert_int_equal(count_entries(dir, ".tmp."), 0);
}

/* ---- EXR -------------------------------------------------------------------------------- */

#define W 7
#define H 5
#define NPX (W * H)

static float beauty[NPX * 4], direct[NPX * 3], normal[NPX * 3], depth[NPX], motion[NPX * 2];

static const char *const rgba_names[] = {"R", "G", "B", "A"};
static const char *const rgb_names[] = {"R", "G", "B"};
static const char *const xyz_names[] = {"X", "Y", "Z"};
static const char *const z_names[] = {"Z"};
static const char *const xy_names[] = {"X", "Y"};

/* Distinct, non-round float values per layer, channel and pixel; motion is stored as half, so
 * its values are multiples of 1/4 below 64, which half represents exactly. */
static void fill_layers(void)
{
    for (int p = 0; p < NPX; p++) {
        for (int c = 0; c < 4; c++)
            beauty[p * 4 + c] = 0.1f * (float)p + (float)c / 3.0f;
        for (int c = 0; c < 3; c++) {
            direct[p * 3 + c] = 10.0f + (float)p / 7.0f + 0.01f * (float)c;
            normal[p * 3 + c] = -1.0f + 0.05f * (float)p + 0.3f * (float)c;
        }
        depth[p] = 1000.0f / (float)(p + 3);
        motion[p * 2 + 0] = 0.25f * (float)p;
        motion[p * 2 + 1] = -0.25f * (float)p - 0.5f;
    }
}

static const float w2c[16] = {1, 0.5f, 0, 0, 0, 1, 0.25f, 0, 0, 0, 1, 0, -3.5f, 2, 7.25f, 1};

static enum rb_status write_test_exr(const char *path, struct rb_err *err)
{
    const struct rb_io_layer layers[] = {
        {.name = "direct", .channel_count = 3, .channel_names = rgb_names, .pixels = direct},
        {.name = NULL, .channel_count = 4, .channel_names = rgba_names, .pixels = beauty},
        {.name = "normal", .channel_count = 3, .channel_names = xyz_names, .pixels = normal},
        {.name = "depth", .channel_count = 1, .channel_names = z_names, .pixels = depth},
        {.name = "motion",
         .channel_count = 2,
         .channel_names = xy_names,
         .pixels = motion,
         .is_half = true},
    };
    struct rb_io_attr attrs[] = {
        {.name = "raybundle/integrator", .type = RB_IO_ATTR_STRING, .s = "bdpt"},
        {.name = "raybundle/frame", .type = RB_IO_ATTR_INT, .i = 12},
        {.name = "raybundle/time_s", .type = RB_IO_ATTR_FLOAT, .f = 0.5f},
        {.name = "worldToCamera", .type = RB_IO_ATTR_M44},
    };
    memcpy(attrs[3].m, w2c, sizeof(w2c));
    return rb_io_exr_write(path, W, H, layers, sizeof(layers) / sizeof(layers[0]), attrs,
                           sizeof(attrs) / sizeof(attrs[0]), err);
}

static void check_channel(const struct rb_io_image *img, const char *name, const float *src,
                          int stride, int c)
{
    int idx = rb_io_image_channel(img, name);
    if (idx < 0)
        fail_msg("channel '%s' missing", name);
    for (int p = 0; p < NPX; p++) {
        float got = img->pixels[(size_t)p * img->channel_count + (size_t)idx];
        float want = src[p * stride + c];
        if (memcmp(&got, &want, sizeof(float)) != 0)
            fail_msg("channel '%s' pixel %d: got %.9g, want %.9g", name, p, got, want);
    }
}

/* One attribute of an EXR header, found by walking the raw bytes (independent of OIIO's
 * renaming): magic, version, then name\0 type\0 int32 size, data ... until an empty name. */
static bool exr_header_attr(const char *buf, size_t n, const char *name, const char **type,
                            const unsigned char **data, int32_t *size)
{
    size_t i = 8;
    assert_true(n > 8 && (unsigned char)buf[0] == 0x76 && buf[1] == 0x2f && buf[2] == 0x31);
    while (i < n && buf[i]) {
        const char *an = buf + i;
        i += strlen(an) + 1;
        const char *at = buf + i;
        i += strlen(at) + 1;
        int32_t sz;
        memcpy(&sz, buf + i, 4);
        i += 4;
        if (!strcmp(an, name)) {
            *type = at;
            *data = (const unsigned char *)buf + i;
            *size = sz;
            return true;
        }
        i += (size_t)sz;
    }
    return false;
}

static void test_exr_roundtrip(void **state)
{
    (void)state;
    fill_layers();
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("rt/shot.0012.exr");
    assert_int_equal(rb_io_make_parent_dirs(path, &err), RB_OK);
    if (write_test_exr(path, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(count_entries(tpath("rt"), ".tmp."), 0);

    struct rb_io_image img = {0};
    if (rb_io_image_read(path, &img, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(img.width_px, W);
    assert_int_equal(img.height_px, H);
    assert_int_equal(img.channel_count, 4 + 3 + 3 + 1 + 2);
    /* The beauty comes first. */
    assert_string_equal(img.channel_names[0], "R");
    assert_string_equal(img.channel_names[3], "A");
    for (int c = 0; c < 4; c++)
        check_channel(&img, rgba_names[c], beauty, 4, c);
    check_channel(&img, "direct.R", direct, 3, 0);
    check_channel(&img, "direct.G", direct, 3, 1);
    check_channel(&img, "direct.B", direct, 3, 2);
    check_channel(&img, "normal.X", normal, 3, 0);
    check_channel(&img, "normal.Y", normal, 3, 1);
    check_channel(&img, "normal.Z", normal, 3, 2);
    check_channel(&img, "depth.Z", depth, 1, 0);
    check_channel(&img, "motion.X", motion, 2, 0);
    check_channel(&img, "motion.Y", motion, 2, 1);
    assert_int_equal(rb_io_image_channel(&img, "direct.A"), -1);
    rb_io_image_release(&img);
    assert_null(img.pixels);

    char v[512];
    assert_true(rb_io_image_attr(path, "raybundle/integrator", v, sizeof(v)));
    assert_string_equal(v, "bdpt");
    assert_true(rb_io_image_attr(path, "raybundle/frame", v, sizeof(v)));
    assert_string_equal(v, "12");
    assert_true(rb_io_image_attr(path, "raybundle/time_s", v, sizeof(v)));
    assert_string_equal(v, "0.5");
    assert_true(rb_io_image_attr(path, "software", v, sizeof(v)));
    assert_string_equal(v, "raybundle " RB_VERSION);
    assert_false(rb_io_image_attr(path, "raybundle/missing", v, sizeof(v)));

    /* The header as OpenEXR stores it. */
    size_t n;
    char *buf = slurp(path, &n);
    const char *type;
    const unsigned char *data;
    int32_t size;
    assert_true(exr_header_attr(buf, n, "chromaticities", &type, &data, &size));
    assert_string_equal(type, "chromaticities");
    assert_int_equal(size, 32);
    const float want_chroma[8] = {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f};
    assert_memory_equal(data, want_chroma, sizeof(want_chroma));
    assert_true(exr_header_attr(buf, n, "worldToCamera", &type, &data, &size));
    assert_string_equal(type, "m44f");
    assert_int_equal(size, 64);
    assert_memory_equal(data, w2c, sizeof(w2c));
    assert_true(exr_header_attr(buf, n, "raybundle/frame", &type, &data, &size));
    assert_string_equal(type, "int");
    assert_true(exr_header_attr(buf, n, "compression", &type, &data, &size));
    assert_string_equal(type, "compression");
    assert_int_equal(data[0], 3); /* ZIP_COMPRESSION */
    assert_true(exr_header_attr(buf, n, "channels", &type, &data, &size));
    assert_string_equal(type, "chlist");
    /* Nothing time-dependent. */
    assert_false(exr_header_attr(buf, n, "capDate", &type, &data, &size));
    assert_false(exr_header_attr(buf, n, "utcOffset", &type, &data, &size));
    assert_false(exr_header_attr(buf, n, "DateTime", &type, &data, &size));
    free(buf);
}

/* The value of the named attribute in a, or NULL. */
static const char *attr_value(const struct rb_io_image_attrs *a, const char *name)
{
    for (size_t i = 0; i < a->count; i++)
        if (!strcmp(a->names[i], name))
            return a->values[i];
    return NULL;
}

/* Every header attribute listed as text, OpenEXR's required ones too; an image without a
 * header to list lists nothing; a missing file fails naming it. */
static void test_image_attrs(void **state)
{
    (void)state;
    fill_layers();
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("attrs.exr");
    if (write_test_exr(path, &err))
        fail_msg("%s", err.msg);
    struct rb_io_image_attrs a = {0};
    assert_int_equal(rb_io_image_attrs_read(path, &a, &err), RB_OK);
    assert_string_equal(attr_value(&a, "raybundle/integrator"), "bdpt");
    assert_string_equal(attr_value(&a, "raybundle/frame"), "12");
    assert_string_equal(attr_value(&a, "raybundle/time_s"), "0.5");
    assert_string_equal(attr_value(&a, "software"), "raybundle " RB_VERSION);
    assert_string_equal(attr_value(&a, "worldToCamera"),
                        "1, 0.5, 0, 0, 0, 1, 0.25, 0, 0, 0, 1, 0, -3.5, 2, 7.25, 1");
    assert_string_equal(attr_value(&a, "compression"), "zip");
    assert_string_equal(attr_value(&a, "lineOrder"), "increasing y");
    assert_string_equal(attr_value(&a, "dataWindow"), "0, 0, 6, 4");
    assert_string_equal(attr_value(&a, "channels"), "(chlist)");
    assert_null(attr_value(&a, "raybundle/missing"));
    /* In the header's order: by name. */
    for (size_t i = 1; i < a.count; i++)
        assert_true(strcmp(a.names[i - 1], a.names[i]) < 0);
    rb_io_image_attrs_release(&a);
    assert_int_equal(a.count, 0);
    assert_null(a.names);

    const char *png = tpath("attrs.png");
    assert_int_equal(
        rb_io_preview_write(png, 2, 2,
                            (const float[16]){0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1},
                            &(struct rb_io_color_desc){.config = CONFIG}, &err),
        RB_OK);
    assert_int_equal(rb_io_image_attrs_read(png, &a, &err), RB_OK);
    assert_int_equal(a.count, 0);
    rb_io_image_attrs_release(&a);

    const char *missing = tpath("no-such.exr");
    assert_int_equal(rb_io_image_attrs_read(missing, &a, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, missing));
    rb_io_image_attrs_release(&a);
    /* A file that starts as an EXR but is not one fails, naming it. */
    const char *torn = tpath("torn.exr");
    spit(torn, "\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    assert_int_equal(rb_io_image_attrs_read(torn, &a, &err), RB_E_EXTERNAL);
    assert_non_null(strstr(err.msg, torn));
    rb_io_image_attrs_release(&a);
}

/* Channels grouped into layers: the beauty, then raybundle's layers in their order, then the
 * others in the order of the channels; a channel's base name. */
static void test_image_layers(void **state)
{
    (void)state;
    char *names[] = {"R",        "G",        "B",     "A",      "depth.Z",  "zeta.X",
                     "direct.R", "direct.G", "a.b.Y", "zeta.Y", "direct.B", "normal.X"};
    struct rb_io_image img = {
        .width_px = 1, .height_px = 1, .channel_count = 12, .channel_names = names};
    struct rb_io_image_layers l = {0};
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_io_image_layers_init(&l, &img, &err), RB_OK);
    assert_int_equal(l.count, 6);
    const char *want_names[] = {"beauty", "direct", "normal", "depth", "zeta", "a.b"};
    const uint32_t want_counts[] = {4, 3, 1, 1, 2, 1};
    for (size_t i = 0; i < 6; i++) {
        assert_string_equal(l.layers[i].name, want_names[i]);
        assert_int_equal(l.layers[i].channel_count, want_counts[i]);
    }
    assert_int_equal(l.layers[1].channels[0], 6);
    assert_int_equal(l.layers[1].channels[2], 10);
    assert_int_equal(l.layers[4].channels[1], 9);
    assert_string_equal(rb_io_channel_base(names[l.layers[5].channels[0]]), "Y");
    assert_string_equal(rb_io_channel_base("R"), "R");
    assert_string_equal(rb_io_channel_base("normal.X"), "X");
    rb_io_image_layers_release(&l);
    assert_int_equal(l.count, 0);
    /* No channel without a '.': no beauty. */
    img.channel_names = names + 4;
    img.channel_count = 2;
    assert_int_equal(rb_io_image_layers_init(&l, &img, &err), RB_OK);
    assert_int_equal(l.count, 2);
    assert_string_equal(l.layers[0].name, "depth");
    assert_string_equal(l.layers[1].name, "zeta");
    rb_io_image_layers_release(&l);
}

static void test_exr_deterministic(void **state)
{
    (void)state;
    fill_layers();
    struct rb_err err = RB_ERR_INIT;
    const char *a = tpath("det_a.exr"), *b = tpath("det_b.exr");
    if (write_test_exr(a, &err))
        fail_msg("%s", err.msg);
    /* Past a second boundary, so a timestamp would differ. */
    nanosleep(&(struct timespec){.tv_sec = 1, .tv_nsec = 100 * 1000 * 1000}, NULL);
    if (write_test_exr(b, &err))
        fail_msg("%s", err.msg);
    size_t na, nb;
    char *da = slurp(a, &na), *db = slurp(b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(da, db, na);
    free(da);
    free(db);
}

static void test_exr_errors(void **state)
{
    (void)state;
    fill_layers();
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("errs.exr");
    const struct rb_io_layer dup[] = {
        {.name = "direct", .channel_count = 3, .channel_names = rgb_names, .pixels = direct},
        {.name = "direct", .channel_count = 1, .channel_names = z_names, .pixels = depth},
        {.name = "direct", .channel_count = 1, .channel_names = rgb_names, .pixels = depth},
    };
    assert_int_equal(rb_io_exr_write(path, W, H, dup, 3, NULL, 0, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "'direct.R' appears twice"));
    const struct rb_io_layer five = {
        .name = "x", .channel_count = 5, .channel_names = rgba_names, .pixels = beauty};
    assert_int_equal(rb_io_exr_write(path, W, H, &five, 1, NULL, 0, &err), RB_E_INVALID);
    assert_int_equal(rb_io_exr_write(path, 0, H, dup, 1, NULL, 0, &err), RB_E_INVALID);
    assert_false(exists(path));

    /* Into a missing directory: the library's failure, naming our path; no temporary. */
    const char *bad = tpath("nodir/x.exr");
    assert_int_equal(write_test_exr(bad, &err), RB_E_EXTERNAL);
    assert_non_null(strstr(err.msg, bad));
    assert_int_equal(count_entries(tmpdir, ".tmp."), 0);
}

static void test_is_complete(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    /* Big enough for several ZIP chunks, so half the bytes cut through pixel data. */
    enum { BW = 64, BH = 48 };
    float *px = malloc(sizeof(float) * BW * BH * 4);
    assert_non_null(px);
    for (int i = 0; i < BW * BH * 4; i++)
        px[i] = sinf((float)i * 0.37f) * 100.0f;
    const struct rb_io_layer layer = {.channel_count = 4, .pixels = px};
    const char *full = tpath("complete.exr"), *half = tpath("truncated.exr");
    if (rb_io_exr_write(full, BW, BH, &layer, 1, NULL, 0, &err))
        fail_msg("%s", err.msg);
    free(px);
    assert_true(rb_io_image_is_complete(full));

    size_t n;
    char *buf = slurp(full, &n);
    spit(half, buf, n / 2);
    free(buf);
    assert_false(rb_io_image_is_complete(half));
    struct rb_io_image img = {0};
    assert_int_not_equal(rb_io_image_read(half, &img, &err), RB_OK);
    assert_null(img.pixels);

    assert_false(rb_io_image_is_complete(tpath("missing.exr")));
    assert_int_equal(rb_io_image_read(tpath("missing.exr"), &img, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, "missing.exr'"));
    assert_non_null(strstr(err.msg, strerror(ENOENT)));

    spit(tpath("text.exr"), "not an image\n", 13);
    assert_false(rb_io_image_is_complete(tpath("text.exr")));
    assert_false(rb_io_image_is_complete(tmpdir)); /* a directory */
}

/* ---- preview ---------------------------------------------------------------------------- */

/* 8-bit value at (x, y), channel c, read back from a PNG written by the preview. */
static int png_value(const struct rb_io_image *img, uint32_t x, uint32_t y, uint32_t c)
{
    return (int)lroundf(img->pixels[((size_t)y * img->width_px + x) * img->channel_count + c] *
                        255.0f);
}

static void test_preview(void **state)
{
    (void)state;
    enum { PW = 16, PH = 2 };
    float px[PW * PH * 4];
    /* Row 0: a gradient 0..1; row 1: 0.18 grey, premultiplied grey at alpha 0.5, 4.0. */
    for (int x = 0; x < PW; x++) {
        for (int c = 0; c < 3; c++) {
            px[x * 4 + c] = (float)x / (PW - 1);
            px[(PW + x) * 4 + c] = 0.18f;
        }
        px[x * 4 + 3] = 1.0f;
        px[(PW + x) * 4 + 3] = 1.0f;
    }
    for (int c = 0; c < 3; c++) {
        px[(PW + 1) * 4 + c] = 0.09f;
        px[(PW + 2) * 4 + c] = 4.0f;
    }
    px[(PW + 1) * 4 + 3] = 0.5f;

    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("preview/shot.0001.png");
    assert_int_equal(rb_io_make_parent_dirs(path, &err), RB_OK);
    if (rb_io_preview_write(path, PW, PH, px,
                            &(struct rb_io_color_desc){.config = CONFIG, .view = "Standard"}, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(count_entries(tpath("preview"), ".tmp."), 0);

    struct rb_io_image img = {0};
    if (rb_io_image_read(path, &img, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(img.width_px, PW);
    assert_int_equal(img.height_px, PH);
    assert_int_equal(img.channel_count, 4);
    assert_int_equal(png_value(&img, 0, 0, 0), 0);
    assert_int_equal(png_value(&img, PW - 1, 0, 0), 255);
    for (int x = 1; x < PW; x++)
        assert_true(png_value(&img, (uint32_t)x, 0, 1) > png_value(&img, (uint32_t)x - 1, 0, 1));
    /* Mid-grey through the sRGB curve: 0.18 -> 0.4614 -> 118. */
    int g = png_value(&img, 0, 1, 0);
    if (g < 116 || g > 120)
        fail_msg("0.18 maps to %d, want 118 +- 2", g);
    assert_int_equal(png_value(&img, 0, 1, 3), 255);
    /* Premultiplied 0.09 at alpha 0.5 is 0.18 grey, stored unassociated. */
    assert_int_equal(png_value(&img, 1, 1, 0), g);
    assert_int_equal(png_value(&img, 1, 1, 3), 128);
    /* Over-range clamps. */
    assert_int_equal(png_value(&img, 2, 1, 2), 255);
    rb_io_image_release(&img);

    /* Raw passes values through; the ACES view tone-maps (darker mid-grey, 4.0 below white). */
    const char *raw = tpath("preview/raw.png"), *aces = tpath("preview/aces.png");
    if (rb_io_preview_write(raw, PW, PH, px,
                            &(struct rb_io_color_desc){.config = CONFIG, .view = "Raw"}, &err))
        fail_msg("%s", err.msg);
    if (rb_io_image_read(raw, &img, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(png_value(&img, 0, 1, 0), 46); /* 0.18 * 255 */
    rb_io_image_release(&img);
    if (rb_io_preview_write(aces, PW, PH, px,
                            &(struct rb_io_color_desc){.config = CONFIG,
                                                       .display = "sRGB",
                                                       .view = "ACES 1.0 - SDR Video"},
                            &err))
        fail_msg("%s", err.msg);
    if (rb_io_image_read(aces, &img, &err))
        fail_msg("%s", err.msg);
    int ag = png_value(&img, 0, 1, 0), a4 = png_value(&img, 2, 1, 0);
    if (!(ag > 46 && ag < g && a4 > ag && a4 < 255))
        fail_msg("ACES view: 0.18 -> %d, 4.0 -> %d", ag, a4);
    rb_io_image_release(&img);

    /* No view named: the display's default, the ACES view (Standard clips high dynamic range). */
    const char *plain = tpath("preview/default.png");
    if (rb_io_preview_write(plain, PW, PH, px, &(struct rb_io_color_desc){.config = CONFIG}, &err))
        fail_msg("%s", err.msg);
    if (rb_io_image_read(plain, &img, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(png_value(&img, 0, 1, 0), ag);
    assert_int_equal(png_value(&img, 2, 1, 0), a4);
    rb_io_image_release(&img);
}

static void test_preview_errors(void **state)
{
    (void)state;
    float px[4] = {0.5f, 0.5f, 0.5f, 1.0f};
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("bad_preview.png");

    assert_int_equal(rb_io_preview_write(
                         path, 1, 1, px,
                         &(struct rb_io_color_desc){.config = CONFIG, .display = "Cinema"}, &err),
                     RB_E_INVALID);
    assert_string_equal(err.msg,
                        "ocio: display 'Cinema' not found in config '" CONFIG "' (has: sRGB)");

    assert_int_equal(
        rb_io_preview_write(path, 1, 1, px,
                            &(struct rb_io_color_desc){.config = CONFIG, .view = "Filmic"}, &err),
        RB_E_INVALID);
    assert_non_null(strstr(err.msg, "view 'Filmic'"));
    assert_non_null(strstr(err.msg, "ACES 1.0 - SDR Video, Standard, Raw"));

    const char *missing = tpath("nope/config.ocio");
    assert_int_equal(
        rb_io_preview_write(path, 1, 1, px, &(struct rb_io_color_desc){.config = missing}, &err),
        RB_E_IO);
    assert_non_null(strstr(err.msg, missing));

    /* A config that does not parse: OCIO's error, naming the file. */
    const char *broken = tpath("broken.ocio");
    spit(broken, "ocio_profile_version: 2\nroles: [\n", 33);
    assert_int_equal(
        rb_io_preview_write(path, 1, 1, px, &(struct rb_io_color_desc){.config = broken}, &err),
        RB_E_EXTERNAL);
    assert_non_null(strstr(err.msg, broken));
    assert_false(exists(path));
}

static void test_default_config(void **state)
{
    (void)state;
    char *saved = rb_strdup(getenv("RB_DATADIR"));
    char *saved_ocio = rb_strdup(getenv("OCIO"));

    assert_int_equal(setenv("RB_DATADIR", "share", 1), 0);
    assert_string_equal(rb_io_default_ocio_config(), "share/ocio/config.ocio");
    /* A datadir without a config falls through to the other places. */
    assert_int_equal(setenv("RB_DATADIR", tmpdir, 1), 0);
    const char *d = rb_io_default_ocio_config();
    assert_null(strstr(d, tmpdir));
    size_t n = strlen(d), m = strlen("/ocio/config.ocio");
    assert_true(n > m && !strcmp(d + n - m, "/ocio/config.ocio"));

    /* With no config in the desc, $OCIO is used. */
    assert_int_equal(setenv("OCIO", CONFIG, 1), 0);
    float px[4] = {0.18f, 0.18f, 0.18f, 1.0f};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_preview_write(tpath("env.png"), 1, 1, px, NULL, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(setenv("OCIO", tpath("no-such.ocio"), 1), 0);
    assert_int_equal(rb_io_preview_write(tpath("env2.png"), 1, 1, px, NULL, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, "no-such.ocio"));

    if (saved)
        setenv("RB_DATADIR", saved, 1);
    else
        unsetenv("RB_DATADIR");
    if (saved_ocio)
        setenv("OCIO", saved_ocio, 1);
    else
        unsetenv("OCIO");
    free(saved);
    free(saved_ocio);
}

/* ---- timing ----------------------------------------------------------------------------- */

static void test_timing_json(void **state)
{
    (void)state;
    const struct rb_pass_time passes[] = {{"gbuffer", 1.25, 0.0, 1}, {"shadow", 0.5, 0.0, 6}};
    const struct rb_io_timing t = {
        .frame = 12,
        .time_s = 0.5,
        .passes = passes,
        .pass_count = 2,
        .wall_ms = 40.1,
        .device = "llvmpipe (LLVM 15.0.6, 256 bits)",
        .driver = "Mesa 22.3.6",
        .integrator = "bdpt",
        .width_px = 640,
        .height_px = 360,
        .nonfinite_count = 6,
    };
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("shot.0012.timing.json");
    if (rb_io_timing_write(path, &t, &err))
        fail_msg("%s", err.msg);
    char *s = slurp(path, NULL);
    assert_string_equal(s, "{\n"
                           "  \"frame\": 12,\n"
                           "  \"time_s\": 0.5,\n"
                           "  \"passes\": [\n"
                           "    {\"name\": \"gbuffer\", \"gpu_ms\": 1.25, \"count\": 1},\n"
                           "    {\"name\": \"shadow\", \"gpu_ms\": 0.5, \"count\": 6}\n"
                           "  ],\n"
                           "  \"wall_ms\": 40.1,\n"
                           "  \"gpu_total_ms\": 1.75,\n"
                           "  \"device\": \"llvmpipe (LLVM 15.0.6, 256 bits)\",\n"
                           "  \"driver\": \"Mesa 22.3.6\",\n"
                           "  \"integrator\": \"bdpt\",\n"
                           "  \"width\": 640,\n"
                           "  \"height\": 360,\n"
                           "  \"nonfinite\": 6\n"
                           "}\n");
    free(s);
    assert_int_equal(count_entries(tmpdir, ".tmp."), 0);
}

static void test_timing_escapes(void **state)
{
    (void)state;
    /* 0.1 + 0.2 needs 17 digits to read back; NaN and infinity are not JSON. */
    const struct rb_pass_time passes[] = {{"a\"b", 0.1, 0.0, 1}, {"c", 0.2, 0.0, 1}};
    const struct rb_io_timing t = {
        .frame = -3,
        .time_s = INFINITY,
        .passes = passes,
        .pass_count = 2,
        .wall_ms = NAN,
        .device = "GPU \"X\" \\ tab\there\nline\x01",
        .driver = NULL,
        .integrator = "direct",
    };
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("esc.timing.json");
    if (rb_io_timing_write(path, &t, &err))
        fail_msg("%s", err.msg);
    char *s = slurp(path, NULL);
    assert_string_equal(s, "{\n"
                           "  \"frame\": -3,\n"
                           "  \"time_s\": null,\n"
                           "  \"passes\": [\n"
                           "    {\"name\": \"a\\\"b\", \"gpu_ms\": 0.1, \"count\": 1},\n"
                           "    {\"name\": \"c\", \"gpu_ms\": 0.2, \"count\": 1}\n"
                           "  ],\n"
                           "  \"wall_ms\": null,\n"
                           "  \"gpu_total_ms\": 0.30000000000000004,\n"
                           "  \"device\": \"GPU \\\"X\\\" \\\\ tab\\there\\nline\\u0001\",\n"
                           "  \"driver\": null,\n"
                           "  \"integrator\": \"direct\",\n"
                           "  \"width\": 0,\n"
                           "  \"height\": 0,\n"
                           "  \"nonfinite\": 0\n"
                           "}\n");
    free(s);

    const struct rb_io_timing none = {.frame = 1, .integrator = "direct"};
    if (rb_io_timing_write(path, &none, &err))
        fail_msg("%s", err.msg);
    s = slurp(path, NULL);
    assert_non_null(strstr(s, "  \"passes\": [],\n"));
    assert_non_null(strstr(s, "  \"gpu_total_ms\": 0,\n"));
    free(s);

    const struct rb_io_timing bad = {.pass_count = 1};
    assert_int_equal(rb_io_timing_write(path, &bad, &err), RB_E_INVALID);
}

/* The hybrid's ray counts at their widest (each near 2^64: sums over many frames' worth of rays
 * would not reach it, but no field may be cut), then the screen check, written only when on. */
static void test_timing_ray_counts(void **state)
{
    (void)state;
    struct rb_ray_counts c = {.requested = UINT64_MAX,
                              .screen_hits = UINT64_MAX - 1,
                              .queued = UINT64_MAX - 2,
                              .bvh_hits = UINT64_MAX - 3,
                              .misses = UINT64_MAX - 4,
                              .dropped = UINT64_MAX - 5};
    struct rb_io_timing t = {.frame = 1, .integrator = "hybrid", .ray_counts = &c};
    struct rb_err err = RB_ERR_INIT;
    const char *path = tpath("rays.timing.json");
    if (rb_io_timing_write(path, &t, &err))
        fail_msg("%s", err.msg);
    char *s = slurp(path, NULL);
    assert_non_null(strstr(s, "  \"ray_counts\": {\"requested\": 18446744073709551615, "
                              "\"screen_hits\": 18446744073709551614, "
                              "\"queued\": 18446744073709551613, "
                              "\"bvh_hits\": 18446744073709551612, "
                              "\"misses\": 18446744073709551611, "
                              "\"dropped\": 18446744073709551610}"));
    assert_null(strstr(s, "screen_check"));
    free(s);
    c.has_check = true;
    c.screen_checked = 13282;
    c.screen_agreed = 12865;
    if (rb_io_timing_write(path, &t, &err))
        fail_msg("%s", err.msg);
    s = slurp(path, NULL);
    assert_non_null(strstr(s, "\"dropped\": 18446744073709551610},\n"
                              "  \"screen_check\": {\"checked\": 13282, \"agreed\": 12865}"));
    free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_path),       cmocka_unit_test(test_sidecar_path),
        cmocka_unit_test(test_make_parent_dirs), cmocka_unit_test(test_write_atomic),
        cmocka_unit_test(test_exr_roundtrip),    cmocka_unit_test(test_image_attrs),
        cmocka_unit_test(test_image_layers),     cmocka_unit_test(test_exr_deterministic),
        cmocka_unit_test(test_exr_errors),       cmocka_unit_test(test_is_complete),
        cmocka_unit_test(test_preview),          cmocka_unit_test(test_preview_errors),
        cmocka_unit_test(test_default_config),   cmocka_unit_test(test_timing_json),
        cmocka_unit_test(test_timing_escapes),   cmocka_unit_test(test_timing_ray_counts),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
