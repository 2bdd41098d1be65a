/* bdpt's MIS weights (shaders/common/bdpt_shared.h, which the connect shader includes too),
 * with no device: over random one-bounce paths light -> z -> x1, the weights of the VPL and
 * bundle strategies are in [0, 1] and sum to one whatever the sample counts; a z close to x1
 * goes to the bundles, whose density there grows as 1 / r^2; a z grazed by the bundle ray goes
 * to the VPLs; one strategy alone takes all. BDPT.md derives them. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "core/core.h"
#include "bdpt_shared.h"

/* A uniform number in [0, 1) from a fixed stream. */
static float uniform(uint64_t *state)
{
    *state = rb_mix64(*state + 0x9e3779b97f4a7c15ull);
    return (float)(*state >> 40) / (float)(1u << 24);
}

static struct rb_vec3 unit(uint64_t *state)
{
    float z = 1.0f - 2.0f * uniform(state), phi = 2.0f * RB_PI * uniform(state);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return rb_v3(r * cosf(phi), r * sinf(phi), z);
}

/* The two densities of z for one path: a point light at y chosen with probability p_light,
 * uniform over its sphere; a bundle ray from x1. z faces both (cosines > 0). */
struct path {
    float p_vpl, p_bundle;
};

static struct path path_at(struct rb_vec3 y, float p_light, struct rb_vec3 z, struct rb_vec3 nz,
                           struct rb_vec3 x1)
{
    struct rb_vec3 to_y = rb_v3_sub(y, z), to_x = rb_v3_sub(x1, z);
    float dy2 = rb_v3_dot(to_y, to_y), dx2 = rb_v3_dot(to_x, to_x);
    float cos_in = fabsf(rb_v3_dot(nz, to_y)) / sqrtf(dy2);
    float cos_out = fabsf(rb_v3_dot(nz, to_x)) / sqrtf(dx2);
    return (struct path){
        .p_vpl = rb_bdpt_vpl_density(p_light / (4.0f * RB_PI), cos_in, dy2),
        .p_bundle = rb_bdpt_bundle_density(cos_out, dx2),
    };
}

static void test_weights_sum_to_one(void **state)
{
    (void)state;
    uint64_t rng = 1;
    double worst = 0.0;
    for (int i = 0; i < 100000; i++) {
        struct rb_vec3 y = rb_v3_scale(unit(&rng), 3.0f * uniform(&rng) + 0.01f);
        struct rb_vec3 x1 = rb_v3_scale(unit(&rng), 3.0f * uniform(&rng) + 0.01f);
        struct rb_vec3 z = rb_v3_scale(unit(&rng), 0.5f * uniform(&rng));
        struct path p = path_at(y, 0.05f + 0.95f * uniform(&rng), z, unit(&rng), x1);
        float n_a = (float)(1 + (int)(uniform(&rng) * 8.0f));
        float n_b = (float)(1 + (int)(uniform(&rng) * 8.0f));
        if (!(p.p_vpl > 0.0f && p.p_bundle > 0.0f))
            continue; /* a path one side cannot make is that side's weight 0 */
        float wa = rb_bdpt_balance(n_a, p.p_vpl, n_b, p.p_bundle);
        float wb = rb_bdpt_balance(n_b, p.p_bundle, n_a, p.p_vpl);
        assert_true(wa >= 0.0f && wa <= 1.0f);
        assert_true(wb >= 0.0f && wb <= 1.0f);
        double err = fabs((double)wa + (double)wb - 1.0);
        if (err > worst)
            worst = err;
    }
    assert_true(worst < 1e-6);
}

static void test_limits(void **state)
{
    (void)state;
    struct rb_vec3 y = rb_v3(0, 2, 0), z = rb_v3(0, 0, 0), n = rb_v3(0, 1, 0);
    /* z close to x1: the bundle's 1 / r^2 density takes the path (a VPL's would spike). */
    struct path near = path_at(y, 1.0f, z, n, rb_v3(0, 0.001f, 0));
    assert_true(rb_bdpt_balance(4, near.p_bundle, 4, near.p_vpl) > 0.999f);
    /* x1 far away and at a grazing angle from z: the VPLs take it. */
    struct path far = path_at(y, 1.0f, z, n, rb_v3(100.0f, 0.01f, 0));
    assert_true(rb_bdpt_balance(4, far.p_vpl, 4, far.p_bundle) > 0.999f);
    /* More samples on one side move weight to it, in proportion. */
    struct path mid = path_at(y, 1.0f, z, n, rb_v3(1, 1, 0));
    float w1 = rb_bdpt_balance(1, mid.p_vpl, 1, mid.p_bundle);
    float w4 = rb_bdpt_balance(4, mid.p_vpl, 1, mid.p_bundle);
    assert_true(w4 > w1);
    assert_float_equal(w4 / (1.0f - w4), 4.0f * w1 / (1.0f - w1), 1e-4);
    /* A strategy that cannot make the path has weight 0; the other then has weight 1. */
    assert_float_equal(rb_bdpt_balance(4, 0.0f, 4, mid.p_bundle), 0.0f, 0.0f);
    assert_float_equal(rb_bdpt_balance(4, mid.p_bundle, 4, 0.0f), 1.0f, 0.0f);
}

static void test_densities(void **state)
{
    (void)state;
    /* A bundle ray's solid-angle density is 1 / 2 pi: over a hemisphere of directions the
     * area density integrates to 1. Sum it over a large plane facing x1 at height 1 (the
     * plane's share of the hemisphere is all of it as the plane grows). */
    double sum = 0.0, step = 0.02;
    for (double u = -50.0; u < 50.0; u += step)
        for (double v = -50.0; v < 50.0; v += step) {
            double px = u + step / 2, py = v + step / 2, d2 = px * px + py * py + 1.0;
            sum += rb_bdpt_bundle_density((float)(1.0 / sqrt(d2)), (float)d2) * step * step;
        }
    assert_true(fabs(sum - 1.0) < 0.02); /* the part beyond 50 m is 1 / sqrt(2501) of it */
    /* A VPL's area density is its solid-angle density times cos / r^2. */
    assert_float_equal(rb_bdpt_vpl_density(0.25f, 0.5f, 4.0f), 0.25f * 0.5f / 4.0f, 1e-7f);
}

/* The emitters' one-bounce paths y0 -> y1 -> x1: the bounce VPL y1 (a cosine-distributed
 * direction from y0) against the bundle from x1 finding y1 with y0 as the emitter VPL (the
 * pairs' strategy (c)). y0's own density is the same on both sides and cancels; the two
 * weights, with their own sample counts, sum to one. And the bounce's area density is a
 * density: over a large plane facing y0 at height 1 it integrates to 1. */
static void test_bounce(void **state)
{
    (void)state;
    uint64_t rng = 7;
    double worst = 0.0;
    for (int i = 0; i < 100000; i++) {
        struct rb_vec3 y0 = rb_v3_scale(unit(&rng), 3.0f * uniform(&rng) + 0.01f);
        struct rb_vec3 n0 = unit(&rng), x1 = rb_v3_scale(unit(&rng), 3.0f);
        struct rb_vec3 y1 = rb_v3_scale(unit(&rng), 0.5f * uniform(&rng)), n1 = unit(&rng);
        struct rb_vec3 to_0 = rb_v3_sub(y0, y1), to_x = rb_v3_sub(x1, y1);
        float d0 = rb_v3_dot(to_0, to_0), dx = rb_v3_dot(to_x, to_x);
        float cos0 = -rb_v3_dot(n0, to_0) / sqrtf(d0),
              cos1 = fabsf(rb_v3_dot(n1, to_0)) / sqrtf(d0);
        if (!(cos0 > 0.0f))
            continue;
        float p_bounce = rb_bdpt_bounce_density(cos0, cos1, d0);
        float p_bundle = rb_bdpt_bundle_density(fabsf(rb_v3_dot(n1, to_x)) / sqrtf(dx), dx);
        float n_a = (float)(1 + (int)(uniform(&rng) * 8.0f));
        float n_c = (float)(1 + (int)(uniform(&rng) * 8.0f));
        if (!(p_bounce > 0.0f && p_bundle > 0.0f))
            continue;
        float wa = rb_bdpt_balance(n_a, p_bounce, n_c, p_bundle);
        float wc = rb_bdpt_balance(n_c, p_bundle, n_a, p_bounce);
        assert_true(wa >= 0.0f && wa <= 1.0f && wc >= 0.0f && wc <= 1.0f);
        double err = fabs((double)wa + (double)wc - 1.0);
        if (err > worst)
            worst = err;
    }
    assert_true(worst < 1e-6);
    double sum = 0.0, step = 0.02;
    for (double u = -50.0; u < 50.0; u += step)
        for (double v = -50.0; v < 50.0; v += step) {
            double px = u + step / 2, py = v + step / 2, d2 = px * px + py * py + 1.0;
            float c = (float)(1.0 / sqrt(d2));
            sum += rb_bdpt_bounce_density(c, c, (float)d2) * step * step;
        }
    assert_true(fabs(sum - 1.0) < 0.002); /* beyond 50 m: 1 / 2501 of it */
}

/* Two-bounce paths y0 -> z -> z1 -> x1 (BDPT.md "Two bounces"): (c), VPL z and the bundle from
 * x1 finding z1, against (a) of z's bounce z1 (a cosine-distributed direction from z), weighed
 * by the power heuristic: the two weights sum to one, and whatever the distance r from z to z1,
 * (c)'s weight times its geometry term G(z, z1) = cos_z cos_z1 / r^2 stays below
 * pi (n_c / n_a) p_B(z1 | x1) (the power weight is at most the ratio of the two sides): the
 * singularity a clamp used to bound is gone, and the weight falls to 0 as z1 nears z, where the
 * bounce takes the paths over. */
static void test_two_bounce(void **state)
{
    (void)state;
    uint64_t rng = 11;
    for (int i = 0; i < 100000; i++) {
        struct rb_vec3 x1 = rb_v3_scale(unit(&rng), 2.0f), n1 = unit(&rng);
        float r = powf(10.0f, -4.0f * uniform(&rng)); /* 1e-4 to 1 */
        float cos_z = uniform(&rng), cos_z1 = uniform(&rng);
        struct rb_vec3 z1 = rb_v3_scale(unit(&rng), 0.5f);
        struct rb_vec3 to_x = rb_v3_sub(x1, z1);
        float dx = rb_v3_dot(to_x, to_x);
        float p_bundle = rb_bdpt_bundle_density(fabsf(rb_v3_dot(n1, to_x)) / sqrtf(dx), dx);
        float p_bounce = rb_bdpt_bounce_density(cos_z, cos_z1, r * r);
        float n_a = (float)(1 + (int)(uniform(&rng) * 8.0f));
        float n_c = (float)(1 + (int)(uniform(&rng) * 8.0f));
        if (!(p_bundle > 0.0f && p_bounce > 0.0f))
            continue;
        float wc = rb_bdpt_power(n_c, p_bundle, n_a, p_bounce);
        float wa = rb_bdpt_power(n_a, p_bounce, n_c, p_bundle);
        assert_true(wa >= 0.0f && wa <= 1.0f && wc >= 0.0f && wc <= 1.0f);
        assert_true(fabs((double)wa + (double)wc - 1.0) < 1e-6);
        double g = (double)cos_z * cos_z1 / ((double)r * r);
        double bound = RB_PI * n_c / n_a * p_bundle;
        assert_true(wc * g <= bound * (1.0 + 1e-4));
    }
    /* Nearer and nearer: the weight of (c) goes to 0. */
    float p_bundle = rb_bdpt_bundle_density(0.7f, 1.0f);
    float near = rb_bdpt_power(1.0f, p_bundle, 1.0f, rb_bdpt_bounce_density(0.7f, 0.7f, 1e-6f));
    assert_true(near < 1e-5f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_weights_sum_to_one), cmocka_unit_test(test_limits),
        cmocka_unit_test(test_densities),          cmocka_unit_test(test_bounce),
        cmocka_unit_test(test_two_bounce),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
