/* Ray casting for the reference through Embree 3: closest hits and shadow rays against the one
 * world-space triangle mesh, with a filter that does what the rasterizer's discards do (alpha
 * MASK for every ray; back faces of single-sided materials for camera rays only, since the
 * shadow maps cull nothing). */
#include "reference/reference_int.h"

#include <math.h>
#include <string.h>

/* Embree's C++-only RTCRayN_* / RTCHitN_* accessors, for C: the packets are structures of
 * arrays of N lanes (rtcore_ray.h). */
static float ray_dir(const struct RTCFilterFunctionNArguments *a, unsigned axis, unsigned i)
{
    return ((const float *)a->ray)[(4 + axis) * a->N + i];
}

static float hit_float(const struct RTCFilterFunctionNArguments *a, unsigned field, unsigned i)
{
    return ((const float *)a->hit)[field * a->N + i];
}

static unsigned hit_prim(const struct RTCFilterFunctionNArguments *a, unsigned i)
{
    return ((const unsigned *)a->hit)[5 * a->N + i];
}

void rb_ref_filter(const struct RTCFilterFunctionNArguments *args)
{
    const struct rb_ref_ray_ctx *ctx = (const struct rb_ref_ray_ctx *)args->context;
    const struct rb_ref_world *w = ctx->world;
    for (unsigned i = 0; i < args->N; i++) {
        if (!args->valid[i])
            continue;
        uint32_t prim = hit_prim(args, i);
        uint8_t flags = w->mat_flags[w->tri_material[prim]];
        if (!(flags & (RB_REF_MAT_MASKED | RB_REF_MAT_SINGLE_SIDED)))
            continue;
        if (ctx->is_camera && (flags & RB_REF_MAT_SINGLE_SIDED)) {
            const uint32_t *tri = &w->tris[(size_t)prim * 3];
            const float *p0 = &w->pos[tri[0] * 4], *p1 = &w->pos[tri[1] * 4];
            const float *p2 = &w->pos[tri[2] * 4];
            float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
            float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            float ng[3];
            rb_f3_cross(e1, e2, ng);
            float d[3] = {ray_dir(args, 0, i), ray_dir(args, 1, i), ray_dir(args, 2, i)};
            if (!(rb_f3_dot(ng, d) < 0.0f)) {
                args->valid[i] = 0;
                continue;
            }
        }
        if (flags & RB_REF_MAT_MASKED) {
            const struct rb_scene_material *m = &w->scene->materials[w->tri_material[prim]];
            float a = rb_ref_alpha(w, prim, hit_float(args, 3, i), hit_float(args, 4, i));
            if (a < m->alpha_cutoff)
                args->valid[i] = 0;
        }
    }
}

static void ctx_init(struct rb_ref_ray_ctx *ctx, const struct rb_ref_world *w, bool is_camera)
{
    rtcInitIntersectContext(&ctx->rtc);
    ctx->rtc.flags =
        is_camera ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    ctx->world = w;
    ctx->is_camera = is_camera;
}

void rb_ref_intersect(const struct rb_ref_world *w, bool is_camera, const float org[3],
                      const float dir[3], float tnear, float tfar, struct rb_ref_hit *hit)
{
    hit->prim = RB_REF_NONE;
    if (!w->rtc)
        return;
    struct rb_ref_ray_ctx ctx;
    ctx_init(&ctx, w, is_camera);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof(rh));
    rh.ray.org_x = org[0];
    rh.ray.org_y = org[1];
    rh.ray.org_z = org[2];
    rh.ray.dir_x = dir[0];
    rh.ray.dir_y = dir[1];
    rh.ray.dir_z = dir[2];
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = UINT32_MAX;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(w->rtc, &ctx.rtc, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return;
    hit->prim = rh.hit.primID;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->t = rh.ray.tfar;
}

bool rb_ref_occluded(const struct rb_ref_world *w, const float org[3], const float dir[3],
                     float tfar)
{
    if (!w->rtc)
        return false;
    struct rb_ref_ray_ctx ctx;
    ctx_init(&ctx, w, false);
    struct RTCRay ray;
    memset(&ray, 0, sizeof(ray));
    ray.org_x = org[0];
    ray.org_y = org[1];
    ray.org_z = org[2];
    ray.dir_x = dir[0];
    ray.dir_y = dir[1];
    ray.dir_z = dir[2];
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.mask = UINT32_MAX;
    rtcOccluded1(w->rtc, &ctx.rtc, &ray);
    return ray.tfar < 0.0f; /* Embree sets tfar to -inf on a hit */
}

static float float_of(int32_t i)
{
    float f;
    memcpy(&f, &i, sizeof(f));
    return f;
}

static int32_t int_of(float f)
{
    int32_t i;
    memcpy(&i, &f, sizeof(i));
    return i;
}

void rb_ref_offset(const float p[3], const float n[3], float out[3])
{
    /* Ray Tracing Gems, chapter 6: a fixed number of ulps away from the surface, and a fixed
     * distance near the origin where ulps get too small. */
    const float origin = 1.0f / 32.0f, float_scale = 1.0f / 65536.0f, int_scale = 256.0f;
    for (int i = 0; i < 3; i++) {
        int32_t of = (int32_t)(int_scale * n[i]);
        float pi = float_of(int_of(p[i]) + (p[i] < 0.0f ? -of : of));
        out[i] = fabsf(p[i]) < origin ? p[i] + float_scale * n[i] : pi;
    }
}

const char *rb_reference_embree_version(void)
{
    return RTC_VERSION_STRING;
}
