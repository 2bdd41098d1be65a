/* Image analysis: error metrics between a test image and a reference (RMSE, relative MSE, MAE,
 * PSNR, the largest error and where it is), masks that choose the pixels compared, and their
 * accumulation over a frame sequence; timing regression between two bench sets (the
 * Mann-Whitney U test per pass); the HTML report of a rendered sequence. Knows nothing of the
 * command line; raybundle compare, timing and report (cmd/) load the files and print. */
#ifndef RB_ANALYSIS_ANALYSIS_H
#define RB_ANALYSIS_ANALYSIS_H

#include "core/core.h"
#include "io/io.h"

/* relMSE's epsilon: (a-b)^2 / (b^2 + eps), so that black reference pixels do not dominate. */
#define RB_ANALYSIS_EPSILON 1e-2
/* PSNR's peak: the largest value a pixel is taken to reach. 1 suits display-referred values;
 * scene-linear renders have no natural peak, and a reference's own largest value (an
 * emitter's, tens of times brighter than any lit surface) would flatter every error. */
#define RB_ANALYSIS_PEAK 1.0
/* Depth differing by more than this fraction between 4-neighbours marks an edge. */
#define RB_ANALYSIS_EDGE_DEPTH_REL 0.05
/* Alpha differing by more than this between 4-neighbours marks an edge. */
#define RB_ANALYSIS_EDGE_ALPHA 0.01
/* A mask or alpha value above this includes the pixel. */
#define RB_ANALYSIS_MASK_THRESHOLD 0.5f
#define RB_ANALYSIS_MAX_CHANNELS 4
/* The most layers one rb_analysis_layers_read call extracts. */
#define RB_ANALYSIS_MAX_LAYERS 8

/* ---- layers ----------------------------------------------------------------------------- */

/* The channels compared for a layer name: "beauty" is R,G,B; a layer the renderer writes has
 * its EXR channels (rb_layer_channel): "normal" is normal.X/Y/Z, "depth" is depth.Z, "motion"
 * is motion.X/Y, "samples" is samples.diffuse/specular, direct is direct.R/G/B, ...; any other
 * NAME is NAME.R/G/B. */
struct rb_analysis_layer {
    char name[64];
    uint32_t channel_count; /* 1..RB_ANALYSIS_MAX_CHANNELS */
    char channels[RB_ANALYSIS_MAX_CHANNELS][80];
};

/* Fills out for the layer called name (NULL or "" is "beauty"). The beauty and the layers the
 * renderer writes are found whatever the case of name ("Normal" is "normal"); any other name
 * is kept as given. Fails with RB_E_INVALID for a name that is too long or holds '.', '/' or
 * spaces. */
enum rb_status rb_analysis_layer_resolve(const char *name, struct rb_analysis_layer *out,
                                         struct rb_err *err);

/* Copies the layer's channels out of img into a new interleaved array of
 * width*height*layer->channel_count floats, which the caller frees with free(). A channel
 * "layer.C" is img's of that name or else the first whose layer is the same but for case (C
 * itself must match). *out is written only on success. A missing layer fails with
 * RB_E_INVALID and a message naming path (used only for the message), the layer and the layers
 * img has; a layer img has in part, naming the missing channel and the layer's channels. */
enum rb_status rb_analysis_layer_extract(const struct rb_analysis_layer *layer,
                                         const struct rb_io_image *img, const char *path,
                                         float **out, struct rb_err *err);

/* Reads the image at path and extracts the count layers names[] (as rb_analysis_layer_resolve
 * names them) into out[i], each freed by the caller with free(), and its size into *width_px and
 * *height_px. Everything is written only on success. Fails with the reader's status and message
 * (RB_E_IO, RB_E_EXTERNAL), or as rb_analysis_layer_extract does for a missing layer. */
enum rb_status rb_analysis_layers_read(const char *path, const char *const *names, size_t count,
                                       float **out, uint32_t *width_px, uint32_t *height_px,
                                       struct rb_err *err);

/* Whether the image at path has a channel of the layer name (as rb_analysis_layer_resolve names
 * it, whatever its case) into *has. Fails as rb_analysis_layers_read does for an unreadable
 * file; *has only on success. */
enum rb_status rb_analysis_layer_probe(const char *path, const char *name, bool *has,
                                       struct rb_err *err);

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
    double peak;            /* PSNR's peak; 0 means RB_ANALYSIS_PEAK; never negative */
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
    double peak;                   /* PSNR's peak, as the desc gave it (RB_ANALYSIS_PEAK) */
    double psnr;                   /* 10 log10(peak^2 / mse) in dB; INFINITY when mse == 0 */
};

/* Compares desc->a against the reference desc->b over the masked-in pixels, in double, in row
 * order (the same inputs give the same bits). Pixels where either image holds a NaN or an
 * infinity are skipped and counted in nonfinite_count. *out is overwritten; its
 * max_error_frame is 0. Fails with RB_E_INVALID for a bad desc. */
enum rb_status rb_analysis_compare(const struct rb_analysis_compare_desc *desc,
                                   struct rb_analysis_metrics *out, struct rb_err *err);

/* Adds frame's sums into total (start from a zeroed struct) and re-derives total's metrics,
 * with the frame's peak (the frames of one sequence share one). The largest error keeps the
 * earliest frame on ties, so add frames in order. */
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

/* ---- timing regression (timing.c) ------------------------------------------------------- */

/* How rb_analysis_mann_whitney computes its p-value. */
enum rb_analysis_mwu_method {
    RB_ANALYSIS_MWU_AUTO = 0, /* exact without ties and at most RB_ANALYSIS_MWU_EXACT_MAX values
                               * a sample, the normal approximation otherwise */
    RB_ANALYSIS_MWU_EXACT,    /* the exact null distribution of U; refuses ties and more than
                               * 60 values in all */
    RB_ANALYSIS_MWU_NORMAL,   /* the normal approximation with the tie and continuity corrections
                               * (SciPy's mannwhitneyu, method="asymptotic") */
};
#define RB_ANALYSIS_MWU_EXACT_MAX 20

struct rb_analysis_mwu {
    double u; /* U of the first sample: pairs (a_i, b_j) with a_i > b_j, a tie counting 1/2 */
    double p; /* two-sided p-value, in [0, 1] */
    enum rb_analysis_mwu_method method; /* the one used: EXACT or NORMAL */
    bool has_ties;
};

/* The two-sided Mann-Whitney U test of a against b (as SciPy's mannwhitneyu with
 * alternative="two-sided"; method AUTO picks exact for more sizes than SciPy's "auto", which stops
 * at 8). Exact: p = 2 P(U >= max(U1, U2)) under the null distribution, counted. Normal:
 * z = (max(U1, U2) - n1 n2 / 2 - 1/2) / sigma, sigma^2 = n1 n2 / 12 ((n + 1) - sum(t^3 - t) /
 * (n (n - 1))) over groups of t tied values, p = erfc(z / sqrt 2); 1 when every value is tied.
 * Fails with RB_E_INVALID for an empty sample, a NaN, or EXACT with ties; RB_E_NOMEM. The inputs
 * are not changed; the same inputs give the same bits. */
enum rb_status rb_analysis_mann_whitney(const double *a, size_t a_count, const double *b,
                                        size_t b_count, enum rb_analysis_mwu_method method,
                                        struct rb_analysis_mwu *out, struct rb_err *err);

/* The one-sided Wilcoxon signed-rank test that the differences d (paired: test minus base) lie
 * above zero. Zero differences are dropped (Wilcoxon's rule); the others are ranked by |d| with
 * midranks for ties; W+ is the sum of the positive ones' ranks. p = P(W+ >= observed) over the
 * 2^n equally likely signs: counted exactly (doubled midranks are integers, so ties are exact
 * too) for n <= RB_ANALYSIS_WILCOXON_EXACT_MAX, else the normal approximation with the tie and
 * continuity corrections. With no non-zero difference p = 1. Fails with RB_E_INVALID for a NaN,
 * RB_E_NOMEM. The same inputs give the same bits. */
#define RB_ANALYSIS_WILCOXON_EXACT_MAX 400
struct rb_analysis_wilcoxon {
    double w_plus; /* the statistic */
    double p;      /* one-sided, test > base */
    size_t count;  /* the non-zero differences */
    bool is_exact; /* counted, not approximated */
};
enum rb_status rb_analysis_wilcoxon_greater(const double *d, size_t n,
                                            struct rb_analysis_wilcoxon *out, struct rb_err *err);

/* The smallest two-sided p-value the exact test can give for samples of these sizes:
 * 2 / C(a_count + b_count, a_count), at most 1 (1 when either is empty). A verdict needs it to be
 * below alpha: 3 runs against 3 can never show a difference at alpha 0.05 (0.1), 4 against 4 can
 * (0.029). */
double rb_analysis_mwu_min_p(size_t a_count, size_t b_count);

/* The median of count values (the mean of the middle two for an even count; NaN for none),
 * sorting values in place. */
double rb_analysis_median(double *values, size_t count);

enum rb_analysis_verdict {
    RB_ANALYSIS_VERDICT_INVALID = 0,
    RB_ANALYSIS_SAME,         /* no significant change beyond the threshold */
    RB_ANALYSIS_FASTER,       /* p < alpha and the median fell by more than the threshold */
    RB_ANALYSIS_SLOWER,       /* p < alpha and the median rose by more than the threshold */
    RB_ANALYSIS_TOO_FEW_RUNS, /* rb_analysis_mwu_min_p >= alpha: no verdict is possible */
    RB_ANALYSIS_ONLY_BASE,    /* the series is in the base set alone */
    RB_ANALYSIS_ONLY_NEW,     /* in the new set alone */
};
/* "same", "faster", "slower", "too few runs", "only in base", "only in new". */
const char *rb_analysis_verdict_name(enum rb_analysis_verdict v);

/* The decision rule. alpha 0 is not a valid level and threshold 0 is (any significant slowdown
 * counts), so there is no zero default: start from RB_ANALYSIS_TIMING_DESC_INIT. */
struct rb_analysis_timing_desc {
    double alpha;         /* in (0, 1) */
    double threshold_pct; /* >= 0: a change of the medians within +-threshold_pct is "same" */
};
#define RB_ANALYSIS_TIMING_DESC_INIT                                                               \
    {                                                                                              \
        .alpha = 0.05, .threshold_pct = 5.0                                                        \
    }

/* One series compared: a pass, or the frame's wall time. */
struct rb_analysis_timing_row {
    char name[32];
    size_t base_count, new_count;         /* runs (0: the series is not in that set) */
    double base_median_ms, new_median_ms; /* NaN where the count is 0 */
    double change_pct;           /* 100 (new - base) / base; 0 when both are 0, INFINITY from 0, NaN
                                  * when a side is missing */
    struct rb_analysis_mwu test; /* zeroed (p = NaN) when a side is missing */
    enum rb_analysis_verdict verdict;
};

/* Compares one series, base values against new values (either count may be 0: the verdict is
 * then ONLY_*). The values are not changed. Fails with RB_E_INVALID for a bad desc or a NaN. */
enum rb_status rb_analysis_timing_compare(const char *name, const double *base, size_t base_count,
                                          const double *new_values, size_t new_count,
                                          const struct rb_analysis_timing_desc *desc,
                                          struct rb_analysis_timing_row *out, struct rb_err *err);

/* A bench directory loaded: bench.json and, per series, one sample a run: the mean over the
 * run's frames of the pass's time (gpu_ms, or cpu_ms for a pass that runs on the CPU; 0 in a
 * frame that did not record it), in ms per frame. The mean is the run's sum in per-frame units,
 * so a pass slower in a few frames only moves it too (a median over frames would hide that); an
 * odd frame is one rank among the runs, the unit the test treats as independent. */
struct rb_analysis_timing_series {
    char name[32];      /* the pass; RB_ANALYSIS_WALL for the frame's wall_ms */
    double *per_run_ms; /* bench.run_count values, run 1 first */
};
#define RB_ANALYSIS_WALL "frame wall"

struct rb_analysis_timing_set {
    char dir[1024];
    struct rb_io_bench bench;
    struct rb_analysis_timing_series *series; /* the passes in order of appearance, then wall */
    size_t series_count;
};

/* Loads dir/bench.json and every run's sidecars (the *.timing.json files in dir/run-01,
 * dir/run-02, ...). Each run must hold one sidecar for each frame bench.json lists, recorded on its
 * device and driver. Fails with the readers' status and a message naming the file (RB_E_IO,
 * RB_E_PARSE), RB_E_INVALID for a run that does not match bench.json, RB_E_NOMEM; *out only on
 * success. */
enum rb_status rb_analysis_timing_set_load(const char *dir, struct rb_analysis_timing_set **out,
                                           struct rb_err *err);
void rb_analysis_timing_set_destroy(struct rb_analysis_timing_set *s);

/* RB_OK when the two sets can be compared: the same device, driver, job hash and frames;
 * otherwise RB_E_INVALID and a message naming what differs and both values. */
enum rb_status rb_analysis_timing_sets_match(const struct rb_analysis_timing_set *base,
                                             const struct rb_analysis_timing_set *new_set,
                                             struct rb_err *err);

/* Compares every series of the two sets: the base set's in order, then those only in the new
 * set. *rows (count in *row_count) is freed with free(); written only on success. */
enum rb_status rb_analysis_timing_compare_sets(const struct rb_analysis_timing_set *base,
                                               const struct rb_analysis_timing_set *new_set,
                                               const struct rb_analysis_timing_desc *desc,
                                               struct rb_analysis_timing_row **rows,
                                               size_t *row_count, struct rb_err *err);

/* ---- sequences (sequence.c) ------------------------------------------------------------- */

/* A frame sequence, as raybundle render and reference write one into a directory: STEM.NNNN.exr,
 * each beside its STEM.NNNN.timing.json and, where the integrator keeps hit ratios, its
 * STEM.NNNN.hits.exr. */
struct rb_analysis_sequence {
    char dir[1024];
    char stem[256]; /* the file names before the frame number: "frame" */
    int *frames;    /* frame_count frame numbers, ascending */
    char **paths;   /* each frame's EXR, "dir/STEM.NNNN.exr" */
    size_t frame_count;
};

/* Finds the frames of seq, a directory or a pattern DIR/STEM.####.exr (one run of '#', any
 * length): in a directory, the files named STEM.DIGITS.exr (so not STEM.DIGITS.hits.exr), which
 * must all share one STEM; with a pattern, only those of its STEM, other files left alone.
 * Fails with RB_E_IO when the directory cannot be read, RB_E_INVALID for a malformed pattern,
 * no frame, frames of two stems in a directory (both named) or a frame twice (frame.1.exr and
 * frame.0001.exr), RB_E_NOMEM. Release *out with rb_analysis_sequence_release, also after a
 * failure. */
enum rb_status rb_analysis_sequence_scan(const char *seq, struct rb_analysis_sequence *out,
                                         struct rb_err *err);
void rb_analysis_sequence_release(struct rb_analysis_sequence *s);
/* The index of frame in s, or -1 when s does not have it. */
long rb_analysis_sequence_find(const struct rb_analysis_sequence *s, int frame);

/* ---- temporal stability (flicker.c) ----------------------------------------------------- */

/* Log luminance is ln(max(Y, 0) + RB_ANALYSIS_FLICKER_LOG_EPSILON) by default, Y the Rec.709
 * luminance 0.2126 R + 0.7152 G + 0.0722 B of the beauty: near-black noise stays bounded. */
#define RB_ANALYSIS_FLICKER_LOG_EPSILON 1e-3
/* The default disocclusion test: a previous pixel is the same surface when its depth is within
 * this fraction of the current pixel's depth. */
#define RB_ANALYSIS_FLICKER_DEPTH_TOLERANCE 0.05
/* A static pixel: geometry in every frame, |motion.X| and |motion.Y| at most this many pixels,
 * and depth within RB_ANALYSIS_FLICKER_STATIC_DEPTH_REL of its first frame's. */
#define RB_ANALYSIS_FLICKER_STATIC_MOTION_PX 1e-3
#define RB_ANALYSIS_FLICKER_STATIC_DEPTH_REL 1e-4

struct rb_analysis_flicker_desc {
    const char *seq;        /* SEQ: a directory or a pattern (rb_analysis_sequence_scan) */
    const char *reference;  /* REFSEQ, the same job's reference sequence; NULL: none */
    double log_epsilon;     /* 0: RB_ANALYSIS_FLICKER_LOG_EPSILON; never negative */
    double depth_tolerance; /* relative; 0: RB_ANALYSIS_FLICKER_DEPTH_TOLERANCE; never negative */
};

/* A copy of in with the defaults filled in. */
struct rb_analysis_flicker_desc
rb_analysis_flicker_desc_resolve(const struct rb_analysis_flicker_desc *in);

/* One frame of one sequence. Pixels without geometry (depth 0: no motion vector) or with a value
 * that is not finite are in none of the counts. */
struct rb_analysis_flicker_stats {
    /* The warped temporal error: the mean over the compared pixels p of
     * |l_t(p) - l_{t-1}(p + motion_t(p))|, l the log luminance, l_{t-1} sampled bilinearly;
     * NaN for a frame whose frame - 1 is not in the sequence, or when no pixel was compared. */
    double warped_error;
    uint64_t compared_count;    /* pixels in warped_error */
    uint64_t disoccluded_count; /* left out: the depth sampled there is another surface's (or a
                                 * pixel the sample reads has no geometry) */
    uint64_t offscreen_count;   /* left out: p + motion_t(p) is off the image */
    /* The mean over the sequence's static pixels of (l_t(p) - mean over frames of l(p))^2;
     * NaN when no pixel is static. */
    double static_deviation;
};

struct rb_analysis_flicker_frame {
    int frame;                            /* the sequence's own number */
    struct rb_analysis_flicker_stats seq; /* the sequence */
    struct rb_analysis_flicker_stats ref; /* the reference's same frame (NaN and 0 without) */
    /* The excess temporal error: the mean over pixels of |(I_t - I_{t-1}) - (R_t - R_{t-1})|
     * on luminance, I the sequence and R the reference; NaN without a reference or frame - 1.
     * It counts the reference's own noise. */
    double excess_error;
    /* Its root mean square, less the reference's noise when the reference has a variance layer
     * (rb_analysis_flicker_excess); NaN where excess_error is. */
    double excess_rms;
    double excess_sq_sum, excess_noise_sum; /* rb_analysis_flicker_excess's, for the summary */
    uint64_t excess_count;                  /* the pixels in them */
};

/* A whole sequence: means over the frames that have a value (NaN where none has). */
struct rb_analysis_flicker_summary {
    double warped_error, warped_error_max;
    uint64_t static_count; /* pixels static over the whole sequence */
    /* The mean over the static pixels of the (population) variance of their log luminance over
     * the frames: the mean of the frames' static_deviation. NaN when no pixel is static. */
    double static_variance;
};

struct rb_analysis_flicker {
    struct rb_analysis_sequence seq, ref; /* ref.frame_count is 0 without a reference */
    struct rb_analysis_flicker_desc desc; /* resolved; its paths are borrowed from the caller's */
    uint32_t width_px, height_px;
    struct rb_analysis_flicker_frame *frames; /* seq.frame_count */
    struct rb_analysis_flicker_summary summary, reference_summary;
    double excess_error, excess_error_max; /* over frames; NaN without a reference */
    /* The excess RMS over every frame's pixels: rb_analysis_flicker_excess_rms of the frames'
     * sums (pooled before the root, not a mean of the frames'); NaN without a reference. */
    double excess_rms;
    bool has_reference;
    /* The reference's frames have a variance layer, and excess_rms leaves its noise out. */
    bool is_noise_corrected;
};

/* Measures the temporal stability of desc->seq from its EXRs' beauty (R, G, B), motion
 * (motion.X/Y: the previous position minus this one, in pixels) and depth (depth.Z) layers,
 * and of the reference's same frames, which must all exist. Every frame is read twice (the
 * static pixels are known only at the end); sums run in double in pixel and frame order, so
 * the same files give the same bits. Fails with the readers' statuses and a message naming the
 * file, RB_E_INVALID for a bad desc, a missing layer or frame, or frames of another size,
 * RB_E_NOMEM; *out only on success. desc's strings must outlive *out. */
enum rb_status rb_analysis_flicker_create(const struct rb_analysis_flicker_desc *desc,
                                          struct rb_analysis_flicker **out, struct rb_err *err);
/* Frees f and what it owns; NULL is fine. */
void rb_analysis_flicker_destroy(struct rb_analysis_flicker *f);

/* The excess temporal error of one frame over n pixels: e = (cur - prev) - (ref - ref_prev) on
 * luminance, over the pixels where e is finite (count of them). error is the mean of |e|;
 * sum_sq the sum of e^2. With the variances of the reference's pixel means in its two frames
 * (ref_var and ref_prev_var, the reference's variance layer; both NULL without it), sum_noise
 * is the sum of ref_var + ref_prev_var over the same pixels: the two frames are independent
 * estimates, so E[e^2] = a^2 + var R_t + var R_{t-1}, a the excess of the sequence over the
 * truth, and sum_sq - sum_noise estimates the sum of a^2 without bias. rms is
 * rb_analysis_flicker_excess_rms of the sums. error and rms are NaN when no e is finite. Pure. */
struct rb_analysis_flicker_excess {
    double error, rms;
    double sum_sq, sum_noise; /* sum_noise is 0 without the variances */
    uint64_t count;
};
struct rb_analysis_flicker_excess rb_analysis_flicker_excess(const double *cur, const double *prev,
                                                             const double *ref,
                                                             const double *ref_prev,
                                                             const float *ref_var,
                                                             const float *ref_prev_var, size_t n);
/* sqrt(max(sum_sq - sum_noise, 0) / count): the root mean square excess less the reference's
 * noise (0 when the noise explains it all); NaN for count 0. */
double rb_analysis_flicker_excess_rms(double sum_sq, double sum_noise, uint64_t count);

/* A gate for CI without a reference: does seq flicker more than base, the same job rendered
 * before a change? The frames both have a warped temporal error for are paired by number;
 * the one-sided Wilcoxon signed-rank test of seq's errors against base's, both ways, decides
 * with the effect, the ratio of their means: MORE when seq's are higher with p < alpha and
 * their mean exceeds base's by more than min_effect (a fraction), LESS the other way, SAME
 * otherwise. Fewer than RB_ANALYSIS_FLICKER_GATE_MIN_PAIRS pairs cannot decide: RB_E_INVALID,
 * as are sequences of different sizes. */
#define RB_ANALYSIS_FLICKER_GATE_MIN_PAIRS 6
enum rb_analysis_flicker_verdict {
    RB_ANALYSIS_FLICKER_SAME = 0,
    RB_ANALYSIS_FLICKER_MORE,
    RB_ANALYSIS_FLICKER_LESS,
};
struct rb_analysis_flicker_gate {
    size_t pair_count;
    double mean, base_mean; /* of the warped temporal error over the paired frames */
    double effect;          /* mean / base_mean - 1; 0 when both are 0, inf when only base's is */
    struct rb_analysis_wilcoxon more, less; /* seq > base, and base > seq */
    enum rb_analysis_flicker_verdict verdict;
};
enum rb_status rb_analysis_flicker_gate(const struct rb_analysis_flicker *seq,
                                        const struct rb_analysis_flicker *base, double alpha,
                                        double min_effect, struct rb_analysis_flicker_gate *out,
                                        struct rb_err *err);

/* ---- report (report.c) ------------------------------------------------------------------ */

/* The report page's fixed layout, in CSS pixels (raybundle-report(1)): the header, then one
 * section a chart, each a title and an SVG whose plot area is at (PLOT_X, PLOT_Y) inside it;
 * the filmstrip follows the charts. Fixed, so a test can find a bar on a screenshot. */
#define RB_ANALYSIS_REPORT_WIDTH 960
#define RB_ANALYSIS_REPORT_HEADER_H 160
#define RB_ANALYSIS_REPORT_CHART_H 250
#define RB_ANALYSIS_REPORT_TITLE_H 30
#define RB_ANALYSIS_REPORT_PLOT_X 72
#define RB_ANALYSIS_REPORT_PLOT_Y 12
#define RB_ANALYSIS_REPORT_PLOT_W 640
#define RB_ANALYSIS_REPORT_PLOT_H 176
#define RB_ANALYSIS_REPORT_THUMB_WIDTH 240 /* the default thumbnail width */
#define RB_ANALYSIS_REPORT_FILMSTRIP 24    /* the default most frames in the filmstrip */

/* A value axis from 0 to max, with a label every step. */
struct rb_analysis_axis {
    double max, step;
};

/* The axis for values up to data_max: step is 1, 2 or 5 times a power of ten, the smallest
 * such that at most 5 steps reach data_max, and max the first multiple of step at or above it
 * (to a relative 1e-9, so that rounding does not add a step).
 * data_max not above 0 (or not finite) gives {1, 0.2}. */
struct rb_analysis_axis rb_analysis_axis_fit(double data_max);

/* A plot area: slot_count frames side by side along x, values up to axis.max along y. */
struct rb_analysis_plot {
    double x_px, y_px, width_px, height_px;
    size_t slot_count;
    struct rb_analysis_axis axis;
};

/* The centre of slot i along x: x_px + (i + 1/2) width_px / slot_count. */
double rb_analysis_plot_x(const struct rb_analysis_plot *p, size_t i);
/* The y of value v: y_px + height_px at 0, y_px at axis.max (not clamped). */
double rb_analysis_plot_y(const struct rb_analysis_plot *p, double v);
/* The width of a bar: 70% of a slot, at least one pixel. */
double rb_analysis_plot_bar_width(const struct rb_analysis_plot *p);

/* The frames a filmstrip of at most max_count (at least 2) shows out of frame_count: all of
 * them when there are no more than max_count, otherwise max_count evenly spaced, the first and
 * the last among them: index k is the nearest to k (frame_count - 1) / (max_count - 1), halves
 * rounded up, in integers. Writes the indices, ascending, to out (room for max_count) and
 * returns how many. */
size_t rb_analysis_filmstrip_pick(size_t frame_count, size_t max_count, size_t *out);

/* One frame of the report. Values not measured are NaN. */
struct rb_analysis_report_frame {
    int frame;
    double wall_ms;       /* the sidecar's wall_ms */
    double *pass_ms;      /* pass_count values: gpu_ms + cpu_ms; 0 where the frame lacks it */
    double pass_total_ms; /* their sum */
    double temporal_rmse; /* beauty RMSE against frame - 1 (NaN for a first frame, or a gap) */
    double reference_temporal_rmse; /* the same in the reference */
    double relmse;                  /* the beauty's relMSE against the reference's same frame */
    double flip;      /* the mean of the beauty's HDR-FLIP against it (rb_analysis_flip_hdr) */
    double hit_ratio; /* the mean of the hit-ratio image's first channel */
    double warped_error, reference_warped_error, excess_error; /* rb_analysis_flicker's */
    char *thumb, *reference_thumb, *hits_thumb; /* data: URIs; NULL when there is none */
    char *flip_thumb;     /* the FLIP map in FLIP's colour map (rb_analysis_flip_color), likewise */
    bool is_in_filmstrip; /* shown in the filmstrip (the thumbnails are made for these only) */
};

struct rb_analysis_report_desc {
    const char *dir;                      /* the sequence, SEQ */
    const char *reference_dir;            /* REFSEQ, or NULL */
    const struct rb_io_color_desc *color; /* the thumbnails' view transform; NULL: defaults */
    uint32_t thumb_width_px;              /* 0: RB_ANALYSIS_REPORT_THUMB_WIDTH */
    /* the most frames the filmstrip shows (rb_analysis_filmstrip_pick), at least 2;
     * 0: RB_ANALYSIS_REPORT_FILMSTRIP; SIZE_MAX: every frame */
    size_t filmstrip_max;
};

struct rb_analysis_report {
    struct rb_analysis_sequence seq, ref; /* ref.frame_count is 0 without a reference */
    char device[256], driver[256];        /* from the first frame's sidecar */
    char integrator[64], reference_integrator[64], reference_spp[32]; /* EXR headers; "" */
    uint32_t width_px, height_px;
    uint32_t thumb_width_px; /* the thumbnails' width on the page */
    size_t filmstrip_count;  /* the frames with is_in_filmstrip */
    char (*pass_names)[32];  /* pass_count passes, in order of first appearance */
    size_t pass_count;
    struct rb_analysis_report_frame *frames; /* seq.frame_count */
    bool has_reference, has_hits;
    char flicker_note[512]; /* why the flicker metrics are missing ("" when they are there) */
    char flip_note[512];    /* why FLIP is missing from a frame with a reference (the first) */
};

/* Reads every frame of desc->dir (its EXR's beauty, its timing sidecar, its hit-ratio image
 * when the sequence has them) and of the reference, and computes the report's series and
 * thumbnails (with a reference, each frame's relMSE and HDR-FLIP against it, as raybundle
 * compare computes them, and its FLIP map; where HDR-FLIP cannot be computed, such as a
 * reference too dark to choose exposures from, the frame's is NaN and flip_note says why); the
 * warped and excess temporal errors come from rb_analysis_flicker_create, and where it cannot
 * compute them (a sequence without motion or depth layers) its message goes in flicker_note instead
 * of failing the report. Every frame of the sequence needs a sidecar and, with a reference, the
 * same frame of the same size there; hit-ratio images are in every frame or in none. Fails with the
 * readers' statuses and a message naming the file, RB_E_INVALID for frames that do not match,
 * RB_E_NOMEM; *out only on success. */
enum rb_status rb_analysis_report_create(const struct rb_analysis_report_desc *desc,
                                         struct rb_analysis_report **out, struct rb_err *err);
void rb_analysis_report_destroy(struct rb_analysis_report *r);

/* Writes the report as one self-contained HTML page (inline CSS and SVG, thumbnails as data:
 * URIs, no script, nothing fetched) to path, atomically. */
enum rb_status rb_analysis_report_write(const struct rb_analysis_report *r, const char *path,
                                        struct rb_err *err);

#endif
