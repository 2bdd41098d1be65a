/* The CPU reference (DESIGN.md "reference", seed 003 "Ground Truth Comparison"): the frame loop,
 * the per-frame world (deformed mesh, Embree scene, lights, emitters) and the threads.
 *
 * What it computes, and where it deliberately matches the GPU rather than a camera model:
 * - pixel_filter center (the default): every sample of a pixel uses the one camera ray through
 *   the pixel centre, the rasterizer's sample position (clipped to the camera's near and far
 *   planes, skipping back faces of single-sided materials and alpha-masked texels, as the
 *   G-buffer's discards do). So the reference and the GPU integrators differ only in light
 *   transport, never in coverage: edges are aliased exactly like the G-buffer's, and the AOVs
 *   are exact. pixel_filter box: each sample takes its own camera ray through a uniform point
 *   of the pixel (its first pair of dimensions), which may miss: beauty, direct and indirect
 *   average what the samples see, alpha is the fraction that hit. The AOVs still come from the
 *   centre's ray under box: an average of depths or normals across an edge is no surface's.
 * - Geometry, materials, textures, punctual lights and the environment are shaders/animate.comp,
 *   gbuffer.frag, brdf.glsl and lights.glsl transcribed (deform.c, material.c, brdf.c,
 *   lights.c); textures are filtered at their own resolution without mipmaps.
 * - Shadow and bounce rays hit both sides of every triangle (the shadow maps cull nothing);
 *   emission leaves both sides. The environment map is read bilinearly, u repeating and v
 *   clamped at the poles.
 * - Light transport (trace.c): path tracing with next-event estimation; MIS with the power
 *   heuristic (beta 2) between BSDF sampling and emitter/environment sampling; one-sample MIS
 *   over the two BRDF lobes; Russian roulette after rr_depth bounces, survival = the
 *   throughput's largest component clamped to [0.05, 0.95]. Rays leave from a point moved off
 *   the surface, and shadow rays are aimed from that point (emitter samples measured from it).
 * - Path spaces: FULL counts every path up to max_bounces bounces past the first hit. DIRECT is
 *   the direct integrator's: emission at x1, punctual lights and the emitters' fixed point
 *   samples (rb_scene_emitter_lights, the direct integrator's) at x1 (exact visibility), the
 *   environment on camera misses; it draws no random numbers but box's pixel positions, so
 *   under center its samples after the first are copies. BDPT is BDPT.md's: emission at x1;
 *   punctual lights and emissive triangles at x1, x2 and x3 (direct light and one and two
 *   bounces: light -> x3 -> x2 -> x1 at the longest; fewer when max_bounces < 2), emitters by
 *   light sample and by each vertex's BSDF sample (MIS, as in FULL; the BSDF sample from x3
 *   counts an emitter it hits and goes no further); the environment at x1 only (light and BSDF
 *   samples, MIS) and on camera misses. With a black environment it is FULL with two bounces.
 * - Blended materials (alphaMode BLEND) as the transparency pass draws them (lib/passes/
 *   transparency.c): no ray hits them (the G-buffer and the shadow maps leave them out); each
 *   sample of a camera ray composites the blended triangles in front of its first hit (the
 *   RB_REF_MAX_LAYERS nearest, single-sided ones from the front), farthest first: the layer's
 *   direct light (rb_ref_trace_direct: x1's light in the path space, no bounce) times its
 *   alpha, over 1 - alpha times the light behind it, whose path goes on through it. In the
 *   direct path space that is the direct integrator's transparency exactly (up to shadow maps
 *   against exact visibility); in bdpt and full the layer also gets the emissive triangles'
 *   and the environment's direct light, which bdpt's and the hybrid's layers approximate by
 *   their layer lights (the emitters' point samples and the environment's directions).
 * - Layers: direct = emission at x1 + light reaching x1 after exactly one scattering + the
 *   environment on camera misses (the blended layers' light composited into it); indirect =
 *   the rest (scaled by the layers' 1 - alpha); beauty = direct + indirect, alpha 1 on a hit
 *   and 0 on a miss (averaged under box; with blended layers, what they and the hit cover).
 *   indirect_diffuse and indirect_specular: indirect
 *   through x1's diffuse or specular lobe alone (x1's BSDF weight split by lobe), summed apart,
 *   so they add up to indirect up to rounding. AOVs from the first hit: albedo (c_diff),
 *   shading normal, view depth, motion (previous minus current pixel position of the same
 *   surface point). samples: the samples taken (the spp reached), in both lobes' channels,
 *   where the pixel's samples were traced (0 where the centre ray sees the environment);
 *   tiles: 0, nothing stops early.
 * Samples (sample.c): a pixel's samples are Owen-scrambled Sobol (0,2)-sequences in pairs of
 * dimensions (the pixel position, each vertex's BSDF direction, emitter point, environment
 * direction), padded with independent seeds per frame, pixel and pair; the error falls faster
 * than 1/sqrt(spp) where a pair's integrand is smooth. RB_REFERENCE_SAMPLER_HASH gives
 * independent hashed numbers instead (plain Monte Carlo), for comparisons.
 * Determinism: every number is a function of (frame, pixel, sample, dimension); each pixel's
 * samples are summed in sample order in double by whichever thread owns its row, so the bits
 * do not depend on the thread count. Samples come in passes of 1, 1, 2, 4, 8, then 16. */
#include "reference/reference_int.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "shared.h" /* RB_OUT_*: shaders/common, on the include path */

#define MAX_CLIPS 64
#define MAX_THREADS 256
#define MAX_PASS_SPP 16
/* doubles per pixel: direct RGB, indirect RGB, samples that hit (box), then indirect by the
 * lobe of x1 that reflects it: diffuse RGB, specular RGB, then the sums of the luminance of
 * the even and of the odd samples (the variance layer's replicates) */
#define ACCUM 15
#define ACCUM_LUM 13

struct rb_reference {
    const struct rb_job *job;
    const struct rb_scene *scene;
    struct rb_scene_setup setup; /* decided once for the job: bounds, default light */
    struct rb_pass_time trace;   /* the result's one pass */
    uint32_t thread_count;
    bool is_hashed_sampler;
    bool use_box_filter; /* job: integrator.reference.pixel_filter box */
    bool use_replicates; /* job: the variance layer (see mean_variance) */
    bool (*on_pass)(void *user, uint32_t spp_done, uint32_t spp_total);
    void *user;

    uint32_t clips[MAX_CLIPS];
    struct rb_anim_selection sel;
    struct rb_scene_pose *pose, *prev_pose;

    /* the world-space mesh, in instance order */
    uint32_t vertex_count, tri_count;
    float *pos; /* 4 per vertex: shared with Embree */
    float *prev_pos, *nrm, *tan, *uv;
    uint32_t *tris; /* shared with Embree */
    uint32_t *tri_material;
    uint8_t *mat_flags;
    bool has_blend; /* a material is blended (RB_REF_MAT_BLEND) */
    float srgb_lut[256];

    RTCDevice device;
    RTCScene rtc;
    RTCGeometry geom;
    enum RTCError embree_code;
    char embree_msg[256];

    struct rb_world_light *world_lights;
    struct rb_ref_light *lights;
    uint32_t light_cap;

    uint32_t *emitters;
    float *emitter_cdf, *emit_pdf_area;
    uint32_t emitter_total; /* triangles with an emissive material */

    struct rb_ref_env env;
    struct rb_ref_world world;

    uint32_t width_px, height_px;
    float *pixels;
    double *accum;
    struct rb_ref_hit *primary;
    uint8_t *layered;   /* per pixel: the centre ray crosses a blended layer */
    float *primary_dir; /* 3 per pixel */

    /* the frame being rendered */
    struct rb_camera cam, prev_cam;
    struct rb_mat4 world_to_ndc, prev_world_to_ndc;
    float cam_forward[3]; /* unit view axis, for near/far clipping */
};

static void embree_error(void *user, enum RTCError code, const char *msg)
{
    struct rb_reference *ref = user;
    if (ref->embree_code == RTC_ERROR_NONE) {
        ref->embree_code = code;
        rb_strlcpy(ref->embree_msg, msg ? msg : "unknown error", sizeof(ref->embree_msg));
    }
}

static enum rb_status embree_check(struct rb_reference *ref, const char *what, struct rb_err *err)
{
    enum RTCError code = rtcGetDeviceError(ref->device);
    if (code == RTC_ERROR_NONE && ref->embree_code == RTC_ERROR_NONE)
        return RB_OK;
    if (ref->embree_code == RTC_ERROR_NONE)
        ref->embree_code = code;
    enum rb_status st = ref->embree_code == RTC_ERROR_OUT_OF_MEMORY ? RB_E_NOMEM : RB_E_EXTERNAL;
    return rb_errf(err, st, "embree: %s: %s (error %d)", what,
                   ref->embree_msg[0] ? ref->embree_msg : "no message", (int)ref->embree_code);
}

static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

/* Counts the mesh, lays out the triangles (global vertex indices, material per triangle) and
 * flags the materials. */
static enum rb_status build_mesh(struct rb_reference *ref, struct rb_err *err)
{
    const struct rb_scene *scene = ref->scene;
    const struct rb_scene_pose *pose = ref->pose;
    if (scene->material_count == 0)
        return rb_errf(err, RB_E_INVALID, "scene has no materials (not even the default)");
    uint64_t verts = 0, tris = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        verts += p->vertex_count;
        tris += p->index_count / 3;
    }
    if (verts > UINT32_MAX / 4 || tris > UINT32_MAX / 4)
        return rb_errf(err, RB_E_UNSUPPORTED, "scene too large: %llu vertices, %llu triangles",
                       (unsigned long long)verts, (unsigned long long)tris);
    ref->vertex_count = (uint32_t)verts;
    ref->tri_count = (uint32_t)tris;
    size_t nv = verts ? verts : 1, nt = tris ? tris : 1;
    ref->pos = aligned_alloc(16, nv * 4 * sizeof(float));
    ref->prev_pos = malloc(nv * 3 * sizeof(float));
    ref->nrm = malloc(nv * 3 * sizeof(float));
    ref->tan = malloc(nv * 4 * sizeof(float));
    ref->uv = malloc(nv * 2 * sizeof(float));
    ref->tris = aligned_alloc(16, ((nt * 3 + 3) & ~(size_t)3) * sizeof(uint32_t));
    ref->tri_material = malloc(nt * sizeof(uint32_t));
    ref->emit_pdf_area = calloc(nt, sizeof(float));
    ref->mat_flags = calloc(scene->material_count, 1);
    if (!ref->pos || !ref->prev_pos || !ref->nrm || !ref->tan || !ref->uv || !ref->tris ||
        !ref->tri_material || !ref->emit_pdf_area || !ref->mat_flags)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %llu vertices, %llu triangles",
                       (unsigned long long)verts, (unsigned long long)tris);

    for (uint32_t m = 0; m < scene->material_count; m++) {
        const struct rb_scene_material *mat = &scene->materials[m];
        uint8_t f = 0;
        if (mat->alpha_mode == RB_ALPHA_MASK && mat->alpha_cutoff > 0.0f)
            f |= RB_REF_MAT_MASKED;
        if (!mat->double_sided)
            f |= RB_REF_MAT_SINGLE_SIDED;
        if (mat->emissive[0] > 0.0f || mat->emissive[1] > 0.0f || mat->emissive[2] > 0.0f)
            f |= RB_REF_MAT_EMISSIVE;
        if (mat->alpha_mode == RB_ALPHA_BLEND) {
            f |= RB_REF_MAT_BLEND;
            ref->has_blend = true;
        }
        ref->mat_flags[m] = f;
    }

    uint32_t dst = 0, t = 0, emitters = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        if (p->material >= scene->material_count)
            return rb_errf(err, RB_E_INVALID, "primitive %u: material %u does not exist",
                           pose->instances[i].primitive, p->material);
        for (uint32_t j = 0; j + 2 < p->index_count; j += 3, t++) {
            for (int k = 0; k < 3; k++) {
                uint32_t idx = scene->indices[p->first_index + j + (uint32_t)k];
                if (idx >= p->vertex_count)
                    return rb_errf(err, RB_E_INVALID,
                                   "primitive %u: index %u out of range (%u vertices)",
                                   pose->instances[i].primitive, idx, p->vertex_count);
                ref->tris[(size_t)t * 3 + (size_t)k] = dst + idx;
            }
            ref->tri_material[t] = p->material;
            if (ref->mat_flags[p->material] & RB_REF_MAT_EMISSIVE)
                emitters++;
        }
        dst += p->vertex_count;
    }
    ref->emitter_total = emitters;
    ref->emitters = malloc((emitters ? emitters : 1) * sizeof(uint32_t));
    ref->emitter_cdf = malloc((emitters + 1) * sizeof(float));
    if (!ref->emitters || !ref->emitter_cdf)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %u emissive triangles", emitters);
    for (uint32_t i = 0, e = 0; i < ref->tri_count; i++)
        if (ref->mat_flags[ref->tri_material[i]] & RB_REF_MAT_EMISSIVE)
            ref->emitters[e++] = i;
    return RB_OK;
}

static enum rb_status build_embree(struct rb_reference *ref, struct rb_err *err)
{
    /* BVH builds use the same number of threads as the tracing, so --threads is a budget */
    char config[64];
    snprintf(config, sizeof(config), "threads=%u", ref->thread_count);
    ref->device = rtcNewDevice(config);
    if (!ref->device)
        return rb_errf(err, RB_E_EXTERNAL, "embree: cannot create a device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    rtcSetDeviceErrorFunction(ref->device, embree_error, ref);
    if (ref->tri_count == 0)
        return RB_OK;
    bool needs_filter = false;
    for (uint32_t m = 0; m < ref->scene->material_count; m++)
        if (ref->mat_flags[m] & (RB_REF_MAT_MASKED | RB_REF_MAT_SINGLE_SIDED | RB_REF_MAT_BLEND))
            needs_filter = true;
    if (needs_filter &&
        !rtcGetDeviceProperty(ref->device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED))
        return rb_errf(err, RB_E_UNSUPPORTED,
                       "embree was built without filter functions, which alpha masks, blending and "
                       "single-sided materials need");
    ref->rtc = rtcNewScene(ref->device);
    ref->geom = rtcNewGeometry(ref->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    enum rb_status st = embree_check(ref, "creating the scene", err);
    if (st)
        return st;
    rtcSetSceneFlags(ref->rtc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(ref->rtc, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSharedGeometryBuffer(ref->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, ref->pos, 0,
                               4 * sizeof(float), ref->vertex_count);
    rtcSetSharedGeometryBuffer(ref->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, ref->tris, 0,
                               3 * sizeof(uint32_t), ref->tri_count);
    rtcSetGeometryUserData(ref->geom, &ref->world);
    if (needs_filter) {
        rtcSetGeometryIntersectFilterFunction(ref->geom, rb_ref_filter);
        rtcSetGeometryOccludedFilterFunction(ref->geom, rb_ref_filter);
    }
    rtcAttachGeometryByID(ref->rtc, ref->geom, 0);
    return embree_check(ref, "setting up the triangle geometry", err);
}

enum rb_status rb_reference_create(const struct rb_reference_desc *desc, struct rb_reference **out,
                                   struct rb_err *err)
{
    const struct rb_job *job = desc->job;
    struct rb_reference *ref = calloc(1, sizeof(*ref));
    if (!ref)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = RB_OK;
    ref->job = job;
    ref->scene = desc->scene;
    ref->on_pass = desc->on_pass;
    ref->user = desc->user;
    ref->is_hashed_sampler = desc->sampler == RB_REFERENCE_SAMPLER_HASH;
    ref->use_box_filter = job->integrator.reference.pixel_filter == RB_PIXEL_FILTER_BOX;
    ref->use_replicates = (job->layer_mask & (1u << RB_LAYER_VARIANCE)) != 0;
    uint32_t threads = desc->thread_count;
    if (threads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (uint32_t)n : 1;
    }
    ref->thread_count = threads > MAX_THREADS ? MAX_THREADS : threads;
    for (int i = 0; i < 256; i++)
        ref->srgb_lut[i] = srgb_to_linear((float)i / 255.0f);

    uint32_t clip_count = 0;
    if (desc->setup)
        ref->setup = *desc->setup;
    else if ((st = rb_scene_setup_init(job, desc->scene, desc->env_rgba, desc->env_width_px,
                                       desc->env_height_px, &ref->setup, err)))
        goto fail;
    if ((st = rb_scene_select_clips(desc->scene, job, ref->clips, MAX_CLIPS, &clip_count, err)))
        goto fail;
    ref->sel = (struct rb_anim_selection){
        .clips = ref->clips,
        .clip_count = clip_count,
        .offset_s = job->animation.offset_s,
        .speed = job->animation.speed,
        .loop = job->animation.loop,
    };
    if ((st = rb_scene_pose_create(desc->scene, &ref->pose, err)) ||
        (st = rb_scene_pose_create(desc->scene, &ref->prev_pose, err)))
        goto fail;
    if ((st = build_mesh(ref, err)) || (st = build_embree(ref, err)))
        goto fail;

    ref->env = (struct rb_ref_env){
        .color = {job->environment.color[0] * job->environment.intensity,
                  job->environment.color[1] * job->environment.intensity,
                  job->environment.color[2] * job->environment.intensity},
        .intensity = job->environment.intensity,
        .rotation_rad = job->environment.rotation_deg * RB_PI / 180.0f,
        .rgba = desc->env_rgba,
        .width_px = desc->env_width_px,
        .height_px = desc->env_height_px,
    };
    if ((st = rb_ref_env_init(&ref->env, err)))
        goto fail;

    if (desc->is_bake_only) {
        *out = ref;
        return RB_OK;
    }
    ref->width_px = job->width_px;
    ref->height_px = job->height_px;
    if (ref->width_px == 0 || ref->height_px == 0) {
        st = rb_errf(err, RB_E_INVALID, "resolution %ux%u", ref->width_px, ref->height_px);
        goto fail;
    }
    size_t px = (size_t)ref->width_px * ref->height_px;
    ref->pixels = calloc(px * RB_OUT_FLOATS, sizeof(float));
    ref->accum = calloc(px * ACCUM, sizeof(double));
    ref->primary = calloc(px, sizeof(*ref->primary));
    ref->layered = calloc(px, 1);
    ref->primary_dir = calloc(px * 3, sizeof(float));
    if (!ref->pixels || !ref->accum || !ref->primary || !ref->primary_dir || !ref->layered) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for a %ux%u image", ref->width_px,
                     ref->height_px);
        goto fail;
    }
    *out = ref;
    return RB_OK;
fail:
    rb_reference_destroy(ref);
    return st;
}

void rb_reference_destroy(struct rb_reference *ref)
{
    if (!ref)
        return;
    if (ref->geom)
        rtcReleaseGeometry(ref->geom);
    if (ref->rtc)
        rtcReleaseScene(ref->rtc);
    if (ref->device)
        rtcReleaseDevice(ref->device);
    rb_ref_env_release(&ref->env);
    free(ref->primary_dir);
    free(ref->primary);
    free(ref->layered);
    free(ref->accum);
    free(ref->pixels);
    free(ref->lights);
    free(ref->world_lights);
    free(ref->emitter_cdf);
    free(ref->emitters);
    free(ref->mat_flags);
    free(ref->emit_pdf_area);
    free(ref->tri_material);
    free(ref->tris);
    free(ref->uv);
    free(ref->tan);
    free(ref->nrm);
    free(ref->prev_pos);
    free(ref->pos);
    rb_scene_pose_destroy(ref->prev_pose);
    rb_scene_pose_destroy(ref->pose);
    free(ref);
}

/* ---- the frame's world ---------------------------------------------------------------------- */

static enum rb_path_space paths_of(const struct rb_job *job)
{
    return job->integrator.reference.paths == RB_PATHS_DEFAULT ? RB_PATHS_FULL
                                                               : job->integrator.reference.paths;
}

static enum rb_status update_lights(struct rb_reference *ref, struct rb_err *err)
{
    uint32_t n = rb_scene_world_lights(ref->job, ref->scene, &ref->setup, ref->pose, NULL, 0);
    if (n > ref->light_cap) {
        struct rb_world_light *wl = realloc(ref->world_lights, n * sizeof(*wl));
        if (wl)
            ref->world_lights = wl;
        struct rb_ref_light *l = realloc(ref->lights, n * sizeof(*l));
        if (l)
            ref->lights = l;
        if (!wl || !l)
            return rb_errf(err, RB_E_NOMEM, "out of memory for %u lights", n);
        ref->light_cap = n;
    }
    n = rb_scene_world_lights(ref->job, ref->scene, &ref->setup, ref->pose, ref->world_lights, n);
    /* The direct path space is the direct integrator's: the emitters light as its point samples
     * do (exact visibility in place of their shadow maps); the other path spaces sample the
     * emissive triangles themselves. */
    if (paths_of(ref->job) == RB_PATHS_DIRECT) {
        struct rb_world_light samples[RB_SCENE_EMITTER_LIGHTS_MAX];
        uint32_t k = rb_scene_emitter_lights(ref->scene, ref->pose,
                                             ref->job->integrator.direct.emitter_lights, samples,
                                             RB_SCENE_EMITTER_LIGHTS_MAX);
        if (n + k > ref->light_cap) {
            struct rb_world_light *wl = realloc(ref->world_lights, (n + k) * sizeof(*wl));
            if (wl)
                ref->world_lights = wl;
            struct rb_ref_light *l = realloc(ref->lights, (n + k) * sizeof(*l));
            if (l)
                ref->lights = l;
            if (!wl || !l)
                return rb_errf(err, RB_E_NOMEM, "out of memory for %u lights", n + k);
            ref->light_cap = n + k;
        }
        memcpy(ref->world_lights + n, samples, k * sizeof(*samples));
        n += k;
    }
    for (uint32_t i = 0; i < n; i++) {
        const struct rb_world_light *w = &ref->world_lights[i];
        ref->lights[i] = (struct rb_ref_light){
            .type = w->type,
            .position = {w->position.x, w->position.y, w->position.z},
            .direction = {w->direction.x, w->direction.y, w->direction.z},
            .color = {w->color[0], w->color[1], w->color[2]},
            .range = w->range,
            .cos_inner = cosf(w->inner_cone_rad),
            .cos_outer = cosf(w->outer_cone_rad),
        };
    }
    ref->world.light_count = n;
    return RB_OK;
}

/* Emitter selection by power: area x luminance of the emissive factor, for this frame's
 * triangle areas. A triangle's pdf per unit area is its probability in the CDF as stored (so the
 * pdf is exactly that of the sampling) over its area. */
static void update_emitters(struct rb_reference *ref)
{
    const struct rb_scene *scene = ref->scene;
    double total = 0.0;
    ref->emitter_cdf[0] = 0.0f;
    for (uint32_t e = 0; e < ref->emitter_total; e++) {
        uint32_t t = ref->emitters[e];
        const uint32_t *tri = &ref->tris[(size_t)t * 3];
        const float *p0 = &ref->pos[tri[0] * 4], *p1 = &ref->pos[tri[1] * 4];
        const float *p2 = &ref->pos[tri[2] * 4];
        float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        float c[3];
        rb_f3_cross(e1, e2, c);
        float area = 0.5f * sqrtf(rb_f3_dot(c, c));
        const float *em = scene->materials[ref->tri_material[t]].emissive;
        float lum_in[3] = {fmaxf(em[0], 0.0f), fmaxf(em[1], 0.0f), fmaxf(em[2], 0.0f)};
        double power = area > 0.0f && area < INFINITY ? area * rb_ref_luminance(lum_in) : 0.0;
        ref->emit_pdf_area[t] = area; /* until the CDF is known */
        total += power;
        ref->emitter_cdf[e + 1] = (float)total;
    }
    for (uint32_t e = 0; e < ref->emitter_total; e++)
        ref->emitter_cdf[e + 1] = total > 0.0 ? (float)(ref->emitter_cdf[e + 1] / total) : 0.0f;
    if (ref->emitter_total && total > 0.0)
        ref->emitter_cdf[ref->emitter_total] = 1.0f;
    for (uint32_t e = 0; e < ref->emitter_total; e++) {
        uint32_t t = ref->emitters[e];
        float p = ref->emitter_cdf[e + 1] - ref->emitter_cdf[e], area = ref->emit_pdf_area[t];
        ref->emit_pdf_area[t] = p > 0.0f && area > 0.0f ? p / area : 0.0f;
    }
    ref->world.emitter_count = total > 0.0 ? ref->emitter_total : 0;
}

/* The cameras of a rendered frame at t and the frame before it (t_prev), with the previous
 * pose's vertices for the motion vectors; after prepare_world, whose pose the camera reads. */
static enum rb_status prepare_camera(struct rb_reference *ref, double t, double t_prev,
                                     struct rb_err *err)
{
    const struct rb_job *job = ref->job;
    rb_scene_evaluate(ref->scene, &ref->sel, t_prev, ref->prev_pose);
    enum rb_status st = rb_camera_evaluate(job, ref->scene, &ref->setup, ref->prev_pose, t_prev,
                                           &ref->prev_cam, err);
    if (st)
        return st;
    rb_scene_deform(ref->scene, ref->prev_pose, ref->prev_pos, 3, NULL, NULL, NULL);
    if ((st = rb_camera_evaluate(job, ref->scene, &ref->setup, ref->pose, t, &ref->cam, err)))
        return st;
    float aspect = (float)ref->width_px / (float)ref->height_px;
    struct rb_mat4 proj =
        rb_mat4_perspective(ref->cam.fov_y_rad, aspect, ref->cam.z_near, ref->cam.z_far);
    ref->world_to_ndc = rb_mat4_mul(&proj, &ref->cam.world_to_camera);
    struct rb_mat4 pproj = rb_mat4_perspective(ref->prev_cam.fov_y_rad, aspect,
                                               ref->prev_cam.z_near, ref->prev_cam.z_far);
    ref->prev_world_to_ndc = rb_mat4_mul(&pproj, &ref->prev_cam.world_to_camera);
    /* the view axis (-Z of the camera) in world space: row 2 of the view's rotation, negated */
    const struct rb_mat4 *v = &ref->cam.world_to_camera;
    float fwd[3] = {-v->m[0][2], -v->m[1][2], -v->m[2][2]};
    float len = sqrtf(rb_f3_dot(fwd, fwd));
    for (int i = 0; i < 3; i++)
        ref->cam_forward[i] = len > 0.0f ? fwd[i] / len : 0.0f;
    return RB_OK;
}

/* The world of frame (time t) that rays see: the pose's vertices, lights, emitters, the Embree
 * scene and the world struct the samples read. The bake needs this alone. */
static enum rb_status prepare_world(struct rb_reference *ref, int frame, double t,
                                    struct rb_err *err)
{
    const struct rb_job *job = ref->job;
    rb_scene_evaluate(ref->scene, &ref->sel, t, ref->pose);
    rb_scene_deform(ref->scene, ref->pose, ref->pos, 4, ref->nrm, ref->tan, ref->uv);
    enum rb_status st = update_lights(ref, err);
    if (st)
        return st;
    update_emitters(ref);

    if (ref->rtc) {
        rtcUpdateGeometryBuffer(ref->geom, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(ref->geom);
        rtcCommitScene(ref->rtc);
        if ((st = embree_check(ref, "building the BVH", err)))
            return st;
    }

    struct rb_ref_world *w = &ref->world;
    w->scene = ref->scene;
    w->mat_flags = ref->mat_flags;
    w->has_blend = ref->has_blend;
    w->srgb_lut = ref->srgb_lut;
    w->vertex_count = ref->vertex_count;
    w->tri_count = ref->tri_count;
    w->pos = ref->pos;
    w->prev_pos = ref->prev_pos;
    w->nrm = ref->nrm;
    w->tan = ref->tan;
    w->uv = ref->uv;
    w->tris = ref->tris;
    w->tri_material = ref->tri_material;
    w->rtc = ref->rtc;
    w->lights = ref->lights;
    w->emitters = ref->emitters;
    w->emitter_cdf = ref->emitter_cdf;
    w->emit_pdf_area = ref->emit_pdf_area;
    w->env = &ref->env;
    w->paths = paths_of(job);
    w->max_bounces = job->integrator.reference.max_bounces;
    w->rr_depth = job->integrator.reference.rr_depth;
    w->frame = (uint32_t)frame;
    w->is_hashed_sampler = ref->is_hashed_sampler;
    return RB_OK;
}

/* ---- pixels --------------------------------------------------------------------------------- */

static void project_px(const struct rb_mat4 *m, const float p[3], float w, float h, float out[2])
{
    struct rb_vec4 c = rb_mat4_vec4(m, (struct rb_vec4){p[0], p[1], p[2], 1.0f});
    out[0] = (c.x / c.w * 0.5f + 0.5f) * w;
    out[1] = (c.y / c.w * 0.5f + 0.5f) * h;
}

/* The unit direction of the camera ray through (sx, sy) in pixels (pixel x's centre is at
 * x + 0.5). */
static void camera_dir(const struct rb_reference *ref, const struct rb_mat4 *inv_vp, float sx,
                       float sy, float dir[3])
{
    float ndc_x = sx / (float)ref->width_px * 2.0f - 1.0f;
    float ndc_y = sy / (float)ref->height_px * 2.0f - 1.0f;
    struct rb_vec4 far = rb_mat4_vec4(inv_vp, (struct rb_vec4){ndc_x, ndc_y, 1.0f, 1.0f});
    dir[0] = far.x / far.w - ref->cam.position.x;
    dir[1] = far.y / far.w - ref->cam.position.y;
    dir[2] = far.z / far.w - ref->cam.position.z;
    float len = sqrtf(rb_f3_dot(dir, dir));
    for (int k = 0; k < 3; k++)
        dir[k] = len > 0.0f ? dir[k] / len : 0.0f;
}

/* The first hit of a camera ray with direction dir (unit). */
static void camera_hit(const struct rb_reference *ref, const float dir[3], struct rb_ref_hit *hit,
                       uint64_t *rays)
{
    /* The rasterizer clips at the near and far planes, which are view depths. */
    float cos_fwd = rb_f3_dot(dir, ref->cam_forward);
    hit->prim = RB_REF_NONE;
    if (cos_fwd > 0.0f) {
        float org[3] = {ref->cam.position.x, ref->cam.position.y, ref->cam.position.z};
        rb_ref_intersect(&ref->world, true, org, dir, ref->cam.z_near / cos_fwd,
                         ref->cam.z_far / cos_fwd, hit);
        (*rays)++;
    }
}

/* The blended layers a camera ray along dir crosses in front of its hit (the far plane on a
 * miss), nearest first: their count into layers. */
static uint32_t camera_layers(const struct rb_reference *ref, const float dir[3],
                              const struct rb_ref_hit *hit, struct rb_ref_hit *layers)
{
    float cos_fwd = rb_f3_dot(dir, ref->cam_forward);
    if (!ref->world.has_blend || !(cos_fwd > 0.0f))
        return 0;
    float org[3] = {ref->cam.position.x, ref->cam.position.y, ref->cam.position.z};
    float tfar = hit->prim == RB_REF_NONE ? ref->cam.z_far / cos_fwd : hit->t;
    return rb_ref_blend_layers(&ref->world, org, dir, ref->cam.z_near / cos_fwd, tfar, layers);
}

/* The transparency pass's composite, for one sample: the blended layers a camera ray along dir
 * crosses before hit, farthest first, each over what lies behind it (premultiplied by its
 * alpha, base colour factor x texture): its direct light is added to the direct layer, the
 * light behind passes scaled by 1 - alpha (indirect and its lobes included); *coverage (1 on a
 * hit, 0 on a miss) becomes the alpha the layers and the hit cover together. */
static void composite_layers(const struct rb_reference *ref, const float dir[3],
                             const struct rb_ref_hit *hit, const struct rb_ref_rng *rng,
                             struct rb_ref_sample_light *light, double *coverage, uint64_t *rays)
{
    const struct rb_ref_world *w = &ref->world;
    struct rb_ref_hit layers[RB_REF_MAX_LAYERS];
    uint32_t n = camera_layers(ref, dir, hit, layers);
    for (uint32_t k = n; k-- > 0;) {
        float a = rb_clampf(rb_ref_alpha(w, layers[k].prim, layers[k].u, layers[k].v), 0, 1);
        if (!(a > 0.0f))
            continue; /* the transparency pass discards it */
        struct rb_ref_sample_light ls = {0};
        rb_ref_trace_direct(w, &layers[k], dir, rng, &ls, rays);
        for (int c = 0; c < 3; c++) {
            light->direct[c] = a * ls.direct[c] + (1.0f - a) * light->direct[c];
            light->indirect[c] *= 1.0f - a;
            for (int j = 0; j < RB_REF_LOBE_COUNT; j++)
                light->indirect_lobe[j][c] *= 1.0f - a;
        }
        *coverage = a + (1.0 - a) * *coverage;
    }
}

/* The camera ray through the centre of pixel (x, y), its first hit, and the AOVs (or the
 * environment on a miss). */
static void primary_pixel(struct rb_reference *ref, const struct rb_mat4 *inv_vp, uint32_t x,
                          uint32_t y, uint64_t *rays)
{
    const struct rb_ref_world *w = &ref->world;
    size_t i = (size_t)y * ref->width_px + x;
    float *o = ref->pixels + i * RB_OUT_FLOATS;
    float fw = (float)ref->width_px, fh = (float)ref->height_px;
    float dir[3];
    camera_dir(ref, inv_vp, (float)x + 0.5f, (float)y + 0.5f, dir);
    memcpy(ref->primary_dir + i * 3, dir, sizeof(dir));
    memset(o, 0, RB_OUT_FLOATS * sizeof(float));
    struct rb_ref_hit *hit = &ref->primary[i];
    camera_hit(ref, dir, hit, rays);
    struct rb_ref_hit layers[RB_REF_MAX_LAYERS];
    ref->layered[i] = camera_layers(ref, dir, hit, layers) > 0;
    if (hit->prim == RB_REF_NONE) {
        float env[3];
        rb_ref_env_eval(&ref->env, dir, env);
        memcpy(o + RB_OUT_BEAUTY, env, sizeof(env));
        memcpy(o + RB_OUT_DIRECT, env, sizeof(env));
        return;
    }
    struct rb_ref_surface s;
    rb_ref_surface_eval(w, hit->prim, hit->u, hit->v, dir, &s);
    memcpy(o + RB_OUT_ALBEDO, s.c_diff, sizeof(s.c_diff));
    memcpy(o + RB_OUT_NORMAL, s.n, sizeof(s.n));
    struct rb_vec3 vp = rb_mat4_point(&ref->cam.world_to_camera, rb_v3(s.p[0], s.p[1], s.p[2]));
    o[RB_OUT_DEPTH] = -vp.z;
    const uint32_t *tri = &w->tris[(size_t)hit->prim * 3];
    float b0 = 1.0f - hit->u - hit->v, prev[3];
    for (int c = 0; c < 3; c++)
        prev[c] = b0 * w->prev_pos[tri[0] * 3 + c] + hit->u * w->prev_pos[tri[1] * 3 + c] +
                  hit->v * w->prev_pos[tri[2] * 3 + c];
    float cur_px[2], prev_px[2];
    project_px(&ref->world_to_ndc, s.p, fw, fh, cur_px);
    project_px(&ref->prev_world_to_ndc, prev, fw, fh, prev_px);
    o[RB_OUT_MOTION + 0] = prev_px[0] - cur_px[0];
    o[RB_OUT_MOTION + 1] = prev_px[1] - cur_px[1];
}

/* Samples [s0, s1) of pixel (x, y): all through the centre ray found by primary_pixel, or each
 * through its own point of the pixel (box filter), which may miss. */
static void trace_pixel(struct rb_reference *ref, const struct rb_mat4 *inv_vp, uint32_t x,
                        uint32_t y, uint32_t s0, uint32_t s1, uint64_t *rays)
{
    const struct rb_ref_world *w = &ref->world;
    size_t i = (size_t)y * ref->width_px + x;
    const struct rb_ref_hit *hit = &ref->primary[i];
    if (!ref->use_box_filter && hit->prim == RB_REF_NONE && !ref->layered[i])
        return;
    double *acc = ref->accum + i * ACCUM;
    if (!ref->use_box_filter && w->paths == RB_PATHS_DIRECT && s0 > 0) {
        /* No random numbers in this path space: every sample is the first one. The sums stay
         * exact (s0 copies of a float, divided by s0, times s1). */
        for (int c = 0; c < ACCUM; c++)
            acc[c] = acc[c] / s0 * s1;
        return;
    }
    for (uint32_t s = s0; s < s1; s++) {
        struct rb_ref_rng rng;
        if (ref->use_replicates) {
            rb_ref_rng_init(&rng, w->is_hashed_sampler, w->frame, (uint32_t)i, s >> 1);
            rb_ref_rng_replicate(&rng, s & 1u);
        } else {
            rb_ref_rng_init(&rng, w->is_hashed_sampler, w->frame, (uint32_t)i, s);
        }
        struct rb_ref_sample_light light = {0};
        if (ref->use_box_filter) {
            float u[2], dir[3];
            rb_ref_rand2(&rng, RB_REF_DIM_PIXEL, u);
            camera_dir(ref, inv_vp, (float)x + u[0], (float)y + u[1], dir);
            struct rb_ref_hit h;
            camera_hit(ref, dir, &h, rays);
            double coverage = 0.0;
            if (h.prim == RB_REF_NONE) {
                rb_ref_env_eval(&ref->env, dir, light.direct);
            } else {
                rb_ref_trace_sample(w, &h, dir, &rng, &light, rays);
                coverage = 1.0;
            }
            composite_layers(ref, dir, &h, &rng, &light, &coverage, rays);
            acc[6] += coverage;
        } else {
            const float *dir = ref->primary_dir + i * 3;
            double coverage = 0.0;
            if (hit->prim == RB_REF_NONE) {
                rb_ref_env_eval(&ref->env, dir, light.direct);
            } else {
                rb_ref_trace_sample(w, hit, dir, &rng, &light, rays);
                coverage = 1.0;
            }
            if (ref->layered[i])
                composite_layers(ref, dir, hit, &rng, &light, &coverage, rays);
            acc[6] += coverage;
        }
        float beauty[3];
        for (int c = 0; c < 3; c++) {
            acc[c] += light.direct[c];
            acc[3 + c] += light.indirect[c];
            acc[7 + c] += light.indirect_lobe[RB_REF_LOBE_DIFFUSE][c];
            acc[10 + c] += light.indirect_lobe[RB_REF_LOBE_SPECULAR][c];
            beauty[c] = light.direct[c] + light.indirect[c];
        }
        acc[ACCUM_LUM + (s & 1u)] += rb_ref_luminance(beauty);
    }
}

/* The variance of a pixel's mean luminance (Rec.709, of the beauty) from its samples' sums:
 * the even samples' and the odd samples' (acc_lum[0] and [1]), done samples in all. The Sobol
 * sampler's samples are not independent (a pixel's net is stratified), so the spread of the
 * samples around their mean overstates the spread of the mean where a pair of dimensions has a
 * smooth integrand. So under the variance layer the even and the odd samples are two
 * replicates, each its own scrambled net (rb_ref_rng_replicate), and their means m0 and m1 (of
 * n0 and n1 samples) are independent: E[(m0 - m1)^2] = var m0 + var m1, and the mean of both,
 * (n0 m0 + n1 m1) / done, has the variance (m0 - m1)^2 n0 n1 / done^2 in expectation (exactly
 * for n0 = n1, taking var m ~ 1/n otherwise). One sample has no replicate to compare with: NaN. */
static double mean_variance(const double acc_lum[2], uint32_t done)
{
    uint32_t n0 = done - done / 2, n1 = done / 2;
    if (n1 == 0)
        return NAN;
    double d = acc_lum[0] / n0 - acc_lum[1] / n1;
    return d * d * ((double)n0 * n1) / ((double)done * done);
}

/* ---- threads -------------------------------------------------------------------------------- */

/* One stage over all rows: the camera rays (is_primary) or samples [s0, s1) of every pixel. */
struct stage {
    struct rb_reference *ref;
    bool is_primary;
    uint32_t s0, s1;
    struct rb_mat4 inv_vp;
    atomic_uint next_row;
    atomic_uint_fast64_t rays;
};

static void *stage_worker(void *arg)
{
    struct stage *st = arg;
    struct rb_reference *ref = st->ref;
    uint64_t rays = 0;
    for (;;) {
        unsigned y = atomic_fetch_add(&st->next_row, 1u);
        if (y >= ref->height_px)
            break;
        for (uint32_t x = 0; x < ref->width_px; x++) {
            if (st->is_primary)
                primary_pixel(ref, &st->inv_vp, x, y, &rays);
            else
                trace_pixel(ref, &st->inv_vp, x, y, st->s0, st->s1, &rays);
        }
    }
    atomic_fetch_add(&st->rays, rays);
    return NULL;
}

/* Runs the stage on the calling thread and up to thread_count - 1 more; a thread that cannot be
 * started only means fewer workers (the rows go to the others, and the bits do not change). */
static uint64_t run_stage(struct rb_reference *ref, struct stage *st)
{
    atomic_init(&st->next_row, 0u);
    atomic_init(&st->rays, 0u);
    pthread_t threads[MAX_THREADS];
    uint32_t want = ref->thread_count < ref->height_px ? ref->thread_count : ref->height_px;
    uint32_t started = 0;
    for (uint32_t i = 1; i < want; i++) {
        if (pthread_create(&threads[started], NULL, stage_worker, st) != 0)
            break;
        started++;
    }
    stage_worker(st);
    for (uint32_t i = 0; i < started; i++)
        pthread_join(threads[i], NULL);
    return atomic_load(&st->rays);
}

/* ---- the bake ------------------------------------------------------------------------------ */

struct bake {
    struct rb_reference *ref;
    const struct rb_reference_bake_point *points;
    uint32_t count, samples;
    float *out;
    atomic_uint next;
    atomic_uint_fast64_t rays;
};

#define BAKE_CHUNK 64

/* Point i on its side: the triangle's face normal, and the interpolated vertex normal turned to
 * the face normal's side (as the BVH's hits shade), both flipped for the back. */
static void bake_point(const struct rb_ref_world *w, const struct rb_reference_bake_point *pt,
                       uint32_t index, uint32_t samples, float out[3], uint64_t *rays)
{
    const uint32_t *tri = pt->vertex;
    const float *p0 = &w->pos[tri[0] * 4], *p1 = &w->pos[tri[1] * 4], *p2 = &w->pos[tri[2] * 4];
    float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    float ng[3], n[3], p[3];
    rb_f3_cross(e1, e2, ng);
    float b0 = 1.0f - pt->u - pt->v;
    for (int c = 0; c < 3; c++)
        n[c] = b0 * w->nrm[tri[0] * 3 + c] + pt->u * w->nrm[tri[1] * 3 + c] +
               pt->v * w->nrm[tri[2] * 3 + c];
    float lg = sqrtf(rb_f3_dot(ng, ng)), ln = sqrtf(rb_f3_dot(n, n));
    out[0] = out[1] = out[2] = 0.0f;
    if (!(lg > 0.0f) || !(lg < INFINITY))
        return;
    float side = pt->is_back ? -1.0f : 1.0f;
    bool has_n = ln > 0.0f && ln < INFINITY;
    for (int c = 0; c < 3; c++) {
        ng[c] *= side / lg;
        n[c] = has_n ? n[c] / ln : ng[c];
    }
    if (rb_f3_dot(n, ng) < 0.0f)
        for (int c = 0; c < 3; c++)
            n[c] = -n[c];
    for (int c = 0; c < 3; c++)
        p[c] = b0 * p0[c] + pt->u * p1[c] + pt->v * p2[c];
    double sum[3] = {0.0, 0.0, 0.0};
    for (uint32_t k = 0; k < samples; k++) {
        struct rb_ref_rng rng;
        rb_ref_rng_init(&rng, w->is_hashed_sampler, 0, index, k);
        float e[3] = {0.0f, 0.0f, 0.0f};
        rb_ref_bake_sample(w, p, n, ng, &rng, e, rays);
        for (int c = 0; c < 3; c++)
            sum[c] += e[c];
    }
    for (int c = 0; c < 3; c++)
        out[c] = (float)(sum[c] / samples);
}

static void *bake_worker(void *arg)
{
    struct bake *bk = arg;
    const struct rb_ref_world *w = &bk->ref->world;
    uint64_t rays = 0;
    for (;;) {
        uint32_t i0 = atomic_fetch_add(&bk->next, BAKE_CHUNK);
        if (i0 >= bk->count)
            break;
        uint32_t i1 = bk->count - i0 < BAKE_CHUNK ? bk->count : i0 + BAKE_CHUNK;
        for (uint32_t i = i0; i < i1; i++)
            bake_point(w, &bk->points[i], i, bk->samples, bk->out + (size_t)i * 3, &rays);
    }
    atomic_fetch_add(&bk->rays, rays);
    return NULL;
}

enum rb_status rb_reference_bake(struct rb_reference *ref, int frame,
                                 const struct rb_reference_bake_point *points, uint32_t count,
                                 uint32_t samples, float *out, uint64_t *rays, struct rb_err *err)
{
    double rate = ref->job->rate_fps > 0.0 ? ref->job->rate_fps : 1.0;
    enum rb_status st = prepare_world(ref, frame, frame / rate, err);
    if (st) {
        rb_err_prefix(err, "the baked light of frame %d", frame);
        return st;
    }
    for (uint32_t i = 0; i < count; i++)
        for (int k = 0; k < 3; k++)
            if (points[i].vertex[k] >= ref->vertex_count)
                return rb_errf(err, RB_E_INVALID, "bake point %u: vertex %u of %u", i,
                               points[i].vertex[k], ref->vertex_count);
    struct bake bk = {
        .ref = ref, .points = points, .count = count, .samples = samples ? samples : 1, .out = out};
    atomic_init(&bk.next, 0u);
    atomic_init(&bk.rays, 0u);
    pthread_t threads[MAX_THREADS];
    uint32_t chunks = (count + BAKE_CHUNK - 1) / BAKE_CHUNK;
    uint32_t want = ref->thread_count < chunks ? ref->thread_count : chunks;
    uint32_t started = 0;
    for (uint32_t i = 1; i < want; i++) {
        if (pthread_create(&threads[started], NULL, bake_worker, &bk) != 0)
            break;
        started++;
    }
    bake_worker(&bk);
    for (uint32_t i = 0; i < started; i++)
        pthread_join(threads[i], NULL);
    if (rays)
        *rays = atomic_load(&bk.rays);
    return RB_OK;
}

enum rb_status rb_reference_render(struct rb_reference *ref, int frame, struct rb_frame_result *out,
                                   struct rb_err *err)
{
    if (!ref->pixels)
        return rb_errf(err, RB_E_INVALID, "a reference made for baking renders no frames");
    double start = rb_monotonic_s();
    double rate = ref->job->rate_fps > 0.0 ? ref->job->rate_fps : 1.0;
    double t = frame / rate, t_prev = (frame - 1) / rate;
    enum rb_status st = prepare_world(ref, frame, t, err);
    if (st == RB_OK)
        st = prepare_camera(ref, t, t_prev, err);
    if (st) {
        rb_err_prefix(err, "reference frame %d", frame);
        return st;
    }
    double trace_start = rb_monotonic_s();
    size_t px = (size_t)ref->width_px * ref->height_px;
    memset(ref->accum, 0, px * ACCUM * sizeof(double));

    struct rb_mat4 inv_vp = rb_mat4_inverse(&ref->world_to_ndc, NULL);
    struct stage stage = {.ref = ref, .is_primary = true, .inv_vp = inv_vp};
    uint64_t rays = run_stage(ref, &stage);

    uint32_t spp_total =
        ref->job->integrator.reference.spp ? ref->job->integrator.reference.spp : 64;
    double limit = ref->job->integrator.reference.time_limit_s;
    uint32_t done = 0, pass = 1;
    while (done < spp_total) {
        uint32_t n = pass < spp_total - done ? pass : spp_total - done;
        stage = (struct stage){
            .ref = ref, .is_primary = false, .s0 = done, .s1 = done + n, .inv_vp = inv_vp};
        rays += run_stage(ref, &stage);
        done += n;
        if (done > 1 && pass < MAX_PASS_SPP)
            pass *= 2;
        bool go_on = ref->on_pass ? ref->on_pass(ref->user, done, spp_total) : true;
        if (!go_on || (limit > 0.0 && rb_monotonic_s() - start >= limit))
            break;
    }

    double inv = 1.0 / (double)done;
    for (size_t i = 0; i < px; i++) {
        if (!ref->use_box_filter && ref->primary[i].prim == RB_REF_NONE && !ref->layered[i])
            continue; /* the environment, written by the camera ray */
        const double *acc = ref->accum + i * ACCUM;
        float *o = ref->pixels + i * RB_OUT_FLOATS;
        for (int c = 0; c < 3; c++) {
            double d = acc[c] * inv, ind = acc[3 + c] * inv;
            o[RB_OUT_BEAUTY + c] = (float)(d + ind);
            o[RB_OUT_DIRECT + c] = (float)d;
            o[RB_OUT_INDIRECT + c] = (float)ind;
            o[RB_OUT_INDIRECT_DIFFUSE + c] = (float)(acc[7 + c] * inv);
            o[RB_OUT_INDIRECT_SPECULAR + c] = (float)(acc[10 + c] * inv);
        }
        /* box: the fraction of the pixel's samples that hit a surface */
        /* (with blended layers, what they and the hit cover together) */
        o[RB_OUT_BEAUTY + 3] =
            ref->use_box_filter || ref->layered[i] ? (float)(acc[6] / (double)done) : 1.0f;
        /* Every path may take either lobe, so both count every sample; no tile ever stops
         * sampling (tiles stays 0). */
        o[RB_OUT_SAMPLES + 0] = o[RB_OUT_SAMPLES + 1] = (float)done;
        /* The direct path space draws no random numbers under center: no variance (and only
         * sample 0 was traced, its sums scaled). Without the layer, nothing to write. */
        if (!ref->use_replicates || (!ref->use_box_filter && ref->world.paths == RB_PATHS_DIRECT))
            o[RB_OUT_VARIANCE] = 0.0f;
        else
            o[RB_OUT_VARIANCE] = (float)mean_variance(acc + ACCUM_LUM, done);
    }
    /* Every float of the result, as the output pass counts them on the GPU. */
    uint32_t nonfinite = 0;
    for (size_t i = 0; i < px * RB_OUT_FLOATS; i++)
        nonfinite += !isfinite(ref->pixels[i]);
    if (nonfinite)
        rb_log(RB_LOG_WARN, "frame %d: %u non-finite values (NaN or Inf) in the output", frame,
               nonfinite);

    ref->trace = (struct rb_pass_time){
        .name = "trace", .cpu_ms = (rb_monotonic_s() - trace_start) * 1e3, .count = 1};
    *out = (struct rb_frame_result){
        .frame = frame,
        .time_s = t,
        .width_px = ref->width_px,
        .height_px = ref->height_px,
        .pixels = ref->pixels,
        .floats_per_pixel = RB_OUT_FLOATS,
        .layer_mask = RB_LAYERS_ALL,
        .passes = &ref->trace,
        .pass_count = 1,
        .world_to_camera = ref->cam.world_to_camera,
        .world_to_ndc = ref->world_to_ndc,
        .spp = done,
        .ray_count = rays,
        .nonfinite_count = nonfinite,
    };
    return RB_OK;
}
