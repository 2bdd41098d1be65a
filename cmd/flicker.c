/* raybundle flicker: reads a rendered sequence (and the same job's reference sequence) through
 * lib/analysis, prints its temporal stability per frame and for the whole sequence as text, JSON
 * or CSV, and gates on the excess over the reference, or, without one, on a baseline: the same
 * job rendered before a change. The metrics are lib/analysis/flicker.c's. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "analysis/analysis.h"

enum format { FORMAT_TEXT = 0, FORMAT_JSON, FORMAT_CSV };

struct options {
    struct rb_analysis_flicker_desc desc;
    enum format format;
    bool has_max_excess;
    double max_excess;
    const char *baseline; /* --baseline: the gate's other sequence */
    double alpha, min_effect;
    bool has_gate_setting; /* --alpha or --min-effect given */
};

#define DEFAULT_ALPHA 0.01
#define DEFAULT_MIN_EFFECT 0.10

static void usage(FILE *f)
{
    fprintf(f,
            "usage: raybundle flicker SEQ [--reference REFSEQ | --baseline BASESEQ] [options]\n"
            "\n"
            "Measures the temporal stability of the sequence SEQ (a directory, or a pattern\n"
            "such as out/frame.####.exr) from its beauty, motion and depth layers: per frame,\n"
            "the warped temporal error (log luminance against the previous frame reprojected\n"
            "through the motion layer, disoccluded pixels left out) and the deviation of\n"
            "static pixels; with a reference sequence of the same job, the excess of the\n"
            "frame-to-frame change over the reference's (its RMS less the reference's noise\n"
            "when the reference has a variance layer), and the reference's own metrics.\n"
            "\n"
            "  --reference SEQ        the reference sequence (raybundle reference --frames A-B)\n"
            "  --max-excess X         exit 1 when the mean excess temporal error exceeds X\n"
            "  --baseline SEQ         the same job rendered before a change: exit 1 when SEQ\n"
            "                         flickers more (paired Wilcoxon signed-rank test of the\n"
            "                         frames' warped errors, one-sided, and the means' ratio)\n"
            "  --alpha A              the gate's significance level (default %g)\n"
            "  --min-effect P%%        the least rise of the mean warped error that counts\n"
            "                         (default %g%%)\n"
            "  --depth-tolerance T    a previous pixel is disoccluded when its depth differs by\n"
            "                         more than T times the pixel's (default %g)\n"
            "  --log-epsilon E        log luminance is ln(Y + E) (default %g)\n"
            "  --json                 print one JSON object\n"
            "  --csv                  print CSV: a row a frame, then the row 'all'\n"
            "  -h, --help             show this help\n"
            "\n"
            "Exit status: 0 ok, 1 --max-excess was exceeded or SEQ flickers more than the\n"
            "baseline, 2 bad usage, or a sequence that cannot be read, lacks a layer or frame,\n"
            "does not match in size, or has fewer than %d frames to pair with the baseline.\n",
            DEFAULT_ALPHA, 100.0 * DEFAULT_MIN_EFFECT, RB_ANALYSIS_FLICKER_DEPTH_TOLERANCE,
            RB_ANALYSIS_FLICKER_LOG_EPSILON, RB_ANALYSIS_FLICKER_GATE_MIN_PAIRS);
}

/* Parses a finite number > 0 (or >= 0 when may_be_zero) for opt into *out. */
static int positive(const char *opt, const char *s, bool may_be_zero, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    bool is_ok = end != s && !*end && !errno && isfinite(v) && (may_be_zero ? v >= 0.0 : v > 0.0);
    if (!is_ok)
        cmd_error("%s expects a number %s 0, got '%s'", opt, may_be_zero ? ">=" : ">", s);
    *out = v;
    return is_ok ? 0 : -1;
}

/* 0 to go on, 1 after --help, -1 after a usage error (already reported). */
static int parse_options(int argc, char **argv, struct options *o)
{
    enum {
        O_REFERENCE = 256,
        O_MAX_EXCESS,
        O_BASELINE,
        O_ALPHA,
        O_MIN_EFFECT,
        O_DEPTH_TOLERANCE,
        O_LOG_EPSILON,
        O_JSON,
        O_CSV
    };
    static const struct option opts[] = {
        {"reference", required_argument, NULL, O_REFERENCE},
        {"max-excess", required_argument, NULL, O_MAX_EXCESS},
        {"baseline", required_argument, NULL, O_BASELINE},
        {"alpha", required_argument, NULL, O_ALPHA},
        {"min-effect", required_argument, NULL, O_MIN_EFFECT},
        {"depth-tolerance", required_argument, NULL, O_DEPTH_TOLERANCE},
        {"log-epsilon", required_argument, NULL, O_LOG_EPSILON},
        {"json", no_argument, NULL, O_JSON},
        {"csv", no_argument, NULL, O_CSV},
        {"help", no_argument, NULL, 'h'},
        {0},
    };
    int c, formats = 0;
    o->alpha = DEFAULT_ALPHA;
    o->min_effect = DEFAULT_MIN_EFFECT;
    optind = 1;
    while ((c = cmd_getopt(argc, argv, "h", opts, "flicker")) != -1) {
        switch (c) {
        case O_REFERENCE: o->desc.reference = optarg; break;
        case O_MAX_EXCESS:
            if (positive("--max-excess", optarg, true, &o->max_excess))
                return -1;
            o->has_max_excess = true;
            break;
        case O_BASELINE: o->baseline = optarg; break;
        case O_ALPHA:
            if (positive("--alpha", optarg, false, &o->alpha))
                return -1;
            if (o->alpha >= 1.0) {
                cmd_error("--alpha expects a number between 0 and 1, got '%s'", optarg);
                return -1;
            }
            o->has_gate_setting = true;
            break;
        case O_MIN_EFFECT: {
            char pct[64];
            size_t len = strlen(optarg);
            snprintf(pct, sizeof(pct), "%.*s", (int)(len && optarg[len - 1] == '%' ? len - 1 : len),
                     optarg);
            if (positive("--min-effect", pct, true, &o->min_effect))
                return -1;
            o->min_effect /= 100.0;
            o->has_gate_setting = true;
            break;
        }
        case O_DEPTH_TOLERANCE:
            if (positive("--depth-tolerance", optarg, false, &o->desc.depth_tolerance))
                return -1;
            break;
        case O_LOG_EPSILON:
            if (positive("--log-epsilon", optarg, false, &o->desc.log_epsilon))
                return -1;
            break;
        case O_JSON:
        case O_CSV:
            o->format = c == O_JSON ? FORMAT_JSON : FORMAT_CSV;
            formats++;
            break;
        case 'h': usage(stdout); return 1;
        default: return -1; /* reported */
        }
    }
    const char *problem = argc - optind > 1 ? "flicker takes one sequence, SEQ"
                          : argc == optind  ? "flicker needs a sequence, SEQ"
                          : formats > 1     ? "--json and --csv exclude each other"
                          : o->has_max_excess && !o->desc.reference
                              ? "--max-excess needs --reference REFSEQ"
                          : o->baseline && o->desc.reference
                              ? "--baseline and --reference exclude each other (the gate compares "
                                "two renders; --reference holds one to the truth)"
                          : o->has_gate_setting && !o->baseline ? "--alpha and --min-effect need "
                                                                  "--baseline BASESEQ"
                                                                : NULL;
    if (problem) {
        cmd_usage_error("flicker", "%s", problem);
        return -1;
    }
    o->desc.seq = argv[optind];
    return 0;
}

/* ---- output --------------------------------------------------------------------------------- */

/* "DIR/STEM.####.exr" of a sequence, into buf. */
static const char *pattern(const struct rb_analysis_sequence *s, char *buf, size_t size)
{
    snprintf(buf, size, "%s/%s.####.exr", s->dir, s->stem);
    return buf;
}

/* A number as text and CSV print it: 9 significant digits, or "-" (text) or "" (CSV) for NaN. */
static const char *num(char *buf, size_t size, double v, const char *none)
{
    if (isfinite(v))
        snprintf(buf, size, "%.9g", v);
    else
        snprintf(buf, size, "%s", none);
    return buf;
}

/* A JSON number, or null for NaN (JSON has none). */
static json_t *jnum(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

/* One frame's columns: the same names in JSON and CSV. */
#define FRAME_COLUMNS                                                                              \
    "frame,warped_error,compared,disoccluded,offscreen,static_deviation,excess_error,"             \
    "reference_warped_error,reference_static_deviation,excess_rms"

static json_t *json_frame(const struct rb_analysis_flicker_frame *fr)
{
    json_t *o = json_object();
    json_object_set_new(o, "frame", json_integer(fr->frame));
    json_object_set_new(o, "warped_error", jnum(fr->seq.warped_error));
    json_object_set_new(o, "compared", json_integer((json_int_t)fr->seq.compared_count));
    json_object_set_new(o, "disoccluded", json_integer((json_int_t)fr->seq.disoccluded_count));
    json_object_set_new(o, "offscreen", json_integer((json_int_t)fr->seq.offscreen_count));
    json_object_set_new(o, "static_deviation", jnum(fr->seq.static_deviation));
    json_object_set_new(o, "excess_error", jnum(fr->excess_error));
    json_object_set_new(o, "reference_warped_error", jnum(fr->ref.warped_error));
    json_object_set_new(o, "reference_static_deviation", jnum(fr->ref.static_deviation));
    json_object_set_new(o, "excess_rms", jnum(fr->excess_rms));
    return o;
}

static json_t *json_summary(const struct rb_analysis_flicker_summary *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "warped_error_mean", jnum(s->warped_error));
    json_object_set_new(o, "warped_error_max", jnum(s->warped_error_max));
    json_object_set_new(o, "static_pixels", json_integer((json_int_t)s->static_count));
    json_object_set_new(o, "static_variance", jnum(s->static_variance));
    return o;
}

/* The baseline's warped error at frame, NaN without it. */
static double base_error(const struct rb_analysis_flicker *base, int frame)
{
    long k = base ? rb_analysis_sequence_find(&base->seq, frame) : -1;
    return k < 0 ? NAN : base->frames[k].seq.warped_error;
}

static const char *verdict_name(enum rb_analysis_flicker_verdict v)
{
    return v == RB_ANALYSIS_FLICKER_MORE ? "more" : v == RB_ANALYSIS_FLICKER_LESS ? "less" : "same";
}

static json_t *json_gate(const struct options *o, const struct rb_analysis_flicker_gate *g)
{
    json_t *j = json_object();
    json_object_set_new(j, "pairs", json_integer((json_int_t)g->pair_count));
    json_object_set_new(j, "warped_error_mean", jnum(g->mean));
    json_object_set_new(j, "baseline_warped_error_mean", jnum(g->base_mean));
    json_object_set_new(j, "effect", jnum(g->effect));
    json_object_set_new(j, "p_more", jnum(g->more.p));
    json_object_set_new(j, "p_less", jnum(g->less.p));
    json_object_set_new(j, "w_plus", jnum(g->more.w_plus));
    json_object_set_new(j, "exact", json_boolean(g->more.is_exact));
    json_object_set_new(j, "alpha", json_real(o->alpha));
    json_object_set_new(j, "min_effect", json_real(o->min_effect));
    json_object_set_new(j, "verdict", json_string(verdict_name(g->verdict)));
    return j;
}

static int print_json(const struct options *o, const struct rb_analysis_flicker *f,
                      const struct rb_analysis_flicker *base,
                      const struct rb_analysis_flicker_gate *g)
{
    char buf[1400];
    json_t *root = json_object(), *frames = json_array(), *summary = json_summary(&f->summary);
    json_object_set_new(root, "sequence", json_string(pattern(&f->seq, buf, sizeof(buf))));
    json_object_set_new(root, "reference",
                        f->has_reference ? json_string(pattern(&f->ref, buf, sizeof(buf)))
                                         : json_null());
    json_object_set_new(root, "width", json_integer(f->width_px));
    json_object_set_new(root, "height", json_integer(f->height_px));
    json_object_set_new(root, "log_epsilon", json_real(f->desc.log_epsilon));
    json_object_set_new(root, "depth_tolerance", json_real(f->desc.depth_tolerance));
    json_object_set_new(root, "reference_noise_corrected",
                        f->has_reference ? json_boolean(f->is_noise_corrected) : json_null());
    for (size_t i = 0; i < f->seq.frame_count; i++) {
        json_t *fr = json_frame(&f->frames[i]);
        if (base)
            json_object_set_new(fr, "baseline_warped_error",
                                jnum(base_error(base, f->frames[i].frame)));
        json_array_append_new(frames, fr);
    }
    json_object_set_new(root, "frames", frames);
    json_object_set_new(root, "baseline",
                        base ? json_string(pattern(&base->seq, buf, sizeof(buf))) : json_null());
    json_object_set_new(root, "gate", base ? json_gate(o, g) : json_null());
    json_object_set_new(summary, "excess_error_mean", jnum(f->excess_error));
    json_object_set_new(summary, "excess_error_max", jnum(f->excess_error_max));
    json_object_set_new(summary, "excess_rms", jnum(f->excess_rms));
    json_object_set_new(summary, "reference",
                        f->has_reference ? json_summary(&f->reference_summary) : json_null());
    json_object_set_new(root, "summary", summary);
    json_object_set_new(root, "max_excess",
                        o->has_max_excess ? json_real(o->max_excess) : json_null());
    int rc = json_dumpf(root, stdout, JSON_INDENT(2) | JSON_REAL_PRECISION(9));
    json_decref(root);
    putchar('\n');
    return rc;
}

static void print_csv(const struct rb_analysis_flicker *f, const struct rb_analysis_flicker *base)
{
    char a[32], b[32], c[32], d[32], e[32], r[32], x[32];
    uint64_t compared = 0, disoccluded = 0, offscreen = 0;
    puts(base ? FRAME_COLUMNS ",baseline_warped_error" : FRAME_COLUMNS);
    for (size_t i = 0; i < f->seq.frame_count; i++) {
        const struct rb_analysis_flicker_frame *fr = &f->frames[i];
        printf("%d,%s,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%s,%s,%s,%s,%s%s%s\n", fr->frame,
               num(a, sizeof(a), fr->seq.warped_error, ""), fr->seq.compared_count,
               fr->seq.disoccluded_count, fr->seq.offscreen_count,
               num(b, sizeof(b), fr->seq.static_deviation, ""),
               num(c, sizeof(c), fr->excess_error, ""), num(d, sizeof(d), fr->ref.warped_error, ""),
               num(e, sizeof(e), fr->ref.static_deviation, ""),
               num(r, sizeof(r), fr->excess_rms, ""), base ? "," : "",
               base ? num(x, sizeof(x), base_error(base, fr->frame), "") : "");
        compared += fr->seq.compared_count;
        disoccluded += fr->seq.disoccluded_count;
        offscreen += fr->seq.offscreen_count;
    }
    printf("all,%s,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%s,%s,%s,%s,%s%s%s\n",
           num(a, sizeof(a), f->summary.warped_error, ""), compared, disoccluded, offscreen,
           num(b, sizeof(b), f->summary.static_variance, ""),
           num(c, sizeof(c), f->excess_error, ""),
           num(d, sizeof(d), f->reference_summary.warped_error, ""),
           num(e, sizeof(e), f->reference_summary.static_variance, ""),
           num(r, sizeof(r), f->excess_rms, ""), base ? "," : "",
           base ? num(x, sizeof(x), base->summary.warped_error, "") : "");
}

/* A pixel count as a percentage of the frame. */
static double pct(const struct rb_analysis_flicker *f, uint64_t count)
{
    return 100.0 * (double)count / ((double)f->width_px * f->height_px);
}

static void print_summary(const char *name, const struct rb_analysis_flicker_summary *s)
{
    char a[32], b[32], c[32];
    printf("%-28s mean %s, max %s\n", name, num(a, sizeof(a), s->warped_error, "-"),
           num(b, sizeof(b), s->warped_error_max, "-"));
    printf("%-28s %s over %" PRIu64 " static pixels\n", "  static variance",
           num(c, sizeof(c), s->static_variance, "-"), s->static_count);
}

static void print_text(const struct rb_analysis_flicker *f)
{
    char a[32], b[32], c[32], d[32], e[32], buf[1400];
    const struct rb_analysis_sequence *s = &f->seq;
    printf("sequence   %s: %zu frame%s, %d to %d, %ux%u\n", pattern(s, buf, sizeof(buf)),
           s->frame_count, s->frame_count == 1 ? "" : "s", s->frames[0],
           s->frames[s->frame_count - 1], f->width_px, f->height_px);
    printf("reference  %s\n", f->has_reference ? pattern(&f->ref, buf, sizeof(buf)) : "none");
    printf("log luminance ln(Y + %g); depth tolerance %g\n\n", f->desc.log_epsilon,
           f->desc.depth_tolerance);
    printf("%8s %14s %9s %9s %14s %14s %14s %14s\n", "frame", "warped", "disocc%", "offscr%",
           "static dev", "excess", "ref warped", "ref static dev");
    for (size_t i = 0; i < s->frame_count; i++) {
        const struct rb_analysis_flicker_frame *fr = &f->frames[i];
        printf("%8d %14s %9.2f %9.2f %14s %14s %14s %14s\n", fr->frame,
               num(a, sizeof(a), fr->seq.warped_error, "-"), pct(f, fr->seq.disoccluded_count),
               pct(f, fr->seq.offscreen_count), num(b, sizeof(b), fr->seq.static_deviation, "-"),
               num(c, sizeof(c), fr->excess_error, "-"),
               num(d, sizeof(d), fr->ref.warped_error, "-"),
               num(e, sizeof(e), fr->ref.static_deviation, "-"));
    }
    printf("\n");
    print_summary("warped temporal error", &f->summary);
    if (f->has_reference) {
        printf("%-28s mean %s, max %s\n", "excess temporal error",
               num(a, sizeof(a), f->excess_error, "-"),
               num(b, sizeof(b), f->excess_error_max, "-"));
        printf("%-28s %s%s\n", "  RMS", num(a, sizeof(a), f->excess_rms, "-"),
               f->is_noise_corrected ? ", less the reference's noise (its variance layer)"
                                     : "; both count the reference's noise (it has no variance "
                                       "layer)");
        print_summary("reference warped error", &f->reference_summary);
    }
}

/* The gate's table and verdict, after the sequence's own. */
static void print_gate(const struct options *o, const struct rb_analysis_flicker *f,
                       const struct rb_analysis_flicker *base,
                       const struct rb_analysis_flicker_gate *g)
{
    char a[32], b[32], c[32], buf[1400];
    printf("\nbaseline   %s\n\n", pattern(&base->seq, buf, sizeof(buf)));
    printf("%8s %14s %14s %14s\n", "frame", "warped", "baseline", "difference");
    for (size_t i = 0; i < f->seq.frame_count; i++) {
        double e = f->frames[i].seq.warped_error, eb = base_error(base, f->frames[i].frame);
        printf("%8d %14s %14s %14s\n", f->frames[i].frame, num(a, sizeof(a), e, "-"),
               num(b, sizeof(b), eb, "-"), num(c, sizeof(c), e - eb, "-"));
    }
    printf("\n%zu paired frames: mean warped error %s, baseline %s (%+.1f%%)\n", g->pair_count,
           num(a, sizeof(a), g->mean, "-"), num(b, sizeof(b), g->base_mean, "-"),
           100.0 * g->effect);
    printf("Wilcoxon signed-rank (%s): p = %.3g that it flickers more, %.3g less; alpha %g, "
           "least effect %g%%\n",
           g->more.is_exact ? "exact" : "normal approximation", g->more.p, g->less.p, o->alpha,
           100.0 * o->min_effect);
    printf("verdict: %s\n",
           g->verdict == RB_ANALYSIS_FLICKER_MORE   ? "flickers more than the baseline"
           : g->verdict == RB_ANALYSIS_FLICKER_LESS ? "flickers less than the baseline"
                                                    : "the same as the baseline");
}

/* ---- the command ---------------------------------------------------------------------------- */

int cmd_flicker(int argc, char **argv)
{
    struct options o = {0};
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;

    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_flicker *f = NULL;
    enum rb_status st = rb_analysis_flicker_create(&o.desc, &f, &err);
    if (st) {
        cmd_error("%s", err.msg);
        return st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
    }
    struct rb_analysis_flicker *base = NULL;
    struct rb_analysis_flicker_gate gate = {0};
    if (o.baseline) {
        struct rb_analysis_flicker_desc bd = o.desc;
        bd.seq = o.baseline;
        if ((st = rb_analysis_flicker_create(&bd, &base, &err)) ||
            (st = rb_analysis_flicker_gate(f, base, o.alpha, o.min_effect, &gate, &err))) {
            cmd_error("%s", err.msg);
            rb_analysis_flicker_destroy(base);
            rb_analysis_flicker_destroy(f);
            return st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
        }
    }
    rc = RB_EXIT_OK;
    if (o.has_max_excess && !isfinite(f->excess_error)) {
        cmd_error("--max-excess needs two consecutive frames in both sequences; '%s' has none",
                  o.desc.seq);
        rc = RB_EXIT_USAGE;
        goto out;
    }
    if (o.format == FORMAT_JSON) {
        if (print_json(&o, f, base, &gate)) {
            cmd_error("cannot write the JSON output");
            rc = RB_EXIT_FAILED;
            goto out;
        }
    } else if (o.format == FORMAT_CSV) {
        print_csv(f, base);
    } else {
        print_text(f);
        if (base)
            print_gate(&o, f, base, &gate);
    }
    fflush(stdout);
    if (o.has_max_excess && f->excess_error > o.max_excess) {
        cmd_error("excess temporal error %.9g exceeds --max-excess %.9g", f->excess_error,
                  o.max_excess);
        rc = RB_EXIT_FAILED;
    }
    if (base && gate.verdict == RB_ANALYSIS_FLICKER_MORE) {
        cmd_error("'%s' flickers more than the baseline '%s': mean warped error %.6g against "
                  "%.6g (%+.1f%%), p = %.3g over %zu frames",
                  o.desc.seq, o.baseline, gate.mean, gate.base_mean, 100.0 * gate.effect,
                  gate.more.p, gate.pair_count);
        rc = RB_EXIT_FAILED;
    }
out:
    rb_analysis_flicker_destroy(base);
    rb_analysis_flicker_destroy(f);
    return rc;
}
