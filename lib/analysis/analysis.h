/* Image analysis: error metrics between a test image and a reference (RMSE, relative MSE, MAE,
 * PSNR, the largest error and where it is), masks that choose the pixels compared, and their
 * accumulation over a frame sequence. Knows nothing of the command line; raybundle compare
 * (cmd/compare.c) loads the files and prints. */
#ifndef RB_ANALYSIS_ANALYSIS_H
#define RB_ANALYSIS_ANALYSIS_H

#include "core/core.h"
#include "io/io.h"

/* relMSE's epsilon: (a-b)^2 / (b^2 + eps), so that black reference pixels do not dominate. */
#define RB_ANALYSIS_EPSILON 1e-2
/* Depth differing by more than this fraction between 4-neighbours marks an edge. */
#define RB_ANALYSIS_EDGE_DEPTH_REL 0.05
/* Alpha differing by more than this between 4-neighbours marks an edge. */
#define RB_ANALYSIS_EDGE_ALPHA 0.01
/* A mask or alpha value above this includes the pixel. */
#define RB_ANALYSIS_MASK_THRESHOLD 0.5f
#define RB_ANALYSIS_MAX_CHANNELS 4

/* ---- layers ----------------------------------------------------------------------------- */

/* The channels compared for a layer name: "beauty" is R,G,B; "normal" is normal.X/Y/Z;
 * "depth" is depth.Z; "motion" is motion.X/Y; any other NAME (direct, indirect, albedo, ...)
 * is NAME.R/G/B. */
struct rb_analysis_layer {
    char name[64];
    uint32_t channel_count; /* 1..RB_ANALYSIS_MAX_CHANNELS */
    char channels[RB_ANALYSIS_MAX_CHANNELS][80];
};

/* Fills out for the layer called name (NULL or "" is "beauty"). Fails with RB_E_INVALID for a
 * name that is too long or holds '.', '/' or spaces. */
enum rb_status rb_analysis_layer_resolve(const char *name, struct rb_analysis_layer *out,
                                         struct rb_err *err);

/* Copies the layer's channels out of img into a new interleaved array of
 * width*height*layer->channel_count floats, which the caller frees with free(). *out is
 * written only on success. A missing channel fails with RB_E_INVALID and a message naming path
 * (used only for the message), the layer and its channels. */
enum rb_status rb_analysis_layer_extract(const struct rb_analysis_layer *layer,
                                         const struct rb_io_image *img, const char *path,
                                         float **out, struct rb_err *err);

/* ---- masks ------------------------------------------------------------------------------ */

/* A mask is width*height bytes, rows top to bottom, nonzero for a pixel that is compared. */

/* Keeps mask[i] only where values[i * stride] > RB_ANALYSIS_MASK_THRESHOLD (stride 0 means 1):
 * the first channel of a mask image, or an alpha channel. NaN excludes. */
void rb_analysis_mask_and(uint8_t *mask, size_t pixel_count, const float *values, size_t stride);

struct rb_analysis_edge_desc {
    uint32_t width_px, height_px;
    const float *depth;  /* the reference's depth, one value per pixel (0 where no geometry) */
    size_t depth_stride; /* floats from one pixel's depth to the next; 0 means 1 */
    const float *alpha;  /* the reference's alpha, or NULL to look at depth only */
    size_t alpha_stride; /* 0 means 1 */
    uint32_t radius_px;  /* 0: exclude nothing; N: see rb_analysis_exclude_edges */
};

/* Clears the mask around depth discontinuities, where point-sampled and filtered renders
 * legitimately differ. Two 4-neighbours p, q straddle an edge when
 * |d_p - d_q| > RB_ANALYSIS_EDGE_DEPTH_REL * max(|d_p|, |d_q|) or their alphas differ by more
 * than RB_ANALYSIS_EDGE_ALPHA; both are edge pixels. A pixel is excluded when it lies within
 * radius_px of the edge, i.e. at a Chebyshev distance below radius_px from an edge pixel
 * (radius 1: the edge pixels themselves; 2: also their 8-neighbours). Fails only with
 * RB_E_INVALID (bad desc) or RB_E_NOMEM; the mask is then unchanged. */
enum rb_status rb_analysis_exclude_edges(const struct rb_analysis_edge_desc *desc, uint8_t *mask,
                                         struct rb_err *err);

/* ---- metrics ---------------------------------------------------------------------------- */

struct rb_analysis_compare_desc {
    uint32_t width_px, height_px;
    uint32_t channel_count; /* 1..RB_ANALYSIS_MAX_CHANNELS, interleaved */
    const float *a;         /* the test image, width*height*channel_count floats */
    const float *b;         /* the reference, the same shape */
    const uint8_t *mask;    /* width*height, nonzero compares the pixel; NULL compares all */
    double epsilon;         /* relMSE's eps; 0 means RB_ANALYSIS_EPSILON; never negative */
    /* Optional outputs, written for every pixel (0 where excluded): */
    float *abs_error; /* width*height*channel_count: |a - b| */
    float *rel_error; /* width*height: (a-b)^2 / (b^2 + eps), averaged over the channels */
};

/* The sums are what frames combine by; the rest is derived from them. */
struct rb_analysis_metrics {
    uint64_t pixel_count;     /* pixels compared */
    uint64_t value_count;     /* pixel_count * channel_count */
    uint64_t nonfinite_count; /* masked-in pixels skipped: a value of A or B is NaN or inf */
    double sum_sq_error;      /* sum of (a-b)^2 */
    double sum_abs_error;     /* sum of |a-b| */
    double sum_rel_error;     /* sum of (a-b)^2 / (b^2 + eps) */
    double max_b;             /* the largest reference value compared (valid if value_count) */
    double max_error;         /* the largest |a-b| (0 when nothing was compared) */
    uint32_t max_error_x, max_error_y; /* its pixel: the first in row order, then frame order */
    int max_error_frame;               /* its frame, as given to rb_analysis_metrics_add */
    /* Derived: */
    double mse, rmse, relmse, mae; /* means over pixels and channels; 0 when nothing compared */
    double peak;                   /* max_b, or 1 when that is not positive */
    double psnr;                   /* 10 log10(peak^2 / mse) in dB; INFINITY when mse == 0 */
};

/* Compares desc->a against the reference desc->b over the masked-in pixels, in double, in row
 * order (the same inputs give the same bits). Pixels where either image holds a NaN or an
 * infinity are skipped and counted in nonfinite_count. *out is overwritten; its
 * max_error_frame is 0. Fails with RB_E_INVALID for a bad desc. */
enum rb_status rb_analysis_compare(const struct rb_analysis_compare_desc *desc,
                                   struct rb_analysis_metrics *out, struct rb_err *err);

/* Adds frame's sums into total (start from a zeroed struct) and re-derives total's metrics.
 * The largest error keeps the earliest frame on ties, so add frames in order. */
void rb_analysis_metrics_add(struct rb_analysis_metrics *total,
                             const struct rb_analysis_metrics *frame, int frame_number);

/* ---- error image ------------------------------------------------------------------------ */

/* Writes an EXR (atomically, through rb_io_exr_write) with R,G,B = abs_error and relmse.Y =
 * rel_error, the outputs of rb_analysis_compare for width*height pixels of channel_count
 * channels. One channel is repeated in R, G and B; two leave B zero; a fourth is not written.
 * The buffers are borrowed. */
enum rb_status rb_analysis_error_write(const char *path, uint32_t width_px, uint32_t height_px,
                                       uint32_t channel_count, const float *abs_error,
                                       const float *rel_error, struct rb_err *err);

#endif
