/* raybundle compare: parse options, load two images (or two frame sequences) through io, build
 * the mask, call lib/analysis for the metrics, write the error images, and print the result as
 * text or JSON. The metrics themselves live in lib/analysis/compare.c. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "analysis/analysis.h"
#include "io/io.h"

#define MAX_FRAMES 1000000

struct options {
    const char *a, *b;
    const char *frames, *layer, *mask, *error_image;
    bool mask_alpha, json;
    uint32_t exclude_edges_px;
    double epsilon;
    double peak; /* --peak: PSNR's peak; 0 means RB_ANALYSIS_PEAK */
    bool has_max_relmse, has_max_rmse;
    double max_relmse, max_rmse;
    /* Derived: */
    bool is_sequence;
    int first, last;
};

struct frame_result {
    int frame;
    struct rb_analysis_metrics m;
};

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: raybundle compare A B [options]\n"
        "\n"
        "Compares the test image A against the reference B (EXR or any image OpenImageIO\n"
        "reads), or two frame sequences given as patterns with a '#' run plus --frames.\n"
        "Prints RMSE, relative MSE, mean absolute error, PSNR and the largest error.\n"
        "PSNR is computed with peak 1.0, i.e. for display-referred values, unless --peak\n"
        "gives another.\n"
        "\n"
        "  --frames A-B         frames A to B (or one frame: A) of two '#' patterns\n"
        "  --layer NAME         beauty (R,G,B; default), direct, indirect, albedo (NAME.R/G/B),\n"
        "                       normal (X/Y/Z), depth (Z), motion (X/Y); any case\n"
        "  --mask PATH          compare only pixels whose first channel is > 0.5\n"
        "  --mask-alpha         compare only pixels where A's and B's alpha are > 0.5\n"
        "  --exclude-edges N    skip pixels within N pixels of a depth or alpha edge in B\n"
        "  --epsilon E          relMSE = (a-b)^2 / (b^2 + E), averaged (default 0.01)\n"
        "  --peak V             PSNR = 10 log10(V^2 / MSE) with V > 0 (default 1.0)\n"
        "  --error-image PATH   write |a-b| as R,G,B and relMSE as relmse.Y ('#' per frame)\n"
        "  --max-relmse X       exit 1 when the relative MSE exceeds X\n"
        "  --max-rmse X         exit 1 when the RMSE exceeds X\n"
        "  --json               print one JSON object instead of text\n"
        "  -h, --help           show this help\n"
        "\n"
        "Exit status: 0 ok, 1 a --max-* threshold was exceeded, 2 bad usage, an unreadable\n"
        "file, mismatched sizes or a missing layer.\n");
}

/* Parses a finite number >= min (or > min when strict) into *out. */
static int parse_number(const char *opt, const char *s, double min, bool strict, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v) || v < min || (strict && v == min)) {
        cmd_error("%s expects a number %s %g, got '%s'", opt, strict ? ">" : ">=", min, s);
        return -1;
    }
    *out = v;
    return 0;
}

static int parse_frames(struct options *o)
{
    int a, b;
    char tail;
    int n = sscanf(o->frames, "%d-%d%c", &a, &b, &tail);
    if (n == 1)
        b = a;
    if ((n != 1 && n != 2) || b < a) {
        cmd_error("--frames expects A-B with A <= B, or A, got '%s'", o->frames);
        return -1;
    }
    if ((long long)b - a >= MAX_FRAMES) {
        cmd_error("--frames '%s' spans more than %d frames", o->frames, MAX_FRAMES);
        return -1;
    }
    o->first = a;
    o->last = b;
    return 0;
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum {
        O_FRAMES = 256,
        O_LAYER,
        O_MASK,
        O_MASK_ALPHA,
        O_EXCLUDE_EDGES,
        O_EPSILON,
        O_PEAK,
        O_ERROR_IMAGE,
        O_MAX_RELMSE,
        O_MAX_RMSE,
        O_JSON
    };
    static const struct option opts[] = {
        {"frames", required_argument, NULL, O_FRAMES},
        {"layer", required_argument, NULL, O_LAYER},
        {"mask", required_argument, NULL, O_MASK},
        {"mask-alpha", no_argument, NULL, O_MASK_ALPHA},
        {"exclude-edges", required_argument, NULL, O_EXCLUDE_EDGES},
        {"epsilon", required_argument, NULL, O_EPSILON},
        {"peak", required_argument, NULL, O_PEAK},
        {"error-image", required_argument, NULL, O_ERROR_IMAGE},
        {"max-relmse", required_argument, NULL, O_MAX_RELMSE},
        {"max-rmse", required_argument, NULL, O_MAX_RMSE},
        {"json", no_argument, NULL, O_JSON},
        {"help", no_argument, NULL, 'h'},
        {0},
    };
    int c;
    optind = 1;
    while ((c = cmd_getopt(argc, argv, "h", opts, "compare")) != -1) {
        switch (c) {
        case O_FRAMES: o->frames = optarg; break;
        case O_LAYER: o->layer = optarg; break;
        case O_MASK: o->mask = optarg; break;
        case O_MASK_ALPHA: o->mask_alpha = true; break;
        case O_EXCLUDE_EDGES: {
            char *end = NULL;
            errno = 0;
            long v = strtol(optarg, &end, 10);
            if (end == optarg || *end || errno || v < 0 || v > 65535) {
                cmd_error("--exclude-edges expects a pixel count 0..65535, got '%s'", optarg);
                return -1;
            }
            o->exclude_edges_px = (uint32_t)v;
            break;
        }
        case O_EPSILON:
            if (parse_number("--epsilon", optarg, 0.0, true, &o->epsilon))
                return -1;
            break;
        case O_PEAK:
            if (parse_number("--peak", optarg, 0.0, true, &o->peak))
                return -1;
            break;
        case O_ERROR_IMAGE: o->error_image = optarg; break;
        case O_MAX_RELMSE:
            if (parse_number("--max-relmse", optarg, 0.0, false, &o->max_relmse))
                return -1;
            o->has_max_relmse = true;
            break;
        case O_MAX_RMSE:
            if (parse_number("--max-rmse", optarg, 0.0, false, &o->max_rmse))
                return -1;
            o->has_max_rmse = true;
            break;
        case O_JSON: o->json = true; break;
        case 'h': usage(stdout); return 1;
        default: return -1; /* reported */
        }
    }
    if (argc - optind != 2) {
        cmd_usage_error("compare", argc - optind < 2 ? "compare needs two images, A and B"
                                                     : "compare takes two images, A and B");
        return -1;
    }
    o->a = argv[optind];
    o->b = argv[optind + 1];
    bool pa = strchr(o->a, '#') != NULL, pb = strchr(o->b, '#') != NULL;
    if (pa != pb) {
        cmd_error("'%s' is a frame pattern and '%s' is not: give two images or two patterns",
                  pa ? o->a : o->b, pa ? o->b : o->a);
        return -1;
    }
    o->is_sequence = pa;
    if (o->is_sequence && !o->frames) {
        cmd_error("frame patterns need --frames A-B");
        return -1;
    }
    if (!o->is_sequence && o->frames) {
        cmd_error("--frames needs A and B to be frame patterns with a '#' run");
        return -1;
    }
    if (o->frames && parse_frames(o))
        return -1;
    if (o->is_sequence && o->error_image && !strchr(o->error_image, '#')) {
        cmd_error("--error-image for a sequence needs a '#' run in '%s'", o->error_image);
        return -1;
    }
    return 0;
}

/* The path of frame f of pattern, or the path itself for single images. */
static int frame_path(const struct options *o, const char *pattern, int f, char *out, size_t size)
{
    struct rb_err err = RB_ERR_INIT;
    if (!o->is_sequence || !strchr(pattern, '#')) {
        if (rb_strlcpy(out, pattern, size) >= size) {
            cmd_error("path '%.60s...' is too long", pattern);
            return -1;
        }
        return 0;
    }
    if (rb_io_frame_path(pattern, f, out, size, &err)) {
        cmd_error("%s", err.msg);
        return -1;
    }
    return 0;
}

/* Fails before any work when a frame is missing from either sequence (or the mask's). */
static int check_frames_exist(const struct options *o)
{
    const char *patterns[] = {o->a, o->b, o->mask};
    for (int f = o->first; f <= o->last; f++) {
        for (size_t k = 0; k < sizeof(patterns) / sizeof(patterns[0]); k++) {
            char path[4096];
            struct stat sb;
            if (!patterns[k] || (k == 2 && !strchr(patterns[k], '#')))
                continue;
            if (frame_path(o, patterns[k], f, path, sizeof(path)))
                return -1;
            if (stat(path, &sb) != 0) {
                cmd_error("frame %d: cannot read '%s': %s", f, path, strerror(errno));
                return -1;
            }
        }
    }
    return 0;
}

/* Starts the mask from the --mask image (all ones without one). */
static enum rb_status load_mask(const char *path, uint32_t w, uint32_t h, uint8_t *mask,
                                struct rb_err *err)
{
    size_t n = (size_t)w * h;
    memset(mask, 1, n);
    if (!path)
        return RB_OK;
    struct rb_io_image img = {0};
    enum rb_status st = rb_io_image_read(path, &img, err);
    if (st)
        return st;
    if (img.width_px != w || img.height_px != h)
        st = rb_errf(err, RB_E_INVALID, "size mismatch: mask '%s' is %ux%u, the images are %ux%u",
                     path, img.width_px, img.height_px, w, h);
    else
        rb_analysis_mask_and(mask, n, img.pixels, img.channel_count);
    rb_io_image_release(&img);
    return st;
}

/* Where the channel is in img, or an error naming the file and the option that needs it. */
static enum rb_status need_channel(const struct rb_io_image *img, const char *path,
                                   const char *channel, const char *option, int *out,
                                   struct rb_err *err)
{
    *out = rb_io_image_channel(img, channel);
    if (*out < 0)
        return rb_errf(err, RB_E_INVALID, "%s needs channel '%s', which '%s' does not have", option,
                       channel, path);
    return RB_OK;
}

/* Compares one pair of files into *out and writes its error image when asked. */
static enum rb_status compare_frame(const struct options *o, const struct rb_analysis_layer *layer,
                                    const char *path_a, const char *path_b, const char *mask_path,
                                    const char *error_path, struct rb_analysis_metrics *out,
                                    struct rb_err *err)
{
    struct rb_io_image ia = {0}, ib = {0};
    float *a = NULL, *b = NULL, *abs_error = NULL, *rel_error = NULL;
    uint8_t *mask = NULL;
    enum rb_status st;

    if ((st = rb_io_image_read(path_a, &ia, err)) || (st = rb_io_image_read(path_b, &ib, err)))
        goto out;
    uint32_t w = ia.width_px, h = ia.height_px;
    size_t n = (size_t)w * h;
    if (ib.width_px != w || ib.height_px != h) {
        st = rb_errf(err, RB_E_INVALID, "size mismatch: '%s' is %ux%u, '%s' is %ux%u", path_a, w, h,
                     path_b, ib.width_px, ib.height_px);
        goto out;
    }
    if ((st = rb_analysis_layer_extract(layer, &ia, path_a, &a, err)) ||
        (st = rb_analysis_layer_extract(layer, &ib, path_b, &b, err)))
        goto out;
    mask = malloc(n);
    if (!mask) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for a %ux%u mask", w, h);
        goto out;
    }
    if ((st = load_mask(mask_path, w, h, mask, err)))
        goto out;
    if (o->mask_alpha) {
        int ca, cb;
        if ((st = need_channel(&ia, path_a, "A", "--mask-alpha", &ca, err)) ||
            (st = need_channel(&ib, path_b, "A", "--mask-alpha", &cb, err)))
            goto out;
        rb_analysis_mask_and(mask, n, ia.pixels + ca, ia.channel_count);
        rb_analysis_mask_and(mask, n, ib.pixels + cb, ib.channel_count);
    }
    if (o->exclude_edges_px) {
        int cd, calpha = rb_io_image_channel(&ib, "A");
        if ((st = need_channel(&ib, path_b, "depth.Z", "--exclude-edges", &cd, err)))
            goto out;
        struct rb_analysis_edge_desc ed = {
            .width_px = w,
            .height_px = h,
            .depth = ib.pixels + cd,
            .depth_stride = ib.channel_count,
            .alpha = calpha >= 0 ? ib.pixels + calpha : NULL,
            .alpha_stride = ib.channel_count,
            .radius_px = o->exclude_edges_px,
        };
        if ((st = rb_analysis_exclude_edges(&ed, mask, err)))
            goto out;
    }
    if (error_path) {
        abs_error = malloc(n * layer->channel_count * sizeof(float));
        rel_error = malloc(n * sizeof(float));
        if (!abs_error || !rel_error) {
            st = rb_errf(err, RB_E_NOMEM, "out of memory for the error image of '%s'", path_a);
            goto out;
        }
    }
    st = rb_analysis_compare(
        &(struct rb_analysis_compare_desc){.width_px = w,
                                           .height_px = h,
                                           .channel_count = layer->channel_count,
                                           .a = a,
                                           .b = b,
                                           .mask = mask,
                                           .epsilon = o->epsilon,
                                           .peak = o->peak,
                                           .abs_error = abs_error,
                                           .rel_error = rel_error},
        out, err);
    if (st)
        goto out;
    if (error_path && ((st = rb_io_make_parent_dirs(error_path, err)) ||
                       (st = rb_analysis_error_write(error_path, w, h, layer->channel_count,
                                                     abs_error, rel_error, err))))
        goto out;
out:
    free(rel_error);
    free(abs_error);
    free(mask);
    free(b);
    free(a);
    rb_io_image_release(&ib);
    rb_io_image_release(&ia);
    return st;
}

/* ---- output ----------------------------------------------------------------------------- */

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

/* The metrics shared by the whole result and each frame, as JSON members. */
static void json_metrics(FILE *f, const struct rb_analysis_metrics *m, const char *sep)
{
    fprintf(f, "\"pixels\": %" PRIu64 ",%s\"rmse\": %.9g,%s\"relmse\": %.9g,%s\"mae\": %.9g,%s",
            m->pixel_count, sep, m->rmse, sep, m->relmse, sep, m->mae, sep);
    if (isinf(m->psnr))
        fprintf(f, "\"psnr\": null,%s", sep);
    else
        fprintf(f, "\"psnr\": %.9g,%s", m->psnr, sep);
    fprintf(f, "\"peak\": %.9g,%s\"max_error\": %.9g,%s\"max_error_pixel\": [%u, %u],%s", m->peak,
            sep, m->max_error, sep, m->max_error_x, m->max_error_y, sep);
    fprintf(f, "\"nonfinite_pixels\": %" PRIu64, m->nonfinite_count);
}

static void print_json(const struct options *o, const struct rb_analysis_layer *layer,
                       const struct rb_analysis_metrics *total, const struct frame_result *frames,
                       size_t frame_count)
{
    printf("{\n  \"a\": ");
    json_string(stdout, o->a);
    printf(",\n  \"b\": ");
    json_string(stdout, o->b);
    printf(",\n  \"layer\": ");
    json_string(stdout, layer->name);
    printf(",\n  \"channels\": [");
    for (uint32_t c = 0; c < layer->channel_count; c++) {
        printf(c ? ", " : "");
        json_string(stdout, layer->channels[c]);
    }
    printf("],\n  \"epsilon\": %.9g,\n  ", o->epsilon > 0.0 ? o->epsilon : RB_ANALYSIS_EPSILON);
    json_metrics(stdout, total, "\n  ");
    if (o->is_sequence) {
        printf(",\n  \"max_error_frame\": %d,\n  \"frames\": [", total->max_error_frame);
        for (size_t i = 0; i < frame_count; i++) {
            char a[4096], b[4096];
            /* These paths were made once already, so they cannot fail now. */
            if (frame_path(o, o->a, frames[i].frame, a, sizeof(a)) ||
                frame_path(o, o->b, frames[i].frame, b, sizeof(b)))
                RB_BUG("frame path for frame %d failed", frames[i].frame);
            printf("%s\n    {\"frame\": %d, \"a\": ", i ? "," : "", frames[i].frame);
            json_string(stdout, a);
            printf(", \"b\": ");
            json_string(stdout, b);
            printf(", ");
            json_metrics(stdout, &frames[i].m, " ");
            printf("}");
        }
        printf("\n  ]");
    }
    printf("\n}\n");
}

static void print_text(const struct options *o, const struct rb_analysis_layer *layer,
                       const struct rb_analysis_metrics *m, const struct frame_result *frames,
                       size_t frame_count)
{
    printf("%-10s %s\n%-10s %s\n%-10s %s (", "a", o->a, "b", o->b, "layer", layer->name);
    for (uint32_t c = 0; c < layer->channel_count; c++)
        printf("%s%s", c ? ", " : "", layer->channels[c]);
    printf(")\n");
    if (o->is_sequence) {
        printf("%-10s %d-%d\n\n", "frames", o->first, o->last);
        printf("%8s %10s %16s %16s %16s %16s %16s %12s\n", "frame", "pixels", "rmse", "relmse",
               "mae", "psnr", "max_error", "at");
        for (size_t i = 0; i < frame_count; i++) {
            const struct rb_analysis_metrics *f = &frames[i].m;
            char psnr[32], at[32];
            if (isinf(f->psnr))
                snprintf(psnr, sizeof(psnr), "inf");
            else
                snprintf(psnr, sizeof(psnr), "%.9g", f->psnr);
            snprintf(at, sizeof(at), "(%u, %u)", f->max_error_x, f->max_error_y);
            printf("%8d %10" PRIu64 " %16.9g %16.9g %16.9g %16s %16.9g %12s\n", frames[i].frame,
                   f->pixel_count, f->rmse, f->relmse, f->mae, psnr, f->max_error, at);
        }
        printf("\n");
    }
    printf("%-10s %" PRIu64 "\n", "pixels", m->pixel_count);
    printf("%-10s %.9g\n", "rmse", m->rmse);
    printf("%-10s %.9g\n", "relmse", m->relmse);
    printf("%-10s %.9g\n", "mae", m->mae);
    if (isinf(m->psnr))
        printf("%-10s inf (peak %.9g)\n", "psnr", m->peak);
    else
        printf("%-10s %.9g dB (peak %.9g)\n", "psnr", m->psnr, m->peak);
    printf("%-10s %.9g at (%u, %u)", "max_error", m->max_error, m->max_error_x, m->max_error_y);
    if (o->is_sequence)
        printf(" in frame %d", m->max_error_frame);
    printf("\n");
    if (m->nonfinite_count)
        printf("%-10s %" PRIu64 " pixels skipped\n", "nonfinite", m->nonfinite_count);
}

/* ---- the command ------------------------------------------------------------------------ */

int cmd_compare(int argc, char **argv)
{
    struct options o = {0};
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;

    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_layer layer;
    struct rb_analysis_metrics total = {0};
    struct frame_result *frames = NULL;
    size_t frame_count = (size_t)(o.last - o.first) + 1;
    enum rb_status st;
    rc = RB_EXIT_OK;

    if ((st = rb_analysis_layer_resolve(o.layer, &layer, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE;
        goto out;
    }
    if (o.is_sequence && check_frames_exist(&o)) {
        rc = RB_EXIT_USAGE;
        goto out;
    }
    frames = calloc(frame_count, sizeof(*frames));
    if (!frames) {
        cmd_error("out of memory for %zu frames", frame_count);
        rc = RB_EXIT_FAILED;
        goto out;
    }
    for (size_t i = 0; i < frame_count; i++) {
        struct frame_result *r = &frames[i];
        char a[4096], b[4096], mask[4096], error[4096];
        r->frame = o.first + (int)i;
        if (frame_path(&o, o.a, r->frame, a, sizeof(a)) ||
            frame_path(&o, o.b, r->frame, b, sizeof(b)) ||
            (o.mask && frame_path(&o, o.mask, r->frame, mask, sizeof(mask))) ||
            (o.error_image && frame_path(&o, o.error_image, r->frame, error, sizeof(error)))) {
            rc = RB_EXIT_USAGE;
            goto out;
        }
        st = compare_frame(&o, &layer, a, b, o.mask ? mask : NULL, o.error_image ? error : NULL,
                           &r->m, &err);
        if (st) {
            if (o.is_sequence)
                cmd_error("frame %d: %s", r->frame, err.msg);
            else
                cmd_error("%s", err.msg);
            rc = st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
            goto out;
        }
        rb_analysis_metrics_add(&total, &r->m, r->frame);
    }
    if (total.pixel_count == 0) {
        cmd_error("no pixel is left to compare (%" PRIu64 " skipped as NaN or infinite); check "
                  "--mask, --mask-alpha and --exclude-edges",
                  total.nonfinite_count);
        rc = RB_EXIT_USAGE;
        goto out;
    }

    if (o.json)
        print_json(&o, &layer, &total, frames, frame_count);
    else
        print_text(&o, &layer, &total, frames, frame_count);
    fflush(stdout);

    /* A threshold exceeded is the "failed" status (1); so is any NaN when a threshold is set,
     * since skipped pixels would otherwise pass unseen. */
    if (total.nonfinite_count && (o.has_max_relmse || o.has_max_rmse)) {
        cmd_error("%" PRIu64 " pixels hold NaN or infinite values, which fails any threshold",
                  total.nonfinite_count);
        rc = RB_EXIT_FAILED;
    } else if (total.nonfinite_count) {
        fprintf(stderr,
                "raybundle: warning: %" PRIu64 " pixels hold NaN or infinite values and "
                "were skipped\n",
                total.nonfinite_count);
    }
    if (o.has_max_relmse && total.relmse > o.max_relmse) {
        cmd_error("relmse %.9g exceeds --max-relmse %.9g", total.relmse, o.max_relmse);
        rc = RB_EXIT_FAILED;
    }
    if (o.has_max_rmse && total.rmse > o.max_rmse) {
        cmd_error("rmse %.9g exceeds --max-rmse %.9g", total.rmse, o.max_rmse);
        rc = RB_EXIT_FAILED;
    }
out:
    free(frames);
    return rc;
}
