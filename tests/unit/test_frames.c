/* lib/render/frames.c: farm frame lists ("1-3,5,7-20:2"), --chunk I/N and a Slurm array task's
 * chunk. The oracle is membership written out (start <= f <= end, (f - start) % step == 0) over a
 * small universe of frames, not the iteration under test. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "render/render.h"

#define UNIVERSE 200 /* random lists use frames 0..UNIVERSE-1 */

/* The frames of f in iteration order into out (at most cap); returns how many. */
static size_t frames_of(const struct rb_render_frames *f, int *out, size_t cap)
{
    size_t n = 0;
    int frame;
    for (int64_t at = INT64_MIN; rb_render_frames_next(f, at, &frame); at = frame) {
        assert_true(n < cap);
        out[n++] = frame;
    }
    return n;
}

static void expect_list(const char *text, const int *want, size_t want_count)
{
    struct rb_render_frames f = RB_RENDER_FRAMES_INIT;
    struct rb_err err = RB_ERR_INIT;
    if (rb_render_frames_parse(&f, text, &err) != RB_OK)
        fail_msg("'%s': %s", text, err.msg);
    int got[64];
    size_t n = frames_of(&f, got, 64);
    assert_int_equal(n, want_count);
    assert_memory_equal(got, want, n * sizeof(int));
    assert_int_equal(rb_render_frames_count(&f), want_count);
    int first, last;
    assert_true(rb_render_frames_bounds(&f, &first, &last));
    assert_int_equal(first, want[0]);
    assert_int_equal(last, want[want_count - 1]);
    rb_render_frames_release(&f);
}

static void test_lists(void **state)
{
    (void)state;
    expect_list("1-10", (int[]){1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 10);
    expect_list("7", (int[]){7}, 1);
    expect_list("0", (int[]){0}, 1);
    expect_list("1-3,5,7-20:2", (int[]){1, 2, 3, 5, 7, 9, 11, 13, 15, 17, 19}, 11);
    /* Ascending, each frame once, whatever the order and overlaps of the entries. */
    expect_list("9,1-3,2", (int[]){1, 2, 3, 9}, 4);
    expect_list("0-12:4,2-6:2", (int[]){0, 2, 4, 6, 8, 12}, 6);
    expect_list(" 2 - 4 , 8 ", (int[]){2, 3, 4, 8}, 4);
    expect_list("5-5:3", (int[]){5}, 1);
    /* Deadline writes the step as "x": the same frames as ':'. */
    expect_list("1-10x2", (int[]){1, 3, 5, 7, 9}, 5);
    expect_list("1-10:2", (int[]){1, 3, 5, 7, 9}, 5);
    expect_list("0-12x4,2-6:2", (int[]){0, 2, 4, 6, 8, 12}, 6);
    expect_list(" 3 - 9 x 3 ", (int[]){3, 6, 9}, 3);
    expect_list("2147483646-2147483647", (int[]){2147483646, 2147483647}, 2);
}

static void expect_bad_list(const char *text, const char *msg)
{
    struct rb_render_frames f = RB_RENDER_FRAMES_INIT;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_render_frames_parse(&f, text, &err), RB_E_INVALID);
    if (!strstr(err.msg, msg))
        fail_msg("'%s': got \"%s\", want \"%s\"", text, err.msg, msg);
    assert_int_equal(f.range_count, 0); /* released */
    assert_null(f.ranges);
}

static void test_bad_lists(void **state)
{
    (void)state;
    expect_bad_list("", "an empty entry");
    expect_bad_list("1,,3", "an empty entry");
    expect_bad_list("1-3,", "an empty entry");
    expect_bad_list("1-3,x,5", "'x' is not a frame");
    expect_bad_list("-3", "'-3' is not a frame");
    expect_bad_list("2.5", "'2.5' is not a frame");
    expect_bad_list("0x10", "'0x10' is not a frame");
    expect_bad_list("1-2-3", "'1-2-3' is not a frame");
    expect_bad_list("1 0", "'1 0' is not a frame");
    expect_bad_list("1,5-2,7", "'5-2': the range ends before it starts");
    expect_bad_list("10-", "'10-': the range's end is not a whole number");
    expect_bad_list("1-10:0", "'1-10:0': the step must be 1 or more");
    expect_bad_list("1-10:", "'1-10:': the step is not a whole number");
    expect_bad_list("5:2", "'5:2': a step needs a range");
    expect_bad_list("1-10x0", "'1-10x0': the step must be 1 or more");
    expect_bad_list("1-10x", "'1-10x': the step is not a whole number");
    expect_bad_list("1-10X2", "'1-10X2' is not a frame");
    expect_bad_list("1-10x2x3", "'1-10x2x3' is not a frame");
    expect_bad_list("2147483648", "'2147483648' is not a frame");
}

/* A random list over the universe, as text, from the generator's state. */
static void random_list(uint64_t *rng, char *text, size_t size)
{
    size_t len = 0;
    int entries = 1 + (int)((*rng = *rng * 6364136223846793005u + 1442695040888963407u) >> 61);
    for (int e = 0; e < entries; e++) {
        *rng = *rng * 6364136223846793005u + 1442695040888963407u;
        uint32_t r = (uint32_t)(*rng >> 32);
        int a = (int)(r % UNIVERSE), b = a + (int)((r >> 8) % 40), step = 1 + (int)((r >> 16) % 4);
        if (b >= UNIVERSE)
            b = UNIVERSE - 1;
        const char *sep = e ? "," : "";
        switch ((r >> 24) % 3) {
        case 0: len += snprintf(text + len, size - len, "%s%d", sep, a); break;
        case 1: len += snprintf(text + len, size - len, "%s%d-%d", sep, a, b); break;
        default: /* the step after ':' or, as Deadline writes it, 'x' */
            len += snprintf(text + len, size - len, "%s%d-%d%c%d", sep, a, b,
                            (*rng >> 20) & 1 ? 'x' : ':', step);
            break;
        }
    }
}

/* Membership by the definition, from the text's entries parsed by sscanf. */
static void oracle(const char *text, bool *in)
{
    memset(in, 0, UNIVERSE * sizeof(*in));
    for (const char *p = text; p; p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL) {
        int a, b, step = 1;
        int got = sscanf(p, "%d-%d%*[:x]%d", &a, &b, &step);
        if (got == 1)
            b = a;
        for (int f = a; f <= b; f++)
            if ((f - a) % step == 0)
                in[f] = true;
    }
}

static void test_random_lists_and_chunks(void **state)
{
    (void)state;
    uint64_t rng = 12;
    for (int trial = 0; trial < 300; trial++) {
        char text[512];
        random_list(&rng, text, sizeof(text));
        bool in[UNIVERSE];
        oracle(text, in);
        int want[UNIVERSE];
        size_t want_count = 0;
        for (int f = 0; f < UNIVERSE; f++)
            if (in[f])
                want[want_count++] = f;

        struct rb_render_frames f = RB_RENDER_FRAMES_INIT;
        struct rb_err err = RB_ERR_INIT;
        if (rb_render_frames_parse(&f, text, &err))
            fail_msg("'%s': %s", text, err.msg);
        int got[UNIVERSE];
        size_t n = frames_of(&f, got, UNIVERSE);
        assert_int_equal(n, want_count);
        assert_memory_equal(got, want, n * sizeof(int));

        /* The chunks of N: in order, their union is the list, sizes n/N rounded down or up. */
        for (uint32_t count = 1; count <= 9; count++) {
            size_t joined = 0;
            for (uint32_t index = 0; index < count; index++) {
                struct rb_render_frames c = f;
                uint64_t size = rb_render_frames_chunk(&c, (struct rb_render_chunk){index, count});
                assert_int_equal(size, n / count + (index < n % count));
                assert_int_equal(rb_render_frames_count(&c), size);
                int part[UNIVERSE];
                size_t m = frames_of(&c, part, UNIVERSE);
                assert_int_equal(m, size);
                assert_true(joined + m <= n);
                assert_memory_equal(part, want + joined, m * sizeof(int));
                int first, last;
                assert_int_equal(rb_render_frames_bounds(&c, &first, &last), m > 0);
                if (m) {
                    assert_int_equal(first, part[0]);
                    assert_int_equal(last, part[m - 1]);
                }
                joined += m;
            }
            assert_int_equal(joined, n);
        }
        rb_render_frames_release(&f);
    }
}

static void test_limit(void **state)
{
    (void)state;
    struct rb_render_frames f = RB_RENDER_FRAMES_INIT;
    assert_int_equal(rb_render_frames_add(&f, 0, 47, 1, NULL), RB_OK);
    assert_int_equal(rb_render_frames_add(&f, 3, 1, 1, NULL), RB_E_INVALID);
    assert_int_equal(rb_render_frames_add(&f, 1, 3, 0, NULL), RB_E_INVALID);
    rb_render_frames_limit(&f, 10, 99);
    rb_render_frames_limit(&f, 0, 20);
    assert_int_equal(rb_render_frames_count(&f), 11);
    int first, last;
    assert_true(rb_render_frames_bounds(&f, &first, &last));
    assert_int_equal(first, 10);
    assert_int_equal(last, 20);
    /* More chunks than frames: the last chunks are empty. */
    struct rb_render_frames g = f;
    assert_int_equal(rb_render_frames_chunk(&g, (struct rb_render_chunk){10, 12}), 1);
    assert_true(rb_render_frames_bounds(&g, &first, &last));
    assert_int_equal(first, 20);
    assert_int_equal(rb_render_frames_chunk(&f, (struct rb_render_chunk){11, 12}), 0);
    assert_false(rb_render_frames_bounds(&f, &first, &last));
    assert_false(rb_render_frames_next(&f, INT64_MIN, &first));
    rb_render_frames_release(&f);
}

static void test_chunk_parse(void **state)
{
    (void)state;
    struct rb_render_chunk c = {99, 99};
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_render_chunk_parse("0/4", &c, &err), RB_OK);
    assert_int_equal(c.index, 0);
    assert_int_equal(c.count, 4);
    assert_int_equal(rb_render_chunk_parse("3/4", &c, &err), RB_OK);
    assert_int_equal(c.index, 3);
    static const struct {
        const char *text, *msg;
    } bad[] = {
        {"4/4", "'4/4': there is no chunk 4 of 4 (chunks are numbered from 0 to 3)"},
        {"0/0", "'0/0': the number of chunks must be 1 or more"},
        {"x", "'x' is not a chunk: expected I/N"},
        {"1/", "'1/' is not a chunk"},
        {"/4", "'/4' is not a chunk"},
        {"-1/4", "'-1/4' is not a chunk"},
        {"1/4x", "'1/4x' is not a chunk"},
        {"1.5/4", "'1.5/4' is not a chunk"},
    };
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
        c = (struct rb_render_chunk){99, 99};
        assert_int_equal(rb_render_chunk_parse(bad[i].text, &c, &err), RB_E_INVALID);
        if (!strstr(err.msg, bad[i].msg))
            fail_msg("'%s': got \"%s\", want \"%s\"", bad[i].text, err.msg, bad[i].msg);
        assert_int_equal(c.index, 99); /* untouched on failure */
    }
}

static void test_slurm(void **state)
{
    (void)state;
    struct rb_render_chunk c = {99, 99};
    struct rb_err err = RB_ERR_INIT;
    /* --array=0-3: task 2 of 4 */
    assert_int_equal(rb_render_chunk_slurm("2", "4", "0", NULL, &c, &err), RB_OK);
    assert_int_equal(c.index, 2);
    assert_int_equal(c.count, 4);
    /* --array=1-4 (MIN 1): task 1 is chunk 0; MIN unset means 0 */
    assert_int_equal(rb_render_chunk_slurm("1", "4", "1", NULL, &c, &err), RB_OK);
    assert_int_equal(c.index, 0);
    assert_int_equal(rb_render_chunk_slurm("3", "4", NULL, NULL, &c, &err), RB_OK);
    assert_int_equal(c.index, 3);
    /* --array=10-16:2: ids 10, 12, 14, 16 */
    assert_int_equal(rb_render_chunk_slurm("14", "4", "10", "2", &c, &err), RB_OK);
    assert_int_equal(c.index, 2);
    static const struct {
        const char *id, *count, *min, *step, *msg;
    } bad[] = {
        {NULL, "4", "0", NULL, "SLURM_ARRAY_TASK_ID is not set: '--chunk slurm' runs as a task"},
        {"", "4", "0", NULL, "SLURM_ARRAY_TASK_ID is not set"},
        {"1", NULL, "0", NULL, "SLURM_ARRAY_TASK_COUNT is not set"},
        {"x", "4", "0", NULL, "SLURM_ARRAY_TASK_ID 'x' is not a whole number"},
        {"1", "4y", "0", NULL, "SLURM_ARRAY_TASK_COUNT '4y' is not a whole number"},
        {"1", "4", "-1", NULL, "SLURM_ARRAY_TASK_MIN '-1' is not a whole number"},
        {"1", "4", "0", "0", "SLURM_ARRAY_TASK_STEP '0' must be 1 or more"},
        {"4", "4", "0", NULL, "SLURM_ARRAY_TASK_ID 4 is not one of the 4 tasks from 0 by 1"},
        {"0", "4", "1", NULL, "SLURM_ARRAY_TASK_ID 0 is not one of the 4 tasks from 1 by 1"},
        {"11", "4", "10", "2", "SLURM_ARRAY_TASK_ID 11 is not one of the 4 tasks from 10 by 2"},
        {"0", "0", "0", NULL, "is not one of the 0 tasks"},
    };
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
        c = (struct rb_render_chunk){99, 99};
        assert_int_equal(
            rb_render_chunk_slurm(bad[i].id, bad[i].count, bad[i].min, bad[i].step, &c, &err),
            RB_E_INVALID);
        if (!strstr(err.msg, bad[i].msg))
            fail_msg("case %zu: got \"%s\", want \"%s\"", i, err.msg, bad[i].msg);
        assert_int_equal(c.index, 99);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lists),       cmocka_unit_test(test_bad_lists),
        cmocka_unit_test(test_limit),       cmocka_unit_test(test_random_lists_and_chunks),
        cmocka_unit_test(test_chunk_parse), cmocka_unit_test(test_slurm),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
