/* The glTF BRDF of shaders/common/brdf.glsl in C, and how the reference samples it: one lobe
 * (Lambert, cosine-weighted; or GGX, visible normals after Heitz 2018, "Sampling the GGX
 * Distribution of Visible Normals", JCGT 7(4)) chosen by a Fresnel-weighted albedo estimate, the
 * pdf of both lobes combined (one-sample MIS over the lobes, i.e. the balance heuristic). */
#include "reference/reference_int.h"

#include <math.h>

/* The pieces of the BRDF for one (n, v, l): the GLSL line by line, same clamps, same order of
 * operations, single precision (pow(y, 5) by multiplication). D = a2 / (pi d^2) is left to the
 * caller, so that the sampler can cancel it (see sample_weight). False: no light from l. */
struct brdf_terms {
    float ndl, a2, d, V, fw;
};

static bool brdf_terms(const float n[3], const float v[3], const float l[3], float roughness,
                       struct brdf_terms *t)
{
    float ndl = rb_ref_maxf(rb_f3_dot(n, l), 0.0f);
    float ndv = rb_ref_maxf(rb_f3_dot(n, v), 1e-4f);
    if (ndl <= 0.0f)
        return false;
    float h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
    float hl = sqrtf(rb_f3_dot(h, h));
    if (!(hl > 0.0f))
        return false; /* l == -v: no half vector (the GLSL returns zero too) */
    h[0] /= hl;
    h[1] /= hl;
    h[2] /= hl;
    float ndh = rb_ref_maxf(rb_f3_dot(n, h), 0.0f);
    /* at most 1 as well: with l close to v, rounding can put it over (see brdf.glsl) */
    float vdh = rb_ref_minf(rb_ref_maxf(rb_f3_dot(v, h), 0.0f), 1.0f);
    float a = rb_ref_maxf(roughness * roughness, 1e-4f);
    float a2 = a * a;
    t->ndl = ndl;
    t->a2 = a2;
    t->fw = rb_ref_pow5(1.0f - vdh);
    t->d = ndh * ndh * (a2 - 1.0f) + 1.0f;
    float vis_den =
        ndl * sqrtf(ndv * ndv * (1.0f - a2) + a2) + ndv * sqrtf(ndl * ndl * (1.0f - a2) + a2);
    t->V = vis_den > 0.0f ? 0.5f / vis_den : 0.0f;
    return true;
}

void rb_reference_brdf(const float n[3], const float v[3], const float l[3], const float c_diff[3],
                       const float f0[3], float f90, float roughness, float out[3])
{
    struct brdf_terms t;
    out[0] = out[1] = out[2] = 0.0f;
    if (!brdf_terms(n, v, l, roughness, &t))
        return;
    float D = t.a2 / (RB_PI * t.d * t.d);
    for (int i = 0; i < 3; i++) {
        float F = f0[i] + (f90 - f0[i]) * t.fw;
        out[i] = (1.0f - F) * c_diff[i] / RB_PI + F * D * t.V;
    }
}

/* An orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis,
 * Revisited"). */
void rb_ref_basis(const float n[3], float t[3], float b[3])
{
    float sign = copysignf(1.0f, n[2]);
    float a = -1.0f / (sign + n[2]);
    float c = n[0] * n[1] * a;
    t[0] = 1.0f + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

static void to_local(const struct rb_ref_bsdf *b, const float d[3], float out[3])
{
    out[0] = rb_f3_dot(d, b->t);
    out[1] = rb_f3_dot(d, b->b);
    out[2] = rb_f3_dot(d, b->s->n);
}

static void to_world(const struct rb_ref_bsdf *b, const float d[3], float out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = d[0] * b->t[i] + d[1] * b->b[i] + d[2] * b->s->n[i];
}

void rb_ref_bsdf_init(struct rb_ref_bsdf *b, const struct rb_ref_surface *s, const float v[3])
{
    b->s = s;
    for (int i = 0; i < 3; i++)
        b->v[i] = v[i];
    b->alpha = rb_ref_maxf(s->roughness * s->roughness, 1e-4f);
    rb_ref_basis(s->n, b->t, b->b);
    to_local(b, v, b->vs);
    /* VNDF sampling needs the view above the shading hemisphere: lift it to n.v = 1e-4, the
     * BRDF's own clamp. The pdf below uses the same lifted view, so it stays exact. */
    if (b->vs[2] < 1e-4f) {
        float r = sqrtf(b->vs[0] * b->vs[0] + b->vs[1] * b->vs[1]);
        float z = 1e-4f, k = r > 0.0f ? sqrtf(1.0f - z * z) / r : 0.0f;
        b->vs[0] = r > 0.0f ? b->vs[0] * k : 1.0f;
        b->vs[1] = r > 0.0f ? b->vs[1] * k : 0.0f;
        b->vs[2] = z;
    }

    float ndv = rb_ref_maxf(rb_f3_dot(s->n, v), 1e-4f);
    float fw = rb_ref_pow5(1.0f - ndv);
    float F[3];
    for (int i = 0; i < 3; i++)
        F[i] = s->f0[i] + (s->f90 - s->f0[i]) * fw;
    float ws = rb_ref_maxf(rb_ref_luminance(F), 0.0f);
    float wd = rb_ref_maxf(rb_ref_luminance(s->c_diff), 0.0f);
    bool has_spec = F[0] > 0.0f || F[1] > 0.0f || F[2] > 0.0f;
    if (!has_spec)
        b->p_spec = 0.0f;
    else if (!(wd > 0.0f))
        b->p_spec = 1.0f;
    else /* both lobes: neither starves (a glossy highlight on a bright diffuse base) */
        b->p_spec = rb_clampf(ws / (ws + wd * (1.0f - rb_ref_minf(ws, 1.0f))), 0.1f, 0.9f);
}

void rb_ref_bsdf_eval(const struct rb_ref_bsdf *b, const float l[3], float out[3])
{
    const struct rb_ref_surface *s = b->s;
    float ndl = rb_f3_dot(s->n, l);
    if (ndl <= 0.0f || rb_f3_dot(s->ng, l) <= 0.0f) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    rb_reference_brdf(s->n, b->v, l, s->c_diff, s->f0, s->f90, s->roughness, out);
    for (int i = 0; i < 3; i++)
        out[i] *= ndl;
}

static float ggx_d(float alpha, float cos_h)
{
    float a2 = alpha * alpha;
    float d = cos_h * cos_h * (a2 - 1.0f) + 1.0f;
    return a2 / (RB_PI * d * d);
}

static float smith_g1(float alpha, float cos_v)
{
    float a2 = alpha * alpha;
    return 2.0f * cos_v / (cos_v + sqrtf(a2 + (1.0f - a2) * cos_v * cos_v));
}

/* The specular lobe's pdf for a local direction l: G1(v) D(h) / (4 n.v) over solid angle. */
static float spec_pdf(const struct rb_ref_bsdf *b, const float l[3])
{
    float h[3] = {b->vs[0] + l[0], b->vs[1] + l[1], b->vs[2] + l[2]};
    float hl = sqrtf(rb_f3_dot(h, h));
    if (!(hl > 0.0f))
        return 0.0f;
    float hz = h[2] / hl, vdh = rb_f3_dot(b->vs, h) / hl;
    if (hz <= 0.0f || vdh <= 0.0f)
        return 0.0f;
    return smith_g1(b->alpha, b->vs[2]) * ggx_d(b->alpha, hz) / (4.0f * b->vs[2]);
}

float rb_ref_bsdf_pdf(const struct rb_ref_bsdf *b, const float l[3])
{
    float ll[3];
    to_local(b, l, ll);
    float pd = ll[2] > 0.0f ? ll[2] / RB_PI : 0.0f;
    float ps = b->p_spec > 0.0f ? spec_pdf(b, ll) : 0.0f;
    return b->p_spec * ps + (1.0f - b->p_spec) * pd;
}

static void clear_weights(float weight[3], float lobe_weight[RB_REF_LOBE_COUNT][3])
{
    for (int i = 0; i < 3; i++)
        weight[i] = lobe_weight[RB_REF_LOBE_DIFFUSE][i] = lobe_weight[RB_REF_LOBE_SPECULAR][i] =
            0.0f;
}

/* f cos / pdf for a sampled l, and the pdf, with GGX's D divided out of both. Near a mirror
 * (alpha down at 1e-4) single precision cannot evaluate D = a2 / (pi d^2) at the peak (d loses
 * every digit, down to 0), but it scales the specular value and the specular pdf alike, so
 * their ratio, F V cos 4 (n.v) / G1 for a metal, stays exact. */
static float sample_weight(const struct rb_ref_bsdf *b, const float l[3], float weight[3],
                           float lobe_weight[RB_REF_LOBE_COUNT][3])
{
    const struct rb_ref_surface *s = b->s;
    struct brdf_terms t;
    clear_weights(weight, lobe_weight);
    if (rb_f3_dot(s->ng, l) <= 0.0f || !brdf_terms(s->n, b->v, l, s->roughness, &t))
        return rb_ref_bsdf_pdf(b, l);
    float cos = t.ndl;
    float inv_d = RB_PI * t.d * t.d / t.a2; /* 1 / D, finite, 0 where D overflows */
    float diff_pdf = (1.0f - b->p_spec) * cos / RB_PI;
    float spec_pdf_d = b->p_spec > 0.0f
                           ? b->p_spec * smith_g1(b->alpha, b->vs[2]) / (4.0f * b->vs[2])
                           : 0.0f; /* the specular pdf over D */
    if (spec_pdf_d > 0.0f) {
        float den = spec_pdf_d + diff_pdf * inv_d;
        for (int i = 0; i < 3; i++) {
            float F = s->f0[i] + (s->f90 - s->f0[i]) * t.fw;
            float fd = (1.0f - F) * s->c_diff[i] / RB_PI;
            weight[i] = (F * t.V * cos + fd * cos * inv_d) / den;
            lobe_weight[RB_REF_LOBE_SPECULAR][i] = F * t.V * cos / den;
            lobe_weight[RB_REF_LOBE_DIFFUSE][i] = fd * cos * inv_d / den;
        }
        return inv_d > 0.0f ? den / inv_d : INFINITY;
    }
    /* no specular lobe to sample means no specular reflection (F is 0): Lambert alone */
    if (!(diff_pdf > 0.0f))
        return 0.0f;
    for (int i = 0; i < 3; i++)
        weight[i] = lobe_weight[RB_REF_LOBE_DIFFUSE][i] = s->c_diff[i] / RB_PI * cos / diff_pdf;
    return diff_pdf;
}

float rb_ref_bsdf_sample(const struct rb_ref_bsdf *b, float u_lobe, float u0, float u1, float l[3],
                         float weight[3], float lobe_weight[RB_REF_LOBE_COUNT][3])
{
    float ll[3];
    if (u_lobe < b->p_spec) {
        /* Heitz 2018, listing 1, isotropic alpha. */
        float a = b->alpha;
        float vh[3] = {a * b->vs[0], a * b->vs[1], b->vs[2]};
        float len = sqrtf(rb_f3_dot(vh, vh));
        vh[0] /= len;
        vh[1] /= len;
        vh[2] /= len;
        float lensq = vh[0] * vh[0] + vh[1] * vh[1];
        float t1v[3] = {1.0f, 0.0f, 0.0f};
        if (lensq > 0.0f) {
            float inv = 1.0f / sqrtf(lensq);
            t1v[0] = -vh[1] * inv;
            t1v[1] = vh[0] * inv;
        }
        float t2v[3];
        rb_f3_cross(vh, t1v, t2v);
        float r = sqrtf(u0), phi = 2.0f * RB_PI * u1;
        float t1 = r * cosf(phi), t2 = r * sinf(phi);
        float sh = 0.5f * (1.0f + vh[2]);
        t2 = (1.0f - sh) * sqrtf(rb_ref_maxf(1.0f - t1 * t1, 0.0f)) + sh * t2;
        float tz = sqrtf(rb_ref_maxf(1.0f - t1 * t1 - t2 * t2, 0.0f));
        float nh[3];
        for (int i = 0; i < 3; i++)
            nh[i] = t1 * t1v[i] + t2 * t2v[i] + tz * vh[i];
        float ne[3] = {a * nh[0], a * nh[1], rb_ref_maxf(nh[2], 0.0f)};
        float nl = sqrtf(rb_f3_dot(ne, ne));
        if (!(nl > 0.0f)) {
            clear_weights(weight, lobe_weight);
            return 0.0f;
        }
        for (int i = 0; i < 3; i++)
            ne[i] /= nl;
        float vdh = rb_f3_dot(b->vs, ne);
        for (int i = 0; i < 3; i++)
            ll[i] = 2.0f * vdh * ne[i] - b->vs[i];
    } else {
        /* Cosine-weighted hemisphere (Malley's method). */
        float r = sqrtf(u0), phi = 2.0f * RB_PI * u1;
        ll[0] = r * cosf(phi);
        ll[1] = r * sinf(phi);
        ll[2] = sqrtf(rb_ref_maxf(1.0f - u0, 0.0f));
    }
    to_world(b, ll, l);
    float len = sqrtf(rb_f3_dot(l, l));
    if (!(len > 0.0f)) {
        clear_weights(weight, lobe_weight);
        return 0.0f;
    }
    l[0] /= len;
    l[1] /= len;
    l[2] /= len;
    return sample_weight(b, l, weight, lobe_weight);
}
