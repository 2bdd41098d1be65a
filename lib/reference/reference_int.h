/* Private to lib/reference: the per-frame world (deformed mesh, Embree scene, lights, emitters,
 * environment), surfaces and materials, the BRDF and its sampling, random numbers, and the path
 * integrator that reference.c runs over the pixels. */
#ifndef RB_REFERENCE_REFERENCE_INT_H
#define RB_REFERENCE_REFERENCE_INT_H

#include "reference/reference.h"

#include <embree3/rtcore.h>

#define RB_REF_NONE UINT32_MAX

/* ---- random numbers (sample.c) -------------------------------------------------------------- */

/* The numbers of one sample of one pixel in one frame. */
struct rb_ref_rng {
    uint64_t seed; /* the pixel's in this frame (hashed: and the sample's) */
    uint32_t sample;
    bool is_hashed; /* RB_REFERENCE_SAMPLER_HASH */
};

void rb_ref_rng_init(struct rb_ref_rng *rng, bool is_hashed, uint32_t frame, uint32_t pixel,
                     uint32_t sample);
/* Makes rng one of independent replicates (0 leaves it as it is): another replicate draws
 * other scrambles and seeds, so the same sample index of two replicates gives independent
 * numbers, and each replicate's samples 0, 1, ... are a net of their own. */
void rb_ref_rng_replicate(struct rb_ref_rng *rng, uint32_t replicate);
/* Dimension dim, in [0, 1); with the default sampler, rb_reference_random. Dimensions 2k and
 * 2k + 1 are one 2D point (stratified together over the samples): give a 2D integral such a
 * pair. rb_ref_rand2 draws both of the pair that starts at dim (even) at once. */
float rb_ref_rand(const struct rb_ref_rng *rng, uint32_t dim);
void rb_ref_rand2(const struct rb_ref_rng *rng, uint32_t dim, float out[2]);

/* ---- the world of one frame ------------------------------------------------------------------ */

enum rb_ref_mat_flags {
    RB_REF_MAT_MASKED = 1 << 0,       /* alpha MASK with a cutoff > 0 */
    RB_REF_MAT_SINGLE_SIDED = 1 << 1, /* camera rays skip its back faces */
    RB_REF_MAT_EMISSIVE = 1 << 2,     /* a non-zero emissive factor */
    RB_REF_MAT_BLEND = 1 << 3,        /* alpha BLEND: no ray hits it; camera rays gather it */
};

/* The environment: a uniform colour or an equirectangular map with its importance table. */
struct rb_ref_env {
    float color[3];  /* radiance without a map (already times the intensity) */
    float intensity; /* the map's scale */
    float rotation_rad;
    const float *rgba; /* borrowed map, or NULL */
    uint32_t width_px, height_px;
    float *marginal;    /* height_px + 1: CDF over rows */
    float *conditional; /* height_px * (width_px + 1): CDF over columns per row */
    float *texel_pdf;   /* width_px * height_px: probability of each texel (sums to 1) */
    bool is_black;      /* nothing to sample: no light from the environment */
};

/* A punctual light as direct.comp reads it. */
struct rb_ref_light {
    enum rb_light_type type;
    float position[3];
    float direction[3]; /* the direction light travels */
    float color[3];     /* color x intensity */
    float range;
    float cos_inner, cos_outer;
};

/* Everything a sample reads; written by reference.c before the threads start, then const. */
struct rb_ref_world {
    const struct rb_scene *scene;
    const uint8_t *mat_flags; /* per material, enum rb_ref_mat_flags */
    bool has_blend;           /* a material has RB_REF_MAT_BLEND */
    const float *srgb_lut;    /* 256 entries: 8-bit sRGB to linear */

    uint32_t vertex_count, tri_count;
    const float *pos;      /* 4 floats per vertex (Embree's buffer), world space */
    const float *prev_pos; /* 3 floats per vertex: the previous frame's positions */
    const float *nrm;      /* 3 per vertex */
    const float *tan;      /* 4 per vertex: xyz, handedness */
    const float *uv;       /* 2 per vertex */
    const uint32_t *tris;  /* 3 per triangle */
    const uint32_t *tri_material;

    RTCScene rtc; /* NULL when there are no triangles */

    const struct rb_ref_light *lights;
    uint32_t light_count;

    /* Emissive triangles, chosen by power (area x luminance of the emissive factor). */
    const uint32_t *emitters; /* triangle indices */
    const float *emitter_cdf; /* emitter_count + 1 */
    uint32_t emitter_count;
    const float *emit_pdf_area; /* per triangle: selection probability / area, 0 if none */

    const struct rb_ref_env *env;

    enum rb_path_space paths;
    uint32_t max_bounces, rr_depth;
    uint32_t frame;         /* for the random numbers */
    bool is_hashed_sampler; /* RB_REFERENCE_SAMPLER_HASH */
};

/* A shading point, as gbuffer.frag builds it. */
struct rb_ref_surface {
    float p[3];
    float n[3];  /* shading normal: interpolated, flipped on back faces, normal-mapped */
    float ng[3]; /* geometric normal on the side of the (unmapped) shading normal */
    float c_diff[3], f0[3], f90, roughness;
    float emission[3];
    bool is_front;
};

/* The hit point of triangle prim at Embree's barycentrics (u on vertex 1, v on vertex 2). */
void rb_ref_hit_point(const struct rb_ref_world *w, uint32_t prim, float u, float v, float out[3]);

/* Shades a hit of a ray with direction dir (unit) on triangle prim. */
void rb_ref_surface_eval(const struct rb_ref_world *w, uint32_t prim, float u, float v,
                         const float dir[3], struct rb_ref_surface *s);

/* The emitted radiance of triangle prim at (u, v), either side. */
void rb_ref_emission(const struct rb_ref_world *w, uint32_t prim, float u, float v, float out[3]);

/* The material's base-colour alpha at (u, v) (factor x texture). */
float rb_ref_alpha(const struct rb_ref_world *w, uint32_t prim, float u, float v);

/* An orthonormal basis t, b around unit n (Duff et al. 2017, branchless; brdf.c). */
void rb_ref_basis(const float n[3], float t[3], float b[3]);

/* ---- ray casting (embree.c) ---------------------------------------------------------------- */

/* The intersect context every ray uses: Embree's first, so the filter can cast back. */
struct rb_ref_ray_ctx {
    struct RTCIntersectContext rtc;
    const struct rb_ref_world *world;
    bool is_camera; /* skip back faces of single-sided materials */
    /* When set: the blended triangles the ray crosses, recorded (at most layer_cap, each once)
     * rather than hit (rb_ref_blend_layers). */
    struct rb_ref_hit *layers;
    uint32_t layer_count, layer_cap;
};

/* The Embree filter for both intersect and occluded: alpha mask, camera back faces. */
void rb_ref_filter(const struct RTCFilterFunctionNArguments *args);

struct rb_ref_hit {
    uint32_t prim; /* RB_REF_NONE: missed */
    float u, v, t;
};

void rb_ref_intersect(const struct rb_ref_world *w, bool is_camera, const float org[3],
                      const float dir[3], float tnear, float tfar, struct rb_ref_hit *hit);
bool rb_ref_occluded(const struct rb_ref_world *w, const float org[3], const float dir[3],
                     float tfar);

/* The most blended layers a camera ray composites (nearest first; farther ones are dropped). */
#define RB_REF_MAX_LAYERS 16
/* The blended triangles a camera ray from org along dir crosses between tnear and tfar (front
 * faces of single-sided materials alone), nearest first (ties by triangle): their count, at most
 * RB_REF_MAX_LAYERS, into layers. */
uint32_t rb_ref_blend_layers(const struct rb_ref_world *w, const float org[3], const float dir[3],
                             float tnear, float tfar, struct rb_ref_hit *layers);

/* Moves p off its surface along n (the side the new ray leaves by), scale-independently
 * (Wachter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection", 2019). */
void rb_ref_offset(const float p[3], const float n[3], float out[3]);

/* ---- lights (lights.c) ----------------------------------------------------------------------- */

/* KHR_lights_punctual's range window times inverse square, as rb_light_falloff. */
float rb_ref_light_falloff(float dist, float range);
/* rb_spot_factor of lights.glsl. */
float rb_ref_spot_factor(const float spot_dir[3], const float to_surface[3], float cos_inner,
                         float cos_outer);

/* rb_equirect_uv of lights.glsl: the map coordinates of direction d (unit) for a map turned by
 * rotation_rad about +Y. */
void rb_ref_equirect_uv(const float d[3], float rotation_rad, float *u, float *v);

/* Builds the importance table of env (its map, colour and intensity already set). */
enum rb_status rb_ref_env_init(struct rb_ref_env *env, struct rb_err *err);
void rb_ref_env_release(struct rb_ref_env *env);
/* Radiance arriving from direction d (unit). */
void rb_ref_env_eval(const struct rb_ref_env *env, const float d[3], float out[3]);
/* Samples a direction toward the environment from a point with shading normal n; returns its
 * solid-angle pdf (0: no sample). rb_ref_env_pdf gives the same pdf for any direction. */
float rb_ref_env_sample(const struct rb_ref_env *env, const float n[3], float u0, float u1,
                        float d[3]);
float rb_ref_env_pdf(const struct rb_ref_env *env, const float n[3], const float d[3]);

/* ---- BRDF sampling (brdf.c) ------------------------------------------------------------------ */

/* The BRDF at one surface for one outgoing direction v, with its two-lobe sampler. */
struct rb_ref_bsdf {
    const struct rb_ref_surface *s;
    float v[3];
    float p_spec;     /* probability of sampling the specular lobe */
    float alpha;      /* GGX alpha = max(roughness^2, 1e-4), as the BRDF */
    float t[3], b[3]; /* tangent frame around s->n */
    float vs[3];      /* v in that frame, lifted to n.v >= 1e-4 for VNDF sampling */
};

void rb_ref_bsdf_init(struct rb_ref_bsdf *b, const struct rb_ref_surface *s, const float v[3]);
/* f x cos(n, l) x [l above the geometric normal]: the BSDF's value for light from l. */
void rb_ref_bsdf_eval(const struct rb_ref_bsdf *b, const float l[3], float out[3]);
/* The combined pdf (solid angle) of both lobes for l. */
float rb_ref_bsdf_pdf(const struct rb_ref_bsdf *b, const float l[3]);
/* The BRDF's two lobes: (1 - F) c_diff / pi and F D V. */
enum rb_ref_lobe { RB_REF_LOBE_DIFFUSE = 0, RB_REF_LOBE_SPECULAR, RB_REF_LOBE_COUNT };
/* Samples l; returns its combined pdf (0 when nothing could be sampled; infinite for a mirror
 * direction single precision cannot resolve) and writes weight = BSDF value / pdf, and each
 * lobe's value over the same pdf in lobe_weight (their sum is weight up to rounding). */
float rb_ref_bsdf_sample(const struct rb_ref_bsdf *b, float u_lobe, float u0, float u1, float l[3],
                         float weight[3], float lobe_weight[RB_REF_LOBE_COUNT][3]);

/* ---- the integrator (trace.c) --------------------------------------------------------------- */

/* Dimensions [0, RB_REF_DIM_CAMERA_END) of each sample are the camera's (the pixel filter's
 * position in the pixel); the path's start after them. */
#define RB_REF_DIM_PIXEL 0
#define RB_REF_DIM_CAMERA_END 16

/* One sample's light, by layer: direct, indirect, and indirect again split by the lobe of x1
 * that reflects it toward the camera (the indirect_diffuse and indirect_specular layers). */
struct rb_ref_sample_light {
    float direct[3], indirect[3];
    float indirect_lobe[RB_REF_LOBE_COUNT][3];
};

/* One sample of one pixel whose camera ray (direction dir) hit hit: adds its light to out
 * (zeroed by the caller). */
void rb_ref_trace_sample(const struct rb_ref_world *w, const struct rb_ref_hit *hit,
                         const float dir[3], const struct rb_ref_rng *rng,
                         struct rb_ref_sample_light *out, uint64_t *rays);

/* The direct light (into out->direct) of a blended surface that a camera ray along dir crosses
 * at hit: as rb_ref_trace_sample with no bounce past it (emission, and the light of the path
 * space's light sources after one scattering there). */
void rb_ref_trace_direct(const struct rb_ref_world *w, const struct rb_ref_hit *hit,
                         const float dir[3], const struct rb_ref_rng *rng,
                         struct rb_ref_sample_light *out, uint64_t *rays);

/* Adds one sample of the direct light of the emitters and the environment at point p (shading
 * normal n, geometric normal ng, both on the lit side) to out, as a white Lambertian surface
 * there reflects it (irradiance / pi): reference.c's rb_reference_bake. */
void rb_ref_bake_sample(const struct rb_ref_world *w, const float p[3], const float n[3],
                        const float ng[3], const struct rb_ref_rng *rng, float out[3],
                        uint64_t *rays);

/* ---- small vector helpers ------------------------------------------------------------------- */

/* max and min that compile to one instruction (fmaxf is a libm call without -ffast-math); a NaN
 * in a gives b, as fmaxf does. */
static inline float rb_ref_maxf(float a, float b)
{
    return a > b ? a : b;
}

static inline float rb_ref_minf(float a, float b)
{
    return a < b ? a : b;
}

/* (1 - x)^5, Schlick's weight, by multiplication (GLSL's pow(y, 5.0) is exp2(5 log2 y), no
 * more exact than this). */
static inline float rb_ref_pow5(float y)
{
    float y2 = y * y;
    return y2 * y2 * y;
}

static inline float rb_ref_luminance(const float c[3])
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

#endif
