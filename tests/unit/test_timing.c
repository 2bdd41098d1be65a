/* lib/analysis timing regression: the Mann-Whitney U test against worked examples (exact and
 * normal, with ties), its false-positive rate over many seeded draws of identical
 * distributions, known shifts detected, the verdict rule, and bench sets written as raybundle
 * bench writes them, loaded, matched and compared. Files go under one mkdtemp directory. */
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

static char tmpdir[512];

static int group_setup(void **state)
{
    (void)state;
    return rb_test_mkdtemp(tmpdir, sizeof(tmpdir), "timing");
}

static int group_teardown(void **state)
{
    (void)state;
    rb_test_rm_rf(tmpdir);
    return 0;
}

static struct rb_analysis_mwu mwu(const double *a, size_t na, const double *b, size_t nb,
                                  enum rb_analysis_mwu_method method)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_mwu r = {0};
    enum rb_status st = rb_analysis_mann_whitney(a, na, b, nb, method, &r, &err);
    if (st)
        fail_msg("mann-whitney failed: %s", err.msg);
    return r;
}

/* Wikipedia, "Mann-Whitney U test", the tortoise and hare example: six tortoises and six hares
 * finish in the order T H H H H H T T T T T H, so the tortoises' places are 1, 7, 8, 9, 10, 11
 * and the hares' 2 to 6 and 12. The smaller U is 11 (the article's answer), so the tortoises'
 * U counted by value is 36 - 11 = 25. The two-sided p-values, from SciPy 1.10.1
 * (scipy.stats.mannwhitneyu(T, H, alternative='two-sided', method=...)): exact 13/42 =
 * 0.30952380952380953, asymptotic 0.2979530616081678. */
static void test_textbook_exact(void **state)
{
    (void)state;
    const double t[] = {1, 7, 8, 9, 10, 11}, h[] = {2, 3, 4, 5, 6, 12};
    struct rb_analysis_mwu r = mwu(t, 6, h, 6, RB_ANALYSIS_MWU_AUTO);
    assert_double_equal(r.u, 25.0, 0.0);
    assert_double_equal(r.p, 13.0 / 42.0, 1e-15);
    assert_int_equal(r.method, RB_ANALYSIS_MWU_EXACT);
    assert_false(r.has_ties);
    struct rb_analysis_mwu s = mwu(h, 6, t, 6, RB_ANALYSIS_MWU_AUTO);
    assert_double_equal(s.u, 11.0, 0.0); /* the article's U: the hares' */
    assert_double_equal(s.p, r.p, 0.0);  /* two-sided: symmetric */
    r = mwu(t, 6, h, 6, RB_ANALYSIS_MWU_NORMAL);
    assert_double_equal(r.p, 0.2979530616081678, 1e-12);
    assert_int_equal(r.method, RB_ANALYSIS_MWU_NORMAL);
}

/* 12 against 15 values without ties, beyond SciPy's own exact cut-off (8) and within ours (20):
 * SciPy 1.10.1 gives U = 44, exact p = 0.024586944441568215, asymptotic p =
 * 0.02640704903191421. */
static void test_exact_larger(void **state)
{
    (void)state;
    const double a[] = {0.8, 1.9, 2.6, 3.1, 4.4, 5.0, 5.7, 6.3, 7.2, 8.1, 9.4, 10.6};
    const double b[] = {2.2, 3.3,  4.9,  5.5,  6.8,  7.7,  8.4, 8.9,
                        9.8, 10.1, 11.3, 11.9, 12.5, 13.6, 14.2};
    struct rb_analysis_mwu r = mwu(a, 12, b, 15, RB_ANALYSIS_MWU_AUTO);
    assert_double_equal(r.u, 44.0, 0.0);
    assert_int_equal(r.method, RB_ANALYSIS_MWU_EXACT);
    assert_double_equal(r.p, 0.024586944441568215, 1e-13);
    r = mwu(a, 12, b, 15, RB_ANALYSIS_MWU_NORMAL);
    assert_double_equal(r.p, 0.02640704903191421, 1e-12);
}

/* Ties: the normal approximation with the tie and continuity corrections. SciPy 1.10.1 on these
 * values (method='asymptotic'): U = 10.5, p = 0.0471253041839123. */
static void test_ties_normal(void **state)
{
    (void)state;
    const double a[] = {1.1, 2.0, 2.0, 3.5, 4.0, 4.0, 5.2};
    const double b[] = {2.0, 3.5, 4.0, 6.1, 6.1, 7.3, 8.0, 9.9};
    struct rb_analysis_mwu r = mwu(a, 7, b, 8, RB_ANALYSIS_MWU_AUTO);
    assert_true(r.has_ties);
    assert_int_equal(r.method, RB_ANALYSIS_MWU_NORMAL);
    assert_double_equal(r.u, 10.5, 0.0);
    assert_double_equal(r.p, 0.0471253041839123, 1e-12);
    /* every value tied: no evidence at all */
    const double c[] = {3, 3, 3}, d[] = {3, 3, 3, 3};
    r = mwu(c, 3, d, 4, RB_ANALYSIS_MWU_AUTO);
    assert_double_equal(r.p, 1.0, 0.0);
}

static void test_bad_input(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_mwu r;
    const double a[] = {1, 2, 3}, tied[] = {1, 1}, nan_b[] = {1, NAN};
    assert_int_equal(rb_analysis_mann_whitney(a, 3, a, 0, RB_ANALYSIS_MWU_AUTO, &r, &err),
                     RB_E_INVALID);
    assert_non_null(strstr(err.msg, "empty"));
    assert_int_equal(rb_analysis_mann_whitney(a, 3, nan_b, 2, RB_ANALYSIS_MWU_AUTO, &r, &err),
                     RB_E_INVALID);
    assert_non_null(strstr(err.msg, "NaN"));
    assert_int_equal(rb_analysis_mann_whitney(a, 3, tied, 2, RB_ANALYSIS_MWU_EXACT, &r, &err),
                     RB_E_INVALID);
    assert_non_null(strstr(err.msg, "ties"));
    struct rb_analysis_timing_row row;
    struct rb_analysis_timing_desc bad = {.alpha = 0.0, .threshold_pct = 5.0};
    assert_int_equal(rb_analysis_timing_compare("x", a, 3, a, 3, &bad, &row, &err), RB_E_INVALID);
}

/* 2 / C(n1 + n2, n1): 3 against 3 can never reach 0.05, 4 against 4 can. */
/* The one-sided signed-rank test against distributions counted by hand: p = P(W+ >= observed)
 * over the 2^n signs, zeros dropped, ties as midranks; the normal approximation past the exact
 * limit. */
static void test_wilcoxon(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_wilcoxon w;
    const double up[8] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8};
    assert_int_equal(rb_analysis_wilcoxon_greater(up, 8, &w, &err), RB_OK);
    assert_true(w.is_exact);
    assert_int_equal(w.count, 8);
    assert_true(w.w_plus == 36.0);
    assert_true(w.p == 1.0 / 256.0); /* only every sign positive reaches 36 */
    /* ranks 1..5, W+ = 1 + 3 + 4 + 5 = 13: the subsets of {1..5} summing to 13 or more are the
     * complements of {}, {1} and {2}: 3 of 32 */
    const double mixed[5] = {1.0, -2.0, 3.0, 4.0, 5.0};
    assert_int_equal(rb_analysis_wilcoxon_greater(mixed, 5, &w, &err), RB_OK);
    assert_true(w.w_plus == 13.0);
    assert_true(fabs(w.p - 3.0 / 32.0) < 1e-15);
    /* zeros are dropped: two positive differences left, p = 1/4 */
    const double zeros[4] = {0.0, 0.0, 1.0, 2.0};
    assert_int_equal(rb_analysis_wilcoxon_greater(zeros, 4, &w, &err), RB_OK);
    assert_int_equal(w.count, 2);
    assert_true(w.p == 0.25);
    /* three tied |d|, midrank 2 each, two positive: W+ = 4, reached by 4 of 8 sign choices */
    const double ties[3] = {1.0, 1.0, -1.0};
    assert_int_equal(rb_analysis_wilcoxon_greater(ties, 3, &w, &err), RB_OK);
    assert_true(w.w_plus == 4.0);
    assert_true(w.p == 0.5);
    /* all negative: W+ = 0, which every sign choice reaches */
    const double down[5] = {-1.0, -2.0, -3.0, -4.0, -5.0};
    assert_int_equal(rb_analysis_wilcoxon_greater(down, 5, &w, &err), RB_OK);
    assert_true(w.p == 1.0);
    /* nothing but zeros: nothing to test */
    assert_int_equal(rb_analysis_wilcoxon_greater(zeros, 2, &w, &err), RB_OK);
    assert_int_equal(w.count, 0);
    assert_true(w.p == 1.0);
    /* past the exact limit: the normal approximation, which agrees with counting where both
     * apply (a shift of half the spread: p far below any alpha) */
    enum { N = RB_ANALYSIS_WILCOXON_EXACT_MAX + 100 };
    double *many = malloc(N * sizeof(*many));
    assert_non_null(many);
    for (int i = 0; i < N; i++)
        many[i] = (i % 3 == 0 ? -1.0 : 1.0) * (double)(i + 1);
    assert_int_equal(rb_analysis_wilcoxon_greater(many, N, &w, &err), RB_OK);
    assert_false(w.is_exact);
    assert_true(w.p < 1e-6);
    struct rb_analysis_wilcoxon exact;
    assert_int_equal(
        rb_analysis_wilcoxon_greater(many, RB_ANALYSIS_WILCOXON_EXACT_MAX, &exact, &err), RB_OK);
    assert_true(exact.is_exact);
    assert_true(exact.p < 1e-4);
    free(many);
    const double bad[2] = {1.0, NAN};
    assert_int_equal(rb_analysis_wilcoxon_greater(bad, 2, &w, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "difference 2 is NaN"));
}

static void test_min_p(void **state)
{
    (void)state;
    assert_double_equal(rb_analysis_mwu_min_p(3, 3), 2.0 / 20.0, 1e-15);
    assert_double_equal(rb_analysis_mwu_min_p(4, 4), 2.0 / 70.0, 1e-15);
    assert_double_equal(rb_analysis_mwu_min_p(9, 9), 2.0 / 48620.0, 1e-15);
    assert_double_equal(rb_analysis_mwu_min_p(1, 1), 1.0, 0.0);
    assert_double_equal(rb_analysis_mwu_min_p(0, 5), 1.0, 0.0);
    /* the exact test reaches it at complete separation */
    const double a[] = {1, 2, 3, 4}, b[] = {5, 6, 7, 8};
    assert_double_equal(mwu(a, 4, b, 4, RB_ANALYSIS_MWU_EXACT).p, rb_analysis_mwu_min_p(4, 4),
                        1e-15);
}

/* ---- random draws ------------------------------------------------------------------------ */

static uint64_t rng_state;

static uint64_t splitmix64(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Roughly normal (mean 10, sd 1: the sum of 12 uniforms) plus shift, like timings in ms. */
static void draw(double *v, size_t n, double shift)
{
    for (size_t i = 0; i < n; i++) {
        double s = 0.0;
        for (int k = 0; k < 12; k++)
            s += (double)(splitmix64() >> 11) / 9007199254740992.0;
        v[i] = 10.0 + (s - 6.0) + shift;
    }
}

/* The share of draws of n against n with p < alpha, the second sample shifted by shift. */
static double rejection_rate(size_t n, double shift, int draws, double alpha)
{
    double a[32], b[32];
    int rejected = 0;
    rng_state = 12345;
    for (int i = 0; i < draws; i++) {
        draw(a, n, 0.0);
        draw(b, n, shift);
        rejected += mwu(a, n, b, n, RB_ANALYSIS_MWU_AUTO).p < alpha;
    }
    return (double)rejected / draws;
}

/* Identical distributions: the rate of p < 0.05 over 2000 draws of 9 against 9 must be the exact
 * test's true size, which is below alpha because U is discrete: 0.039983545865898806 (the
 * share of the C(18, 9) = 48620 arrangements with p < 0.05, counted in Python by enumerating
 * them). Its binomial standard deviation over 2000 draws is 0.0044; the band is +-4 of them,
 * [0.022, 0.058], which a rate near alpha or a test that never rejects would leave. Beyond 20
 * values a sample the normal approximation applies, whose size is close to alpha: 25 against
 * 25, the same band width around 0.05 ([0.03, 0.07]). */
static void test_false_positive_rate(void **state)
{
    (void)state;
    double rate = rejection_rate(9, 0.0, 2000, 0.05);
    print_message("# false-positive rate, 9 vs 9, exact: %.4f (true size 0.0400)\n", rate);
    assert_true(rate >= 0.022 && rate <= 0.058);
    rate = rejection_rate(25, 0.0, 2000, 0.05);
    print_message("# false-positive rate, 25 vs 25, normal: %.4f\n", rate);
    assert_true(rate >= 0.03 && rate <= 0.07);
}

/* A shift of 2.5 standard deviations is found in nearly every draw of 9 against 9 (the power is
 * above 0.99); half a standard deviation, seldom. */
static void test_shift_detected(void **state)
{
    (void)state;
    double rate = rejection_rate(9, 2.5, 500, 0.05);
    print_message("# detection rate, shift 2.5 sd, 9 vs 9: %.4f\n", rate);
    assert_true(rate >= 0.97);
    assert_true(rejection_rate(9, 0.5, 500, 0.05) < 0.5);
}

/* The verdict: slower and faster need p < alpha and a change beyond the threshold. */
static void test_verdict(void **state)
{
    (void)state;
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_desc desc = RB_ANALYSIS_TIMING_DESC_INIT;
    struct rb_analysis_timing_row row;
    double base[9], slow[9], fast[9], tight[9], slight[9];
    rng_state = 7;
    draw(base, 9, 0.0);
    for (int i = 0; i < 9; i++) {
        slow[i] = base[i] * 3.0;
        fast[i] = base[i] / 2.0;
        tight[i] = 100.0 + i * 0.01; /* 2% apart, every pair in order: p is the smallest */
        slight[i] = 102.0 + i * 0.01;
    }
    assert_int_equal(rb_analysis_timing_compare("gbuffer", base, 9, slow, 9, &desc, &row, &err),
                     RB_OK);
    assert_int_equal(row.verdict, RB_ANALYSIS_SLOWER);
    assert_string_equal(rb_analysis_verdict_name(row.verdict), "slower");
    assert_double_equal(row.change_pct, 200.0, 1e-9);
    assert_true(row.test.p < 0.05);
    assert_int_equal(rb_analysis_timing_compare("g", base, 9, fast, 9, &desc, &row, &err), RB_OK);
    assert_int_equal(row.verdict, RB_ANALYSIS_FASTER);
    /* significant, but within the 5% threshold */
    assert_int_equal(rb_analysis_timing_compare("g", tight, 9, slight, 9, &desc, &row, &err),
                     RB_OK);
    assert_double_equal(row.test.p, rb_analysis_mwu_min_p(9, 9), 1e-15);
    assert_int_equal(row.verdict, RB_ANALYSIS_SAME);
    desc.threshold_pct = 1.0;
    assert_int_equal(rb_analysis_timing_compare("g", tight, 9, slight, 9, &desc, &row, &err),
                     RB_OK);
    assert_int_equal(row.verdict, RB_ANALYSIS_SLOWER);
    desc.threshold_pct = 5.0;
    /* 3 runs against 3 can never be significant at 0.05 */
    assert_int_equal(rb_analysis_timing_compare("g", base, 3, slow, 3, &desc, &row, &err), RB_OK);
    assert_int_equal(row.verdict, RB_ANALYSIS_TOO_FEW_RUNS);
    assert_int_equal(rb_analysis_timing_compare("g", base, 3, NULL, 0, &desc, &row, &err), RB_OK);
    assert_int_equal(row.verdict, RB_ANALYSIS_ONLY_BASE);
    assert_true(isnan(row.change_pct));
}

/* ---- bench sets ---------------------------------------------------------------------------- */

static const char *const pass_names[] = {"gbuffer", "shadow", "direct"};

/* Writes a bench set as raybundle bench does: bench.json and runs x frames sidecars, pass p of
 * run r, frame f taking (p + 1) * (1 + r / 100 + f / 1000) * scale ms. */
static void write_set(const char *dir, uint32_t runs, double scale, const char *hash)
{
    struct rb_err err = RB_ERR_INIT;
    char path[1024];
    int frames[] = {3, 4};
    char *options[] = {"--runs", "5"};
    struct rb_io_bench b = {.device = "llvmpipe (LLVM 15.0.6, 256 bits)",
                            .driver = "llvmpipe Mesa 22.3.6",
                            .build = "raybundle " RB_VERSION,
                            .job = "jobs/demo.yaml",
                            .integrator = "direct",
                            .width_px = 64,
                            .height_px = 36,
                            .run_count = runs,
                            .order = "run-by-run",
                            .frames = frames,
                            .frame_count = 2,
                            .options = options,
                            .option_count = 2};
    rb_strlcpy(b.job_hash, hash, sizeof(b.job_hash));
    mkdir(dir, 0777);
    snprintf(path, sizeof(path), "%s/bench.json", dir);
    assert_int_equal(rb_io_bench_write(path, &b, &err), RB_OK);
    for (uint32_t r = 0; r < runs; r++) {
        snprintf(path, sizeof(path), "%s/run-%02u", dir, r + 1);
        mkdir(path, 0777);
        for (int f = 0; f < 2; f++) {
            struct rb_pass_time p[3];
            for (int i = 0; i < 3; i++) {
                p[i] = (struct rb_pass_time){
                    .gpu_ms = (i + 1) * (1.0 + r / 100.0 + f / 1000.0) * scale, .count = 1};
                rb_strlcpy(p[i].name, pass_names[i], sizeof(p[i].name));
            }
            snprintf(path, sizeof(path), "%s/run-%02u/frame.%04d.timing.json", dir, r + 1,
                     frames[f]);
            struct rb_io_timing t = {.frame = frames[f],
                                     .passes = p,
                                     .pass_count = 3,
                                     .wall_ms = 20.0 * scale + r,
                                     .device = b.device,
                                     .driver = b.driver,
                                     .job_hash = b.job_hash,
                                     .integrator = "direct",
                                     .width_px = 64,
                                     .height_px = 36};
            assert_int_equal(rb_io_timing_write(path, &t, &err), RB_OK);
        }
    }
}

static struct rb_analysis_timing_set *load(const char *dir)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_set *s = NULL;
    if (rb_analysis_timing_set_load(dir, &s, &err))
        fail_msg("loading '%s': %s", dir, err.msg);
    return s;
}

static void test_set_load(void **state)
{
    (void)state;
    char dir[600];
    snprintf(dir, sizeof(dir), "%s/load", tmpdir);
    write_set(dir, 5, 1.0, "0123456789abcdef");
    struct rb_analysis_timing_set *s = load(dir);
    assert_int_equal(s->bench.run_count, 5);
    assert_string_equal(s->bench.job_hash, "0123456789abcdef");
    assert_string_equal(s->bench.order, "run-by-run");
    assert_int_equal(s->bench.frame_count, 2);
    assert_int_equal(s->bench.frames[1], 4);
    assert_int_equal(s->bench.option_count, 2);
    assert_string_equal(s->bench.options[1], "5");
    assert_int_equal(s->series_count, 4);
    for (int i = 0; i < 3; i++)
        assert_string_equal(s->series[i].name, pass_names[i]);
    assert_string_equal(s->series[3].name, RB_ANALYSIS_WALL);
    /* one sample a run: the mean over its two frames */
    for (uint32_t r = 0; r < 5; r++) {
        assert_double_equal(s->series[1].per_run_ms[r], 2.0 * (1.0 + r / 100.0 + 0.0005), 1e-12);
        assert_double_equal(s->series[3].per_run_ms[r], 20.0 + r, 1e-12);
    }
    rb_analysis_timing_set_destroy(s);
}

static void test_sets_compare(void **state)
{
    (void)state;
    char base_dir[600], same_dir[600], slow_dir[600], other_dir[600];
    snprintf(base_dir, sizeof(base_dir), "%s/base", tmpdir);
    snprintf(same_dir, sizeof(same_dir), "%s/same", tmpdir);
    snprintf(slow_dir, sizeof(slow_dir), "%s/slow", tmpdir);
    snprintf(other_dir, sizeof(other_dir), "%s/other", tmpdir);
    write_set(base_dir, 5, 1.0, "0123456789abcdef");
    write_set(same_dir, 5, 1.0, "0123456789abcdef");
    write_set(slow_dir, 5, 3.0, "0123456789abcdef");
    write_set(other_dir, 5, 1.0, "fedcba9876543210");
    struct rb_analysis_timing_set *base = load(base_dir), *same = load(same_dir),
                                  *slow = load(slow_dir), *other = load(other_dir);
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_desc desc = RB_ANALYSIS_TIMING_DESC_INIT;
    struct rb_analysis_timing_row *rows = NULL;
    size_t n = 0;

    assert_int_equal(rb_analysis_timing_sets_match(base, slow, &err), RB_OK);
    assert_int_equal(rb_analysis_timing_sets_match(base, other, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "'0123456789abcdef' and 'fedcba9876543210'"));
    /* The same job measured with another driver, or on another device: refused, both named. */
    rb_strlcpy(other->bench.job_hash, base->bench.job_hash, sizeof(other->bench.job_hash));
    rb_strlcpy(other->bench.driver, "llvmpipe Mesa 24.0.9", sizeof(other->bench.driver));
    assert_int_equal(rb_analysis_timing_sets_match(base, other, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "different drivers: 'llvmpipe Mesa 22.3.6' and 'llvmpipe Mesa "
                                    "24.0.9'"));
    rb_strlcpy(other->bench.device, "NVIDIA H100", sizeof(other->bench.device));
    assert_int_equal(rb_analysis_timing_sets_match(base, other, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "different devices: 'llvmpipe (LLVM 15.0.6, 256 bits)' and "
                                    "'NVIDIA H100'"));

    assert_int_equal(rb_analysis_timing_compare_sets(base, same, &desc, &rows, &n, &err), RB_OK);
    assert_int_equal(n, 4);
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(rows[i].verdict, RB_ANALYSIS_SAME);
        assert_double_equal(rows[i].change_pct, 0.0, 0.0);
    }
    free(rows);
    assert_int_equal(rb_analysis_timing_compare_sets(base, slow, &desc, &rows, &n, &err), RB_OK);
    assert_int_equal(n, 4);
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(rows[i].verdict, RB_ANALYSIS_SLOWER);
        assert_double_equal(rows[i].test.p, rb_analysis_mwu_min_p(5, 5), 1e-15);
    }
    assert_double_equal(rows[0].change_pct, 200.0, 1e-9);
    free(rows);
    assert_int_equal(rb_analysis_timing_compare_sets(slow, base, &desc, &rows, &n, &err), RB_OK);
    assert_int_equal(rows[2].verdict, RB_ANALYSIS_FASTER);
    free(rows);
    rb_analysis_timing_set_destroy(base);
    rb_analysis_timing_set_destroy(same);
    rb_analysis_timing_set_destroy(slow);
    rb_analysis_timing_set_destroy(other);
}

/* A run that lacks a frame, a sidecar from another device, a broken file: errors naming it. */
static void test_set_errors(void **state)
{
    (void)state;
    char dir[600], path[800];
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_set *s = NULL;
    snprintf(dir, sizeof(dir), "%s/broken", tmpdir);
    write_set(dir, 3, 1.0, "0123456789abcdef");
    snprintf(path, sizeof(path), "%s/run-02/frame.0004.timing.json", dir);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rb_analysis_timing_set_load(dir, &s, &err), RB_E_INVALID);
    assert_null(s);
    assert_non_null(strstr(err.msg, "run-02': no timing sidecar for frame 4"));
    /* The sidecar of another job (its own job_hash) in the set. */
    struct rb_pass_time p = {.name = "gbuffer", .gpu_ms = 1.0, .count = 1};
    struct rb_io_timing t = {.frame = 4,
                             .passes = &p,
                             .pass_count = 1,
                             .wall_ms = 2.0,
                             .device = "llvmpipe (LLVM 15.0.6, 256 bits)",
                             .driver = "llvmpipe Mesa 22.3.6",
                             .job_hash = "00000000deadbeef"};
    assert_int_equal(rb_io_timing_write(path, &t, &err), RB_OK);
    assert_int_equal(rb_analysis_timing_set_load(dir, &s, &err), RB_E_INVALID);
    assert_null(s);
    assert_non_null(strstr(err.msg, "frame.0004.timing.json': rendered from job 00000000deadbeef, "
                                    "and bench.json says job 0123456789abcdef"));
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("{\"frame\": 4,\n \"passes\": [}\n", f);
    fclose(f);
    assert_int_equal(rb_analysis_timing_set_load(dir, &s, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, "frame.0004.timing.json:2:"));
    snprintf(path, sizeof(path), "%s/bench.json", dir);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rb_analysis_timing_set_load(dir, &s, &err), RB_E_IO);
    assert_non_null(strstr(err.msg, "bench.json"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_textbook_exact), cmocka_unit_test(test_exact_larger),
        cmocka_unit_test(test_ties_normal),    cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_min_p),          cmocka_unit_test(test_false_positive_rate),
        cmocka_unit_test(test_shift_detected), cmocka_unit_test(test_verdict),
        cmocka_unit_test(test_set_load),       cmocka_unit_test(test_sets_compare),
        cmocka_unit_test(test_set_errors),     cmocka_unit_test(test_wilcoxon),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
