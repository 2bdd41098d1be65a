/* Temporal stability of a rendered sequence (raybundle-flicker(1)): the flicker of seed 000
 * section A.2, which temporal interleaved sampling removes where every cache hits and leaves
 * around moving objects where caches miss. Per frame: the warped temporal error on log luminance
 * (the previous frame reprojected through this frame's motion layer, with disoccluded pixels left
 * out by a depth test, as reverse reprojection caching detects a miss) and the deviation of the
 * static pixels from their mean over the sequence; with a reference sequence of the same job,
 * the excess of the frame-to-frame change over the reference's, and its root mean square less
 * the reference's own noise when the reference has a variance layer. The files are read through
 * rb_analysis_layers_read; nothing here prints or knows the command line. */
#include "analysis/analysis.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rec.709 luminance weights. */
#define LUM_R 0.2126
#define LUM_G 0.7152
#define LUM_B 0.0722

/* One frame read: its luminance (NaN where R, G or B is not finite), log luminance, and (when
 * asked for) motion (2 floats a pixel), depth and the variance of the luminance (a reference's
 * variance layer). */
struct frame {
    uint32_t width_px, height_px;
    double *lum, *log_lum;
    float *motion, *depth, *variance;
};

static void frame_release(struct frame *f)
{
    free(f->lum);
    free(f->log_lum);
    free(f->motion);
    free(f->depth);
    free(f->variance);
    memset(f, 0, sizeof(*f));
}

/* One sequence measured: the sequence itself or the reference, frame i at paths[i]. */
struct track {
    const char **paths;
    struct frame cur, prev;
    uint8_t *is_static; /* per pixel: static in every frame read so far */
    float *first_depth; /* the first frame's depth */
    double *log_sum;    /* per static pixel: the sum of its log luminance over the frames */
    struct rb_analysis_flicker_summary *summary;
    bool is_reference;
};

static void track_release(struct track *t)
{
    frame_release(&t->cur);
    frame_release(&t->prev);
    free(t->is_static);
    free(t->first_depth);
    free(t->log_sum);
}

static struct rb_analysis_flicker_stats *stats(struct rb_analysis_flicker *f, struct track *t,
                                               size_t i)
{
    return t->is_reference ? &f->frames[i].ref : &f->frames[i].seq;
}

struct rb_analysis_flicker_desc
rb_analysis_flicker_desc_resolve(const struct rb_analysis_flicker_desc *in)
{
    struct rb_analysis_flicker_desc d = *in;
    if (d.log_epsilon == 0.0)
        d.log_epsilon = RB_ANALYSIS_FLICKER_LOG_EPSILON;
    if (d.depth_tolerance == 0.0)
        d.depth_tolerance = RB_ANALYSIS_FLICKER_DEPTH_TOLERANCE;
    return d;
}

void rb_analysis_flicker_destroy(struct rb_analysis_flicker *f)
{
    if (!f)
        return;
    free(f->frames);
    rb_analysis_sequence_release(&f->seq);
    rb_analysis_sequence_release(&f->ref);
    free(f);
}

/* Reads path's beauty and, with_geometry, its motion and depth (and, with_variance, its
 * variance) into out (replacing what it held), and checks its size against f's (set by the first
 * frame read, from first_path). */
static enum rb_status read_frame(struct rb_analysis_flicker *f, const char *path,
                                 bool with_geometry, bool with_variance, struct frame *out,
                                 struct rb_err *err)
{
    const char *names[4] = {"beauty", "motion", "depth", "variance"};
    float *layers[4] = {0};
    size_t count = with_geometry ? 3 : 1;
    uint32_t w = 0, h = 0;
    frame_release(out);
    if (with_variance)
        names[count++] = "variance";
    enum rb_status st = rb_analysis_layers_read(path, names, count, layers, &w, &h, err);
    if (st)
        return st;
    float *variance = with_variance ? layers[count - 1] : NULL;
    if (f->width_px && (w != f->width_px || h != f->height_px)) {
        st = rb_errf(err, RB_E_INVALID, "size mismatch: '%s' is %ux%u, '%s' is %ux%u", path, w, h,
                     f->seq.paths[0], f->width_px, f->height_px);
        goto out;
    }
    size_t n = (size_t)w * h;
    out->lum = malloc(n * sizeof(*out->lum));
    out->log_lum = malloc(n * sizeof(*out->log_lum));
    if (!out->lum || !out->log_lum) {
        st = rb_errf(err, RB_E_NOMEM, "'%s': out of memory for %ux%u", path, w, h);
        goto out;
    }
    const float *rgb = layers[0];
    for (size_t i = 0; i < n; i++) {
        double y = LUM_R * rgb[3 * i] + LUM_G * rgb[3 * i + 1] + LUM_B * rgb[3 * i + 2];
        out->lum[i] = isfinite(y) ? y : NAN;
        out->log_lum[i] = log(fmax(out->lum[i], 0.0) + f->desc.log_epsilon);
        if (isnan(out->lum[i]))
            out->log_lum[i] = NAN; /* fmax would have taken the 0 */
        if (variance && isfinite(y) && !(variance[i] >= 0.0f && isfinite(variance[i]))) {
            st = rb_errf(err, RB_E_INVALID,
                         "'%s': pixel (%zu, %zu) has variance %g, not a number >= 0 (a reference "
                         "of one sample a pixel has no variance)",
                         path, i % w, i / w, (double)variance[i]);
            goto out;
        }
    }
    out->width_px = w;
    out->height_px = h;
    if (with_geometry) {
        out->motion = layers[1];
        out->depth = layers[2];
        layers[1] = layers[2] = NULL;
    }
    out->variance = variance;
    if (with_variance)
        layers[count - 1] = NULL;
out:
    for (size_t i = 0; i < 4; i++)
        free(layers[i]);
    return st;
}

/* The warped temporal error of cur against prev into s (see struct rb_analysis_flicker_stats):
 * pixel p's previous position is its centre plus its motion; the previous frame's log luminance
 * and depth are sampled there bilinearly (clamped to the edge pixels' centres). p is disoccluded
 * when a pixel the sample reads with a weight holds no geometry, or the sampled depth differs
 * from p's by more than the tolerance times p's depth: another surface was there (an edge mixes
 * the two depths, and fails too). */
static void warp(const struct frame *cur, const struct frame *prev, double tolerance,
                 struct rb_analysis_flicker_stats *s)
{
    uint32_t w = cur->width_px, h = cur->height_px;
    double sum = 0.0;
    for (uint32_t y = 0; y < h; y++) {
        for (uint32_t x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            double d = cur->depth[i], l = cur->log_lum[i];
            double qx = x + 0.5 + cur->motion[2 * i], qy = y + 0.5 + cur->motion[2 * i + 1];
            if (!(d > 0.0) || !isfinite(d) || !isfinite(l) || !isfinite(qx) || !isfinite(qy))
                continue;
            if (!(qx >= 0.0 && qx < w && qy >= 0.0 && qy < h)) {
                s->offscreen_count++;
                continue;
            }
            double u = fmin(fmax(qx - 0.5, 0.0), w - 1.0), v = fmin(fmax(qy - 0.5, 0.0), h - 1.0);
            uint32_t x0 = (uint32_t)u, y0 = (uint32_t)v;
            uint32_t x1 = x0 + 1 < w ? x0 + 1 : x0, y1 = y0 + 1 < h ? y0 + 1 : y0;
            double fx = u - x0, fy = v - y0;
            const size_t taps[4] = {(size_t)y0 * w + x0, (size_t)y0 * w + x1, (size_t)y1 * w + x0,
                                    (size_t)y1 * w + x1};
            const double weights[4] = {(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy,
                                       fx * fy};
            double lp = 0.0, dp = 0.0;
            bool has_geometry = true;
            for (int k = 0; k < 4; k++) {
                if (!(weights[k] > 0.0))
                    continue;
                has_geometry = has_geometry && prev->depth[taps[k]] > 0.0;
                dp += weights[k] * prev->depth[taps[k]];
                lp += weights[k] * prev->log_lum[taps[k]];
            }
            if (!has_geometry || !(fabs(dp - d) <= tolerance * d)) {
                s->disoccluded_count++;
                continue;
            }
            if (!isfinite(lp))
                continue;
            sum += fabs(l - lp);
            s->compared_count++;
        }
    }
    s->warped_error = s->compared_count ? sum / (double)s->compared_count : NAN;
}

/* Narrows t's static pixels to those that are static in frame cur too, and adds their log
 * luminance to their sums. */
static void update_static(struct track *t, bool is_first)
{
    const struct frame *c = &t->cur;
    size_t n = (size_t)c->width_px * c->height_px;
    for (size_t i = 0; i < n; i++) {
        double d = c->depth[i], mx = c->motion[2 * i], my = c->motion[2 * i + 1];
        if (is_first)
            t->first_depth[i] = c->depth[i];
        double d0 = t->first_depth[i];
        bool is_static = isfinite(c->log_lum[i]) && d > 0.0 && isfinite(d) &&
                         fabs(mx) <= RB_ANALYSIS_FLICKER_STATIC_MOTION_PX &&
                         fabs(my) <= RB_ANALYSIS_FLICKER_STATIC_MOTION_PX &&
                         fabs(d - d0) <= RB_ANALYSIS_FLICKER_STATIC_DEPTH_REL * d0;
        if (!is_static)
            t->is_static[i] = 0;
        else
            t->log_sum[i] += c->log_lum[i];
    }
}

struct rb_analysis_flicker_excess rb_analysis_flicker_excess(const double *cur, const double *prev,
                                                             const double *ref,
                                                             const double *ref_prev,
                                                             const float *ref_var,
                                                             const float *ref_prev_var, size_t n)
{
    struct rb_analysis_flicker_excess x = {.error = NAN, .rms = NAN};
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double e = (cur[i] - prev[i]) - (ref[i] - ref_prev[i]);
        if (!isfinite(e))
            continue;
        sum += fabs(e);
        x.sum_sq += e * e;
        if (ref_var)
            x.sum_noise += (double)ref_var[i] + (double)ref_prev_var[i];
        x.count++;
    }
    if (x.count) {
        x.error = sum / (double)x.count;
        x.rms = rb_analysis_flicker_excess_rms(x.sum_sq, x.sum_noise, x.count);
    }
    return x;
}

double rb_analysis_flicker_excess_rms(double sum_sq, double sum_noise, uint64_t count)
{
    return count ? sqrt(fmax(sum_sq - sum_noise, 0.0) / (double)count) : NAN;
}

/* The mean and largest of a frame value over the frames that have one (NaN for none). */
static void mean_max(const struct rb_analysis_flicker *f, const double *first, size_t stride,
                     double *mean, double *max)
{
    double sum = 0.0, top = NAN;
    size_t count = 0;
    for (size_t i = 0; i < f->seq.frame_count; i++) {
        double v = *(const double *)(const void *)((const char *)first + i * stride);
        if (isfinite(v)) {
            sum += v;
            top = count ? fmax(top, v) : v;
            count++;
        }
    }
    *mean = count ? sum / (double)count : NAN;
    if (max)
        *max = top;
}

/* Frame i of every track: read, warped against the previous, static pixels narrowed; then the
 * excess against the reference. */
static enum rb_status first_pass(struct rb_analysis_flicker *f, struct track *tracks,
                                 size_t track_count, size_t i, struct rb_err *err)
{
    bool has_prev = i > 0 && f->seq.frames[i - 1] == f->seq.frames[i] - 1;
    enum rb_status st;
    for (size_t k = 0; k < track_count; k++) {
        struct track *t = &tracks[k];
        struct frame swap = t->prev;
        t->prev = t->cur;
        t->cur = swap;
        if ((st = read_frame(f, t->paths[i], true, t->is_reference && f->is_noise_corrected,
                             &t->cur, err)))
            return st;
        if (!f->width_px) {
            f->width_px = t->cur.width_px;
            f->height_px = t->cur.height_px;
        }
        size_t n = (size_t)f->width_px * f->height_px;
        if (!t->is_static) {
            t->is_static = malloc(n);
            t->first_depth = malloc(n * sizeof(*t->first_depth));
            t->log_sum = calloc(n, sizeof(*t->log_sum));
            if (!t->is_static || !t->first_depth || !t->log_sum)
                return rb_errf(err, RB_E_NOMEM, "'%s': out of memory", t->paths[i]);
            memset(t->is_static, 1, n);
        }
        if (has_prev)
            warp(&t->cur, &t->prev, f->desc.depth_tolerance, stats(f, t, i));
        update_static(t, i == 0);
    }
    if (track_count == 2 && has_prev) {
        const struct track *s = &tracks[0], *r = &tracks[1];
        struct rb_analysis_flicker_excess x = rb_analysis_flicker_excess(
            s->cur.lum, s->prev.lum, r->cur.lum, r->prev.lum, r->cur.variance, r->prev.variance,
            (size_t)f->width_px * f->height_px);
        f->frames[i].excess_error = x.error;
        f->frames[i].excess_rms = x.rms;
        f->frames[i].excess_sq_sum = x.sum_sq;
        f->frames[i].excess_noise_sum = x.sum_noise;
        f->frames[i].excess_count = x.count;
    }
    return RB_OK;
}

/* Every frame of t again: the static pixels' deviation from their mean; then t's summary. */
static enum rb_status second_pass(struct rb_analysis_flicker *f, struct track *t,
                                  struct rb_err *err)
{
    size_t n = (size_t)f->width_px * f->height_px, count = 0;
    double frame_count = (double)f->seq.frame_count;
    for (size_t p = 0; p < n; p++)
        count += t->is_static[p] ? 1 : 0;
    t->summary->static_count = count;
    for (size_t i = 0; i < f->seq.frame_count && count; i++) {
        enum rb_status st = read_frame(f, t->paths[i], false, false, &t->cur, err);
        if (st)
            return st;
        double sum = 0.0;
        for (size_t p = 0; p < n; p++) {
            if (!t->is_static[p])
                continue;
            double d = t->cur.log_lum[p] - t->log_sum[p] / frame_count;
            sum += d * d;
        }
        stats(f, t, i)->static_deviation = sum / (double)count;
    }
    const struct rb_analysis_flicker_stats *s = stats(f, t, 0);
    mean_max(f, &s->warped_error, sizeof(f->frames[0]), &t->summary->warped_error,
             &t->summary->warped_error_max);
    mean_max(f, &s->static_deviation, sizeof(f->frames[0]), &t->summary->static_variance, NULL);
    return RB_OK;
}

/* Finds the reference's frame for each of the sequence's into *paths (borrowed from f->ref). */
static enum rb_status reference_paths(struct rb_analysis_flicker *f, const char ***paths,
                                      struct rb_err *err)
{
    const char **p = calloc(f->seq.frame_count, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "flicker: out of memory");
    for (size_t i = 0; i < f->seq.frame_count; i++) {
        long k = rb_analysis_sequence_find(&f->ref, f->seq.frames[i]);
        if (k < 0) {
            free(p);
            return rb_errf(err, RB_E_INVALID, "the reference '%s' has no frame %d (for '%s')",
                           f->ref.dir, f->seq.frames[i], f->seq.paths[i]);
        }
        p[i] = f->ref.paths[k];
    }
    *paths = p;
    return RB_OK;
}

static enum rb_status measure(struct rb_analysis_flicker *f, struct rb_err *err)
{
    struct track tracks[2] = {
        {.paths = (const char **)f->seq.paths, .summary = &f->summary},
        {.summary = &f->reference_summary, .is_reference = true},
    };
    size_t track_count = f->has_reference ? 2 : 1;
    enum rb_status st = RB_OK;
    if (f->has_reference && ((st = reference_paths(f, &tracks[1].paths, err)) ||
                             (st = rb_analysis_layer_probe(tracks[1].paths[0], "variance",
                                                           &f->is_noise_corrected, err))))
        goto out;
    for (size_t i = 0; i < f->seq.frame_count && st == RB_OK; i++)
        st = first_pass(f, tracks, track_count, i, err);
    for (size_t k = 0; k < track_count && st == RB_OK; k++)
        st = second_pass(f, &tracks[k], err);
    if (st == RB_OK && f->has_reference) {
        mean_max(f, &f->frames[0].excess_error, sizeof(f->frames[0]), &f->excess_error,
                 &f->excess_error_max);
        /* pooled before the root: a frame's noise estimate errs either way, and summing first
         * lets those errors cancel where clamping each frame at 0 would not */
        double sq = 0.0, noise = 0.0;
        uint64_t count = 0;
        for (size_t i = 0; i < f->seq.frame_count; i++) {
            sq += f->frames[i].excess_sq_sum;
            noise += f->frames[i].excess_noise_sum;
            count += f->frames[i].excess_count;
        }
        f->excess_rms = rb_analysis_flicker_excess_rms(sq, noise, count);
    }
out:
    free(tracks[1].paths);
    for (size_t k = 0; k < 2; k++)
        track_release(&tracks[k]);
    return st;
}

enum rb_status rb_analysis_flicker_create(const struct rb_analysis_flicker_desc *desc,
                                          struct rb_analysis_flicker **out, struct rb_err *err)
{
    if (!desc || !desc->seq || !*desc->seq || !out)
        return rb_errf(err, RB_E_INVALID, "flicker: no sequence");
    if (!(desc->log_epsilon >= 0.0) || !isfinite(desc->log_epsilon))
        return rb_errf(err, RB_E_INVALID, "flicker: log epsilon %g is not a number >= 0",
                       desc->log_epsilon);
    if (!(desc->depth_tolerance >= 0.0) || !isfinite(desc->depth_tolerance))
        return rb_errf(err, RB_E_INVALID, "flicker: depth tolerance %g is not a number >= 0",
                       desc->depth_tolerance);
    struct rb_analysis_flicker *f = calloc(1, sizeof(*f));
    if (!f)
        return rb_errf(err, RB_E_NOMEM, "flicker: out of memory");
    enum rb_status st;
    f->desc = rb_analysis_flicker_desc_resolve(desc);
    f->has_reference = desc->reference && *desc->reference;
    f->excess_error = f->excess_error_max = f->excess_rms = NAN;
    if ((st = rb_analysis_sequence_scan(desc->seq, &f->seq, err)) ||
        (f->has_reference && (st = rb_analysis_sequence_scan(desc->reference, &f->ref, err))))
        goto fail;
    if (!(f->frames = calloc(f->seq.frame_count, sizeof(*f->frames)))) {
        st = rb_errf(err, RB_E_NOMEM, "flicker: out of memory for %zu frames", f->seq.frame_count);
        goto fail;
    }
    const struct rb_analysis_flicker_stats none = {.warped_error = NAN, .static_deviation = NAN};
    const struct rb_analysis_flicker_summary no_summary = {
        .warped_error = NAN, .warped_error_max = NAN, .static_variance = NAN};
    for (size_t i = 0; i < f->seq.frame_count; i++)
        f->frames[i] = (struct rb_analysis_flicker_frame){.frame = f->seq.frames[i],
                                                          .seq = none,
                                                          .ref = none,
                                                          .excess_error = NAN,
                                                          .excess_rms = NAN};
    f->summary = f->reference_summary = no_summary;
    if ((st = measure(f, err)))
        goto fail;
    *out = f;
    return RB_OK;
fail:
    rb_analysis_flicker_destroy(f);
    return st;
}

enum rb_status rb_analysis_flicker_gate(const struct rb_analysis_flicker *seq,
                                        const struct rb_analysis_flicker *base, double alpha,
                                        double min_effect, struct rb_analysis_flicker_gate *out,
                                        struct rb_err *err)
{
    *out = (struct rb_analysis_flicker_gate){.mean = NAN, .base_mean = NAN, .effect = NAN};
    if (seq->width_px != base->width_px || seq->height_px != base->height_px)
        return rb_errf(err, RB_E_INVALID,
                       "flicker: the sequence is %ux%u and the baseline %ux%u: not one job's",
                       seq->width_px, seq->height_px, base->width_px, base->height_px);
    size_t n = seq->seq.frame_count;
    double *d = malloc((n ? n : 1) * 2 * sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "flicker: out of memory");
    double *neg = d + n, sum = 0.0, base_sum = 0.0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        const struct rb_analysis_flicker_frame *a = &seq->frames[i];
        long k = rb_analysis_sequence_find(&base->seq, a->frame);
        if (k < 0 || !isfinite(a->seq.warped_error))
            continue;
        const struct rb_analysis_flicker_frame *b = &base->frames[k];
        if (!isfinite(b->seq.warped_error))
            continue;
        d[m] = a->seq.warped_error - b->seq.warped_error;
        neg[m] = -d[m];
        sum += a->seq.warped_error;
        base_sum += b->seq.warped_error;
        m++;
    }
    out->pair_count = m;
    enum rb_status st = RB_OK;
    if (m < RB_ANALYSIS_FLICKER_GATE_MIN_PAIRS) {
        st = rb_errf(err, RB_E_INVALID,
                     "flicker: %zu frame%s of the sequence and the baseline %s a warped temporal "
                     "error (a frame and the one before it); the gate needs at least %d",
                     m, m == 1 ? "" : "s", m == 1 ? "has" : "have",
                     RB_ANALYSIS_FLICKER_GATE_MIN_PAIRS);
        goto out;
    }
    out->mean = sum / (double)m;
    out->base_mean = base_sum / (double)m;
    out->effect = out->base_mean > 0.0 ? out->mean / out->base_mean - 1.0
                  : out->mean > 0.0    ? INFINITY
                                       : 0.0;
    if ((st = rb_analysis_wilcoxon_greater(d, m, &out->more, err)) ||
        (st = rb_analysis_wilcoxon_greater(neg, m, &out->less, err)))
        goto out;
    if (out->more.p < alpha && out->effect > min_effect)
        out->verdict = RB_ANALYSIS_FLICKER_MORE;
    else if (out->less.p < alpha && out->effect < -min_effect)
        out->verdict = RB_ANALYSIS_FLICKER_LESS;
out:
    free(d);
    return st;
}
