/* The CPU reference: a unidirectional path tracer over the same evaluated scene, materials,
 * textures, lights and environment as the GPU integrators (Embree for intersection), used as
 * the ground truth every GPU integrator is judged against (DESIGN.md "reference", seed 003's
 * "Ground Truth Comparison"). Deterministic: per-pixel, per-sample random numbers keyed by
 * (frame, pixel, sample, dimension), so the result does not depend on the thread count. */
#ifndef RB_REFERENCE_REFERENCE_H
#define RB_REFERENCE_REFERENCE_H

#include "core/core.h"
#include "job/job.h"
#include "scene/scene.h"

struct rb_reference;

/* Where the random numbers come from (sample.c). */
enum rb_reference_sampler {
    RB_REFERENCE_SAMPLER_DEFAULT = 0, /* resolves to SOBOL */
    RB_REFERENCE_SAMPLER_SOBOL,       /* Owen-scrambled Sobol (0,2)-sequences, padded in pairs */
    RB_REFERENCE_SAMPLER_HASH,        /* independent hashed numbers: plain Monte Carlo, for
                                       * measuring what the sequences gain */
};

struct rb_reference_desc {
    const struct rb_job *job;     /* borrowed: settings in job->integrator.reference */
    const struct rb_scene *scene; /* borrowed */
    const float *env_rgba;        /* equirectangular RGBA, or NULL: job->environment.color */
    uint32_t env_width_px, env_height_px;
    const struct rb_scene_setup *setup; /* borrowed, or NULL: the reference decides its own */
    uint32_t thread_count;              /* 0: all cores */
    enum rb_reference_sampler sampler;  /* 0: Sobol */
    /* Called after each whole pass of samples with the samples done so far (for progress);
     * may be NULL. Returning false stops after that pass (as a time limit does). */
    bool (*on_pass)(void *user, uint32_t spp_done, uint32_t spp_total);
    void *user;
    /* Only for rb_reference_bake: no image (rb_reference_render refuses), so the job's
     * resolution costs no memory. */
    bool is_bake_only;
};

/* Builds the reference for the job and scene (Embree device, light tables). Fails with
 * RB_E_EXTERNAL for an Embree error, RB_E_NOMEM. */
enum rb_status rb_reference_create(const struct rb_reference_desc *desc, struct rb_reference **out,
                                   struct rb_err *err);

/* Renders one frame (time = frame / rate): evaluates the animation, deforms the geometry on the
 * CPU (skins, morphs, node transforms: the same math as the animate pass), rebuilds the BVH,
 * traces. The result is the GPU integrators' (core.h): its one pass, "trace", holds the tracing's
 * wall time as cpu_ms; spp is the samples reached (fewer than asked when a limit or on_pass
 * stopped it); ray_count counts camera, bounce and shadow rays. NaN and infinite values are
 * counted and logged as a warning, as the GPU integrators do. Thread-safe only against itself:
 * one render at a time per object. */
enum rb_status rb_reference_render(struct rb_reference *ref, int frame, struct rb_frame_result *out,
                                   struct rb_err *err);

void rb_reference_destroy(struct rb_reference *ref);

/* The importance table by which the reference samples an environment map (RGBA floats, width x
 * height, equirectangular), for a device that samples it the same way (the hybrid integrator):
 * into out, height + 1 floats of the CDF over rows, then each row's CDF (width + 1 floats a row),
 * then each texel's probability (width x height); rb_reference_env_table_floats floats in all. */
size_t rb_reference_env_table_floats(uint32_t width_px, uint32_t height_px);
enum rb_status rb_reference_env_table(const float *rgba, uint32_t width_px, uint32_t height_px,
                                      float *out, struct rb_err *err);

/* A point of the bake: on the triangle of world vertices vertex[0..2] (in the order of the
 * scene's instances, as lib/integrators/frame.c lays them out; any three, so a simplified mesh's
 * triangles too) at barycentrics u, v of the second and third, on the side their winding faces
 * (front) or the other (is_back). */
struct rb_reference_bake_point {
    uint32_t vertex[3];
    float u, v;
    bool is_back;
};

/* The direct light of the emissive triangles and the environment at surface points, with exact
 * visibility through the whole scene at frame (the hybrid integrator's baked light: seed 003,
 * "bake direct artificial light"). Point i gets in out[3i..3i+2] the radiance a white
 * Lambertian surface there reflects, irradiance / pi, on its side, with the interpolated vertex
 * normal turned to that side (no normal map), from `samples` samples each of an emitter point
 * (chosen by power, then by area) and of an environment direction (by the map's importance),
 * light sampling alone. Deterministic: the numbers of point i are the reference's of (frame 0,
 * pixel i, sample k) whatever the frame, summed in sample order whatever the threads, so the
 * bake is a function of the points and the frame's geometry alone. rays, if not NULL, gets
 * the shadow rays cast. Fails with RB_E_INVALID for a vertex out of range. */
enum rb_status rb_reference_bake(struct rb_reference *ref, int frame,
                                 const struct rb_reference_bake_point *points, uint32_t count,
                                 uint32_t samples, float *out, uint64_t *rays, struct rb_err *err);

/* Embree's version, e.g. "3.13.5". */
const char *rb_reference_embree_version(void);

/* ---- shading model, shared with the tests ------------------------------------------------ */

/* The glTF BRDF exactly as shaders/common/brdf.glsl evaluates it (f, without the cosine), for
 * the BRDF parity test: n, v, l unit vectors; c_diff, f0 RGB; f90 scalar. */
void rb_reference_brdf(const float n[3], const float v[3], const float l[3], const float c_diff[3],
                       const float f0[3], float f90, float roughness, float out[3]);

/* The default sampler's number in [0, 1) for (frame, pixel, sample, dimension): dimensions 2k
 * and 2k + 1 of one pixel's samples are an Owen-scrambled Sobol (0,2)-sequence; different
 * pixels, frames and pairs are independent. */
float rb_reference_random(uint32_t frame, uint32_t pixel, uint32_t sample, uint32_t dim);

#endif
