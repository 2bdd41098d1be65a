/* Image comparison: layer channels out of a loaded image, masks (threshold, edges), the error
 * metrics and their accumulation over frames, and the error image. Every sum runs in double in
 * row order, so the same inputs give the same digits. */
#include "analysis/analysis.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- layers ----------------------------------------------------------------------------- */

enum rb_status rb_analysis_layer_resolve(const char *name, struct rb_analysis_layer *out,
                                         struct rb_err *err)
{
    static const char *const rgb[] = {"R", "G", "B"};
    struct rb_analysis_layer l;

    if (!out)
        return rb_errf(err, RB_E_INVALID, "layer: no output");
    memset(&l, 0, sizeof(l));
    if (!name || !*name)
        name = "beauty";
    if (strlen(name) >= sizeof(l.name))
        return rb_errf(err, RB_E_INVALID, "layer name '%.40s...' is longer than %zu bytes", name,
                       sizeof(l.name) - 1);
    if (strpbrk(name, "./ \t\n"))
        return rb_errf(err, RB_E_INVALID, "bad layer name '%s': no '.', '/' or spaces", name);
    /* A layer the renderer writes has its channels (rb_layer_channel) and its own spelling,
     * whatever the case it is asked for in; any other is RGB, spelt as asked. */
    uint32_t known = 0;
    while (known < RB_LAYER_COUNT && strcasecmp(name, rb_layer_name((enum rb_layer)known)))
        known++;
    bool is_beauty = !strcasecmp(name, "beauty");
    if (is_beauty)
        name = "beauty";
    else if (known < RB_LAYER_COUNT)
        name = rb_layer_name((enum rb_layer)known);
    rb_strlcpy(l.name, name, sizeof(l.name));
    l.channel_count = known < RB_LAYER_COUNT ? rb_layer_width((enum rb_layer)known) : 3;
    for (uint32_t c = 0; c < l.channel_count; c++)
        snprintf(l.channels[c], sizeof(l.channels[c]), "%s%s%s", is_beauty ? "" : name,
                 is_beauty ? "" : ".",
                 known < RB_LAYER_COUNT ? rb_layer_channel((enum rb_layer)known, c) : rgb[c]);
    *out = l;
    return RB_OK;
}

/* "R, G, B" into buf. */
static const char *channel_list(const struct rb_analysis_layer *layer, char *buf, size_t size)
{
    size_t len = 0;
    buf[0] = '\0';
    for (uint32_t c = 0; c < layer->channel_count && len < size; c++) {
        int n = snprintf(buf + len, size - len, "%s%s", c ? ", " : "", layer->channels[c]);
        if (n < 0)
            break;
        len += (size_t)n;
    }
    return buf;
}

/* Where the channel "layer.C" (or a beauty's "C") is in img: that very name, or else the
 * first channel whose layer is the same but for case, with the same C. -1 when neither. */
static int find_channel(const struct rb_io_image *img, const char *name)
{
    int exact = rb_io_image_channel(img, name);
    const char *base = rb_io_channel_base(name);
    size_t len = base == name ? 0 : (size_t)(base - name); /* the layer and its '.' */
    if (exact >= 0 || !len)
        return exact;
    for (uint32_t c = 0; c < img->channel_count; c++) {
        const char *other = img->channel_names[c];
        if (other && rb_io_channel_base(other) == other + len && !strncasecmp(other, name, len) &&
            !strcmp(other + len, base))
            return (int)c;
    }
    return -1;
}

/* True when img has a channel of the layer, whatever the case of the layer's name. */
static bool has_layer(const struct rb_io_image *img, const struct rb_analysis_layer *layer)
{
    bool is_beauty = !strcmp(layer->name, "beauty");
    size_t len = strlen(layer->name);
    for (uint32_t c = 0; c < img->channel_count; c++) {
        const char *name = img->channel_names[c];
        const char *base = name ? rb_io_channel_base(name) : NULL;
        if (base && (is_beauty ? base == name
                               : base == name + len + 1 && !strncasecmp(name, layer->name, len)))
            return true;
    }
    return false;
}

/* The names of img's layers, "beauty, direct, normal", into buf (the message's list; cut to
 * fit, and "?" when they cannot be listed for want of memory). */
static const char *layer_names(const struct rb_io_image *img, char *buf, size_t size)
{
    struct rb_io_image_layers layers;
    size_t len = 0;
    buf[0] = '\0';
    if (rb_io_image_layers_init(&layers, img, NULL) != RB_OK)
        snprintf(buf, size, "?");
    else if (!layers.count)
        snprintf(buf, size, "none");
    for (size_t i = 0; buf[0] != '?' && i < layers.count && len < size; i++) {
        int n = snprintf(buf + len, size - len, "%s%s", i ? ", " : "", layers.layers[i].name);
        if (n < 0)
            break;
        len += (size_t)n;
    }
    rb_io_image_layers_release(&layers);
    return buf;
}

enum rb_status rb_analysis_layer_extract(const struct rb_analysis_layer *layer,
                                         const struct rb_io_image *img, const char *path,
                                         float **out, struct rb_err *err)
{
    int index[RB_ANALYSIS_MAX_CHANNELS];
    char list[400];

    if (!layer || !img || !out)
        return rb_errf(err, RB_E_INVALID, "layer extract: missing argument");
    if (!path)
        path = "image";
    if (layer->channel_count < 1 || layer->channel_count > RB_ANALYSIS_MAX_CHANNELS)
        return rb_errf(err, RB_E_INVALID, "layer '%s' has %u channels (1..%d)", layer->name,
                       layer->channel_count, RB_ANALYSIS_MAX_CHANNELS);
    for (uint32_t c = 0; c < layer->channel_count; c++)
        index[c] = find_channel(img, layer->channels[c]);
    for (uint32_t c = 0; c < layer->channel_count; c++)
        if (index[c] < 0 && !has_layer(img, layer))
            return rb_errf(err, RB_E_INVALID, "'%s' has no layer '%s'; its layers: %s", path,
                           layer->name, layer_names(img, list, sizeof(list)));
    for (uint32_t c = 0; c < layer->channel_count; c++)
        if (index[c] < 0)
            return rb_errf(err, RB_E_INVALID,
                           "'%s' has no layer '%s': channel '%s' is missing (the layer is %s)",
                           path, layer->name, layer->channels[c],
                           channel_list(layer, list, sizeof(list)));
    size_t n = (size_t)img->width_px * img->height_px;
    if (!n)
        return rb_errf(err, RB_E_INVALID, "'%s' is empty (%ux%u)", path, img->width_px,
                       img->height_px);
    float *px = malloc(n * layer->channel_count * sizeof(float));
    if (!px)
        return rb_errf(err, RB_E_NOMEM, "'%s': out of memory for layer '%s'", path, layer->name);
    for (size_t i = 0; i < n; i++)
        for (uint32_t c = 0; c < layer->channel_count; c++)
            px[i * layer->channel_count + c] =
                img->pixels[i * img->channel_count + (size_t)index[c]];
    *out = px;
    return RB_OK;
}

enum rb_status rb_analysis_layer_probe(const char *path, const char *name, bool *has,
                                       struct rb_err *err)
{
    struct rb_analysis_layer layer;
    struct rb_io_image img = {0};
    enum rb_status st;
    if ((st = rb_analysis_layer_resolve(name, &layer, err)) ||
        (st = rb_io_image_read(path, &img, err)))
        return st;
    *has = has_layer(&img, &layer);
    rb_io_image_release(&img);
    return RB_OK;
}

enum rb_status rb_analysis_layers_read(const char *path, const char *const *names, size_t count,
                                       float **out, uint32_t *width_px, uint32_t *height_px,
                                       struct rb_err *err)
{
    struct rb_io_image img = {0};
    float *px[RB_ANALYSIS_MAX_LAYERS] = {0};
    enum rb_status st;
    if (count > RB_ANALYSIS_MAX_LAYERS)
        return rb_errf(err, RB_E_INVALID, "'%s': %zu layers asked for, at most %d", path, count,
                       RB_ANALYSIS_MAX_LAYERS);
    if ((st = rb_io_image_read(path, &img, err)))
        return st;
    for (size_t i = 0; i < count && st == RB_OK; i++) {
        struct rb_analysis_layer layer;
        if (!(st = rb_analysis_layer_resolve(names[i], &layer, err)))
            st = rb_analysis_layer_extract(&layer, &img, path, &px[i], err);
    }
    for (size_t i = 0; i < count; i++) {
        if (st)
            free(px[i]);
        else
            out[i] = px[i];
    }
    if (!st) {
        *width_px = img.width_px;
        *height_px = img.height_px;
    }
    rb_io_image_release(&img);
    return st;
}

/* ---- masks ------------------------------------------------------------------------------ */

void rb_analysis_mask_and(uint8_t *mask, size_t pixel_count, const float *values, size_t stride)
{
    if (!mask || !values)
        return;
    if (!stride)
        stride = 1;
    for (size_t i = 0; i < pixel_count; i++)
        if (!(values[i * stride] > RB_ANALYSIS_MASK_THRESHOLD))
            mask[i] = 0;
}

/* True when pixels i and j straddle a depth or alpha discontinuity. */
static bool is_edge(const struct rb_analysis_edge_desc *d, size_t ds, size_t as, size_t i, size_t j)
{
    double dp = d->depth[i * ds], dq = d->depth[j * ds];
    double scale = fmax(fabs(dp), fabs(dq));
    /* Written so that NaN on either side counts as an edge. */
    if (!(fabs(dp - dq) <= RB_ANALYSIS_EDGE_DEPTH_REL * scale))
        return true;
    if (d->alpha &&
        !(fabs((double)d->alpha[i * as] - (double)d->alpha[j * as]) <= RB_ANALYSIS_EDGE_ALPHA))
        return true;
    return false;
}

/* Dilates the 0/1 flags of one row or column (count entries, step apart) by r in place, with
 * a running count so that the cost does not grow with r. prefix holds count + 1 entries. */
static void dilate_line(uint8_t *flags, size_t count, size_t step, size_t r, uint32_t *prefix)
{
    prefix[0] = 0;
    for (size_t i = 0; i < count; i++)
        prefix[i + 1] = prefix[i] + (flags[i * step] ? 1u : 0u);
    for (size_t i = 0; i < count; i++) {
        size_t lo = i > r ? i - r : 0;
        size_t hi = i + r + 1 < count ? i + r + 1 : count;
        flags[i * step] = prefix[hi] > prefix[lo];
    }
}

enum rb_status rb_analysis_exclude_edges(const struct rb_analysis_edge_desc *desc, uint8_t *mask,
                                         struct rb_err *err)
{
    if (!desc || !mask)
        return rb_errf(err, RB_E_INVALID, "edge exclusion: missing argument");
    if (desc->radius_px == 0)
        return RB_OK;
    if (!desc->depth)
        return rb_errf(err, RB_E_INVALID, "edge exclusion: no depth");
    size_t w = desc->width_px, h = desc->height_px, n = w * h;
    if (!n)
        return rb_errf(err, RB_E_INVALID, "edge exclusion: empty image (%ux%u)", desc->width_px,
                       desc->height_px);
    size_t ds = desc->depth_stride ? desc->depth_stride : 1;
    size_t as = desc->alpha_stride ? desc->alpha_stride : 1;
    uint8_t *edge = calloc(n, 1);
    uint32_t *prefix = malloc(((w > h ? w : h) + 1) * sizeof(uint32_t));
    if (!edge || !prefix) {
        free(edge);
        free(prefix);
        return rb_errf(err, RB_E_NOMEM, "edge exclusion: out of memory for %ux%u", desc->width_px,
                       desc->height_px);
    }
    for (size_t y = 0; y < h; y++) {
        for (size_t x = 0; x < w; x++) {
            size_t i = y * w + x;
            if (x + 1 < w && is_edge(desc, ds, as, i, i + 1))
                edge[i] = edge[i + 1] = 1;
            if (y + 1 < h && is_edge(desc, ds, as, i, i + w))
                edge[i] = edge[i + w] = 1;
        }
    }
    /* A square window is separable: rows, then columns. */
    size_t r = desc->radius_px - 1;
    if (r) {
        for (size_t y = 0; y < h; y++)
            dilate_line(edge + y * w, w, 1, r, prefix);
        for (size_t x = 0; x < w; x++)
            dilate_line(edge + x, h, w, r, prefix);
    }
    for (size_t i = 0; i < n; i++)
        if (edge[i])
            mask[i] = 0;
    free(prefix);
    free(edge);
    return RB_OK;
}

/* ---- metrics ---------------------------------------------------------------------------- */

/* Fills the derived fields of m from its sums. */
static void derive(struct rb_analysis_metrics *m)
{
    double n = (double)m->value_count;
    m->mse = m->value_count ? m->sum_sq_error / n : 0.0;
    m->rmse = sqrt(m->mse);
    m->relmse = m->value_count ? m->sum_rel_error / n : 0.0;
    m->mae = m->value_count ? m->sum_abs_error / n : 0.0;
    if (!(m->peak > 0.0))
        m->peak = RB_ANALYSIS_PEAK;
    m->psnr = m->mse > 0.0 ? 10.0 * log10(m->peak * m->peak / m->mse) : INFINITY;
}

enum rb_status rb_analysis_compare(const struct rb_analysis_compare_desc *desc,
                                   struct rb_analysis_metrics *out, struct rb_err *err)
{
    if (!desc || !out)
        return rb_errf(err, RB_E_INVALID, "compare: missing argument");
    if (!desc->a || !desc->b)
        return rb_errf(err, RB_E_INVALID, "compare: missing image");
    if (!desc->width_px || !desc->height_px)
        return rb_errf(err, RB_E_INVALID, "compare: empty image (%ux%u)", desc->width_px,
                       desc->height_px);
    if (desc->channel_count < 1 || desc->channel_count > RB_ANALYSIS_MAX_CHANNELS)
        return rb_errf(err, RB_E_INVALID, "compare: %u channels (1..%d)", desc->channel_count,
                       RB_ANALYSIS_MAX_CHANNELS);
    if (!(desc->epsilon >= 0.0) || isinf(desc->epsilon))
        return rb_errf(err, RB_E_INVALID, "compare: epsilon %g is not a finite value >= 0",
                       desc->epsilon);

    if (!(desc->peak >= 0.0) || isinf(desc->peak))
        return rb_errf(err, RB_E_INVALID, "compare: peak %g is not a finite value >= 0",
                       desc->peak);

    struct rb_analysis_metrics m = {.peak = desc->peak};
    const double eps = desc->epsilon > 0.0 ? desc->epsilon : RB_ANALYSIS_EPSILON;
    const uint32_t nc = desc->channel_count;
    const size_t w = desc->width_px, n = w * desc->height_px;

    for (size_t i = 0; i < n; i++) {
        const float *a = desc->a + i * nc, *b = desc->b + i * nc;
        float *abs_out = desc->abs_error ? desc->abs_error + i * nc : NULL;
        bool use = !desc->mask || desc->mask[i];
        for (uint32_t c = 0; use && c < nc; c++)
            if (!isfinite(a[c]) || !isfinite(b[c])) {
                m.nonfinite_count++;
                use = false;
            }
        if (!use) {
            for (uint32_t c = 0; abs_out && c < nc; c++)
                abs_out[c] = 0.0f;
            if (desc->rel_error)
                desc->rel_error[i] = 0.0f;
            continue;
        }
        double pixel_rel = 0.0;
        for (uint32_t c = 0; c < nc; c++) {
            double av = a[c], bv = b[c], d = av - bv, ad = fabs(d);
            double rel = d * d / (bv * bv + eps);
            m.sum_sq_error += d * d;
            m.sum_abs_error += ad;
            m.sum_rel_error += rel;
            pixel_rel += rel;
            if (m.value_count == 0 || bv > m.max_b)
                m.max_b = bv;
            if (m.value_count == 0 || ad > m.max_error) {
                m.max_error = ad;
                m.max_error_x = (uint32_t)(i % w);
                m.max_error_y = (uint32_t)(i / w);
            }
            m.value_count++;
            if (abs_out)
                abs_out[c] = (float)ad;
        }
        if (desc->rel_error)
            desc->rel_error[i] = (float)(pixel_rel / nc);
        m.pixel_count++;
    }
    derive(&m);
    *out = m;
    return RB_OK;
}

void rb_analysis_metrics_add(struct rb_analysis_metrics *total,
                             const struct rb_analysis_metrics *frame, int frame_number)
{
    if (!total || !frame)
        return;
    total->nonfinite_count += frame->nonfinite_count;
    if (frame->peak > 0.0)
        total->peak = frame->peak;
    if (frame->value_count) {
        if (!total->value_count || frame->max_b > total->max_b)
            total->max_b = frame->max_b;
        if (!total->value_count || frame->max_error > total->max_error) {
            total->max_error = frame->max_error;
            total->max_error_x = frame->max_error_x;
            total->max_error_y = frame->max_error_y;
            total->max_error_frame = frame_number;
        }
        total->pixel_count += frame->pixel_count;
        total->value_count += frame->value_count;
        total->sum_sq_error += frame->sum_sq_error;
        total->sum_abs_error += frame->sum_abs_error;
        total->sum_rel_error += frame->sum_rel_error;
    }
    derive(total);
}

/* ---- error image ------------------------------------------------------------------------ */

enum rb_status rb_analysis_error_write(const char *path, uint32_t width_px, uint32_t height_px,
                                       uint32_t channel_count, const float *abs_error,
                                       const float *rel_error, struct rb_err *err)
{
    static const char *const rgb[] = {"R", "G", "B"};
    static const char *const y[] = {"Y"};

    if (!path || !abs_error || !rel_error)
        return rb_errf(err, RB_E_INVALID, "error image: missing argument");
    if (channel_count < 1 || channel_count > RB_ANALYSIS_MAX_CHANNELS)
        return rb_errf(err, RB_E_INVALID, "error image '%s': %u channels (1..%d)", path,
                       channel_count, RB_ANALYSIS_MAX_CHANNELS);
    size_t n = (size_t)width_px * height_px;
    if (!n)
        return rb_errf(err, RB_E_INVALID, "error image '%s': empty image (%ux%u)", path, width_px,
                       height_px);
    float *px = malloc(n * 3 * sizeof(float));
    if (!px)
        return rb_errf(err, RB_E_NOMEM, "error image '%s': out of memory", path);
    for (size_t i = 0; i < n; i++) {
        const float *e = abs_error + i * channel_count;
        px[i * 3 + 0] = e[0];
        px[i * 3 + 1] = channel_count > 1 ? e[1] : e[0];
        px[i * 3 + 2] = channel_count > 2 ? e[2] : (channel_count == 1 ? e[0] : 0.0f);
    }
    const struct rb_io_layer layers[] = {
        {.name = NULL, .channel_count = 3, .channel_names = rgb, .pixels = px},
        {.name = "relmse", .channel_count = 1, .channel_names = y, .pixels = rel_error},
    };
    enum rb_status st = rb_io_exr_write(path, width_px, height_px, layers, 2, NULL, 0, err);
    free(px);
    return st;
}
