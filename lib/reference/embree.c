/* Ray casting for the reference through Embree 3: closest hits and shadow rays against the one
 * world-space triangle mesh, with a filter that does what the rasterizer's discards do (alpha
 * MASK for every ray; back faces of single-sided materials for camera rays only, since the
 * shadow maps cull nothing; alpha BLEND for every ray, as the deferred passes and the shadow
 * maps leave blended triangles out), and the blended layers a camera ray crosses, which the
 * transparency pass draws over the frame. */
#include "reference/reference_int.h"

#include <math.h>
#include <stdlib.h>
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

/* The potential hit's distance: the ray's tfar while the filter runs. */
static float ray_tfar(const struct RTCFilterFunctionNArguments *a, unsigned i)
{
    return ((const float *)a->ray)[8 * a->N + i];
}

/* Records a blended hit once (Embree may offer a triangle more than once), dropping it when the
 * list is full; the caller sorts. */
static void record_layer(struct rb_ref_ray_ctx *ctx, const struct RTCFilterFunctionNArguments *a,
                         unsigned i, uint32_t prim)
{
    for (uint32_t k = 0; k < ctx->layer_count; k++)
        if (ctx->layers[k].prim == prim)
            return;
    struct rb_ref_hit h = {
        .prim = prim, .u = hit_float(a, 3, i), .v = hit_float(a, 4, i), .t = ray_tfar(a, i)};
    if (ctx->layer_count < ctx->layer_cap) {
        ctx->layers[ctx->layer_count++] = h;
        return;
    }
    /* Full: keep the nearest (the list's farthest gives way), so the bits do not depend on
     * the order Embree offers them in. */
    uint32_t far = 0;
    for (uint32_t k = 1; k < ctx->layer_count; k++)
        if (ctx->layers[k].t > ctx->layers[far].t ||
            (ctx->layers[k].t == ctx->layers[far].t && ctx->layers[k].prim > ctx->layers[far].prim))
            far = k;
    if (h.t < ctx->layers[far].t || (h.t == ctx->layers[far].t && h.prim < ctx->layers[far].prim))
        ctx->layers[far] = h;
}

void rb_ref_filter(const struct RTCFilterFunctionNArguments *args)
{
    struct rb_ref_ray_ctx *ctx = (struct rb_ref_ray_ctx *)args->context;
    const struct rb_ref_world *w = ctx->world;
    for (unsigned i = 0; i < args->N; i++) {
        if (!args->valid[i])
            continue;
        uint32_t prim = hit_prim(args, i);
        uint8_t flags = w->mat_flags[w->tri_material[prim]];
        if (!(flags & (RB_REF_MAT_MASKED | RB_REF_MAT_SINGLE_SIDED | RB_REF_MAT_BLEND)))
            continue;
        if (ctx->layers) { /* collecting: only blended triangles count, and none is hit */
            args->valid[i] = 0;
            if (!(flags & RB_REF_MAT_BLEND))
                continue;
        } else if (flags & RB_REF_MAT_BLEND) {
            args->valid[i] = 0;
            continue;
        }
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
        if (ctx->layers) {
            record_layer(ctx, args, i, prim);
            continue;
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
    ctx->layers = NULL;
    ctx->layer_count = ctx->layer_cap = 0;
}

/* A ray from org along dir over [tnear, tfar], no hit yet. */
static void ray_hit_init(struct RTCRayHit *rh, const float org[3], const float dir[3], float tnear,
                         float tfar)
{
    memset(rh, 0, sizeof(*rh));
    rh->ray.org_x = org[0];
    rh->ray.org_y = org[1];
    rh->ray.org_z = org[2];
    rh->ray.dir_x = dir[0];
    rh->ray.dir_y = dir[1];
    rh->ray.dir_z = dir[2];
    rh->ray.tnear = tnear;
    rh->ray.tfar = tfar;
    rh->ray.mask = UINT32_MAX;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
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
    ray_hit_init(&rh, org, dir, tnear, tfar);
    rtcIntersect1(w->rtc, &ctx.rtc, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return;
    hit->prim = rh.hit.primID;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->t = rh.ray.tfar;
}

static int nearer_first(const void *a, const void *b)
{
    const struct rb_ref_hit *x = a, *y = b;
    if (x->t != y->t)
        return x->t < y->t ? -1 : 1;
    return x->prim < y->prim ? -1 : x->prim > y->prim;
}

uint32_t rb_ref_blend_layers(const struct rb_ref_world *w, const float org[3], const float dir[3],
                             float tnear, float tfar, struct rb_ref_hit *layers)
{
    if (!w->rtc || !w->has_blend)
        return 0;
    struct rb_ref_ray_ctx ctx;
    ctx_init(&ctx, w, true);
    ctx.layers = layers;
    ctx.layer_cap = RB_REF_MAX_LAYERS;
    struct RTCRayHit rh;
    ray_hit_init(&rh, org, dir, tnear, tfar);
    rtcIntersect1(w->rtc, &ctx.rtc, &rh); /* the filter rejects every hit: all are offered */
    qsort(layers, ctx.layer_count, sizeof(*layers), nearer_first);
    return ctx.layer_count;
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
