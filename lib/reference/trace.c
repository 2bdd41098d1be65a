/* The reference's path integrator: one sample of one pixel. Unidirectional path tracing from the
 * camera's first hit, next-event estimation at every vertex (each punctual light with an exact
 * shadow ray; one emissive triangle by power; one environment direction) and BSDF sampling,
 * the two combined with the power heuristic (beta = 2) for the emitters and the environment.
 * Punctual lights are deltas: light sampling only. Which vertices may do what follows the path
 * space (enum rb_path_space); see the header comment of reference.c. */
#include "reference/reference_int.h"

#include <math.h>

/* Random dimensions: a block per path vertex, after the camera's. Even offsets start 2D pairs
 * (sample.c): the three 2D integrals get one each, the 1D choices share the rest. */
enum {
    DIM_DIR = 0,     /* and 1: the BSDF sample's direction */
    DIM_EMIT_UV = 2, /* and 3: the point on the emissive triangle */
    DIM_ENV_UV = 4,  /* and 5: the environment's direction */
    DIM_LOBE = 6,
    DIM_EMIT_PICK = 7,
    DIM_RR = 8,
    DIMS_PER_VERTEX = 16
};

/* Shadow rays stop this fraction short of the light's point. */
#define SHADOW_SHORTEN 1e-4f

/* The shadow ray from org (already off the surface) toward point q: true when something is in
 * between. It is aimed from org itself: a ray aimed from the surface point but started at org
 * runs parallel to the intended one, off by the offset, and near a surface nearly parallel to
 * the ray it crosses that surface before its end. */
static bool occluded_toward(const struct rb_ref_world *w, const float org[3], const float q[3],
                            uint64_t *rays)
{
    float d[3] = {q[0] - org[0], q[1] - org[1], q[2] - org[2]};
    float dist = sqrtf(rb_f3_dot(d, d));
    if (!(dist > 0.0f))
        return false;
    float l[3] = {d[0] / dist, d[1] / dist, d[2] / dist};
    (*rays)++;
    return rb_ref_occluded(w, org, l, dist * (1.0f - SHADOW_SHORTEN));
}

static float power_heuristic(float a, float b)
{
    if (!(a < INFINITY))
        return 1.0f;
    if (!(b < INFINITY))
        return 0.0f;
    float a2 = a * a, b2 = b * b;
    return a2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

/* True for no light, and for what single precision could not evaluate (a GGX peak near a
 * mirror overflows), which is dropped rather than spread as NaN. */
static bool is_black(const float c[3])
{
    return !(c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f) || !(c[0] + c[1] + c[2] < INFINITY);
}

/* Where a vertex's light goes: acc gains beta x the light; past x1, each lobe's acc gains the
 * same light through that lobe of x1 alone (its beta starts from x1's weight for that lobe). */
struct sink {
    const float *beta;
    float *acc;
    bool has_lobes;
    float (*lobe_beta)[3], (*lobe_acc)[3];
};

static void add_scaled(const struct sink *sk, const float a[3], const float b[3], float s)
{
    for (int i = 0; i < 3; i++)
        sk->acc[i] += sk->beta[i] * a[i] * b[i] * s;
    for (int j = 0; sk->has_lobes && j < RB_REF_LOBE_COUNT; j++)
        for (int i = 0; i < 3; i++)
            sk->lobe_acc[j][i] += sk->lobe_beta[j][i] * a[i] * b[i] * s;
}

/* Every punctual light, as shaders/direct.comp lights a G-buffer pixel, with a shadow ray in
 * place of the shadow map. */
static void nee_punctual(const struct rb_ref_world *w, const struct rb_ref_surface *s,
                         const struct rb_ref_bsdf *b, const struct sink *sk, uint64_t *rays)
{
    static const float one[3] = {1.0f, 1.0f, 1.0f};
    for (uint32_t i = 0; i < w->light_count; i++) {
        const struct rb_ref_light *L = &w->lights[i];
        float l[3], dist, atten;
        if (L->type == RB_LIGHT_DIRECTIONAL) {
            l[0] = -L->direction[0];
            l[1] = -L->direction[1];
            l[2] = -L->direction[2];
            dist = INFINITY;
            atten = 1.0f;
        } else {
            float d[3] = {L->position[0] - s->p[0], L->position[1] - s->p[1],
                          L->position[2] - s->p[2]};
            dist = sqrtf(rb_f3_dot(d, d));
            float inv = 1.0f / rb_ref_maxf(dist, 1e-8f);
            l[0] = d[0] * inv;
            l[1] = d[1] * inv;
            l[2] = d[2] * inv;
            atten = rb_ref_light_falloff(dist, L->range);
            if (L->type == RB_LIGHT_SPOT) {
                float to_surface[3] = {-l[0], -l[1], -l[2]};
                atten *= rb_ref_spot_factor(L->direction, to_surface, L->cos_inner, L->cos_outer);
            } else if (L->type == RB_LIGHT_EMITTER) {
                atten *= fabsf(rb_f3_dot(L->direction, l)); /* emission leaves both sides */
            }
        }
        float ndl = rb_f3_dot(s->n, l);
        if (ndl <= 0.0f || atten <= 0.0f || rb_f3_dot(s->ng, l) <= 0.0f)
            continue;
        float f[3];
        rb_reference_brdf(s->n, b->v, l, s->c_diff, s->f0, s->f90, s->roughness, f);
        float c[3];
        for (int j = 0; j < 3; j++)
            c[j] = f[j] * L->color[j] * atten * ndl;
        if (is_black(c))
            continue;
        /* Shaded at the surface point, as direct.comp does; the shadow ray leaves from off the
         * surface, toward the light's position (or along the directional light's rays). */
        float org[3];
        rb_ref_offset(s->p, s->ng, org);
        bool is_blocked;
        if (dist < INFINITY) {
            is_blocked = occluded_toward(w, org, L->position, rays);
        } else {
            (*rays)++;
            is_blocked = rb_ref_occluded(w, org, l, INFINITY);
        }
        if (is_blocked)
            continue;
        add_scaled(sk, c, one, 1.0f); /* exact: beta x c */
    }
}

static uint32_t pick_emitter(const struct rb_ref_world *w, float u)
{
    uint32_t lo = 0, hi = w->emitter_count;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (w->emitter_cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    while (lo + 1 < w->emitter_count && !(w->emitter_cdf[lo + 1] > w->emitter_cdf[lo]))
        lo++;
    return w->emitters[lo];
}

/* Triangle prim's unit face normal (zero for a degenerate one). */
static void face_normal(const struct rb_ref_world *w, uint32_t prim, float n[3])
{
    const uint32_t *tri = &w->tris[(size_t)prim * 3];
    const float *p0 = &w->pos[tri[0] * 4], *p1 = &w->pos[tri[1] * 4], *p2 = &w->pos[tri[2] * 4];
    float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    rb_f3_cross(e1, e2, n);
    float len = sqrtf(rb_f3_dot(n, n));
    for (int i = 0; i < 3; i++)
        n[i] = len > 0.0f ? n[i] / len : 0.0f;
}

/* |cos| between triangle prim's face and unit direction l. */
static float face_cos(const struct rb_ref_world *w, uint32_t prim, const float l[3])
{
    float n[3];
    face_normal(w, prim, n);
    return fabsf(rb_f3_dot(n, l));
}

/* One point on one emissive triangle, chosen by power, then uniformly by area. Direction,
 * distance and pdf are measured from the shadow ray's origin off the surface, as the BSDF
 * samples' hits are (their distance is from the same origin), so the two MIS weights agree. */
static void nee_area(const struct rb_ref_world *w, const struct rb_ref_surface *s,
                     const struct rb_ref_bsdf *b, const struct sink *sk,
                     const struct rb_ref_rng *rng, uint32_t dim, uint64_t *rays)
{
    uint32_t prim = pick_emitter(w, rb_ref_rand(rng, dim + DIM_EMIT_PICK));
    float uv[2];
    rb_ref_rand2(rng, dim + DIM_EMIT_UV, uv);
    float su = sqrtf(uv[0]), r = uv[1];
    float bu = su * (1.0f - r), bv = su * r;
    float q[3], org[3];
    rb_ref_hit_point(w, prim, bu, bv, q);
    rb_ref_offset(s->p, s->ng, org);
    float d[3] = {q[0] - org[0], q[1] - org[1], q[2] - org[2]};
    float dist2 = rb_f3_dot(d, d), dist = sqrtf(dist2);
    if (!(dist > 0.0f))
        return;
    float l[3] = {d[0] / dist, d[1] / dist, d[2] / dist};
    float ne[3];
    face_normal(w, prim, ne);
    float cos_l = fabsf(rb_f3_dot(ne, l));
    if (!(cos_l > 0.0f))
        return;
    float pdf = w->emit_pdf_area[prim] * dist2 / cos_l;
    if (!(pdf > 0.0f) || !(pdf < INFINITY))
        return;
    float f[3], le[3];
    rb_ref_bsdf_eval(b, l, f);
    if (is_black(f))
        return;
    rb_ref_emission(w, prim, bu, bv, le);
    if (is_black(le))
        return;
    /* The ray ends just off the emitter on org's side, so that it cannot hit the emitter
     * itself (a relative shortening alone leaves a gap of only a few ulps when the ray is
     * nearly parallel to the emitter). */
    if (rb_f3_dot(ne, l) > 0.0f)
        for (int i = 0; i < 3; i++)
            ne[i] = -ne[i];
    float q_off[3];
    rb_ref_offset(q, ne, q_off);
    if (occluded_toward(w, org, q_off, rays))
        return;
    /* A blended emitter is a light no BSDF sample can hit (no ray hits blended triangles): its
     * light samples are its only strategy. */
    bool is_blended = w->mat_flags[w->tri_material[prim]] & RB_REF_MAT_BLEND;
    float mis = is_blended ? 1.0f : power_heuristic(pdf, rb_ref_bsdf_pdf(b, l));
    add_scaled(sk, f, le, mis / pdf);
}

/* The environment is at infinity: a shadow ray along l from anywhere near the surface aims at
 * the same light. */
static void nee_env(const struct rb_ref_world *w, const struct rb_ref_surface *s,
                    const struct rb_ref_bsdf *b, const struct sink *sk,
                    const struct rb_ref_rng *rng, uint32_t dim, uint64_t *rays)
{
    float l[3], u[2];
    rb_ref_rand2(rng, dim + DIM_ENV_UV, u);
    float pdf = rb_ref_env_sample(w->env, s->n, u[0], u[1], l);
    if (!(pdf > 0.0f))
        return;
    float f[3], le[3];
    rb_ref_bsdf_eval(b, l, f);
    if (is_black(f))
        return;
    rb_ref_env_eval(w->env, l, le);
    if (is_black(le))
        return;
    float org[3];
    rb_ref_offset(s->p, s->ng, org);
    (*rays)++;
    if (rb_ref_occluded(w, org, l, INFINITY))
        return;
    add_scaled(sk, f, le, power_heuristic(pdf, rb_ref_bsdf_pdf(b, l)) / pdf);
}

/* rb_ref_trace_sample, or with is_direct_only rb_ref_trace_direct: the path stops at x1. */
static void trace(const struct rb_ref_world *w, const struct rb_ref_hit *hit, const float dir0[3],
                  const struct rb_ref_rng *rng, bool is_direct_only,
                  struct rb_ref_sample_light *out, uint64_t *rays)
{
    struct rb_ref_surface s;
    rb_ref_surface_eval(w, hit->prim, hit->u, hit->v, dir0, &s);
    for (int i = 0; i < 3; i++)
        out->direct[i] += s.emission[i];

    /* How many bounces past x1 the path may take, and what each vertex may gather. Emitters
     * light as punctual lights do, at every vertex up to the last one, by light sample and by
     * that vertex's BSDF sample: both make a path with the same scatterings (emitter -> x_k ->
     * ... -> x1), so the BSDF sample from the last vertex finds emitters but goes no further. */
    uint32_t bounces = w->max_bounces;
    bool has_area = w->paths != RB_PATHS_DIRECT && w->emitter_count > 0;
    bool has_env = w->paths != RB_PATHS_DIRECT && !w->env->is_black;
    if (w->paths == RB_PATHS_DIRECT || is_direct_only)
        bounces = 0;
    else if (w->paths == RB_PATHS_BDPT && bounces > 2)
        bounces = 2;

    float beta[3] = {1.0f, 1.0f, 1.0f}, dir[3] = {dir0[0], dir0[1], dir0[2]};
    float lobe_beta[RB_REF_LOBE_COUNT][3] = {{0}};
    for (uint32_t k = 1;; k++) {
        struct sink sk = {.beta = beta,
                          .acc = k == 1 ? out->direct : out->indirect,
                          .has_lobes = k > 1,
                          .lobe_beta = lobe_beta,
                          .lobe_acc = out->indirect_lobe};
        bool do_area = has_area;
        bool do_env = has_env && (w->paths == RB_PATHS_FULL || k == 1);
        bool do_continue = k <= bounces;
        uint32_t dim = RB_REF_DIM_CAMERA_END + (k - 1) * DIMS_PER_VERTEX;
        float v[3] = {-dir[0], -dir[1], -dir[2]};
        struct rb_ref_bsdf b;
        rb_ref_bsdf_init(&b, &s, v);

        nee_punctual(w, &s, &b, &sk, rays);
        if (do_area)
            nee_area(w, &s, &b, &sk, rng, dim, rays);
        if (do_env)
            nee_env(w, &s, &b, &sk, rng, dim, rays);
        if (!do_continue && !do_area && !do_env)
            break;

        /* The BSDF sample: it finds emitters and the environment (MIS'd against the light
         * samples above) and, where allowed, the next vertex. */
        float l[3], weight[3], lobe_weight[RB_REF_LOBE_COUNT][3], u[2];
        rb_ref_rand2(rng, dim + DIM_DIR, u);
        float pdf = rb_ref_bsdf_sample(&b, rb_ref_rand(rng, dim + DIM_LOBE), u[0], u[1], l, weight,
                                       lobe_weight);
        if (!(pdf > 0.0f) || is_black(weight))
            break;
        float org[3];
        rb_ref_offset(s.p, s.ng, org);
        struct rb_ref_hit h;
        rb_ref_intersect(w, false, org, l, 0.0f, INFINITY, &h);
        (*rays)++;
        if (h.prim == RB_REF_NONE) {
            if (do_env) {
                float le[3];
                rb_ref_env_eval(w->env, l, le);
                float mis = power_heuristic(pdf, rb_ref_env_pdf(w->env, s.n, l));
                add_scaled(&sk, weight, le, mis);
            }
            break;
        }
        if (!do_area && !do_continue)
            break;
        struct rb_ref_surface next;
        rb_ref_surface_eval(w, h.prim, h.u, h.v, l, &next);
        if (do_area && !is_black(next.emission)) {
            float cos_l = face_cos(w, h.prim, l);
            float pdf_light =
                cos_l > 0.0f ? w->emit_pdf_area[h.prim] * h.t * h.t / cos_l : INFINITY;
            add_scaled(&sk, weight, next.emission, power_heuristic(pdf, pdf_light));
        }
        if (!do_continue)
            break;
        for (int i = 0; i < 3; i++) {
            beta[i] *= weight[i];
            for (int j = 0; j < RB_REF_LOBE_COUNT; j++) /* x1's own lobe, then the path's */
                lobe_beta[j][i] = k == 1 ? lobe_weight[j][i] : lobe_beta[j][i] * weight[i];
        }
        if (k > w->rr_depth) {
            float q = rb_clampf(rb_ref_maxf(beta[0], rb_ref_maxf(beta[1], beta[2])), 0.05f, 0.95f);
            if (rb_ref_rand(rng, dim + DIM_RR) >= q)
                break;
            for (int i = 0; i < 3; i++) {
                beta[i] /= q;
                for (int j = 0; j < RB_REF_LOBE_COUNT; j++)
                    lobe_beta[j][i] /= q;
            }
        }
        s = next;
        dir[0] = l[0];
        dir[1] = l[1];
        dir[2] = l[2];
    }
}

void rb_ref_trace_sample(const struct rb_ref_world *w, const struct rb_ref_hit *hit,
                         const float dir[3], const struct rb_ref_rng *rng,
                         struct rb_ref_sample_light *out, uint64_t *rays)
{
    trace(w, hit, dir, rng, false, out, rays);
}

void rb_ref_trace_direct(const struct rb_ref_world *w, const struct rb_ref_hit *hit,
                         const float dir[3], const struct rb_ref_rng *rng,
                         struct rb_ref_sample_light *out, uint64_t *rays)
{
    trace(w, hit, dir, rng, true, out, rays);
}

/* One sample of the direct light at a point for the hybrid's bake: one emitter point chosen by
 * power and one environment direction by its importance, each with its shadow ray and without
 * MIS (light sampling alone is unbiased), weighted as a white Lambertian surface reflects them:
 * cos / pi. n is the shading normal and ng the geometric normal, on the side being lit. */
void rb_ref_bake_sample(const struct rb_ref_world *w, const float p[3], const float n[3],
                        const float ng[3], const struct rb_ref_rng *rng, float out[3],
                        uint64_t *rays)
{
    float org[3];
    rb_ref_offset(p, ng, org);
    if (w->emitter_count > 0) {
        uint32_t prim = pick_emitter(w, rb_ref_rand(rng, DIM_EMIT_PICK));
        float uv[2];
        rb_ref_rand2(rng, DIM_EMIT_UV, uv);
        float su = sqrtf(uv[0]), r = uv[1];
        float bu = su * (1.0f - r), bv = su * r;
        float q[3], ne[3], le[3];
        rb_ref_hit_point(w, prim, bu, bv, q);
        float d[3] = {q[0] - org[0], q[1] - org[1], q[2] - org[2]};
        float dist2 = rb_f3_dot(d, d), dist = sqrtf(dist2);
        face_normal(w, prim, ne);
        float l[3] = {d[0] / dist, d[1] / dist, d[2] / dist};
        float cos_l = dist > 0.0f ? fabsf(rb_f3_dot(ne, l)) : 0.0f;
        float cos_s = dist > 0.0f && rb_f3_dot(ng, l) > 0.0f ? rb_f3_dot(n, l) : 0.0f;
        float pdf = w->emit_pdf_area[prim] * dist2 / cos_l;
        rb_ref_emission(w, prim, bu, bv, le);
        if (cos_l > 0.0f && cos_s > 0.0f && pdf > 0.0f && pdf < INFINITY && !is_black(le)) {
            if (rb_f3_dot(ne, l) > 0.0f)
                for (int i = 0; i < 3; i++)
                    ne[i] = -ne[i];
            float q_off[3];
            rb_ref_offset(q, ne, q_off);
            if (!occluded_toward(w, org, q_off, rays))
                for (int i = 0; i < 3; i++)
                    out[i] += le[i] * cos_s / (RB_PI * pdf);
        }
    }
    if (!w->env->is_black) {
        float l[3], u[2], le[3];
        rb_ref_rand2(rng, DIM_ENV_UV, u);
        float pdf = rb_ref_env_sample(w->env, n, u[0], u[1], l);
        float cos_s = pdf > 0.0f && rb_f3_dot(ng, l) > 0.0f ? rb_f3_dot(n, l) : 0.0f;
        if (cos_s > 0.0f) {
            rb_ref_env_eval(w->env, l, le);
            (*rays)++;
            if (!is_black(le) && !rb_ref_occluded(w, org, l, INFINITY))
                for (int i = 0; i < 3; i++)
                    out[i] += le[i] * cos_s / (RB_PI * pdf);
        }
    }
}
