/* Timing regression: the two-sided Mann-Whitney U test (exact null distribution without ties,
 * the normal approximation with tie and continuity corrections otherwise, as SciPy's
 * mannwhitneyu), the verdict per series, and bench sets loaded from their sidecars. The unit of
 * the test is the run: one sample a run per series, the mean over its frames. Pure computation
 * in double in a fixed order, so the same files give the same table. Prints nothing. */
#include "analysis/analysis.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the test ------------------------------------------------------------------------------ */

struct ranked {
    double value;
    int is_a;
};

static int cmp_ranked(const void *pa, const void *pb)
{
    const struct ranked *a = pa, *b = pb;
    if (a->value != b->value)
        return a->value < b->value ? -1 : 1;
    return a->is_a - b->is_a;
}

static int cmp_double(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return a < b ? -1 : a > b;
}

/* P(U >= u) under the null for samples of m and n values without ties: the number of
 * arrangements with U = k is the coefficient of q^k in the Gaussian binomial [m + n choose m],
 * built as the product over i = 1..m of (1 - q^(n+i)) / (1 - q^i); every partial product is
 * itself a Gaussian binomial, so the counts stay exact integers (C(40, 20) < 2^53, and
 * C(60, 30) < 2^63). Worked modulo q^(mn+1): the result has degree mn. */
static enum rb_status exact_sf(size_t m, size_t n, double u, double *out, struct rb_err *err)
{
    size_t top = m * n;
    long long *c = calloc(top + 1, sizeof(*c));
    if (!c)
        return rb_errf(err, RB_E_NOMEM, "mann-whitney: out of memory");
    c[0] = 1;
    for (size_t i = 1; i <= m; i++) {
        for (size_t k = top; k >= n + i; k--) /* times (1 - q^(n+i)), mod q^(top+1) */
            c[k] -= c[k - n - i];
        for (size_t k = i; k <= top; k++) /* divided by (1 - q^i) */
            c[k] += c[k - i];
    }
    long long total = 0, tail = 0;
    for (size_t k = 0; k <= top; k++) {
        total += c[k];
        if ((double)k >= u)
            tail += c[k];
    }
    free(c);
    *out = (double)tail / (double)total;
    return RB_OK;
}

enum rb_status rb_analysis_mann_whitney(const double *a, size_t a_count, const double *b,
                                        size_t b_count, enum rb_analysis_mwu_method method,
                                        struct rb_analysis_mwu *out, struct rb_err *err)
{
    if (!a_count || !b_count)
        return rb_errf(err, RB_E_INVALID, "mann-whitney: an empty sample (%zu and %zu values)",
                       a_count, b_count);
    size_t n = a_count + b_count;
    struct ranked *v = malloc(n * sizeof(*v));
    if (!v)
        return rb_errf(err, RB_E_NOMEM, "mann-whitney: out of memory");
    for (size_t i = 0; i < n; i++) {
        v[i] = i < a_count ? (struct ranked){a[i], 1} : (struct ranked){b[i - a_count], 0};
        if (isnan(v[i].value)) {
            free(v);
            return rb_errf(err, RB_E_INVALID, "mann-whitney: value %zu of sample %s is NaN",
                           i < a_count ? i + 1 : i - a_count + 1, i < a_count ? "a" : "b");
        }
    }
    qsort(v, n, sizeof(*v), cmp_ranked);
    /* Midranks: a group of t tied values at ranks i+1..i+t all get i + (t + 1) / 2. */
    double rank_sum_a = 0.0, tie_term = 0.0;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && v[j].value == v[i].value)
            j++;
        double t = (double)(j - i), rank = (double)i + (t + 1.0) / 2.0;
        for (size_t k = i; k < j; k++)
            if (v[k].is_a)
                rank_sum_a += rank;
        tie_term += t * t * t - t;
        i = j;
    }
    free(v);
    double n1 = (double)a_count, n2 = (double)b_count;
    double u1 = rank_sum_a - n1 * (n1 + 1.0) / 2.0, u2 = n1 * n2 - u1;
    double u = u1 > u2 ? u1 : u2;
    bool has_ties = tie_term > 0.0;
    if (method == RB_ANALYSIS_MWU_AUTO)
        method = !has_ties && a_count <= RB_ANALYSIS_MWU_EXACT_MAX &&
                         b_count <= RB_ANALYSIS_MWU_EXACT_MAX
                     ? RB_ANALYSIS_MWU_EXACT
                     : RB_ANALYSIS_MWU_NORMAL;
    double p = 1.0;
    if (method == RB_ANALYSIS_MWU_EXACT) {
        if (has_ties)
            return rb_errf(err, RB_E_INVALID,
                           "mann-whitney: the exact test needs samples "
                           "without ties");
        if (n > 60) /* C(60, 30) < 2^63: the counts fit */
            return rb_errf(err, RB_E_INVALID,
                           "mann-whitney: the exact test takes at most 60 values in all, not %zu",
                           n);
        enum rb_status st = exact_sf(a_count, b_count, u, &p, err);
        if (st)
            return st;
        p *= 2.0;
    } else if (method == RB_ANALYSIS_MWU_NORMAL) {
        double nn = n1 + n2;
        double var = n1 * n2 / 12.0 * ((nn + 1.0) - tie_term / (nn * (nn - 1.0)));
        double z = (u - n1 * n2 / 2.0 - 0.5) / sqrt(var); /* -inf when every value is tied */
        p = erfc(z / sqrt(2.0));
    } else {
        return rb_errf(err, RB_E_INVALID, "mann-whitney: unknown method %d", (int)method);
    }
    *out = (struct rb_analysis_mwu){
        .u = u1, .p = p > 1.0 ? 1.0 : p, .method = method, .has_ties = has_ties};
    return RB_OK;
}

static int cmp_abs(const void *pa, const void *pb)
{
    double a = fabs(*(const double *)pa), b = fabs(*(const double *)pb);
    return (a > b) - (a < b);
}

enum rb_status rb_analysis_wilcoxon_greater(const double *d, size_t n,
                                            struct rb_analysis_wilcoxon *out, struct rb_err *err)
{
    *out = (struct rb_analysis_wilcoxon){.p = 1.0, .is_exact = true};
    double *v = malloc((n ? n : 1) * sizeof(*v));
    if (!v)
        return rb_errf(err, RB_E_NOMEM, "wilcoxon: out of memory");
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (isnan(d[i])) {
            free(v);
            return rb_errf(err, RB_E_INVALID, "wilcoxon: difference %zu is NaN", i + 1);
        }
        if (d[i] != 0.0)
            v[m++] = d[i];
    }
    out->count = m;
    if (!m) {
        free(v);
        return RB_OK;
    }
    qsort(v, m, sizeof(*v), cmp_abs);
    /* Doubled midranks (integers): a group of t tied |d| at ranks i+1..i+t gets 2i + t + 1. */
    uint64_t *rank2 = malloc(m * sizeof(*rank2));
    if (!rank2) {
        free(v);
        return rb_errf(err, RB_E_NOMEM, "wilcoxon: out of memory");
    }
    uint64_t w2 = 0, total2 = 0;
    double tie_term = 0.0;
    for (size_t i = 0; i < m;) {
        size_t j = i + 1;
        while (j < m && fabs(v[j]) == fabs(v[i]))
            j++;
        for (size_t k = i; k < j; k++) {
            rank2[k] = 2 * i + (j - i) + 1;
            total2 += rank2[k];
            if (v[k] > 0.0)
                w2 += rank2[k];
        }
        double t = (double)(j - i);
        tie_term += t * t * t - t;
        i = j;
    }
    free(v);
    out->w_plus = (double)w2 / 2.0;
    double mm = (double)m;
    if (m <= RB_ANALYSIS_WILCOXON_EXACT_MAX) {
        /* count[s]: sign choices whose positive ranks sum to s (doubled), as a share of them,
         * halved at each step so that nothing overflows. */
        double *count = calloc(total2 + 1, sizeof(*count));
        if (!count) {
            free(rank2);
            return rb_errf(err, RB_E_NOMEM, "wilcoxon: out of memory");
        }
        count[0] = 1.0;
        uint64_t reach = 0;
        for (size_t k = 0; k < m; k++) {
            for (uint64_t s = reach + 1; s-- > 0;)
                if (count[s] != 0.0) {
                    count[s + rank2[k]] += count[s] * 0.5;
                    count[s] *= 0.5;
                }
            reach += rank2[k];
        }
        double tail = 0.0;
        for (uint64_t s = total2 + 1; s-- > w2;)
            tail += count[s];
        free(count);
        out->p = tail > 1.0 ? 1.0 : tail;
    } else {
        double mean = mm * (mm + 1.0) / 4.0;
        double var = mm * (mm + 1.0) * (2.0 * mm + 1.0) / 24.0 - tie_term / 48.0;
        double z = var > 0.0 ? (out->w_plus - mean - 0.5) / sqrt(var) : -INFINITY;
        out->p = 0.5 * erfc(z / sqrt(2.0));
        out->is_exact = false;
    }
    free(rank2);
    return RB_OK;
}

double rb_analysis_mwu_min_p(size_t a_count, size_t b_count)
{
    if (!a_count || !b_count)
        return 1.0;
    double c = 1.0; /* C(a + b, a), built as a product that stays exact while it is small */
    for (size_t i = 1; i <= a_count; i++)
        c = c * (double)(b_count + i) / (double)i;
    double p = 2.0 / c;
    return p > 1.0 ? 1.0 : p;
}

double rb_analysis_median(double *values, size_t count)
{
    if (!count)
        return NAN;
    qsort(values, count, sizeof(*values), cmp_double);
    return count % 2 ? values[count / 2] : (values[count / 2 - 1] + values[count / 2]) / 2.0;
}

const char *rb_analysis_verdict_name(enum rb_analysis_verdict v)
{
    switch (v) {
    case RB_ANALYSIS_SAME: return "same";
    case RB_ANALYSIS_FASTER: return "faster";
    case RB_ANALYSIS_SLOWER: return "slower";
    case RB_ANALYSIS_TOO_FEW_RUNS: return "too few runs";
    case RB_ANALYSIS_ONLY_BASE: return "only in base";
    case RB_ANALYSIS_ONLY_NEW: return "only in new";
    case RB_ANALYSIS_VERDICT_INVALID: break;
    }
    return "invalid";
}

/* The median of a copy (values are not changed). */
static enum rb_status median_of(const double *values, size_t count, double *out, struct rb_err *err)
{
    double *copy = count ? malloc(count * sizeof(*copy)) : NULL;
    if (count && !copy)
        return rb_errf(err, RB_E_NOMEM, "timing: out of memory");
    if (count)
        memcpy(copy, values, count * sizeof(*copy));
    *out = rb_analysis_median(copy, count);
    free(copy);
    return RB_OK;
}

enum rb_status rb_analysis_timing_compare(const char *name, const double *base, size_t base_count,
                                          const double *new_values, size_t new_count,
                                          const struct rb_analysis_timing_desc *desc,
                                          struct rb_analysis_timing_row *out, struct rb_err *err)
{
    if (!desc || !(desc->alpha > 0.0 && desc->alpha < 1.0) || !(desc->threshold_pct >= 0.0))
        return rb_errf(err, RB_E_INVALID,
                       "timing: alpha must be in (0, 1) and the threshold "
                       "at least 0");
    struct rb_analysis_timing_row row = {.base_count = base_count, .new_count = new_count};
    rb_strlcpy(row.name, name, sizeof(row.name));
    enum rb_status st;
    if ((st = median_of(base, base_count, &row.base_median_ms, err)) ||
        (st = median_of(new_values, new_count, &row.new_median_ms, err)))
        return st;
    row.test.p = NAN;
    if (!base_count || !new_count) {
        row.change_pct = NAN;
        row.verdict = base_count ? RB_ANALYSIS_ONLY_BASE : RB_ANALYSIS_ONLY_NEW;
        *out = row;
        return RB_OK;
    }
    if ((st = rb_analysis_mann_whitney(base, base_count, new_values, new_count,
                                       RB_ANALYSIS_MWU_AUTO, &row.test, err))) {
        rb_err_prefix(err, "'%s'", name);
        return st;
    }
    double b = row.base_median_ms, d = row.new_median_ms - b;
    row.change_pct = b != 0.0 ? 100.0 * d / b : d == 0.0 ? 0.0 : d > 0.0 ? INFINITY : -INFINITY;
    if (rb_analysis_mwu_min_p(base_count, new_count) >= desc->alpha)
        row.verdict = RB_ANALYSIS_TOO_FEW_RUNS;
    else if (row.test.p < desc->alpha && row.change_pct > desc->threshold_pct)
        row.verdict = RB_ANALYSIS_SLOWER;
    else if (row.test.p < desc->alpha && row.change_pct < -desc->threshold_pct)
        row.verdict = RB_ANALYSIS_FASTER;
    else
        row.verdict = RB_ANALYSIS_SAME;
    *out = row;
    return RB_OK;
}

/* ---- bench sets ---------------------------------------------------------------------------- */

void rb_analysis_timing_set_destroy(struct rb_analysis_timing_set *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->series_count; i++)
        free(s->series[i].per_run_ms);
    free(s->series);
    rb_io_bench_release(&s->bench);
    free(s);
}

/* The series named name, added (zero for every run) when it is new; NULL when out of memory. */
static struct rb_analysis_timing_series *series(struct rb_analysis_timing_set *s, const char *name)
{
    for (size_t i = 0; i < s->series_count; i++)
        if (strcmp(s->series[i].name, name) == 0)
            return &s->series[i];
    struct rb_analysis_timing_series *grown =
        realloc(s->series, (s->series_count + 1) * sizeof(*grown));
    if (!grown)
        return NULL;
    s->series = grown;
    struct rb_analysis_timing_series *x = &grown[s->series_count];
    memset(x, 0, sizeof(*x));
    rb_strlcpy(x->name, name, sizeof(x->name));
    if (!(x->per_run_ms = calloc(s->bench.run_count, sizeof(double))))
        return NULL;
    s->series_count++;
    return x;
}

static int cmp_name(const void *pa, const void *pb)
{
    return strcmp(*(char *const *)pa, *(char *const *)pb);
}

/* The *.timing.json names in dir, sorted; *names freed (each and the array) by the caller. */
static enum rb_status list_sidecars(const char *dir, char ***names, size_t *count,
                                    struct rb_err *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", dir, strerror(errno));
    static const char suffix[] = ".timing.json";
    size_t len = sizeof(suffix) - 1;
    enum rb_status st = RB_OK;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t n = strlen(e->d_name);
        if (n <= len || strcmp(e->d_name + n - len, suffix) != 0)
            continue;
        char **grown = realloc(*names, (*count + 1) * sizeof(*grown));
        if (!grown || !(grown[*count] = rb_strdup(e->d_name))) {
            if (grown)
                *names = grown;
            st = rb_errf(err, RB_E_NOMEM, "'%s': out of memory", dir);
            break;
        }
        *names = grown;
        (*count)++;
    }
    closedir(d);
    if (*count)
        qsort(*names, *count, sizeof(**names), cmp_name);
    return st;
}

/* Adds run r's sidecars (in dir) to the set's series, checking them against bench.json. */
static enum rb_status load_run(struct rb_analysis_timing_set *s, uint32_t r, const char *dir,
                               struct rb_err *err)
{
    const struct rb_io_bench *b = &s->bench;
    char **names = NULL;
    size_t count = 0;
    bool *seen = calloc(b->frame_count ? b->frame_count : 1, sizeof(*seen));
    struct rb_io_timing_file t = {0};
    enum rb_status st = seen ? list_sidecars(dir, &names, &count, err)
                             : rb_errf(err, RB_E_NOMEM, "'%s': out of memory", dir);
    for (size_t i = 0; st == RB_OK && i < count; i++) {
        char path[4096];
        if ((size_t)snprintf(path, sizeof(path), "%s/%s", dir, names[i]) >= sizeof(path)) {
            st = rb_errf(err, RB_E_INVALID, "'%s/%s': path too long", dir, names[i]);
            break;
        }
        if ((st = rb_io_timing_read(path, &t, err)))
            break;
        size_t f = 0;
        while (f < b->frame_count && b->frames[f] != t.frame)
            f++;
        if (f == b->frame_count || seen[f]) {
            st = rb_errf(err, RB_E_INVALID, "'%s': frame %d is %s", path, t.frame,
                         f == b->frame_count ? "not among bench.json's frames" : "there twice");
            break;
        }
        seen[f] = true;
        if (strcmp(t.device, b->device) != 0 || strcmp(t.driver, b->driver) != 0) {
            st = rb_errf(err, RB_E_INVALID,
                         "'%s': rendered on '%s' (driver '%s'), and bench.json says '%s' "
                         "(driver '%s')",
                         path, t.device, t.driver, b->device, b->driver);
            break;
        }
        if (*t.job_hash && strcmp(t.job_hash, b->job_hash) != 0) {
            st =
                rb_errf(err, RB_E_INVALID, "'%s': rendered from job %s, and bench.json says job %s",
                        path, t.job_hash, b->job_hash);
            break;
        }
        for (size_t p = 0; p <= t.pass_count; p++) {
            const char *name = p < t.pass_count ? t.passes[p].name : RB_ANALYSIS_WALL;
            double ms = p < t.pass_count ? t.passes[p].gpu_ms + t.passes[p].cpu_ms : t.wall_ms;
            struct rb_analysis_timing_series *x = series(s, name);
            if (!x) {
                st = rb_errf(err, RB_E_NOMEM, "'%s': out of memory", path);
                break;
            }
            x->per_run_ms[r] += ms / (double)b->frame_count;
        }
        rb_io_timing_file_release(&t);
    }
    rb_io_timing_file_release(&t);
    for (size_t f = 0; st == RB_OK && f < b->frame_count; f++)
        if (!seen[f])
            st = rb_errf(err, RB_E_INVALID, "'%s': no timing sidecar for frame %d", dir,
                         b->frames[f]);
    for (size_t i = 0; i < count; i++)
        free(names[i]);
    free(names);
    free(seen);
    return st;
}

/* Moves the wall series last, after the passes. */
static void wall_last(struct rb_analysis_timing_set *s)
{
    for (size_t i = 0; i + 1 < s->series_count; i++)
        if (strcmp(s->series[i].name, RB_ANALYSIS_WALL) == 0) {
            struct rb_analysis_timing_series w = s->series[i];
            memmove(&s->series[i], &s->series[i + 1],
                    (s->series_count - i - 1) * sizeof(s->series[0]));
            s->series[s->series_count - 1] = w;
            return;
        }
}

enum rb_status rb_analysis_timing_set_load(const char *dir, struct rb_analysis_timing_set **out,
                                           struct rb_err *err)
{
    struct rb_analysis_timing_set *s = calloc(1, sizeof(*s));
    if (!s)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = RB_OK;
    char path[2048];
    if (rb_strlcpy(s->dir, dir, sizeof(s->dir)) >= sizeof(s->dir)) {
        st = rb_errf(err, RB_E_INVALID, "bench directory '%.40s...' is too long", dir);
        goto fail;
    }
    snprintf(path, sizeof(path), "%s/bench.json", dir);
    if ((st = rb_io_bench_read(path, &s->bench, err)))
        goto fail;
    if (!s->bench.frame_count) {
        st = rb_errf(err, RB_E_INVALID, "'%s': no frames", path);
        goto fail;
    }
    for (uint32_t r = 0; r < s->bench.run_count; r++) {
        snprintf(path, sizeof(path), "%s/run-%02u", dir, r + 1);
        if ((st = load_run(s, r, path, err)))
            goto fail;
    }
    wall_last(s);
    *out = s;
    return RB_OK;
fail:
    rb_analysis_timing_set_destroy(s);
    return st;
}

/* What differs between a and b (named what), as the refusal's message; false when equal. */
static bool differs(const char *what, const char *a, const char *b, struct rb_err *err)
{
    if (strcmp(a, b) == 0)
        return false;
    rb_errf(err, RB_E_INVALID, "the sets were measured with different %s: '%s' and '%s'", what, a,
            b);
    return true;
}

enum rb_status rb_analysis_timing_sets_match(const struct rb_analysis_timing_set *base,
                                             const struct rb_analysis_timing_set *new_set,
                                             struct rb_err *err)
{
    const struct rb_io_bench *a = &base->bench, *b = &new_set->bench;
    if (differs("devices", a->device, b->device, err) ||
        differs("drivers", a->driver, b->driver, err) ||
        differs("job hashes (the job, scene or options differ)", a->job_hash, b->job_hash, err))
        return RB_E_INVALID;
    bool same_frames = a->frame_count == b->frame_count;
    for (size_t i = 0; same_frames && i < a->frame_count; i++)
        same_frames = a->frames[i] == b->frames[i];
    if (!same_frames)
        return rb_errf(err, RB_E_INVALID,
                       "the sets rendered different frames: %zu from %d and %zu from %d",
                       a->frame_count, a->frames[0], b->frame_count, b->frames[0]);
    return RB_OK;
}

enum rb_status rb_analysis_timing_compare_sets(const struct rb_analysis_timing_set *base,
                                               const struct rb_analysis_timing_set *new_set,
                                               const struct rb_analysis_timing_desc *desc,
                                               struct rb_analysis_timing_row **rows,
                                               size_t *row_count, struct rb_err *err)
{
    size_t cap = base->series_count + new_set->series_count, n = 0;
    struct rb_analysis_timing_row *out = calloc(cap ? cap : 1, sizeof(*out));
    if (!out)
        return rb_errf(err, RB_E_NOMEM, "timing: out of memory");
    enum rb_status st = RB_OK;
    /* Base's series in order (a match from new, or none), then new's that base lacks. */
    for (size_t i = 0; st == RB_OK && i < cap; i++) {
        bool is_base = i < base->series_count;
        const struct rb_analysis_timing_series *x =
            is_base ? &base->series[i] : &new_set->series[i - base->series_count];
        const struct rb_analysis_timing_set *other = is_base ? new_set : base;
        const struct rb_analysis_timing_series *y = NULL;
        for (size_t j = 0; j < other->series_count && !y; j++)
            if (strcmp(other->series[j].name, x->name) == 0)
                y = &other->series[j];
        if (!is_base && y)
            continue; /* compared with base's */
        const struct rb_analysis_timing_series *bs = is_base ? x : y, *ns = is_base ? y : x;
        st = rb_analysis_timing_compare(x->name, bs ? bs->per_run_ms : NULL,
                                        bs ? base->bench.run_count : 0, ns ? ns->per_run_ms : NULL,
                                        ns ? new_set->bench.run_count : 0, desc, &out[n++], err);
    }
    if (st) {
        free(out);
        return st;
    }
    *rows = out;
    *row_count = n;
    return RB_OK;
}
