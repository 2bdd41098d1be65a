/* The report of a rendered sequence: its frames found in a directory, per frame the timing
 * sidecar's passes and wall time, the beauty's change from the previous frame, its error against
 * a reference sequence and the hit-ratio image's mean, thumbnails through the OCIO view; then one
 * self-contained HTML page with inline SVG charts drawn at fixed positions (raybundle-report(1)).
 * The numbers come from the readers and metrics the other commands use (rb_io_timing_read,
 * rb_analysis_compare, rb_analysis_flicker_create); this file adds the layout. Plots whose data
 * the sequence does not have (hit ratios; flicker without motion and depth layers) say so in
 * their place; nothing is made up. */
#include "analysis/analysis.h"
#include "analysis/flip.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ---- the plot's geometry ------------------------------------------------------------------ */

struct rb_analysis_axis rb_analysis_axis_fit(double data_max)
{
    if (!(data_max > 0.0) || !isfinite(data_max))
        return (struct rb_analysis_axis){.max = 1.0, .step = 0.2};
    /* Powers of ten below 1 as 1 / 10^-e, which rounds once: 1e-5, not 1.0000000000000001e-05. */
    double raw = data_max / 5.0, e = floor(log10(raw));
    double mag = e >= 0.0 ? pow(10.0, e) : 1.0 / pow(10.0, -e), norm = raw / mag;
    double step = norm <= 1.0   ? mag
                  : norm <= 2.0 ? 2.0 * mag
                  : norm <= 5.0 ? 5.0 * mag
                                : 10.0 * mag;
    /* A quotient a rounding above a whole number is that number: 3e-5 / 1e-5 is 3, not 4. */
    double k = ceil(data_max / step - 1e-9);
    return (struct rb_analysis_axis){.max = k * step, .step = step};
}

double rb_analysis_plot_x(const struct rb_analysis_plot *p, size_t i)
{
    return p->x_px + ((double)i + 0.5) * p->width_px / (double)(p->slot_count ? p->slot_count : 1);
}

double rb_analysis_plot_y(const struct rb_analysis_plot *p, double v)
{
    return p->y_px + p->height_px - v / p->axis.max * p->height_px;
}

double rb_analysis_plot_bar_width(const struct rb_analysis_plot *p)
{
    double w = 0.7 * p->width_px / (double)(p->slot_count ? p->slot_count : 1);
    return w < 1.0 ? 1.0 : w;
}

/* ---- the filmstrip ------------------------------------------------------------------------ */

size_t rb_analysis_filmstrip_pick(size_t frame_count, size_t max_count, size_t *out)
{
    assert(max_count >= 2);
    if (frame_count <= max_count) {
        for (size_t i = 0; i < frame_count; i++)
            out[i] = i;
        return frame_count;
    }
    /* frame_count - 1 > max_count - 1, so the steps are more than one apart: no index twice. */
    size_t span = frame_count - 1, steps = max_count - 1;
    for (size_t k = 0; k < max_count; k++)
        out[k] = (k * span + steps / 2) / steps;
    return max_count;
}

/* ---- reading a sequence ------------------------------------------------------------------- */

void rb_analysis_report_destroy(struct rb_analysis_report *r)
{
    if (!r)
        return;
    for (size_t i = 0; r->frames && i < r->seq.frame_count; i++) {
        struct rb_analysis_report_frame *f = &r->frames[i];
        free(f->pass_ms);
        free(f->thumb);
        free(f->reference_thumb);
        free(f->hits_thumb);
        free(f->flip_thumb);
    }
    free(r->frames);
    free(r->pass_names);
    rb_analysis_sequence_release(&r->seq);
    rb_analysis_sequence_release(&r->ref);
    free(r);
}

/* One image's beauty (R, G, B), read and checked against the sequence's size. */
struct beauty {
    uint32_t width_px, height_px;
    float *rgb;
};

static enum rb_status read_beauty(const char *path, struct beauty *out, struct rb_err *err)
{
    static const char *const beauty[] = {"beauty"};
    free(out->rgb);
    out->rgb = NULL;
    return rb_analysis_layers_read(path, beauty, 1, &out->rgb, &out->width_px, &out->height_px,
                                   err);
}

/* RMSE or relMSE of a against the reference b, the same size. */
static enum rb_status metrics(const struct beauty *a, const struct beauty *b,
                              struct rb_analysis_metrics *m, struct rb_err *err)
{
    return rb_analysis_compare(&(struct rb_analysis_compare_desc){.width_px = a->width_px,
                                                                  .height_px = a->height_px,
                                                                  .channel_count = 3,
                                                                  .a = a->rgb,
                                                                  .b = b->rgb},
                               m, err);
}

/* The thumbnail's size for a w x h image: at most width_px wide, the aspect kept. */
static void thumb_size(uint32_t w, uint32_t h, uint32_t width_px, uint32_t *tw, uint32_t *th)
{
    *tw = w < width_px ? w : width_px;
    double t = (double)h * *tw / w + 0.5;
    *th = t < 1.0 ? 1 : (uint32_t)t;
}

/* A thumbnail of the first 3 of each stride values (the first alone as grey when is_grey) made
 * opaque: through the view transform, or as they are for data. */
static enum rb_status thumbnail(const struct rb_analysis_report_desc *desc, uint32_t w, uint32_t h,
                                const float *values, size_t stride, bool is_grey, bool is_data,
                                char **out, struct rb_err *err)
{
    size_t n = (size_t)w * h;
    float *rgba = malloc(n * 4 * sizeof(*rgba));
    if (!rgba)
        return rb_errf(err, RB_E_NOMEM, "thumbnail: out of memory for %ux%u", w, h);
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            rgba[i * 4 + c] = values[i * stride + (is_grey ? 0 : (size_t)c)];
        rgba[i * 4 + 3] = 1.0f;
    }
    struct rb_io_thumbnail_desc td = {.color = desc->color, .is_data = is_data};
    thumb_size(w, h, desc->thumb_width_px ? desc->thumb_width_px : RB_ANALYSIS_REPORT_THUMB_WIDTH,
               &td.width_px, &td.height_px);
    enum rb_status st = rb_io_thumbnail_data_uri(w, h, rgba, &td, out, err);
    free(rgba);
    return st;
}

/* HDR-FLIP of the sequence's frame i (cur) against its reference (ref): its mean, and the
 * thumbnail of its map through FLIP's colour map for the filmstrip. A pair it cannot be
 * computed for gets NaN and, the first time, its reason in flip_note; only running out of
 * memory fails. */
static enum rb_status flip_frame(const struct rb_analysis_report_desc *desc,
                                 struct rb_analysis_report *r, size_t i, const struct beauty *cur,
                                 const struct beauty *ref, struct rb_err *err)
{
    struct rb_analysis_report_frame *f = &r->frames[i];
    uint32_t w = cur->width_px, h = cur->height_px;
    size_t n = (size_t)w * h;
    struct rb_analysis_flip_stats stats;
    struct rb_err why = RB_ERR_INIT;
    float *map = malloc(n * sizeof(*map)), *rgb = NULL;
    enum rb_status st = RB_OK;
    if (!map) {
        st = rb_errf(err, RB_E_NOMEM, "FLIP: out of memory for %ux%u", w, h);
        goto out;
    }
    if (rb_analysis_flip_hdr(cur->rgb, ref->rgb, w, h, NULL, map, &stats, NULL, &why)) {
        if (why.status == RB_E_NOMEM)
            st = rb_errf(err, why.status, "%s", why.msg);
        else if (!*r->flip_note)
            snprintf(r->flip_note, sizeof(r->flip_note), "frame %d: %.480s", f->frame, why.msg);
        goto out;
    }
    f->flip = stats.mean;
    if (!f->is_in_filmstrip)
        goto out;
    /* The map's colours as they are (data: no view transform); 8 bits divided by 255 come back
     * as the same 8 bits. */
    if (!(rgb = malloc(n * 3 * sizeof(*rgb)))) {
        st = rb_errf(err, RB_E_NOMEM, "FLIP: out of memory for %ux%u", w, h);
        goto out;
    }
    for (size_t p = 0; p < n; p++) {
        uint8_t c[3];
        rb_analysis_flip_color(map[p], c);
        for (int k = 0; k < 3; k++)
            rgb[3 * p + (size_t)k] = (float)c[k] / 255.0f;
    }
    st = thumbnail(desc, w, h, rgb, 3, false, true, &f->flip_thumb, err);
out:
    free(rgb);
    free(map);
    return st;
}

/* The index of the pass called name, added when it is new; -1 when out of memory. */
static long pass_index(struct rb_analysis_report *r, const char *name)
{
    for (size_t i = 0; i < r->pass_count; i++)
        if (strcmp(r->pass_names[i], name) == 0)
            return (long)i;
    char(*names)[32] = realloc(r->pass_names, (r->pass_count + 1) * sizeof(*names));
    if (!names)
        return -1;
    r->pass_names = names;
    rb_strlcpy(names[r->pass_count], name, sizeof(names[0]));
    for (size_t f = 0; f < r->seq.frame_count; f++) {
        double *ms = realloc(r->frames[f].pass_ms, (r->pass_count + 1) * sizeof(*ms));
        if (!ms)
            return -1;
        ms[r->pass_count] = 0.0;
        r->frames[f].pass_ms = ms;
    }
    return (long)r->pass_count++;
}

/* The frame's timing sidecar: its passes and wall time, and the device of the first. */
static enum rb_status read_timing(struct rb_analysis_report *r, size_t i, struct rb_err *err)
{
    char path[4096];
    struct rb_io_timing_file t = {0};
    struct rb_analysis_report_frame *f = &r->frames[i];
    enum rb_status st =
        rb_io_sidecar_path(r->seq.paths[i], ".timing.json", path, sizeof(path), err);
    if (st || (st = rb_io_timing_read(path, &t, err)))
        goto out;
    if (t.frame != f->frame) {
        st = rb_errf(err, RB_E_INVALID, "'%s' is the sidecar of frame %d, not of frame %d", path,
                     t.frame, f->frame);
        goto out;
    }
    if (i == 0) {
        rb_strlcpy(r->device, t.device, sizeof(r->device));
        rb_strlcpy(r->driver, t.driver, sizeof(r->driver));
    }
    f->wall_ms = t.wall_ms;
    for (size_t p = 0; p < t.pass_count; p++) {
        long k = pass_index(r, t.passes[p].name);
        if (k < 0) {
            st = rb_errf(err, RB_E_NOMEM, "'%s': out of memory", path);
            goto out;
        }
        double ms = t.passes[p].gpu_ms + t.passes[p].cpu_ms;
        f->pass_ms[k] += ms;
        f->pass_total_ms += ms;
    }
out:
    rb_io_timing_file_release(&t);
    return st;
}

/* The frame's hit-ratio image, where the sequence has them: its mean and thumbnail. */
static enum rb_status read_hits(const struct rb_analysis_report_desc *desc,
                                struct rb_analysis_report *r, size_t i, struct rb_err *err)
{
    char path[4096];
    struct rb_io_image img = {0};
    struct rb_analysis_report_frame *f = &r->frames[i];
    enum rb_status st = rb_io_sidecar_path(r->seq.paths[i], ".hits.exr", path, sizeof(path), err);
    if (st)
        return st;
    struct stat sb;
    bool is_there = stat(path, &sb) == 0;
    if (i == 0)
        r->has_hits = is_there;
    if (!is_there && !r->has_hits)
        return RB_OK;
    if (!is_there || !r->has_hits)
        return rb_errf(err, RB_E_INVALID, "'%s' %s, but '%s' has %s", path,
                       is_there ? "is there" : "is missing", r->seq.paths[0],
                       is_there ? "none" : "one");
    if ((st = rb_io_image_read(path, &img, err)))
        return st;
    double sum = 0.0;
    size_t n = (size_t)img.width_px * img.height_px, finite = 0;
    for (size_t p = 0; p < n; p++) {
        float v = img.pixels[p * img.channel_count];
        if (isfinite(v)) {
            sum += v;
            finite++;
        }
    }
    f->hit_ratio = finite ? sum / (double)finite : NAN;
    if (f->is_in_filmstrip)
        st = thumbnail(desc, img.width_px, img.height_px, img.pixels, img.channel_count, true, true,
                       &f->hits_thumb, err);
    if (st)
        rb_err_prefix(err, "'%s'", path);
    rb_io_image_release(&img);
    return st;
}

/* Checks that b has a's size; path names b. */
static enum rb_status same_size(const struct beauty *a, const char *a_path, const struct beauty *b,
                                const char *path, struct rb_err *err)
{
    if (a->width_px == b->width_px && a->height_px == b->height_px)
        return RB_OK;
    return rb_errf(err, RB_E_INVALID, "size mismatch: '%s' is %ux%u, '%s' is %ux%u", path,
                   b->width_px, b->height_px, a_path, a->width_px, a->height_px);
}

/* The reference's frame i: its error against the sequence's beauty cur, its change from its
 * previous frame (kept in prev), its thumbnail. */
static enum rb_status read_reference(const struct rb_analysis_report_desc *desc,
                                     struct rb_analysis_report *r, size_t i,
                                     const struct beauty *cur, struct beauty *ref,
                                     struct beauty *prev, bool has_prev, struct rb_err *err)
{
    struct rb_analysis_report_frame *f = &r->frames[i];
    long k = rb_analysis_sequence_find(&r->ref, f->frame);
    if (k < 0)
        return rb_errf(err, RB_E_INVALID, "the reference '%s' has no frame %d (for '%s')",
                       r->ref.dir, f->frame, r->seq.paths[i]);
    const char *path = r->ref.paths[k];
    struct rb_analysis_metrics m;
    enum rb_status st;
    if ((st = read_beauty(path, ref, err)) ||
        (st = same_size(cur, r->seq.paths[i], ref, path, err)) || (st = metrics(cur, ref, &m, err)))
        return st;
    f->relmse = m.relmse;
    if (has_prev) {
        if ((st = metrics(ref, prev, &m, err)))
            return st;
        f->reference_temporal_rmse = m.rmse;
    }
    if (i == 0) {
        rb_io_image_attr(path, "raybundle:integrator", r->reference_integrator,
                         sizeof(r->reference_integrator));
        rb_io_image_attr(path, "raybundle:spp", r->reference_spp, sizeof(r->reference_spp));
    }
    if (!f->is_in_filmstrip)
        return flip_frame(desc, r, i, cur, ref, err);
    if ((st = thumbnail(desc, ref->width_px, ref->height_px, ref->rgb, 3, false, false,
                        &f->reference_thumb, err)))
        return st;
    return flip_frame(desc, r, i, cur, ref, err);
}

static enum rb_status read_frames(const struct rb_analysis_report_desc *desc,
                                  struct rb_analysis_report *r, struct rb_err *err)
{
    struct beauty cur = {0}, prev = {0}, ref = {0}, ref_prev = {0}, first = {0};
    enum rb_status st = RB_OK;
    for (size_t i = 0; i < r->seq.frame_count && st == RB_OK; i++) {
        struct rb_analysis_report_frame *f = &r->frames[i];
        const char *path = r->seq.paths[i];
        bool has_prev = i > 0 && r->seq.frames[i - 1] == f->frame - 1;
        struct rb_analysis_metrics m;
        if ((st = read_timing(r, i, err)) || (st = read_beauty(path, &cur, err)))
            break;
        if (i == 0) {
            r->width_px = cur.width_px;
            r->height_px = cur.height_px;
            first = (struct beauty){cur.width_px, cur.height_px, NULL};
            rb_io_image_attr(path, "raybundle:integrator", r->integrator, sizeof(r->integrator));
        }
        if ((st = same_size(&first, r->seq.paths[0], &cur, path, err)))
            break;
        if (has_prev) {
            if ((st = metrics(&cur, &prev, &m, err)))
                break;
            f->temporal_rmse = m.rmse;
        }
        if (f->is_in_filmstrip && (st = thumbnail(desc, cur.width_px, cur.height_px, cur.rgb, 3,
                                                  false, false, &f->thumb, err))) {
            rb_err_prefix(err, "'%s'", path);
            break;
        }
        if ((st = read_hits(desc, r, i, err)))
            break;
        if (r->has_reference) {
            if ((st = read_reference(desc, r, i, &cur, &ref, &ref_prev, has_prev, err)))
                break;
            struct beauty t = ref;
            ref = ref_prev;
            ref_prev = t;
        }
        struct beauty t = cur;
        cur = prev;
        prev = t;
    }
    free(cur.rgb);
    free(prev.rgb);
    free(ref.rgb);
    free(ref_prev.rgb);
    return st;
}

/* The flicker metrics of the same sequences, or the reason there are none in flicker_note. */
static enum rb_status read_flicker(const struct rb_analysis_report_desc *desc,
                                   struct rb_analysis_report *r, struct rb_err *err)
{
    struct rb_analysis_flicker *f = NULL;
    struct rb_err why = RB_ERR_INIT;
    enum rb_status st = rb_analysis_flicker_create(
        &(struct rb_analysis_flicker_desc){.seq = desc->dir, .reference = desc->reference_dir}, &f,
        &why);
    if (st == RB_E_NOMEM)
        return rb_errf(err, st, "%s", why.msg);
    if (st) {
        rb_strlcpy(r->flicker_note, why.msg, sizeof(r->flicker_note));
        return RB_OK;
    }
    for (size_t i = 0; i < r->seq.frame_count; i++) {
        r->frames[i].warped_error = f->frames[i].seq.warped_error;
        r->frames[i].reference_warped_error = f->frames[i].ref.warped_error;
        r->frames[i].excess_error = f->frames[i].excess_error;
    }
    rb_analysis_flicker_destroy(f);
    return RB_OK;
}

/* Marks the frames the filmstrip shows. */
static enum rb_status pick_filmstrip(const struct rb_analysis_report_desc *desc,
                                     struct rb_analysis_report *r, struct rb_err *err)
{
    size_t n = r->seq.frame_count,
           max = desc->filmstrip_max ? desc->filmstrip_max : RB_ANALYSIS_REPORT_FILMSTRIP;
    if (max > n)
        max = n < 2 ? 2 : n;
    size_t *picked = malloc(max * sizeof(*picked));
    if (!picked)
        return rb_errf(err, RB_E_NOMEM, "report: out of memory for %zu frames", n);
    r->filmstrip_count = rb_analysis_filmstrip_pick(n, max, picked);
    for (size_t k = 0; k < r->filmstrip_count; k++)
        r->frames[picked[k]].is_in_filmstrip = true;
    free(picked);
    return RB_OK;
}

enum rb_status rb_analysis_report_create(const struct rb_analysis_report_desc *desc,
                                         struct rb_analysis_report **out, struct rb_err *err)
{
    if (!desc || !desc->dir || !*desc->dir)
        return rb_errf(err, RB_E_INVALID, "report: no sequence directory");
    if (desc->filmstrip_max == 1)
        return rb_errf(err, RB_E_INVALID,
                       "report: a filmstrip of 1 frame cannot show the first "
                       "and the last");
    struct rb_analysis_report *r = calloc(1, sizeof(*r));
    if (!r)
        return rb_errf(err, RB_E_NOMEM, "report: out of memory");
    enum rb_status st;
    r->has_reference = desc->reference_dir && *desc->reference_dir;
    r->thumb_width_px =
        desc->thumb_width_px ? desc->thumb_width_px : RB_ANALYSIS_REPORT_THUMB_WIDTH;
    if ((st = rb_analysis_sequence_scan(desc->dir, &r->seq, err)) ||
        (r->has_reference && (st = rb_analysis_sequence_scan(desc->reference_dir, &r->ref, err))))
        goto fail;
    if (!(r->frames = calloc(r->seq.frame_count, sizeof(*r->frames)))) {
        st = rb_errf(err, RB_E_NOMEM, "report: out of memory for %zu frames", r->seq.frame_count);
        goto fail;
    }
    for (size_t i = 0; i < r->seq.frame_count; i++)
        r->frames[i] = (struct rb_analysis_report_frame){
            .frame = r->seq.frames[i],
            .temporal_rmse = NAN,
            .reference_temporal_rmse = NAN,
            .relmse = NAN,
            .flip = NAN,
            .hit_ratio = NAN,
            .warped_error = NAN,
            .reference_warped_error = NAN,
            .excess_error = NAN,
        };
    if ((st = pick_filmstrip(desc, r, err)))
        goto fail;
    if ((st = read_frames(desc, r, err)) || (st = read_flicker(desc, r, err)))
        goto fail;
    *out = r;
    return RB_OK;
fail:
    rb_analysis_report_destroy(r);
    return st;
}

/* ---- the page ----------------------------------------------------------------------------- */

/* Twenty colours that tell apart (Tableau 20, the strong half first); passes past twenty take
 * them again. */
static const char *const pass_colors[] = {
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1",
    "#ff9da7", "#9c755f", "#79706e", "#a0cbe8", "#ffbe7d", "#8cd17d", "#b6992d",
    "#499894", "#86bcb6", "#f1ce63", "#d37295", "#fabfd2", "#d4a6c8",
};
#define PASS_COLOR(i) pass_colors[(i) % (sizeof(pass_colors) / sizeof(pass_colors[0]))]
#define GRID_COLOR "#e6e6e6"
#define AXIS_COLOR "#888888"

/* Writes s with HTML's special characters escaped (text and attribute values alike). */
static void html(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&#39;", f); break;
        default: fputc(*s, f);
        }
    }
}

/* A number for a label or a tooltip: 4 significant digits, "-" where it is not finite. */
static const char *num(char *buf, size_t size, double v)
{
    if (!isfinite(v))
        snprintf(buf, size, "-");
    else
        snprintf(buf, size, "%.4g", v);
    return buf;
}

/* One series of a line chart: a double of each frame, at offset in its struct (NaN: none). */
struct series {
    const char *name, *color;
    size_t offset;
};

static double value(const struct rb_analysis_report *r, const struct series *s, size_t i)
{
    double v;
    memcpy(&v, (const char *)&r->frames[i] + s->offset, sizeof(v));
    return v;
}

/* The top of a chart's section and of its SVG's plot area, on the page. */
static double section_top(int chart)
{
    return RB_ANALYSIS_REPORT_HEADER_H + chart * RB_ANALYSIS_REPORT_CHART_H;
}

static struct rb_analysis_plot plot_for(int chart, size_t slot_count, double data_max)
{
    return (struct rb_analysis_plot){
        .x_px = RB_ANALYSIS_REPORT_PLOT_X,
        .y_px = section_top(chart) + RB_ANALYSIS_REPORT_TITLE_H + RB_ANALYSIS_REPORT_PLOT_Y,
        .width_px = RB_ANALYSIS_REPORT_PLOT_W,
        .height_px = RB_ANALYSIS_REPORT_PLOT_H,
        .slot_count = slot_count,
        .axis = rb_analysis_axis_fit(data_max),
    };
}

/* Opens a chart's section: its title, and its SVG (in page coordinates through a viewBox, so
 * the numbers in the file are the pixels on the page) with data-plot="x y width height max
 * slots" for tests and scripts to find the plot area. */
static void chart_open(FILE *f, int chart, const char *id, const char *title,
                       const struct rb_analysis_plot *p)
{
    double top = section_top(chart), svg_top = top + RB_ANALYSIS_REPORT_TITLE_H;
    double svg_h = RB_ANALYSIS_REPORT_CHART_H - RB_ANALYSIS_REPORT_TITLE_H;
    fprintf(f, "<section id=\"%s\" style=\"top:%gpx\">\n<h2>", id, top);
    html(f, title);
    fprintf(f,
            "</h2>\n<svg width=\"%d\" height=\"%g\" viewBox=\"0 %g %d %g\" "
            "data-plot=\"%g %g %g %g %.9g %zu\">\n",
            RB_ANALYSIS_REPORT_WIDTH, svg_h, svg_top, RB_ANALYSIS_REPORT_WIDTH, svg_h, p->x_px,
            p->y_px, p->width_px, p->height_px, p->axis.max, p->slot_count);
}

/* A section with a note in place of its plot. */
static void chart_none(FILE *f, int chart, const char *id, const char *title, const char *note)
{
    fprintf(f, "<section id=\"%s\" style=\"top:%gpx\">\n<h2>", id, section_top(chart));
    html(f, title);
    fputs("</h2>\n<p class=\"none\">", f);
    html(f, note);
    fputs("</p>\n</section>\n", f);
}

/* The grid, the value labels, the axes and the frame labels (at most about 12). */
static void chart_axes(FILE *f, const struct rb_analysis_report *r,
                       const struct rb_analysis_plot *p)
{
    char buf[32];
    double x0 = p->x_px, x1 = p->x_px + p->width_px, y0 = p->y_px + p->height_px;
    size_t steps = (size_t)(p->axis.max / p->axis.step + 0.5);
    for (size_t k = 0; k <= steps; k++) {
        double v = (double)k * p->axis.step, y = rb_analysis_plot_y(p, v);
        fprintf(f,
                "<line x1=\"%g\" y1=\"%.2f\" x2=\"%g\" y2=\"%.2f\" stroke=\"" GRID_COLOR
                "\" shape-rendering=\"crispEdges\"/>"
                "<text x=\"%g\" y=\"%.2f\" class=\"v\">%s</text>\n",
                x0, y, x1, y, x0 - 6, y + 4, num(buf, sizeof(buf), v));
    }
    size_t every = (p->slot_count + 11) / 12;
    for (size_t i = 0; i < p->slot_count; i += every ? every : 1)
        fprintf(f, "<text x=\"%.2f\" y=\"%g\" class=\"f\">%d</text>\n", rb_analysis_plot_x(p, i),
                y0 + 16, r->frames[i].frame);
    fprintf(f,
            "<path d=\"M%g %g V%g H%g\" fill=\"none\" stroke=\"" AXIS_COLOR
            "\" shape-rendering=\"crispEdges\"/>\n",
            x0, p->y_px, y0, x1);
}

/* A legend entry k (in two columns past 11): a swatch with data-series naming it. */
static void legend(FILE *f, const struct rb_analysis_plot *p, size_t k, size_t count,
                   const char *name, const char *color)
{
    size_t rows = count > 11 ? (count + 1) / 2 : count;
    double x = p->x_px + p->width_px + 24 + (double)(k / rows) * 112;
    double y = p->y_px + (double)(k % rows) * 16;
    fprintf(f, "<rect x=\"%g\" y=\"%g\" width=\"10\" height=\"10\" fill=\"%s\" data-series=\"", x,
            y, color);
    html(f, name);
    fprintf(f, "\"/><text x=\"%g\" y=\"%g\">", x + 14, y + 9);
    html(f, name);
    fputs("</text>\n", f);
}

static void stacked_passes(FILE *f, const struct rb_analysis_report *r, int chart)
{
    size_t n = r->seq.frame_count;
    double max = 0.0;
    char a[32], b[32];
    for (size_t i = 0; i < n; i++)
        max = fmax(max, r->frames[i].pass_total_ms);
    struct rb_analysis_plot p = plot_for(chart, n, max);
    chart_open(f, chart, "passes", "Time per pass (ms: GPU time, and CPU time of CPU passes)", &p);
    chart_axes(f, r, &p);
    double w = rb_analysis_plot_bar_width(&p);
    for (size_t i = 0; i < n; i++) {
        const struct rb_analysis_report_frame *fr = &r->frames[i];
        fprintf(f, "<g><title>frame %d: %s ms", fr->frame, num(a, sizeof(a), fr->pass_total_ms));
        for (size_t k = 0; k < r->pass_count; k++) {
            fprintf(f, "%s", k ? ", " : "; ");
            html(f, r->pass_names[k]);
            fprintf(f, " %s", num(b, sizeof(b), fr->pass_ms[k]));
        }
        fputs("</title>\n", f);
        double sum = 0.0;
        for (size_t k = 0; k < r->pass_count; k++) {
            double lo = rb_analysis_plot_y(&p, sum),
                   hi = rb_analysis_plot_y(&p, sum + fr->pass_ms[k]);
            sum += fr->pass_ms[k];
            if (fr->pass_ms[k] <= 0.0)
                continue;
            fprintf(f,
                    "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"%s\" "
                    "shape-rendering=\"crispEdges\"/>\n",
                    rb_analysis_plot_x(&p, i) - w / 2, hi, w, lo - hi, PASS_COLOR(k));
        }
        fputs("</g>\n", f);
    }
    for (size_t k = 0; k < r->pass_count; k++)
        legend(f, &p, k, r->pass_count, r->pass_names[k], PASS_COLOR(k));
    fputs("</svg>\n</section>\n", f);
}

/* A line chart of series (a NaN breaks its line), each point a dot with a tooltip; unit follows
 * the values there. The axis fits the values, or runs to fixed_max when that is above 0. Each
 * series is drawn 2 px wider than the next, so that where two coincide (a frame's wall time and
 * its passes' sum, when nothing else takes time) the one underneath still shows either side. */
static void lines(FILE *f, const struct rb_analysis_report *r, int chart, const char *id,
                  const char *title, const struct series *s, size_t series_count, const char *unit,
                  double fixed_max)
{
    size_t n = r->seq.frame_count;
    double max = fixed_max;
    char buf[32];
    for (size_t k = 0; k < series_count && !(fixed_max > 0.0); k++)
        for (size_t i = 0; i < n; i++)
            if (isfinite(value(r, &s[k], i)))
                max = fmax(max, value(r, &s[k], i));
    struct rb_analysis_plot p = plot_for(chart, n, max);
    chart_open(f, chart, id, title, &p);
    chart_axes(f, r, &p);
    for (size_t k = 0; k < series_count; k++) {
        for (size_t i = 0; i < n; i++) { /* each run of values, one polyline */
            if (!isfinite(value(r, &s[k], i)) || (i > 0 && isfinite(value(r, &s[k], i - 1))))
                continue;
            fputs("<polyline points=\"", f);
            for (size_t j = i; j < n && isfinite(value(r, &s[k], j)); j++)
                fprintf(f, "%s%.2f,%.2f", j > i ? " " : "", rb_analysis_plot_x(&p, j),
                        rb_analysis_plot_y(&p, value(r, &s[k], j)));
            fprintf(f, "\" fill=\"none\" stroke=\"%s\" stroke-width=\"%zu\"/>\n", s[k].color,
                    2 + 2 * (series_count - 1 - k));
        }
        for (size_t i = 0; i < n; i++) {
            double v = value(r, &s[k], i);
            if (!isfinite(v))
                continue;
            fprintf(f, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"3\" fill=\"%s\"><title>frame %d: ",
                    rb_analysis_plot_x(&p, i), rb_analysis_plot_y(&p, v), s[k].color,
                    r->frames[i].frame);
            html(f, s[k].name);
            fprintf(f, " %s%s</title></circle>\n", num(buf, sizeof(buf), v), unit);
        }
        legend(f, &p, k, series_count, s[k].name, s[k].color);
    }
    fputs("</svg>\n</section>\n", f);
}

static const char style[] =
    "body{margin:0;background:#fff;color:#222;font:13px/1.35 sans-serif}\n"
    "header,section{position:absolute;left:0;width:960px;box-sizing:border-box;overflow:hidden}\n"
    "header{top:0;height:160px;padding:0 12px}\n"
    "section{height:250px}\n"
    "h1{font-size:20px;margin:10px 0 6px}\n"
    "h2{font-size:14px;margin:0;padding:0 12px;height:30px;line-height:30px;white-space:nowrap}\n"
    "th{text-align:left;font-weight:600;padding:0 12px 0 0;vertical-align:top}\n"
    "td{padding:0 12px 0 0;vertical-align:top}\n"
    "svg{display:block;font-size:11px}\n"
    "svg text{fill:#444}\n"
    "svg text.v{text-anchor:end}\n"
    "svg text.f{text-anchor:middle}\n"
    "p.none{margin:12px 0 0 72px;width:640px;height:176px;box-sizing:border-box;padding:16px;"
    "background:#f4f4f4;color:#555}\n"
    "#filmstrip{height:auto;overflow:visible}\n"
    "#filmstrip p,#filmstrip table{margin:0 0 0 12px}\n"
    "#filmstrip td{padding:4px 12px 4px 0}\n"
    "img{display:block;image-rendering:pixelated}\n";

/* "DIR/STEM.####.exr" of a sequence. */
static void pattern(FILE *f, const struct rb_analysis_sequence *s)
{
    html(f, s->dir);
    fputc('/', f);
    html(f, s->stem);
    fputs(".####.exr", f);
}

/* The mean of a frame value over the frames that have it (NaN for none). */
static double mean(const struct rb_analysis_report *r, size_t offset)
{
    struct series s = {.offset = offset};
    double sum = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < r->seq.frame_count; i++)
        if (isfinite(value(r, &s, i))) {
            sum += value(r, &s, i);
            count++;
        }
    return count ? sum / (double)count : NAN;
}

static void header(FILE *f, const struct rb_analysis_report *r)
{
    const struct rb_analysis_sequence *s = &r->seq;
    char a[32], b[32], c[32], d[32];
    fputs("<header>\n<h1>raybundle report</h1>\n<table>\n<tr><th>sequence</th><td>", f);
    pattern(f, s);
    fprintf(f, ": %zu frame%s, %d to %d%s, %ux%u", s->frame_count, s->frame_count == 1 ? "" : "s",
            s->frames[0], s->frames[s->frame_count - 1],
            s->frames[s->frame_count - 1] - s->frames[0] + 1 == (int)s->frame_count ? ""
                                                                                    : " with gaps",
            r->width_px, r->height_px);
    if (*r->integrator) {
        fputs(", integrator ", f);
        html(f, r->integrator);
    }
    fputs("</td></tr>\n<tr><th>device</th><td>", f);
    html(f, r->device);
    fputs(" (", f);
    html(f, r->driver);
    fputs(")</td></tr>\n<tr><th>reference</th><td>", f);
    if (r->has_reference) {
        pattern(f, &r->ref);
        if (*r->reference_integrator) {
            fputs(", integrator ", f);
            html(f, r->reference_integrator);
        }
        if (*r->reference_spp) {
            fputs(", ", f);
            html(f, r->reference_spp);
            fputs(" spp", f);
        }
    } else {
        fputs("none (--reference REFSEQ)", f);
    }
    fprintf(f,
            "</td></tr>\n<tr><th>means</th><td>frame wall time %s ms, passes %s ms, relMSE %s, "
            "FLIP %s</td></tr>\n</table>\n</header>\n",
            num(a, sizeof(a), mean(r, offsetof(struct rb_analysis_report_frame, wall_ms))),
            num(b, sizeof(b), mean(r, offsetof(struct rb_analysis_report_frame, pass_total_ms))),
            num(c, sizeof(c), mean(r, offsetof(struct rb_analysis_report_frame, relmse))),
            num(d, sizeof(d), mean(r, offsetof(struct rb_analysis_report_frame, flip))));
}

static void image(FILE *f, const char *uri, uint32_t width_px, int frame, const char *what)
{
    fprintf(f, "<td><img src=\"%s\" style=\"width:%upx\" alt=\"%s of frame %d\"></td>", uri,
            width_px, what, frame);
}

static void filmstrip(FILE *f, const struct rb_analysis_report *r, int chart)
{
    char buf[32];
    fprintf(f,
            "<section id=\"filmstrip\" style=\"top:%gpx\">\n<h2>Frames, display-referred "
            "through the OpenColorIO view%s%s</h2>\n",
            section_top(chart),
            r->has_reference ? ", their FLIP maps (magma: black 0, light yellow 1)" : "",
            r->has_hits ? ", and their hit ratios (black 0, white 1)" : "");
    if (r->filmstrip_count < r->seq.frame_count)
        fprintf(f,
                "<p class=\"stride\">%zu of the %zu frames, evenly spaced, the first and the "
                "last among them (raybundle report --filmstrip N).</p>\n",
                r->filmstrip_count, r->seq.frame_count);
    if (!r->has_hits)
        fputs("<p>No hit-ratio images (NAME.####.hits.exr) in this sequence.</p>\n", f);
    fprintf(f, "<table>\n<tr><th>frame</th><th>sequence</th>%s%s</tr>\n",
            r->has_reference ? "<th>reference</th><th>FLIP</th>" : "",
            r->has_hits ? "<th>hit ratio</th>" : "");
    for (size_t i = 0; i < r->seq.frame_count; i++) {
        const struct rb_analysis_report_frame *fr = &r->frames[i];
        if (!fr->is_in_filmstrip)
            continue;
        fprintf(f, "<tr><td>%d", fr->frame);
        if (r->has_reference) {
            fprintf(f, "<br>relMSE %s", num(buf, sizeof(buf), fr->relmse));
            fprintf(f, "<br>FLIP %s", num(buf, sizeof(buf), fr->flip));
        }
        fputs("</td>", f);
        image(f, fr->thumb, r->thumb_width_px, fr->frame, "sequence");
        if (r->has_reference) {
            image(f, fr->reference_thumb, r->thumb_width_px, fr->frame, "reference");
            if (fr->flip_thumb)
                image(f, fr->flip_thumb, r->thumb_width_px, fr->frame, "FLIP");
            else
                fputs("<td>-</td>", f);
        }
        if (r->has_hits)
            image(f, fr->hits_thumb, r->thumb_width_px, fr->frame, "hit ratio");
        fputs("</tr>\n", f);
    }
    fputs("</table>\n</section>\n", f);
}

#define FIELD(name) offsetof(struct rb_analysis_report_frame, name)

static void page(FILE *f, const struct rb_analysis_report *r)
{
    fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
          "<meta name=\"generator\" content=\"raybundle " RB_VERSION
          "\">\n<title>raybundle report: ",
          f);
    pattern(f, &r->seq);
    fprintf(f, "</title>\n<style>\n%s</style>\n</head>\n<body>\n", style);
    header(f, r);
    int chart = 0;
    stacked_passes(f, r, chart++);
    const struct series times[] = {
        {"frame wall", "#4e79a7", FIELD(wall_ms)},
        {"sum of passes", "#f28e2b", FIELD(pass_total_ms)},
    };
    lines(f, r, chart++, "frame-time",
          "Frame time (ms: the wall time from start to written, and "
          "the passes' sum)",
          times, 2, " ms", 0.0);
    const struct series hits[] = {{"hit ratio", "#b07aa1", FIELD(hit_ratio)}};
    if (r->has_hits)
        lines(f, r, chart++, "hit-ratio", "Hit ratio (the mean of each frame's hit-ratio image)",
              hits, 1, "", 1.0);
    else
        chart_none(f, chart++, "hit-ratio", "Hit ratio",
                   "No hit-ratio images (NAME.####.hits.exr) in this sequence: the integrator "
                   "that rendered it wrote none.");
    const struct series temporal[] = {
        {"sequence", "#4e79a7", FIELD(temporal_rmse)},
        {"reference", "#59a14f", FIELD(reference_temporal_rmse)},
    };
    lines(f, r, chart++, "temporal",
          "Frame-to-frame difference (RMSE of the beauty against the previous frame; "
          "motion counts)",
          temporal, r->has_reference ? 2 : 1, "", 0.0);
    const struct series warped[] = {
        {"sequence", "#4e79a7", FIELD(warped_error)},
        {"reference", "#59a14f", FIELD(reference_warped_error)},
        {"excess", "#e15759", FIELD(excess_error)},
    };
    char note[600];
    snprintf(note, sizeof(note), "Not computed: %s.", r->flicker_note);
    if (*r->flicker_note)
        chart_none(f, chart++, "warped", "Warped and excess temporal error", note);
    else
        lines(f, r, chart++, "warped",
              "Warped temporal error (log luminance, motion-compensated) and excess over the "
              "reference (raybundle flicker)",
              warped, r->has_reference ? 3 : 1, "", 0.0);
    const struct series relmse[] = {{"relMSE", "#e15759", FIELD(relmse)}};
    if (r->has_reference)
        lines(f, r, chart++, "reference-error",
              "Error against the reference (relMSE of the beauty, eps 0.01)", relmse, 1, "", 0.0);
    else
        chart_none(f, chart++, "reference-error", "Error against the reference",
                   "No reference given: raybundle report --reference REFSEQ adds this plot.");
    const struct series flip[] = {{"FLIP", "#b07aa1", FIELD(flip)}};
    snprintf(note, sizeof(note), "Not computed for every frame: %s.", r->flip_note);
    if (!r->has_reference)
        chart_none(f, chart++, "reference-flip", "FLIP against the reference",
                   "No reference given: raybundle report --reference REFSEQ adds this plot.");
    else
        lines(f, r, chart++, "reference-flip",
              *r->flip_note ? note
                            : "FLIP against the reference (the mean of HDR-FLIP's per-pixel "
                              "error, 0 to 1: what a viewer sees)",
              flip, 1, "", 0.0);
    filmstrip(f, r, chart);
    fputs("</body>\n</html>\n", f);
}

enum rb_status rb_analysis_report_write(const struct rb_analysis_report *r, const char *path,
                                        struct rb_err *err)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return rb_errf(err, RB_E_NOMEM, "report '%s': %s", path, strerror(errno));
    page(f, r);
    bool is_bad = ferror(f) != 0;
    if (fclose(f) != 0 || is_bad) {
        free(buf);
        return rb_errf(err, RB_E_NOMEM, "report '%s': out of memory", path);
    }
    enum rb_status st = rb_io_write_atomic(path, buf, len, err);
    free(buf);
    return st;
}
