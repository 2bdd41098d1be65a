/* Core services every module uses: status codes and error messages, logging, small math,
 * hashing and quasi-Monte Carlo points. Depends on nothing but libc. */
#ifndef RB_CORE_CORE_H
#define RB_CORE_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#define RB_NORETURN [[noreturn]]
#else
#define RB_NORETURN _Noreturn
#endif

#define RB_VERSION "0.1.0"

/* ---- errors ------------------------------------------------------------------------------ */

enum rb_status {
    RB_OK = 0,
    RB_E_INVALID, /* bad argument or bad input data */
    RB_E_NOMEM,
    RB_E_IO,
    RB_E_PARSE, /* a job file or scene that does not parse */
    RB_E_VULKAN,
    RB_E_NODEVICE,    /* no usable Vulkan device */
    RB_E_UNSUPPORTED, /* valid input using something raybundle does not implement */
    RB_E_EXTERNAL,    /* an error reported by a C++ library through a shim */
    RB_E_INTERRUPTED, /* the user asked us to stop */
    RB_E_OVERFLOW,    /* a fixed-size buffer was too small; never silently truncated */
};

/* The message of the innermost failure, with context prepended by callers. */
struct rb_err {
    enum rb_status status;
    char msg[512];
};

#define RB_ERR_INIT                                                                                \
    {                                                                                              \
        RB_OK,                                                                                     \
        {                                                                                          \
            0                                                                                      \
        }                                                                                          \
    }

/* Stores a formatted message in err (which may be NULL) and returns code. */
enum rb_status rb_errf(struct rb_err *err, enum rb_status code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Prepends "<context>: " to err's message. */
void rb_err_prefix(struct rb_err *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A short name for a status ("io error", ...). */
const char *rb_status_name(enum rb_status st);

/* Always-on check for states that mean raybundle's own code is wrong. */
#define RB_BUG(...) rb_bug(__FILE__, __LINE__, __VA_ARGS__)
RB_NORETURN void rb_bug(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* ---- logging ----------------------------------------------------------------------------- */

enum rb_log_level { RB_LOG_ERROR = 0, RB_LOG_WARN, RB_LOG_INFO, RB_LOG_DEBUG };

typedef void (*rb_log_fn)(enum rb_log_level level, const char *msg, void *user);

/* Replaces the log sink (NULL restores the default, which writes to stderr). Not thread-safe:
 * set it before starting work. */
void rb_log_set_sink(rb_log_fn fn, void *user);
void rb_log_set_level(enum rb_log_level max_level);
enum rb_log_level rb_log_get_level(void);
void rb_log(enum rb_log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Number of warnings logged so far (for tests and exit summaries). */
unsigned rb_log_warning_count(void);

/* ---- memory and strings ------------------------------------------------------------------- */

/* Duplicates s (NULL gives NULL). */
char *rb_strdup(const char *s);
/* Copies at most size-1 bytes and always terminates. Returns strlen(src). */
size_t rb_strlcpy(char *dst, const char *src, size_t size);
/* Seconds on the monotonic clock, for measuring durations (thread-safe). */
double rb_monotonic_s(void);
/* Input files larger than this are refused before a byte is read: no job, scene, buffer,
 * texture or environment map comes near it, and a bound keeps a hostile file from growing the
 * process until the kernel steps in. glTF itself cannot address more (tinygltf: 32-bit sizes). */
#define RB_FILE_MAX_BYTES (4ull << 30)

/* Whether path is a regular file (symlinks followed); RB_E_IO naming path and what it is ("a
 * FIFO", "a directory", "a character device") when not. Readers check before they open, so a
 * FIFO never blocks an open and a device or directory is never read as if it were data. */
enum rb_status rb_file_check_regular(const char *path, struct rb_err *err);
/* Opens path read-only (O_NONBLOCK, so that a FIFO swapped in after a check cannot block) and
 * checks the opened file itself: regular, and at most max_bytes long. *fd and *size_bytes only
 * on success; the caller closes *fd. */
enum rb_status rb_file_open_regular(const char *path, uint64_t max_bytes, int *fd,
                                    uint64_t *size_bytes, struct rb_err *err);
/* Reads a whole regular file (rb_file_open_regular, RB_FILE_MAX_BYTES) into a new
 * NUL-terminated buffer; never more than the size fstat reported when it was opened. */
enum rb_status rb_read_file(const char *path, char **out, size_t *out_size, struct rb_err *err);

/* ---- suggestions (suggest.c) ---------------------------------------------------------------- */

/* The number of edits (insert, delete or change a character, or swap two neighbours) that turn
 * a[0..la) into b[0..lb), ignoring ASCII case; SIZE_MAX when either is longer than 64. */
size_t rb_edit_distance(const char *a, size_t la, const char *b, size_t lb);

/* The candidate nearest to a mistyped word, for "did you mean 'x'?": init with the word, offer
 * every candidate, then read best. A candidate is close enough within two edits that are at
 * most a third of the longer length; the first of equally near ones wins, and a candidate that
 * equals the word but for case is nearest of all. Caller storage; word is borrowed. */
struct rb_suggest {
    const char *word;
    size_t distance; /* best's edits; SIZE_MAX while none is close enough */
    char best[48];   /* "" while none is close enough; longer names are not offered */
};
void rb_suggest_init(struct rb_suggest *s, const char *word);
/* Offers the candidate name[0..len) (not NUL-terminated there). */
void rb_suggest_offer(struct rb_suggest *s, const char *name, size_t len);

/* ---- hashing ----------------------------------------------------------------------------- */

/* FNV-1a, 64 bits; chain by passing the previous value as seed (start with RB_HASH_SEED). */
#define RB_HASH_SEED 0xcbf29ce484222325ull
uint64_t rb_hash64(const void *data, size_t size, uint64_t seed);
/* XXH3 (libxxhash), 64 bits, for large data (scene buffers, textures, environment maps): many
 * GB/s where FNV-1a does one byte at a time. Chain by passing the previous value as seed. */
uint64_t rb_hash_bulk(const void *data, size_t size, uint64_t seed);

/* SplitMix64's finalizer: a bijection of 64 bits with full avalanche, for counter-based random
 * numbers (hash a counter, or chain a key through it). */
uint64_t rb_mix64(uint64_t z);

/* ---- quasi-Monte Carlo (qmc.c) ------------------------------------------------------------- */

/* Points as 32-bit fixed-point fractions in [0, 1). All are pure functions: thread-safe and
 * independent of the order of the calls. */

/* Point index of the Sobol sequence in dimension dim, 0 or 1 (0 is van der Corput's radical
 * inverse); the two together are a (0,2)-sequence in base 2. Other dims are a bug. */
uint32_t rb_qmc_sobol(uint32_t index, uint32_t dim);

/* A nested uniform (Owen) scramble of the fraction x keyed by seed (Burley 2020's hash-based
 * form): a bijection under which two fractions that share their first k bits still share
 * their first k (so it maps elementary intervals onto elementary intervals). Applied to a
 * sample index, it maps every aligned block of 2^k indices onto an aligned block of 2^k. */
uint32_t rb_qmc_owen(uint32_t x, uint32_t seed);

/* Point index of the 2D stream numbered stream: the Sobol (0,2)-sequence with its index
 * shuffled and each dimension Owen-scrambled, all by seeds hashed from stream. Any aligned
 * block of 2^k indices (the first 2^k, say) has exactly one point in each elementary interval
 * of area 2^-k; over streams, every point is uniform on the unit square. Different streams are
 * independent, which is how a renderer pads 2D pairs into more dimensions. */
void rb_qmc_point2(uint64_t stream, uint32_t index, uint32_t out[2]);

/* A fraction as a float in [0, 1) (its 24 leading bits, exactly). */
float rb_qmc_float(uint32_t x);

/* ---- frame results ------------------------------------------------------------------------- */

/* One pass of a frame, as the timing sidecar reports it: a pass recorded many times in a frame
 * (a VPL map per VPL) is one entry, its times summed and its recordings counted. */
struct rb_pass_time {
    char name[32];
    double gpu_ms; /* summed over its recordings; 0 for a CPU pass */
    double cpu_ms; /* passes that run on the CPU (the reference's trace); 0 otherwise */
    uint32_t count;
};

/* ---- math ---------------------------------------------------------------------------------- */

#define RB_PI 3.14159265358979323846f

/* The most radiance (a colour times its intensity or strength) a light, an emitter or the
 * environment may have, from the scene or the job: far above any real one, and low enough that
 * the renderer's float sums and products of such values stay finite (FLT_MAX is 3.4e38). */
#define RB_MAX_RADIANCE 1e30

struct rb_vec3 {
    float x, y, z;
};
struct rb_vec4 {
    float x, y, z, w;
};
/* Quaternion (x, y, z, w), w the scalar part, as glTF stores it. */
struct rb_quat {
    float x, y, z, w;
};
/* Column-major 4x4 (m[col][row]), as glTF and GLSL store it. */
struct rb_mat4 {
    float m[4][4];
};

static inline struct rb_vec3 rb_v3(float x, float y, float z)
{
    struct rb_vec3 v = {x, y, z};
    return v;
}
struct rb_vec3 rb_v3_add(struct rb_vec3 a, struct rb_vec3 b);
struct rb_vec3 rb_v3_sub(struct rb_vec3 a, struct rb_vec3 b);
struct rb_vec3 rb_v3_scale(struct rb_vec3 a, float s);
struct rb_vec3 rb_v3_lerp(struct rb_vec3 a, struct rb_vec3 b, float t);
float rb_v3_dot(struct rb_vec3 a, struct rb_vec3 b);
struct rb_vec3 rb_v3_cross(struct rb_vec3 a, struct rb_vec3 b);
float rb_v3_length(struct rb_vec3 a);
/* Returns a unit vector, or a itself when its length is zero. */
struct rb_vec3 rb_v3_normalize(struct rb_vec3 a);
struct rb_vec3 rb_v3_min(struct rb_vec3 a, struct rb_vec3 b);
struct rb_vec3 rb_v3_max(struct rb_vec3 a, struct rb_vec3 b);

struct rb_quat rb_quat_identity(void);
struct rb_quat rb_quat_normalize(struct rb_quat q);
/* Shortest-arc spherical interpolation; falls back to nlerp for nearly equal inputs. */
struct rb_quat rb_quat_slerp(struct rb_quat a, struct rb_quat b, float t);
struct rb_quat rb_quat_mul(struct rb_quat a, struct rb_quat b);
struct rb_vec3 rb_quat_rotate(struct rb_quat q, struct rb_vec3 v);

struct rb_mat4 rb_mat4_identity(void);
struct rb_mat4 rb_mat4_mul(const struct rb_mat4 *a, const struct rb_mat4 *b);
/* T * R * S, the glTF node transform. */
struct rb_mat4 rb_mat4_trs(struct rb_vec3 t, struct rb_quat r, struct rb_vec3 s);
/* General inverse; returns identity for a singular matrix and sets *ok to false when ok. */
struct rb_mat4 rb_mat4_inverse(const struct rb_mat4 *a, bool *ok);
struct rb_mat4 rb_mat4_transpose(const struct rb_mat4 *a);
struct rb_vec3 rb_mat4_point(const struct rb_mat4 *a, struct rb_vec3 p);
struct rb_vec3 rb_mat4_dir(const struct rb_mat4 *a, struct rb_vec3 d);
struct rb_vec4 rb_mat4_vec4(const struct rb_mat4 *a, struct rb_vec4 v);
/* Right-handed view matrix looking from eye at target (camera looks down -Z, as glTF). */
struct rb_mat4 rb_mat4_look_at(struct rb_vec3 eye, struct rb_vec3 target, struct rb_vec3 up);
/* Vulkan-style perspective: depth 0..1, y down in NDC flipped so +Y is up on screen. */
struct rb_mat4 rb_mat4_perspective(float fov_y_rad, float aspect, float z_near, float z_far);
struct rb_mat4 rb_mat4_ortho(float left, float right, float bottom, float top, float z_near,
                             float z_far);

/* Dot and cross products of float[3]s, the CPU shading code's vectors (the reference, the CPU
 * deformation), in GLSL's order of operations; out may be an input (it is written last). */
static inline float rb_f3_dot(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void rb_f3_cross(const float a[3], const float b[3], float out[3])
{
    float x = a[1] * b[2] - a[2] * b[1];
    float y = a[2] * b[0] - a[0] * b[2];
    float z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

static inline float rb_clampf(float x, float lo, float hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

#ifdef __cplusplus
}
#endif

/* The named layers of a frame, in the order they are packed and written after the beauty (RGBA,
 * always first): a layer mask has bit l for layer l. */
enum rb_layer {
    RB_LAYER_DIRECT = 0, /* RGB */
    RB_LAYER_INDIRECT,   /* RGB */
    RB_LAYER_ALBEDO,     /* RGB */
    RB_LAYER_NORMAL,     /* XYZ */
    RB_LAYER_DEPTH,      /* Z */
    RB_LAYER_MOTION,     /* XY */
    /* indirect's two parts, textured by the diffuse and specular maps: indirect exactly. Last,
     * so that the bits (and job hashes) of the layers before them stay as they were. */
    RB_LAYER_INDIRECT_DIFFUSE,  /* RGB */
    RB_LAYER_INDIRECT_SPECULAR, /* RGB */
    /* How the pixel was sampled, per lobe (diffuse, specular): the samples its light averages
     * and whether the adaptive tile mask stops its rays. The hybrid integrator's (and the
     * reference's fixed count); after the others for the same reason. */
    RB_LAYER_SAMPLES, /* diffuse, specular */
    RB_LAYER_TILES,   /* diffuse, specular */
    /* The reference's estimate of the variance of each pixel's mean, on luminance: how much its
     * beauty would differ between two renders with other random numbers. Last, as above. */
    RB_LAYER_VARIANCE, /* Y */
    RB_LAYER_COUNT,
};
#define RB_LAYERS_ALL ((1u << RB_LAYER_COUNT) - 1u)
/* The packed pixel of a layer mask: the beauty's 4 floats, then each layer in the mask, in
 * order, the whole rounded up to a multiple of 4 floats (16 bytes). With every layer this is
 * the RB_OUT_* layout of shaders/common/shared.h (32 floats). */
uint32_t rb_layer_width(enum rb_layer layer);
uint32_t rb_layer_offset(uint32_t mask, enum rb_layer layer); /* in floats; for a layer in mask */
uint32_t rb_layer_stride(uint32_t mask);                      /* floats per pixel */
const char *rb_layer_name(enum rb_layer layer);               /* "direct", ... */
/* The EXR name of channel c of a layer, after "<layer>.": "R", "X", "diffuse", ...; NULL past
 * its width. */
const char *rb_layer_channel(enum rb_layer layer, uint32_t c);

/* What one frame produced, whichever renderer made it (a GPU integrator or the CPU reference);
 * the library writes it out (EXR layers, sidecars). Pointers are owned by the renderer and valid
 * until its next render or destroy. */
/* The hybrid integrator's rays of a frame: those its pixels requested, then where they ended:
 * hit in screen space, queued for the BVH (which hit, missed, or were dropped because the queue
 * was full), so requested = screen_hits + queued + those sampled below the surface, and queued =
 * bvh_hits + misses + dropped. */
struct rb_ray_counts {
    uint64_t requested, screen_hits, queued, bvh_hits, misses, dropped;
    /* integrator.hybrid.check_screen: screen hits traced again through the BVH, and those whose
     * BVH hit is the same surface; has_check false: not checked (and not written) */
    bool has_check;
    uint64_t screen_checked, screen_agreed;
};

struct rb_frame_result {
    int frame;
    double time_s;
    uint32_t width_px, height_px;
    const float *pixels;       /* floats_per_pixel floats a pixel, rows top to bottom: the
                                * beauty, then the layers of layer_mask (rb_layer_offset) */
    uint32_t floats_per_pixel; /* rb_layer_stride(layer_mask) */
    uint32_t layer_mask;       /* the layers in pixels: the job's (GPU) or all (reference) */
    const struct rb_pass_time *passes;
    uint32_t pass_count;
    struct rb_mat4 world_to_camera, world_to_ndc; /* column-major; NDC as Vulkan: y down, z 0..1 */
    uint32_t spp;             /* samples per pixel reached (the reference); 0 otherwise */
    uint64_t ray_count;       /* rays traced (the reference); 0 otherwise */
    uint32_t nonfinite_count; /* NaN or infinite floats among the pixels */
    /* bdpt's ray-bundle node buffer (0 for other integrators): the most nodes one bundle
     * asked for, how many the buffer holds, and the fragments dropped because it was full */
    uint32_t bundle_nodes_max, bundle_nodes_capacity, bundle_nodes_dropped;
    const float *hits; /* width_px x height_px floats, rows top to bottom: the temporal
                        * caches' hit ratio, sum of h / l (bdpt); NULL: none */
    const struct rb_ray_counts *ray_counts; /* the hybrid integrator's; NULL: none */
};

#endif
