/* The specular lobe's fitted cosines (lib/passes/ltc_ggx.inc, tools/ltcfit.c), read as the
 * emitters' closed form reads them (bdpt_connect.comp's ltc_at, bilinear), held to the lobe
 * itself (the CPU reference's BRDF with Fresnel 1 and no diffuse part, times the cosine):
 * - every transform keeps the surface's plane (m20 = 0), so the fit vanishes at the horizon;
 * - over squares overhead, toward the mirror direction, beside it and behind the view, at
 *   roughness 0.25 to 1 and n.v 0.95 to 0.15, the fit times the lobe's integral gives the
 *   lobe's integral over the square within 0.08 of the lobe's integral, and within 35% of the
 *   square's own where that is at least 5% of it (measured: at most 0.044 and 21%);
 * - a light just above the horizon, seen at a grazing angle (the Cornell box's light quad, 0.9
 *   units below the ceiling, from the ceiling beside it), within a factor of 2: the paper's fit
 *   about the lobe's mean direction took 4 times the lobe's light there;
 * - near a mirror (roughness 0.03 to 0.1), the lobe's shape about the mirror direction. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "passes/passes.h"
#include "reference/reference.h"

#define PI 3.14159265358979323846

struct vec3 {
    double x, y, z;
};

static struct vec3 v3(double x, double y, double z)
{
    return (struct vec3){x, y, z};
}

static double dot3(struct vec3 a, struct vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static struct vec3 cross3(struct vec3 a, struct vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

static struct vec3 axpy(double a, struct vec3 x, struct vec3 y)
{
    return v3(a * x.x + y.x, a * x.y + y.y, a * x.z + y.z);
}

static struct vec3 unit(struct vec3 a)
{
    double l = sqrt(dot3(a, a));
    return v3(a.x / l, a.y / l, a.z / l);
}

/* The lobe toward l for the view v, normal z: the reference's specular BRDF with F = 1, times
 * the cosine. */
static double lobe(struct vec3 v, struct vec3 l, double roughness)
{
    if (l.z <= 0.0)
        return 0.0;
    const float n[3] = {0, 0, 1}, vf[3] = {(float)v.x, (float)v.y, (float)v.z};
    const float lf[3] = {(float)l.x, (float)l.y, (float)l.z}, none[3] = {0, 0, 0},
                one[3] = {1, 1, 1};
    float out[3];
    rb_reference_brdf(n, vf, lf, none, one, 1.0f, (float)roughness, out);
    return out[0] * l.z;
}

/* The table's inverse transform at (roughness, n.v), bilinear as ltc_at reads it. */
static void fit_at(double roughness, double ndv, double m[4])
{
    const int size = RB_LTC_SIZE;
    double ax = fmin(fmax(roughness, 0.0), 1.0) * (size - 1);
    double ay = sqrt(fmin(fmax(1.0 - ndv, 0.0), 1.0)) * (size - 1);
    int ix = (int)ax < size - 2 ? (int)ax : size - 2, iy = (int)ay < size - 2 ? (int)ay : size - 2;
    double fx = ax - ix, fy = ay - iy;
    for (int k = 0; k < 4; k++) {
        const float *t = rb_pass_ltc_ggx;
        double a = t[(iy * size + ix) * 4 + k], b = t[(iy * size + ix + 1) * 4 + k];
        double c = t[((iy + 1) * size + ix) * 4 + k], d = t[((iy + 1) * size + ix + 1) * 4 + k];
        m[k] = (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
    }
}

/* The fitted density's integral over the polygon p (corners relative to the shading point, in
 * the frame whose x axis is the view's tangent part): transformed, clipped to z > 0, Lambert's
 * sum / 2 pi. */
static double fit_integral(const double m[4], const struct vec3 *p, int count)
{
    struct vec3 q[4], c[5];
    for (int i = 0; i < count; i++)
        q[i] = v3(m[0] * p[i].x + m[1] * p[i].z, p[i].y, m[2] * p[i].x + m[3] * p[i].z);
    int cm = 0;
    for (int i = 0; i < count; i++) {
        struct vec3 a = q[i], b = q[(i + 1) % count];
        if (a.z > 0.0)
            c[cm++] = a;
        if ((a.z > 0.0) != (b.z > 0.0))
            c[cm++] = axpy(a.z / (a.z - b.z), axpy(-1.0, a, b), a);
    }
    double s = 0.0;
    for (int i = 0; i < cm; i++) {
        struct vec3 a = unit(c[i]), b = unit(c[(i + 1) % cm]), g = cross3(a, b);
        double len = sqrt(dot3(g, g));
        if (len > 1e-12)
            s += atan2(len, dot3(a, b)) * g.z / len;
    }
    return fabs(s) / (2.0 * PI);
}

/* The lobe's integral over the parallelogram with corners p[0], p[1] and p[3] (p[2] their
 * fourth), by the midpoint rule over its area. */
static double lobe_integral(struct vec3 v, double roughness, const struct vec3 *p)
{
    struct vec3 e1 = axpy(-1.0, p[0], p[1]), e2 = axpy(-1.0, p[0], p[3]);
    struct vec3 nn = cross3(e1, e2);
    double area = sqrt(dot3(nn, nn)), sum = 0.0;
    nn = unit(nn);
    const int steps = 160;
    for (int j = 0; j < steps; j++)
        for (int i = 0; i < steps; i++) {
            struct vec3 y = axpy((j + 0.5) / steps, e2, axpy((i + 0.5) / steps, e1, p[0]));
            double r2 = dot3(y, y);
            struct vec3 l = unit(y);
            sum += lobe(v, l, roughness) * fabs(dot3(nn, l)) / r2;
        }
    return sum * area / ((double)steps * steps);
}

/* The lobe's integral over the hemisphere: over a sphere's latitude-longitude grid. */
static double lobe_norm(struct vec3 v, double roughness)
{
    const int steps = 400;
    double sum = 0.0;
    for (int j = 0; j < steps; j++) {
        double mu = (j + 0.5) / steps; /* cos theta, uniform: d omega = d mu d phi */
        for (int i = 0; i < 2 * steps; i++) {
            double phi = PI * (i + 0.5) / steps, s = sqrt(1.0 - mu * mu);
            sum += lobe(v, v3(s * cos(phi), s * sin(phi), mu), roughness);
        }
    }
    return sum * (1.0 / steps) * (PI / steps);
}

/* A square of side 2 h centred at distance r toward the direction (elevation el, azimuth az
 * from the view's side), facing the point. */
static void square(double el, double az, double r, double h, struct vec3 out[4])
{
    struct vec3 d = v3(cos(el) * cos(az), cos(el) * sin(az), sin(el));
    struct vec3 u = unit(v3(-d.y, d.x, 0.0)), w = cross3(d, u), c = v3(r * d.x, r * d.y, r * d.z);
    out[0] = axpy(-h, u, axpy(-h, w, c));
    out[1] = axpy(h, u, axpy(-h, w, c));
    out[2] = axpy(h, u, axpy(h, w, c));
    out[3] = axpy(-h, u, axpy(h, w, c));
}

static void transform_keeps_the_plane(void **state)
{
    (void)state;
    for (int i = 0; i < RB_LTC_SIZE * RB_LTC_SIZE; i++) {
        assert_true(rb_pass_ltc_ggx[4 * i + 2] == 0.0f);
        assert_true(rb_pass_ltc_ggx[4 * i + 0] > 0.0f && rb_pass_ltc_ggx[4 * i + 3] > 0.0f);
    }
}

static void fit_integrates_the_lobe(void **state)
{
    (void)state;
    static const double roughnesses[] = {0.25, 0.5, 0.75, 1.0};
    static const double cosines[] = {0.95, 0.7, 0.4, 0.15};
    /* elevation, azimuth (0: the view's side, pi: the mirror side) */
    static const double places[][2] = {{PI / 2, 0},      {PI / 4, PI}, {PI / 6, PI},
                                       {PI / 4, PI / 2}, {PI / 3, 0},  {PI / 5, 3 * PI / 4}};
    double worst_abs = 0.0, worst_rel = 0.0;
    for (size_t a = 0; a < sizeof(roughnesses) / sizeof(*roughnesses); a++)
        for (size_t c = 0; c < sizeof(cosines) / sizeof(*cosines); c++) {
            double r = roughnesses[a], ndv = cosines[c];
            struct vec3 v = v3(sqrt(1.0 - ndv * ndv), 0.0, ndv);
            double m[4], norm = lobe_norm(v, r);
            fit_at(r, ndv, m);
            for (size_t k = 0; k < sizeof(places) / sizeof(*places); k++) {
                struct vec3 p[4];
                /* toward the mirror side is azimuth pi: x < 0 */
                square(places[k][0], places[k][1], 2.0, 0.5, p);
                double fit = norm * fit_integral(m, p, 4), want = lobe_integral(v, r, p);
                double err = fabs(fit - want);
                double rel = err / want, abs_ = err / norm;
                bool holds = want >= 0.05 * norm;
                if (abs_ > worst_abs)
                    worst_abs = abs_;
                if (holds && rel > worst_rel)
                    worst_rel = rel;
                if (abs_ > 0.08 || (holds && rel > 0.35))
                    fail_msg(
                        "roughness %.2f, n.v %.2f, square %zu: fit %.4f, lobe %.4f (norm %.4f)", r,
                        ndv, k, fit, want, norm);
            }
        }
    print_message("worst error: %.3f of the lobe's integral; %.3f of the square's\n", worst_abs,
                  worst_rel);
}

static void fit_vanishes_at_the_horizon(void **state)
{
    (void)state;
    /* The ceiling beside the Cornell box's light quad, seen from its camera (n.v 0.26): the
     * quad's back 0.9 units below it, 20 to 125 units away toward the mirror side, 130 wide. */
    double r = 0.5, ndv = 0.2624, m[4];
    struct vec3 v = v3(sqrt(1.0 - ndv * ndv), 0.0, ndv);
    double norm = lobe_norm(v, r);
    fit_at(r, ndv, m);
    struct vec3 p[4] = {v3(-20, -65, 0.9), v3(-125, -65, 0.9), v3(-125, 65, 0.9), v3(-20, 65, 0.9)};
    double fit = norm * fit_integral(m, p, 4), want = lobe_integral(v, r, p);
    print_message("beside the quad: fit %.5f, lobe %.5f\n", fit, want);
    assert_true(fit < 2.0 * want && fit > 0.5 * want);
}

static void fit_follows_a_mirror(void **state)
{
    (void)state;
    /* Nearly a mirror, where the lobe's integral over the hemisphere is out of a grid's reach:
     * its shape, the share of a square of half-angle 8 alpha about the mirror direction that
     * the squares of 1 and 2 alpha hold, the fit's against the lobe's, at roughness 0.03 to 0.1
     * (alpha 0.0009 to 0.01; the float BRDF of the reference loses its peak below) and n.v 0.95
     * to 0.06, where the fits below roughness 0.1 once came out tens of times too wide at some
     * view angles and not at the next (at roughness 0.04, n.v 0.15, the square of 1 alpha held
     * 0.008 of the fit's 8 alpha and 0.455 of the lobe's; measured since: at most 0.041 off). */
    static const double roughnesses[] = {0.03, 0.04, 0.05, 0.065, 0.08, 0.1};
    static const double cosines[] = {0.95, 0.855, 0.742, 0.5, 0.21, 0.152, 0.0625};
    static const double sizes[] = {1.0, 2.0, 8.0};
    double worst = 0.0;
    for (size_t a = 0; a < sizeof(roughnesses) / sizeof(*roughnesses); a++)
        for (size_t c = 0; c < sizeof(cosines) / sizeof(*cosines); c++) {
            double r = roughnesses[a], ndv = cosines[c], alpha = r * r;
            struct vec3 v = v3(sqrt(1.0 - ndv * ndv), 0.0, ndv);
            double m[4], fit[3], want[3];
            fit_at(r, ndv, m);
            for (size_t k = 0; k < 3; k++) {
                struct vec3 p[4];
                square(asin(ndv), PI, 2.0, 2.0 * tan(sizes[k] * alpha), p);
                fit[k] = fit_integral(m, p, 4);
                want[k] = lobe_integral(v, r, p);
            }
            for (size_t k = 0; k < 2; k++) {
                double f = fit[k] / fit[2], w = want[k] / want[2], err = fabs(f - w);
                if (err > worst)
                    worst = err;
                if (err > 0.1)
                    fail_msg("roughness %.3f, n.v %.3f: the square of %.0f alpha holds %.3f of "
                             "the fit's 8 alpha, %.3f of the lobe's",
                             r, ndv, sizes[k], f, w);
            }
        }
    print_message("worst share near a mirror: %.3f off\n", worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(transform_keeps_the_plane),
        cmocka_unit_test(fit_integrates_the_lobe),
        cmocka_unit_test(fit_vanishes_at_the_horizon),
        cmocka_unit_test(fit_follows_a_mirror),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
