/* lib/core: error messages and their context, string helpers, FNV-1a, reading files, logging. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "core/core.h"
#include "shared.h"

static void test_errf_and_prefix(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_errf(&err, RB_E_IO, "cannot open '%s': %s", "a.exr", "No such file"),
                     RB_E_IO);
    assert_int_equal(err.status, RB_E_IO);
    assert_string_equal(err.msg, "cannot open 'a.exr': No such file");
    rb_err_prefix(&err, "frame %d", 12);
    assert_string_equal(err.msg, "frame 12: cannot open 'a.exr': No such file");
    /* NULL err is allowed: the status still comes back. */
    assert_int_equal(rb_errf(NULL, RB_E_PARSE, "x"), RB_E_PARSE);
    rb_err_prefix(NULL, "ignored");
    /* A message longer than the buffer is cut, never overrun, and stays terminated. */
    char long_text[2048];
    memset(long_text, 'x', sizeof(long_text) - 1);
    long_text[sizeof(long_text) - 1] = '\0';
    rb_errf(&err, RB_E_INVALID, "%s", long_text);
    assert_int_equal(strlen(err.msg), sizeof(err.msg) - 1);
    rb_err_prefix(&err, "context");
    assert_int_equal(strlen(err.msg), sizeof(err.msg) - 1);
    assert_memory_equal(err.msg, "context: xxx", 12);
}

static void test_status_names(void **state)
{
    (void)state;
    for (int s = RB_OK; s <= RB_E_OVERFLOW; s++) {
        const char *name = rb_status_name((enum rb_status)s);
        assert_non_null(name);
        assert_string_not_equal(name, "unknown status");
    }
    assert_string_equal(rb_status_name((enum rb_status)999), "unknown status");
}

static void test_strings(void **state)
{
    (void)state;
    char buf[4];
    assert_int_equal(rb_strlcpy(buf, "abcdef", sizeof(buf)), 6);
    assert_string_equal(buf, "abc");
    assert_int_equal(rb_strlcpy(buf, "ab", sizeof(buf)), 2);
    assert_string_equal(buf, "ab");
    assert_null(rb_strdup(NULL));
    char *d = rb_strdup("raybundle");
    assert_string_equal(d, "raybundle");
    free(d);
}

static void test_hash(void **state)
{
    (void)state;
    /* FNV-1a 64 reference values: the empty string is the offset basis. */
    assert_true(rb_hash64("", 0, RB_HASH_SEED) == 0xcbf29ce484222325ull);
    assert_true(rb_hash64("a", 1, RB_HASH_SEED) == 0xaf63dc4c8601ec8cull);
    assert_true(rb_hash64("foobar", 6, RB_HASH_SEED) == 0x85944171f73967e8ull);
    /* Chaining equals hashing the concatenation. */
    uint64_t h = rb_hash64("foo", 3, RB_HASH_SEED);
    assert_true(rb_hash64("bar", 3, h) == rb_hash64("foobar", 6, RB_HASH_SEED));
}

static void test_read_file(void **state)
{
    (void)state;
    char path[] = "/tmp/rb-core-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    /* Larger than the first read block, with a NUL inside. */
    size_t n = 200000;
    char *data = malloc(n);
    for (size_t i = 0; i < n; i++)
        data[i] = (char)(i * 7);
    assert_int_equal(write(fd, data, n), (ssize_t)n);
    close(fd);
    char *got = NULL;
    size_t size = 0;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_read_file(path, &got, &size, &err), RB_OK);
    assert_int_equal(size, n);
    assert_memory_equal(got, data, n);
    assert_int_equal(got[n], '\0');
    free(got);
    free(data);
    unlink(path);
    assert_int_equal(rb_read_file(path, &got, &size, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, path));
}

static char logged[256];
static enum rb_log_level logged_level;

static void sink(enum rb_log_level level, const char *msg, void *user)
{
    (void)user;
    logged_level = level;
    rb_strlcpy(logged, msg, sizeof(logged));
}

static void test_log(void **state)
{
    (void)state;
    rb_log_set_sink(sink, NULL);
    enum rb_log_level old = rb_log_get_level();
    rb_log_set_level(RB_LOG_WARN);
    unsigned warnings = rb_log_warning_count();
    logged[0] = '\0';
    rb_log(RB_LOG_INFO, "hidden %d", 1);
    assert_string_equal(logged, "");
    rb_log(RB_LOG_WARN, "shown %d", 2);
    assert_string_equal(logged, "shown 2");
    assert_int_equal(logged_level, RB_LOG_WARN);
    assert_int_equal(rb_log_warning_count(), warnings + 1);
    rb_log_set_level(old);
    rb_log_set_sink(NULL, NULL);
}

/* The packed layout of a frame's layers: with every layer it is shaders' RB_OUT_* layout. */
static void test_layers(void **state)
{
    (void)state;
    static const uint32_t out[RB_LAYER_COUNT] = {
        RB_OUT_DIRECT,  RB_OUT_INDIRECT, RB_OUT_ALBEDO,           RB_OUT_NORMAL,
        RB_OUT_DEPTH,   RB_OUT_MOTION,   RB_OUT_INDIRECT_DIFFUSE, RB_OUT_INDIRECT_SPECULAR,
        RB_OUT_SAMPLES, RB_OUT_TILES,    RB_OUT_VARIANCE};
    for (uint32_t l = 0; l < RB_LAYER_COUNT; l++)
        assert_int_equal(rb_layer_offset(RB_LAYERS_ALL, (enum rb_layer)l), out[l]);
    assert_int_equal(rb_layer_stride(RB_LAYERS_ALL), RB_OUT_FLOATS);
    /* depth alone follows the beauty; a pixel stays a multiple of 16 bytes */
    uint32_t depth = 1u << RB_LAYER_DEPTH, dn = depth | 1u << RB_LAYER_NORMAL;
    assert_int_equal(rb_layer_offset(depth, RB_LAYER_DEPTH), 4);
    assert_int_equal(rb_layer_stride(depth), 8);
    assert_int_equal(rb_layer_offset(dn, RB_LAYER_NORMAL), 4);
    assert_int_equal(rb_layer_offset(dn, RB_LAYER_DEPTH), 7);
    assert_int_equal(rb_layer_stride(dn), 8);
    assert_int_equal(rb_layer_stride(0), 4);
    /* indirect's parts come last: the layers before them keep their offsets */
    uint32_t parts = 1u << RB_LAYER_INDIRECT_DIFFUSE | 1u << RB_LAYER_INDIRECT_SPECULAR;
    assert_int_equal(rb_layer_offset(parts | depth, RB_LAYER_DEPTH), 4);
    assert_int_equal(rb_layer_offset(parts | depth, RB_LAYER_INDIRECT_DIFFUSE), 5);
    assert_int_equal(rb_layer_offset(parts | depth, RB_LAYER_INDIRECT_SPECULAR), 8);
    assert_int_equal(rb_layer_stride(parts | depth), 12);
    assert_string_equal(rb_layer_name(RB_LAYER_INDIRECT_SPECULAR), "indirect_specular");
    assert_string_equal(rb_layer_name(RB_LAYER_MOTION), "motion");
    assert_null(rb_layer_name(RB_LAYER_COUNT));
    /* samples and tiles come after them: two channels each, one a lobe */
    uint32_t adaptive = 1u << RB_LAYER_SAMPLES | 1u << RB_LAYER_TILES;
    assert_int_equal(rb_layer_offset(adaptive | parts, RB_LAYER_INDIRECT_SPECULAR), 7);
    assert_int_equal(rb_layer_offset(adaptive | parts, RB_LAYER_SAMPLES), 10);
    assert_int_equal(rb_layer_offset(adaptive | parts, RB_LAYER_TILES), 12);
    assert_int_equal(rb_layer_stride(adaptive | parts), 16);
    assert_int_equal(rb_layer_stride(adaptive), 8);
    assert_string_equal(rb_layer_name(RB_LAYER_SAMPLES), "samples");
    assert_string_equal(rb_layer_name(RB_LAYER_TILES), "tiles");
    /* the EXR's channel names */
    assert_string_equal(rb_layer_channel(RB_LAYER_NORMAL, 2), "Z");
    assert_string_equal(rb_layer_channel(RB_LAYER_MOTION, 1), "Y");
    assert_null(rb_layer_channel(RB_LAYER_MOTION, 2));
    assert_string_equal(rb_layer_channel(RB_LAYER_SAMPLES, 0), "diffuse");
    assert_string_equal(rb_layer_channel(RB_LAYER_TILES, 1), "specular");
    assert_null(rb_layer_channel(RB_LAYER_TILES, 2));
    /* the reference's variance comes last: one channel, of luminance */
    uint32_t variance = 1u << RB_LAYER_VARIANCE;
    assert_int_equal(rb_layer_offset(variance | adaptive, RB_LAYER_VARIANCE), 8);
    assert_int_equal(rb_layer_stride(variance | adaptive), 12);
    assert_int_equal(rb_layer_offset(variance | depth, RB_LAYER_DEPTH), 4);
    assert_string_equal(rb_layer_name(RB_LAYER_VARIANCE), "variance");
    assert_string_equal(rb_layer_channel(RB_LAYER_VARIANCE, 0), "Y");
    assert_null(rb_layer_channel(RB_LAYER_VARIANCE, 1));
    assert_null(rb_layer_channel(RB_LAYER_COUNT, 0));
}

/* The oracle is the edit distance written out by hand for each pair. */
static void test_edit_distance(void **state)
{
    (void)state;
    struct {
        const char *a, *b;
        size_t d;
    } pairs[] = {
        {"render", "render", 0}, {"rendr", "render", 1},    {"preveiw", "preview", 1},
        {"bdtp", "bdpt", 1},     {"BDPT", "bdpt", 0},       {"", "abc", 3},
        {"abc", "", 3},          {"kitten", "sitting", 3},  {"ca", "abc", 3},
        {"nmae", "name", 1},     {"lights[]", "lights", 2},
    };
    for (size_t i = 0; i < sizeof(pairs) / sizeof(pairs[0]); i++) {
        size_t d = rb_edit_distance(pairs[i].a, strlen(pairs[i].a), pairs[i].b, strlen(pairs[i].b));
        if (d != pairs[i].d)
            fail_msg("'%s' to '%s': %zu edits, want %zu", pairs[i].a, pairs[i].b, d, pairs[i].d);
    }
    char longer[80];
    memset(longer, 'a', sizeof(longer));
    assert_int_equal(rb_edit_distance(longer, 65, "a", 1), SIZE_MAX);
    /* The length given is what counts, not the terminator. */
    assert_int_equal(rb_edit_distance("frames.start", 6, "frames", 6), 0);
}

static const char *nearest(const char *word, const char *const *names, size_t count)
{
    static struct rb_suggest s;
    rb_suggest_init(&s, word);
    for (size_t i = 0; i < count; i++)
        rb_suggest_offer(&s, names[i], strlen(names[i]));
    return s.best;
}

static void test_suggest(void **state)
{
    (void)state;
    const char *const commands[] = {"render", "reference", "compare", "bench",
                                    "timing", "flicker",   "report",  "info"};
    size_t n = sizeof(commands) / sizeof(commands[0]);
    assert_string_equal(nearest("rendr", commands, n), "render");
    assert_string_equal(nearest("refrence", commands, n), "reference");
    assert_string_equal(nearest("Render", commands, n), "render");
    assert_string_equal(nearest("ifno", commands, n), "info");
    assert_string_equal(nearest("frobnicate", commands, n), "");
    assert_string_equal(nearest("", commands, n), "");
    /* Two edits at most, and a third of the longer length at most: 'set' is not 'out'. */
    const char *const options[] = {"out", "output", "set", "size", "spp"};
    assert_string_equal(nearest("set", options + 0, 1), "");
    assert_string_equal(nearest("outptu", options, 5), "output");
    assert_string_equal(nearest("sze", options, 5), "size");
    assert_string_equal(nearest("xyz", options, 5), "");
    /* The nearest wins, and the first of equals. */
    const char *const names[] = {"direct", "bdpt", "hybrid", "reference"};
    assert_string_equal(nearest("bdtp", names, 4), "bdpt");
    const char *const equals[] = {"abce", "abcf"};
    assert_string_equal(nearest("abcd", equals, 2), "abce");
    /* A name too long for best is not offered. */
    char name[60];
    memset(name, 'n', sizeof(name) - 1);
    name[sizeof(name) - 1] = '\0';
    const char *const too_long[] = {name};
    assert_string_equal(nearest(name, too_long, 1), "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_errf_and_prefix), cmocka_unit_test(test_status_names),
        cmocka_unit_test(test_strings),         cmocka_unit_test(test_hash),
        cmocka_unit_test(test_read_file),       cmocka_unit_test(test_log),
        cmocka_unit_test(test_layers),          cmocka_unit_test(test_edit_distance),
        cmocka_unit_test(test_suggest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
