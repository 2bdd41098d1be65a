/* Files in and out: multi-layer OpenEXR frames with metadata (OpenImageIO), images read as
 * float RGBA (environment maps, tests, compare), display previews (OpenColorIO), the timing
 * sidecar, frame-path patterns, and atomic writes (temporary name, then rename). */
#ifndef RB_IO_IO_H
#define RB_IO_IO_H

#include "core/core.h"

/* ---- paths ------------------------------------------------------------------------------ */

/* Replaces the last run of '#' in pattern with frame, zero-padded to the run's length (more
 * digits when needed). A pattern with no '#' gets ".####" inserted before its extension. */
enum rb_status rb_io_frame_path(const char *pattern, int frame, char *out, size_t size,
                                struct rb_err *err);

/* The sidecar beside an EXR: "a/shot.0012.exr" + ".timing.json" -> "a/shot.0012.timing.json". */
enum rb_status rb_io_sidecar_path(const char *exr_path, const char *suffix, char *out, size_t size,
                                  struct rb_err *err);

/* Creates every missing directory leading to path's file (like mkdir -p of its dirname). */
enum rb_status rb_io_make_parent_dirs(const char *path, struct rb_err *err);

/* Creates the directories leading to path's file and checks that a file can be created there
 * (a probe, removed at once), so a run fails before rendering rather than at its first write.
 * RB_E_IO names the directory and the cause. */
enum rb_status rb_io_check_writable(const char *path, struct rb_err *err);

/* Bytes free to an unprivileged writer on the file system of path's directory; UINT64_MAX when
 * it cannot be told. */
uint64_t rb_io_free_bytes(const char *path);

/* Writes data to path + ".tmp.<pid>", fsyncs, and renames it over path. */
enum rb_status rb_io_write_atomic(const char *path, const void *data, size_t size,
                                  struct rb_err *err);

/* Removes the temporary files a killed writer of path (or of its sidecars) left behind:
 * "<stem>.*.tmp.*" beside it, stem being path without its extension. Returns how many. For
 * --resume, which renders the frame again; only for a frame this process holds through
 * rb_io_output_lock_claim, so that no other writer of the frame can be running. */
unsigned rb_io_remove_stale_temps(const char *path);

/* One writer per frame of an output. The lock file is ".<pattern's file name>.lock" in the
 * pattern's directory (the part before any '#'), created there (with its directories) when
 * missing; each frame a run claims is a POSIX record lock on one byte of it (at the frame's
 * number plus 2^31). Renders of different frames of one output, such as a farm's chunks, share
 * the folder; a second render of a frame another process holds fails at once. The kernel drops
 * the locks when the process ends, however it ends, so a lock left behind cannot be stale, and
 * the file itself is left in place. The directory's identity is kept, to tell when it is removed
 * (or replaced) during the run. */
struct rb_io_output_lock;
/* Opens the lock file of pattern; *out only on success. RB_E_IO names the directory. */
enum rb_status rb_io_output_lock_create(const char *pattern, struct rb_io_output_lock **out,
                                        struct rb_err *err);
/* Releases every claim and closes the file; accepts NULL. */
void rb_io_output_lock_destroy(struct rb_io_output_lock *lock);
/* Claims frame for this process without waiting. RB_E_INVALID when another process holds it:
 * "frame F of 'pattern' is being rendered by another raybundle (pid N)". */
enum rb_status rb_io_output_lock_claim(struct rb_io_output_lock *lock, int frame,
                                       struct rb_err *err);
/* RB_E_IO when the output directory was removed or replaced since the lock was created. */
enum rb_status rb_io_output_lock_check(const struct rb_io_output_lock *lock, struct rb_err *err);

/* ---- EXR -------------------------------------------------------------------------------- */

/* A group of channels. name NULL or "" is the beauty (channels R,G,B,A); otherwise channels are
 * written as "<name>.<channel>". pixels are interleaved, width*height*channel_count floats,
 * rows top to bottom. */
struct rb_io_layer {
    const char *name;
    uint32_t channel_count;           /* 1..4 */
    const char *const *channel_names; /* e.g. {"X","Y","Z"} */
    const float *pixels;
    bool is_half; /* store as half instead of float */
};

/* One string, int, float or matrix attribute of the EXR header. */
enum rb_io_attr_type { RB_IO_ATTR_STRING = 1, RB_IO_ATTR_INT, RB_IO_ATTR_FLOAT, RB_IO_ATTR_M44 };
struct rb_io_attr {
    const char *name; /* e.g. "raybundle/integrator", "worldToCamera" */
    enum rb_io_attr_type type;
    const char *s;
    int i;
    float f;
    float m[16]; /* row-major, as OpenEXR's M44f */
};

/* Writes a multi-layer EXR (ZIP, lossless) atomically, with the given attributes plus the
 * Rec.709 chromaticities; nothing time-dependent goes in, so equal pixels give equal bytes. */
enum rb_status rb_io_exr_write(const char *path, uint32_t width_px, uint32_t height_px,
                               const struct rb_io_layer *layers, size_t layer_count,
                               const struct rb_io_attr *attrs, size_t attr_count,
                               struct rb_err *err);

/* True when path exists and reads back completely as an image (used by --resume). */
bool rb_io_image_is_complete(const char *path);

/* An image in memory: float channels, interleaved. */
struct rb_io_image {
    uint32_t width_px, height_px, channel_count;
    char **channel_names; /* channel_count names as stored in the file */
    float *pixels;
};

/* Reads every channel of an image file (EXR, HDR, PNG, ...) as float. Free with
 * rb_io_image_release. */
enum rb_status rb_io_image_read(const char *path, struct rb_io_image *out, struct rb_err *err);
void rb_io_image_release(struct rb_io_image *img);
/* Index of the named channel ("R", "direct.R"), or -1. */
int rb_io_image_channel(const struct rb_io_image *img, const char *name);
/* Reads a string attribute of the file's header into out; false when absent. */
bool rb_io_image_attr(const char *path, const char *name, char *out, size_t size);

/* Every attribute of an image file's header, as text. */
struct rb_io_image_attrs {
    size_t count;
    char **names;  /* count names, owned, in the header's order (OpenEXR's: by name) */
    char **values; /* count values, owned, formatted as rb_io_image_attr formats them; one of a
                    * type that is not formatted is its type name in parentheses: "(chlist)" */
};

/* Reads every attribute of the header of the image at path (OpenEXR's required ones too) into
 * *out, which is released with rb_io_image_attrs_release, also after a failure. An EXR lists
 * its whole header; other formats list nothing. Fails with RB_E_IO when path cannot be
 * opened, RB_E_EXTERNAL when OpenEXR cannot read its header, RB_E_NOMEM; each message names
 * path. */
enum rb_status rb_io_image_attrs_read(const char *path, struct rb_io_image_attrs *out,
                                      struct rb_err *err);
void rb_io_image_attrs_release(struct rb_io_image_attrs *a);

/* One layer of an image: the channels whose names share the part before their last '.'; the
 * channels without a '.' are the beauty's. */
struct rb_io_image_layer {
    char *name;             /* owned; "beauty" for the channels without a '.' */
    uint32_t channel_count; /* >= 1 */
    uint32_t *channels;     /* owned; indices into the image's channels, in its reading order */
};
struct rb_io_image_layers {
    size_t count;
    struct rb_io_image_layer *layers;
};

/* Groups img's channels into its layers (borrowing nothing from img): the beauty first, then
 * the layers raybundle writes in the order of enum rb_layer (direct, indirect, albedo, normal,
 * depth, motion, ...), then any other in the order of img's channels. Released with
 * rb_io_image_layers_release, also after a failure, which is RB_E_NOMEM only. */
enum rb_status rb_io_image_layers_init(struct rb_io_image_layers *out,
                                       const struct rb_io_image *img, struct rb_err *err);
void rb_io_image_layers_release(struct rb_io_image_layers *l);

/* A channel's name within its layer, the part after its last '.': "X" for "normal.X", "R" for
 * "R". Points into name. */
const char *rb_io_channel_base(const char *name);

/* ---- color ------------------------------------------------------------------------------ */

struct rb_io_color_desc {
    const char *config;  /* path; NULL: $OCIO, then RB_DATADIR/ocio/config.ocio */
    const char *display; /* NULL: the config's default display */
    const char *view;    /* NULL: the display's default view */
};

/* Converts scene-linear Rec.709 RGBA (width*height*4 floats) through the config's view
 * transform and writes an 8-bit sRGB PNG atomically. */
/* Checks before any frame that desc's config loads, has its display and view, and that their
 * transform builds and applies (the files it names found): RB_E_INVALID for a name it lacks,
 * listing the config's names and the nearest one ("did you mean"), RB_E_IO or RB_E_EXTERNAL for
 * a config that does not load or a transform that does not build. */
enum rb_status rb_io_color_check(const struct rb_io_color_desc *desc, struct rb_err *err);
enum rb_status rb_io_preview_write(const char *path, uint32_t width_px, uint32_t height_px,
                                   const float *rgba, const struct rb_io_color_desc *desc,
                                   struct rb_err *err);

/* Writes width*height 8-bit RGBA pixels (rows top to bottom, unassociated alpha), display values
 * taken as they are (no view transform), as a PNG to path, atomically. RB_E_INVALID for an empty
 * image, RB_E_EXTERNAL when libpng fails, rb_io_write_atomic's statuses; each names path. */
enum rb_status rb_io_png_write(const char *path, uint32_t width_px, uint32_t height_px,
                               const uint8_t *rgba, struct rb_err *err);

/* A thumbnail for an HTML page: a PNG inline, as a data: URI. */
struct rb_io_thumbnail_desc {
    uint32_t width_px, height_px;         /* the thumbnail's size, at most the image's; 0: its */
    const struct rb_io_color_desc *color; /* the view transform; NULL: as rb_io_preview_write's */
    bool is_data; /* values are data (a hit ratio): shown as they are, no view transform */
};

/* Resizes premultiplied scene-linear RGBA (width*height*4 floats) with OpenImageIO's filtered
 * resize, converts it as rb_io_preview_write does (or, for data, quantizes [0, 1] to 8 bits),
 * encodes an 8-bit PNG in memory and returns "data:image/png;base64,..." in *out (freed with
 * free()), only on success. Fails with RB_E_INVALID for a bad size, RB_E_EXTERNAL from the
 * libraries, RB_E_IO for an unreadable config, RB_E_NOMEM. */
enum rb_status rb_io_thumbnail_data_uri(uint32_t width_px, uint32_t height_px, const float *rgba,
                                        const struct rb_io_thumbnail_desc *desc, char **out,
                                        struct rb_err *err);

/* The versions of the image and colour libraries, e.g. "OpenImageIO 2.4.7, OpenColorIO 2.1.2"
 * (for `raybundle info` and bug reports). */
const char *rb_io_library_versions(void);

/* The bundled OCIO config (installed with the binary; the source tree's when run from it). */
const char *rb_io_default_ocio_config(void);

/* ---- timing sidecar ------------------------------------------------------------------- */

/* A hit-ratio image summed up, as the timing sidecar's "hits" object records it. */
struct rb_io_hits {
    double mean;         /* the sum in double, in pixel order, over the count */
    double p5, p50, p95; /* nearest rank: the k-th smallest value, k = ceil(p * count / 100) */
};

/* Sums up count values (a hit-ratio image, rows top to bottom): the mean and the nearest-rank
 * percentiles of the finite ones (values that are not finite are left out, as raybundle report
 * leaves them out). The percentile p of N values is the k-th smallest, k = ceil(p * N / 100)
 * counted from 1 and computed in integers, on a sorted copy: each is one of the values, and
 * equal values give equal bits. With no finite value all four are NaN (null in the sidecar).
 * RB_E_NOMEM for the copy; *out only on success. */
enum rb_status rb_io_hits_summarize(const float *values, size_t count, struct rb_io_hits *out,
                                    struct rb_err *err);

struct rb_io_timing {
    int frame;
    double time_s;
    const struct rb_pass_time *passes; /* one entry a pass name (core.h), count its recordings */
    size_t pass_count;
    double wall_ms;
    const char *device;
    const char *driver;
    const char *job_hash; /* 16 hex digits, as the EXR's raybundle:jobHash; NULL: not written */
    const char *integrator;
    uint32_t width_px, height_px;
    uint32_t spp;       /* samples per pixel reached (the reference); written when > 0 */
    uint64_t ray_count; /* rays traced (the reference); written when > 0 */
    /* NaN or infinite values in the frame's layers; always written */
    uint32_t nonfinite_count;
    /* bdpt's ray-bundle node buffer, written when capacity > 0: the most nodes one bundle
     * asked for, the capacity, the fragments dropped (overflow: dropped > 0) */
    uint32_t bundle_nodes_max, bundle_nodes_capacity, bundle_nodes_dropped;
    const struct rb_io_hits *hits;          /* the hit-ratio image's summary; NULL: none written */
    const struct rb_ray_counts *ray_counts; /* the hybrid integrator's rays; NULL: none */
};

/* Writes NAME.####.timing.json atomically:
 * {"frame": 12, "time_s": 0.5, "passes": [{"name": "gbuffer", "gpu_ms": 1.25, "count": 1}, ...],
 * (cpu_ms too where it is > 0)
 *  "wall_ms": 40.1, "device": "...", "driver": "...", "job_hash": "0123456789abcdef" (when
 *  given), ..., "nonfinite": 0}, and for bdpt
 *  "bundle_nodes": {"max": 5120, "capacity": 1048576, "dropped": 0, "overflow": false}, and
 *  with hits "hits": {"mean": 0.97, "p5": 0.75, "p50": 1, "p95": 1}, and with ray counts
 *  "ray_counts": {"requested": 1000, "screen_hits": 700, "queued": 290, "bvh_hits": 250,
 *  "misses": 40, "dropped": 0}. */
enum rb_status rb_io_timing_write(const char *path, const struct rb_io_timing *t,
                                  struct rb_err *err);

/* ---- reading timing sidecars, and bench sets (timing.c) --------------------------------- */

/* A timing sidecar read back: the fields raybundle timing compare needs. */
struct rb_io_timing_file {
    int frame;
    struct rb_pass_time *passes; /* pass_count entries, owned; gpu_ms, cpu_ms and count */
    size_t pass_count;
    double wall_ms;
    char device[256], driver[256];
    char job_hash[17];      /* "job_hash" ("" in a sidecar without one) */
    bool has_hits;          /* the sidecar has a "hits" object */
    struct rb_io_hits hits; /* its numbers (NaN for null) when it has */
};

/* Reads a sidecar as rb_io_timing_write writes it into *out (released with
 * rb_io_timing_file_release, also after a failure). RB_E_IO when it cannot be opened,
 * RB_E_PARSE for bad JSON ("path:line:col: ...") or a missing or mistyped field (named by its
 * JSON path, e.g. 'passes[2].gpu_ms'). */
enum rb_status rb_io_timing_read(const char *path, struct rb_io_timing_file *out,
                                 struct rb_err *err);
/* Parses a sidecar's text (size bytes, not necessarily NUL-terminated) as rb_io_timing_read
 * does; name stands for the file in messages. */
enum rb_status rb_io_timing_parse(const char *name, const char *text, size_t size,
                                  struct rb_io_timing_file *out, struct rb_err *err);
void rb_io_timing_file_release(struct rb_io_timing_file *t);

/* bench.json, what raybundle bench records beside its runs' sidecars (run-01/, run-02/, ...). */
struct rb_io_bench {
    char device[256], driver[256]; /* as in the sidecars */
    char build[128];               /* "raybundle 0.1.0 (git describe)" */
    char job[1024];                /* the job file as given */
    char job_hash[17];             /* 16 hex digits, as the EXR's raybundle:jobHash */
    char integrator[32];
    uint32_t width_px, height_px;
    uint32_t run_count;
    char order[32]; /* how runs were interleaved: "run-by-run" */
    int *frames;    /* the frames each run rendered, in order; owned */
    size_t frame_count;
    char **options; /* the command line after 'bench', as given; owned */
    size_t option_count;
};

/* Writes bench.json atomically (2-space indented JSON). */
enum rb_status rb_io_bench_write(const char *path, const struct rb_io_bench *b, struct rb_err *err);
/* Reads bench.json into *out (released with rb_io_bench_release, also after a failure); fails
 * as rb_io_timing_read does. */
enum rb_status rb_io_bench_read(const char *path, struct rb_io_bench *out, struct rb_err *err);
/* Parses bench.json's text as rb_io_bench_read does; name stands for the file in messages. */
enum rb_status rb_io_bench_parse(const char *name, const char *text, size_t size,
                                 struct rb_io_bench *out, struct rb_err *err);
void rb_io_bench_release(struct rb_io_bench *b);

#endif
