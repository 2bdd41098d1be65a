/* FLIP, the perceptual difference between a test image and its reference that its authors
 * designed for rendered images seen alternately (Andersson et al., "FLIP: A Difference
 * Evaluator for Alternating Images", HPG 2020), and HDR-FLIP for scene-linear images ("Visualizing
 * and Communicating Errors in Rendered Images", Ray Tracing Gems II, 2021; Andersson et al.,
 * "Visualizing Errors in Rendered High Dynamic Range Images", Eurographics 2021), with the pooled
 * values that NVIDIA's reference tool (NVlabs/flip 1.6) prints. Not the command line. */
#ifndef RB_ANALYSIS_FLIP_H
#define RB_ANALYSIS_FLIP_H

#include "core/core.h"

/* The default viewing conditions: 0.7 m from a display 0.7 m wide and 3840 pixels across,
 * about 67.02 pixels per degree. */
#define RB_ANALYSIS_FLIP_DISTANCE_M 0.7
#define RB_ANALYSIS_FLIP_DISPLAY_WIDTH_M 0.7
#define RB_ANALYSIS_FLIP_DISPLAY_WIDTH_PX 3840
/* The largest pixels per degree accepted: the filters grow with it (0.14 px per PPD). */
#define RB_ANALYSIS_FLIP_MAX_PPD 10000.0

/* HDR-FLIP's tone mappers (the reference tool's three), applied per channel after exposure. */
enum rb_analysis_flip_tonemapper {
    RB_ANALYSIS_FLIP_TONEMAPPER_DEFAULT = 0, /* ACES */
    RB_ANALYSIS_FLIP_TONEMAPPER_ACES,        /* Narkowicz's fit, its 0.6 pre-exposure removed */
    RB_ANALYSIS_FLIP_TONEMAPPER_REINHARD,    /* c / (1 + luminance) */
    RB_ANALYSIS_FLIP_TONEMAPPER_HABLE,       /* Hable's filmic curve, as a rational fit */
};

/* A zeroed field means the default. Exposures are in stops (powers of two); 0 is a real
 * exposure, so each has a has_ flag. */
struct rb_analysis_flip_desc {
    double pixels_per_degree; /* 0: rb_analysis_flip_ppd of the RB_ANALYSIS_FLIP_* conditions */
    /* HDR-FLIP only: */
    enum rb_analysis_flip_tonemapper tonemapper;
    bool has_start_exposure, has_stop_exposure; /* false: from the reference's luminance */
    double start_exposure, stop_exposure;
    uint32_t exposure_count; /* 0: ceil(stop - start), at least 2 */
};

/* The exposures HDR-FLIP evaluated: count of them, evenly spaced from start to stop. */
struct rb_analysis_flip_exposures {
    double start, stop;
    uint32_t count;
};

/* Pooled values of a FLIP error map, as the reference tool reports them. The weighted
 * percentiles weigh each pixel by its own error: the weighted median is the smallest error e
 * (in ascending order) where the running sum of the errors up to and including e exceeds half
 * their total, and q1 and q3 the same at a quarter and three quarters; 0 for an error-free map. */
struct rb_analysis_flip_stats {
    double mean;
    double weighted_median, weighted_q1, weighted_q3;
    double min, max;
    uint32_t max_x, max_y; /* the first pixel (row-major) that has the largest error */
};

/* Pixels per degree for a viewer distance_m from a display width_m wide, resolution_px across
 * (the reference's formula, in float as it computes it). */
double rb_analysis_flip_ppd(double distance_m, double width_m, double resolution_px);

/* A copy of in (NULL: all defaults) with the defaults filled in; exposures that depend on the
 * reference stay unset. */
struct rb_analysis_flip_desc rb_analysis_flip_desc_resolve(const struct rb_analysis_flip_desc *in);

/* LDR-FLIP of test against ref, both width_px x height_px interleaved RGB, rows top to bottom,
 * display-referred and sRGB-encoded (a PNG's values / 255), clamped to [0,1] after decoding.
 * Writes the per-pixel error in [0,1] to error_map (width_px * height_px floats; NULL: not
 * wanted) and its pooled values to *out (NULL: not wanted). The inputs are only read.
 * Fails with RB_E_INVALID for a missing image, a zero size, a value that is not finite (the
 * message names the image and the pixel) or a bad desc, RB_E_NOMEM; the outputs are written
 * only on success. Single-threaded; the same inputs give the same bits. */
enum rb_status rb_analysis_flip_ldr(const float *test_rgb, const float *ref_rgb, uint32_t width_px,
                                    uint32_t height_px, const struct rb_analysis_flip_desc *desc,
                                    float *error_map, struct rb_analysis_flip_stats *out,
                                    struct rb_err *err);

/* HDR-FLIP of test against ref, scene-linear RGB (an EXR's R, G, B), laid out as for
 * rb_analysis_flip_ldr: both are exposed by each of the exposures, tone-mapped and clamped to
 * [0,1], compared with LDR-FLIP, and each pixel keeps its largest error. Exposures desc does not
 * give come from the reference (rb_analysis_flip_exposures_compute); those used go to
 * *exposures (NULL: not wanted). Fails as rb_analysis_flip_ldr does, and with RB_E_INVALID when
 * the exposures are needed from a reference whose luminance is not positive where they are
 * computed (its largest and median values), or a start above the stop. */
enum rb_status rb_analysis_flip_hdr(const float *test_rgb, const float *ref_rgb, uint32_t width_px,
                                    uint32_t height_px, const struct rb_analysis_flip_desc *desc,
                                    float *error_map, struct rb_analysis_flip_stats *out,
                                    struct rb_analysis_flip_exposures *exposures,
                                    struct rb_err *err);

/* The exposure range HDR-FLIP derives from a reference, as the reference tool does: with x85
 * the input where the tone mapper reaches 0.85, start = log2(x85 / Ymax) and stop =
 * log2(x85 / Ymedian), Y the Rec.709 luminance and its median the upper middle value; count =
 * max(2, ceil(stop - start)). Fails with RB_E_INVALID for a missing image, a zero size, a value
 * that is not finite, or a largest or median luminance that is not positive; RB_E_NOMEM. */
enum rb_status rb_analysis_flip_exposures_compute(const float *ref_rgb, uint32_t width_px,
                                                  uint32_t height_px,
                                                  enum rb_analysis_flip_tonemapper tonemapper,
                                                  struct rb_analysis_flip_exposures *out,
                                                  struct rb_err *err);

/* Pools an error map of width_px x height_px values, each finite and not negative (FLIP's are in
 * [0,1]), into *out. Fails with RB_E_INVALID for a bad value (named with its pixel),
 * RB_E_NOMEM; *out only on success. */
enum rb_status rb_analysis_flip_pool(const float *error_map, uint32_t width_px, uint32_t height_px,
                                     struct rb_analysis_flip_stats *out, struct rb_err *err);

/* The colour map of FLIP's error images, as NVIDIA's tool draws them: magma (van der Walt and
 * Smith's, for matplotlib), 256 sRGB colours from near black (0, 0, 4) at error 0 through purple
 * and orange to light yellow (252, 253, 191) at 1. */
#define RB_ANALYSIS_FLIP_COLORMAP_SIZE 256

/* The sRGB colour (8 bits a channel) of an error: the map's entry nearest to error * 255,
 * errors below 0 (and NaN) taking the first and above 1 the last. */
void rb_analysis_flip_color(float error, uint8_t rgb[3]);

/* Writes the error map (width_px x height_px values, rows top to bottom) through the colour map
 * as an opaque 8-bit PNG to path, atomically (a temporary name, then renamed). Fails as
 * rb_io_png_write does, and with RB_E_NOMEM. */
enum rb_status rb_analysis_flip_png_write(const char *path, const float *error_map,
                                          uint32_t width_px, uint32_t height_px,
                                          struct rb_err *err);

#endif
