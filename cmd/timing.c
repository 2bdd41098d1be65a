/* raybundle timing compare: loads two bench sets (raybundle bench), refuses to compare sets from
 * different devices, drivers or jobs unless --force, and prints per pass and for the frame's
 * wall time the medians, the change, the Mann-Whitney p-value and a verdict, as a table or
 * JSON. The statistics live in lib/analysis (timing.c). */
#include "cmd.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analysis/analysis.h"

#define FEW_RUNS 9 /* fewer runs a set than this earn a warning */

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle timing compare BASE NEW [options]\n"
               "\n"
               "Compares two bench sets (directories made by 'raybundle bench') per pass and\n"
               "for the frame wall time: one sample a run (the mean over its frames), the\n"
               "two-sided Mann-Whitney U test, and a verdict: faster, slower, same or too few\n"
               "runs.\n"
               "\n"
               "  --threshold P%%   a change of the medians within P percent is 'same' (5%%)\n"
               "  --alpha A        the significance level (0.05)\n"
               "  --json           print JSON instead of the table\n"
               "  --force          compare sets from different devices, drivers or jobs\n"
               "  -h, --help       show this help\n"
               "\n"
               "Exit status: 0 nothing slower, 1 a pass slower beyond the threshold with\n"
               "p < alpha, 2 bad usage, a set that cannot be read, or sets that differ.\n");
}

/* A number in (lo, hi) with an optional suffix ('%' for the threshold). */
static int parse_number(const char *opt, const char *arg, const char *suffix, double lo, double hi,
                        double *out)
{
    char *end = NULL;
    double v = strtod(arg, &end);
    if (end != arg && suffix && strcmp(end, suffix) == 0)
        end += strlen(suffix);
    if (end == arg || *end || !(v >= lo && v < hi)) {
        cmd_error("%s expects a number in [%g, %g), got '%s'", opt, lo, hi, arg);
        return -1;
    }
    *out = v;
    return 0;
}

static void json_str(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        if (*s == '"' || *s == '\\')
            printf("\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            printf("\\u%04x", *s);
        else
            putchar(*s);
    }
    putchar('"');
}

/* ", \"key\": " and a string, or a number (null where it is not finite: JSON has neither NaN
 * nor infinity). */
static void json_field_str(const char *key, const char *v)
{
    printf(", \"%s\": ", key);
    json_str(v);
}

static void json_field_num(const char *key, double v)
{
    printf(", \"%s\": ", key);
    if (isfinite(v))
        printf("%.17g", v);
    else
        fputs("null", stdout);
}

static void print_json(const struct rb_analysis_timing_set *base,
                       const struct rb_analysis_timing_set *new_set,
                       const struct rb_analysis_timing_desc *desc,
                       const struct rb_analysis_timing_row *rows, size_t n, bool is_regression)
{
    const struct rb_analysis_timing_set *sets[] = {base, new_set};
    printf("{\n  \"alpha\": %g,\n  \"threshold_pct\": %g,\n", desc->alpha, desc->threshold_pct);
    for (int i = 0; i < 2; i++) {
        const struct rb_io_bench *b = &sets[i]->bench;
        printf("  \"%s\": {\"runs\": %u", i ? "new" : "base", b->run_count);
        json_field_str("dir", sets[i]->dir);
        json_field_str("device", b->device);
        json_field_str("driver", b->driver);
        json_field_str("build", b->build);
        json_field_str("job_hash", b->job_hash);
        fputs("},\n", stdout);
    }
    fputs("  \"rows\": [", stdout);
    for (size_t i = 0; i < n; i++) {
        const struct rb_analysis_timing_row *r = &rows[i];
        bool has_both = r->base_count && r->new_count;
        fputs(i ? ",\n    {\"name\": " : "\n    {\"name\": ", stdout);
        json_str(r->name);
        printf(", \"base_runs\": %zu, \"new_runs\": %zu", r->base_count, r->new_count);
        json_field_num("base_median_ms", r->base_median_ms);
        json_field_num("new_median_ms", r->new_median_ms);
        json_field_num("change_pct", r->change_pct);
        json_field_num("u", has_both ? r->test.u : NAN);
        json_field_num("p", r->test.p);
        json_field_str("method", !has_both                                 ? "none"
                                 : r->test.method == RB_ANALYSIS_MWU_EXACT ? "exact"
                                                                           : "normal");
        json_field_str("verdict", rb_analysis_verdict_name(r->verdict));
        fputs("}", stdout);
    }
    printf("\n  ],\n  \"regression\": %s\n}\n", is_regression ? "true" : "false");
}

static void print_table(const struct rb_analysis_timing_row *rows, size_t n)
{
    printf("%-12s %14s %14s %9s %9s  %s\n", "pass", "base median", "new median", "change",
           "p-value", "verdict");
    for (size_t i = 0; i < n; i++) {
        const struct rb_analysis_timing_row *r = &rows[i];
        char base[32] = "-", new_ms[32] = "-", change[32] = "-", p[32] = "-";
        if (r->base_count)
            snprintf(base, sizeof(base), "%.3f ms", r->base_median_ms);
        if (r->new_count)
            snprintf(new_ms, sizeof(new_ms), "%.3f ms", r->new_median_ms);
        if (!isnan(r->change_pct))
            snprintf(change, sizeof(change), "%+.1f%%", r->change_pct);
        if (!isnan(r->test.p))
            snprintf(p, sizeof(p), "%.4f", r->test.p);
        printf("%-12s %14s %14s %9s %9s  %s\n", r->name, base, new_ms, change, p,
               rb_analysis_verdict_name(r->verdict));
    }
}

static int compare(int argc, char **argv)
{
    enum { O_THRESHOLD = 256, O_ALPHA, O_JSON, O_FORCE };
    static const struct option opts[] = {
        {"threshold", required_argument, NULL, O_THRESHOLD},
        {"alpha", required_argument, NULL, O_ALPHA},
        {"json", no_argument, NULL, O_JSON},
        {"force", no_argument, NULL, O_FORCE},
        {"help", no_argument, NULL, 'h'},
        {0},
    };
    struct rb_analysis_timing_desc desc = RB_ANALYSIS_TIMING_DESC_INIT;
    bool is_json = false, is_forced = false;
    int c;
    optind = 1;
    while ((c = cmd_getopt(argc, argv, "h", opts, "timing compare")) != -1) {
        int bad = 0;
        switch (c) {
        case O_THRESHOLD:
            bad = parse_number("--threshold", optarg, "%", 0.0, INFINITY, &desc.threshold_pct);
            break;
        case O_ALPHA: bad = parse_number("--alpha", optarg, NULL, 1e-12, 1.0, &desc.alpha); break;
        case O_JSON: is_json = true; break;
        case O_FORCE: is_forced = true; break;
        case 'h': usage(stdout); return RB_EXIT_OK;
        default: return RB_EXIT_USAGE; /* reported */
        }
        if (bad)
            return RB_EXIT_USAGE;
    }
    if (argc - optind != 2) {
        cmd_usage_error("timing compare", "timing compare %s BASE and NEW, two bench directories",
                        argc - optind < 2 ? "needs" : "takes");
        return RB_EXIT_USAGE;
    }
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_set *base = NULL, *new_set = NULL;
    struct rb_analysis_timing_row *rows = NULL;
    size_t n = 0;
    int rc = RB_EXIT_OK;
    enum rb_status st;
    if ((st = rb_analysis_timing_set_load(argv[optind], &base, &err)) ||
        (st = rb_analysis_timing_set_load(argv[optind + 1], &new_set, &err))) {
        cmd_error("%s", err.msg);
        rc = st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
        goto out;
    }
    if (rb_analysis_timing_sets_match(base, new_set, &err)) {
        if (!is_forced) {
            cmd_error("%s (--force compares them anyway)", err.msg);
            rc = RB_EXIT_USAGE;
            goto out;
        }
        fprintf(stderr, "raybundle: warning: %s; compared anyway (--force)\n", err.msg);
    }
    for (int i = 0; i < 2; i++) {
        const struct rb_analysis_timing_set *s = i ? new_set : base;
        if (s->bench.run_count < FEW_RUNS)
            fprintf(stderr,
                    "raybundle: warning: %s '%s' has %u run%s: %d or more are recommended for a "
                    "verdict to mean much\n",
                    i ? "new" : "base", s->dir, s->bench.run_count,
                    s->bench.run_count == 1 ? "" : "s", FEW_RUNS);
    }
    if ((st = rb_analysis_timing_compare_sets(base, new_set, &desc, &rows, &n, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_FAILED;
        goto out;
    }
    bool is_regression = false;
    for (size_t i = 0; i < n; i++)
        is_regression = is_regression || rows[i].verdict == RB_ANALYSIS_SLOWER;
    if (is_json)
        print_json(base, new_set, &desc, rows, n, is_regression);
    else
        print_table(rows, n);
    rc = is_regression ? RB_EXIT_FAILED : RB_EXIT_OK;
out:
    free(rows);
    rb_analysis_timing_set_destroy(base);
    rb_analysis_timing_set_destroy(new_set);
    return rc;
}

int cmd_timing(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "compare") == 0)
        return compare(argc - 1, argv + 1);
    if (argc > 1 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0)) {
        usage(stdout);
        return RB_EXIT_OK;
    }
    if (argc < 2) {
        cmd_usage_error("timing", "timing needs a command: 'timing compare BASE NEW'");
        return RB_EXIT_USAGE;
    }
    struct rb_suggest near;
    rb_suggest_init(&near, argv[1]);
    rb_suggest_offer(&near, "compare", strlen("compare"));
    if (near.best[0])
        cmd_error("unknown timing command '%s'; did you mean 'compare'?", argv[1]);
    else
        cmd_usage_error("timing", "unknown timing command '%s' (its one command is 'compare')",
                        argv[1]);
    return RB_EXIT_USAGE;
}
