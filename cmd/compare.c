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
#include <strings.h>
#include <sys/stat.h>

#include "analysis/analysis.h"
#include "analysis/flip.h"
#include "io/io.h"

#define MAX_FRAMES 1000000

struct options {
    const char *a, *b;
    const char *frames, *layer, *mask, *error_image, *flip_map;
    bool mask_alpha, json, no_flip;
    uint32_t exclude_edges_px;
    double epsilon;
    double peak; /* --peak: PSNR's peak; 0 means RB_ANALYSIS_PEAK */
    bool has_max_relmse, has_max_rmse, has_max_flip;
    double max_relmse, max_rmse, max_flip;
    /* Derived: */
    bool is_sequence;
    int first, last;
};

/* FLIP of one frame: LDR-FLIP for two PNGs, HDR-FLIP otherwise (scene-linear EXRs), pooled over
 * the compared pixels (the mask's). */
struct flip_result {
    bool has;    /* computed: an RGB layer, not --no-flip */
    bool is_hdr; /* HDR-FLIP, with exposures */
    struct rb_analysis_flip_stats stats;
    struct rb_analysis_flip_exposures exposures;
    char why[400]; /* without it on a colour layer: why it could not be computed */
};

struct frame_result {
    int frame;
    struct rb_analysis_metrics m;
    struct flip_result flip;
};

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: raybundle compare A B [options]\n"
        "\n"
        "Compares the test image A against the reference B (EXR or any image OpenImageIO\n"
        "reads), or two frame sequences given as patterns with a '#' run plus --frames.\n"
        "Prints RMSE, relative MSE, mean absolute error, PSNR, the largest error and, for\n"
        "an RGB layer, FLIP (HDR-FLIP for EXRs, LDR-FLIP for two PNGs; the mean, the\n"
        "weighted median and the largest per-pixel error, 0 to 1).\n"
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
        "  --flip-map PATH      write the per-pixel FLIP error as an EXR (flip.Y) and a\n"
        "                       PNG in FLIP's colour map, magma, beside it (.exr replaced\n"
        "                       by .png); a PATH ending in .png writes the PNG alone\n"
        "                       ('#' per frame)\n"
        "  --no-flip            do not compute FLIP\n"
        "  --max-relmse X       exit 1 when the relative MSE exceeds X\n"
        "  --max-rmse X         exit 1 when the RMSE exceeds X\n"
        "  --max-flip X         exit 1 when the mean FLIP exceeds X\n"
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
        O_MAX_FLIP,
        O_FLIP_MAP,
        O_NO_FLIP,
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
        {"max-flip", required_argument, NULL, O_MAX_FLIP},
        {"flip-map", required_argument, NULL, O_FLIP_MAP},
        {"no-flip", no_argument, NULL, O_NO_FLIP},
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
        case O_MAX_FLIP:
            if (parse_number("--max-flip", optarg, 0.0, false, &o->max_flip))
                return -1;
            o->has_max_flip = true;
            break;
        case O_FLIP_MAP: o->flip_map = optarg; break;
        case O_NO_FLIP: o->no_flip = true; break;
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
    if (o->is_sequence && o->flip_map && !strchr(o->flip_map, '#')) {
        cmd_error("--flip-map for a sequence needs a '#' run in '%s'", o->flip_map);
        return -1;
    }
    if (o->no_flip && (o->flip_map || o->has_max_flip)) {
        cmd_error("--no-flip contradicts %s", o->flip_map ? "--flip-map" : "--max-flip");
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
/* Whether the layer is colour: three channels R, G, B (or NAME.R, NAME.G, NAME.B). FLIP is a
 * difference of colours; a normal or a motion vector has none. */
static bool is_color_layer(const struct rb_analysis_layer *layer)
{
    static const char rgb[3] = {'R', 'G', 'B'};
    if (layer->channel_count != 3)
        return false;
    for (uint32_t c = 0; c < 3; c++) {
        const char *name = layer->channels[c], *dot = strrchr(name, '.');
        const char *base = dot ? dot + 1 : name;
        if (base[0] != rgb[c] || base[1])
            return false;
    }
    return true;
}

/* Whether path names a PNG (by its extension, any case). */
static bool is_png(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && !strcasecmp(path + n - 4, ".png");
}

/* The FLIP map to path: a PNG through FLIP's colour map when path ends in .png; otherwise the
 * values as an EXR (flip.Y) at path and the PNG beside it, path with its .exr (or nothing)
 * replaced by .png. */
static enum rb_status write_flip_map(const char *path, const float *map, uint32_t w, uint32_t h,
                                     struct rb_err *err)
{
    static const char *const y[1] = {"Y"};
    const struct rb_io_layer layers[1] = {
        {.name = "flip", .channel_count = 1, .channel_names = y, .pixels = map}};
    char png[4096];
    size_t n = strlen(path);
    enum rb_status st = rb_io_make_parent_dirs(path, err);
    if (st || is_png(path))
        return st ? st : rb_analysis_flip_png_write(path, map, w, h, err);
    if (n >= 4 && !strcasecmp(path + n - 4, ".exr"))
        n -= 4;
    if (n + sizeof(".png") > sizeof(png))
        return rb_errf(err, RB_E_INVALID, "--flip-map path '%.60s...' is too long", path);
    memcpy(png, path, n);
    memcpy(png + n, ".png", sizeof(".png"));
    if ((st = rb_io_exr_write(path, w, h, layers, 1, NULL, 0, err)))
        return st;
    return rb_analysis_flip_png_write(png, map, w, h, err);
}

/* FLIP of a and b (RGB, w x h) into *out, pooled over the pixels mask keeps, and its map to
 * map_path when asked. */
static enum rb_status compare_flip(const float *a, const float *b, uint32_t w, uint32_t h,
                                   const uint8_t *mask, bool is_hdr, const char *map_path,
                                   struct flip_result *out, struct rb_err *err)
{
    size_t n = (size_t)w * h, kept = 0;
    float *map = malloc(n * sizeof(float));
    enum rb_status st;
    if (!map)
        return rb_errf(err, RB_E_NOMEM, "out of memory for a %ux%u FLIP map", w, h);
    struct flip_result r = {.has = true, .is_hdr = is_hdr};
    st = is_hdr ? rb_analysis_flip_hdr(a, b, w, h, NULL, map, NULL, &r.exposures, err)
                : rb_analysis_flip_ldr(a, b, w, h, NULL, map, NULL, err);
    if (!st && map_path)
        st = write_flip_map(map_path, map, w, h, err);
    /* Pooled over the compared pixels: the map compacted to them (the pooled values do not
     * depend on where a pixel is; the largest error's pixel is taken from the map). */
    uint32_t max_x = 0, max_y = 0;
    float max = -1.0f;
    for (size_t i = 0; !st && i < n; i++)
        if (mask[i]) {
            if (map[i] > max) {
                max = map[i];
                max_x = (uint32_t)(i % w);
                max_y = (uint32_t)(i / w);
            }
            map[kept++] = map[i];
        }
    if (!st && kept)
        st = rb_analysis_flip_pool(map, (uint32_t)kept, 1, &r.stats, err);
    r.stats.max_x = max_x;
    r.stats.max_y = max_y;
    free(map);
    if (!st && kept)
        *out = r;
    return st;
}

static enum rb_status compare_frame(const struct options *o, const struct rb_analysis_layer *layer,
                                    const char *path_a, const char *path_b, const char *mask_path,
                                    const char *error_path, const char *flip_path,
                                    struct rb_analysis_metrics *out, struct flip_result *flip,
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
    if (!o->no_flip && is_color_layer(layer)) {
        /* FLIP is asked for (a map, a bound) or only shown: where it cannot be computed (NaN
         * pixels, a reference too dark to choose HDR exposures from: a median luminance of 0),
         * the first fails and the second prints why in its place. */
        bool is_asked = flip_path || o->has_max_flip;
        struct rb_err flip_err = RB_ERR_INIT;
        if (out->nonfinite_count)
            rb_errf(&flip_err, RB_E_INVALID,
                    "FLIP needs finite pixels; '%s' or '%s' has NaN or "
                    "infinite ones",
                    path_a, path_b);
        else
            (void)compare_flip(a, b, w, h, mask, !(is_png(path_a) && is_png(path_b)), flip_path,
                               flip, &flip_err);
        if (flip_err.status == RB_E_NOMEM || (flip_err.status && is_asked)) {
            st = rb_errf(err, flip_err.status, "%s", flip_err.msg);
            goto out;
        }
        if (flip_err.status) /* said in the output, beside the other figures */
            rb_strlcpy(flip->why, flip_err.msg, sizeof(flip->why));
    }
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

/* FLIP as a JSON member ("flip": null when not computed). */
static void json_flip(FILE *f, const struct flip_result *r, const char *sep)
{
    if (!r->has) {
        fprintf(f, ",%s\"flip\": null", sep);
        return;
    }
    fprintf(f,
            ",%s\"flip\": {\"kind\": \"%s\", \"mean\": %.9g, \"weighted_median\": %.9g, "
            "\"q1\": %.9g, \"q3\": %.9g, \"max\": %.9g, \"max_pixel\": [%u, %u]",
            sep, r->is_hdr ? "hdr" : "ldr", r->stats.mean, r->stats.weighted_median,
            r->stats.weighted_q1, r->stats.weighted_q3, r->stats.max, r->stats.max_x,
            r->stats.max_y);
    if (r->is_hdr)
        fprintf(f, ", \"exposures\": {\"start\": %.9g, \"stop\": %.9g, \"count\": %u}",
                r->exposures.start, r->exposures.stop, r->exposures.count);
    fprintf(f, "}");
}

static void print_json(const struct options *o, const struct rb_analysis_layer *layer,
                       const struct rb_analysis_metrics *total, const struct flip_result *flip,
                       const struct frame_result *frames, size_t frame_count)
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
    if (!o->is_sequence)
        json_flip(stdout, flip, "\n  ");
    else if (flip->has)
        printf(",\n  \"flip\": {\"mean\": %.9g, \"max\": %.9g}", flip->stats.mean, flip->stats.max);
    else
        printf(",\n  \"flip\": null");
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
            json_flip(stdout, &frames[i].flip, " ");
            printf("}");
        }
        printf("\n  ]");
    }
    printf("\n}\n");
}

static void print_text(const struct options *o, const struct rb_analysis_layer *layer,
                       const struct rb_analysis_metrics *m, const struct flip_result *flip,
                       const struct frame_result *frames, size_t frame_count)
{
    printf("%-10s %s\n%-10s %s\n%-10s %s (", "a", o->a, "b", o->b, "layer", layer->name);
    for (uint32_t c = 0; c < layer->channel_count; c++)
        printf("%s%s", c ? ", " : "", layer->channels[c]);
    printf(")\n");
    if (o->is_sequence) {
        printf("%-10s %d-%d\n\n", "frames", o->first, o->last);
        printf("%8s %10s %16s %16s %16s %16s %16s %12s %12s\n", "frame", "pixels", "rmse", "relmse",
               "mae", "psnr", "max_error", "at", "flip");
        for (size_t i = 0; i < frame_count; i++) {
            const struct rb_analysis_metrics *f = &frames[i].m;
            char psnr[32], at[32];
            if (isinf(f->psnr))
                snprintf(psnr, sizeof(psnr), "inf");
            else
                snprintf(psnr, sizeof(psnr), "%.9g", f->psnr);
            snprintf(at, sizeof(at), "(%u, %u)", f->max_error_x, f->max_error_y);
            char fl[32] = "-";
            if (frames[i].flip.has)
                snprintf(fl, sizeof(fl), "%.6g", frames[i].flip.stats.mean);
            printf("%8d %10" PRIu64 " %16.9g %16.9g %16.9g %16s %16.9g %12s %12s\n",
                   frames[i].frame, f->pixel_count, f->rmse, f->relmse, f->mae, psnr, f->max_error,
                   at, fl);
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
    if (flip->has && o->is_sequence)
        printf("%-10s %.6g (mean of the frames' means), max %.6g\n", "flip", flip->stats.mean,
               flip->stats.max);
    else if (flip->has && flip->is_hdr)
        printf("%-10s %.6g (HDR-FLIP, %u exposures from %.4g to %.4g; weighted median %.6g, "
               "max %.6g)\n",
               "flip", flip->stats.mean, flip->exposures.count, flip->exposures.start,
               flip->exposures.stop, flip->stats.weighted_median, flip->stats.max);
    else if (flip->has)
        printf("%-10s %.6g (LDR-FLIP; weighted median %.6g, max %.6g)\n", "flip", flip->stats.mean,
               flip->stats.weighted_median, flip->stats.max);
    else if (flip->why[0])
        printf("%-10s none: %s\n", "flip", flip->why);
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
    struct flip_result flip = {0}; /* a sequence's: the mean of the frames' means, the max */
    struct frame_result *frames = NULL;
    size_t frame_count = (size_t)(o.last - o.first) + 1;
    enum rb_status st;
    rc = RB_EXIT_OK;

    if ((st = rb_analysis_layer_resolve(o.layer, &layer, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE;
        goto out;
    }
    if ((o.flip_map || o.has_max_flip) && !is_color_layer(&layer)) {
        cmd_error("%s needs FLIP, which needs an RGB layer (not '%s')",
                  o.flip_map ? "--flip-map" : "--max-flip", layer.name);
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
        char a[4096], b[4096], mask[4096], error[4096], fmap[4096];
        r->frame = o.first + (int)i;
        if (frame_path(&o, o.a, r->frame, a, sizeof(a)) ||
            frame_path(&o, o.b, r->frame, b, sizeof(b)) ||
            (o.mask && frame_path(&o, o.mask, r->frame, mask, sizeof(mask))) ||
            (o.error_image && frame_path(&o, o.error_image, r->frame, error, sizeof(error))) ||
            (o.flip_map && frame_path(&o, o.flip_map, r->frame, fmap, sizeof(fmap)))) {
            rc = RB_EXIT_USAGE;
            goto out;
        }
        st = compare_frame(&o, &layer, a, b, o.mask ? mask : NULL, o.error_image ? error : NULL,
                           o.flip_map ? fmap : NULL, &r->m, &r->flip, &err);
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
    /* FLIP over the frames: the mean of their means and the largest, when every frame has it. */
    flip = frames[0].flip;
    for (size_t i = 1; flip.has && i < frame_count; i++) {
        flip.has = frames[i].flip.has;
        flip.stats.mean += frames[i].flip.stats.mean;
        if (frames[i].flip.stats.max > flip.stats.max)
            flip.stats.max = frames[i].flip.stats.max;
    }
    if (flip.has)
        flip.stats.mean /= (double)frame_count;
    for (size_t i = 0; !flip.has && !flip.why[0] && i < frame_count; i++)
        if (frames[i].flip.why[0])
            snprintf(flip.why, sizeof(flip.why), "frame %d: %.360s", frames[i].frame,
                     frames[i].flip.why);
    if (total.pixel_count == 0) {
        cmd_error("no pixel is left to compare (%" PRIu64 " skipped as NaN or infinite); check "
                  "--mask, --mask-alpha and --exclude-edges",
                  total.nonfinite_count);
        rc = RB_EXIT_USAGE;
        goto out;
    }

    if (o.json)
        print_json(&o, &layer, &total, &flip, frames, frame_count);
    else
        print_text(&o, &layer, &total, &flip, frames, frame_count);
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
    if (o.has_max_flip && !flip.has) {
        cmd_error("--max-flip: no pixel was left to compute FLIP on");
        rc = RB_EXIT_FAILED;
    } else if (o.has_max_flip && flip.stats.mean > o.max_flip) {
        cmd_error("flip %.9g exceeds --max-flip %.9g", flip.stats.mean, o.max_flip);
        rc = RB_EXIT_FAILED;
    }
out:
    free(frames);
    return rc;
}
