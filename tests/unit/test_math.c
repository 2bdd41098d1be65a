/* lib/core math: mat4 multiply, inverse and TRS, quaternion slerp, look_at, and the Vulkan
 * perspective/ortho depth mapping (near -> 0, far -> 1, +Y up on screen). */
#include "core/core.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

static void assert_mat_near(const struct rb_mat4 *a, const struct rb_mat4 *b, float tol)
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++)
            if (!(fabsf(a->m[c][r] - b->m[c][r]) <= tol))
                fail_msg("m[%d][%d]: %g != %g", c, r, a->m[c][r], b->m[c][r]);
}

static void assert_v3(struct rb_vec3 a, float x, float y, float z, float tol)
{
    if (!(fabsf(a.x - x) <= tol && fabsf(a.y - y) <= tol && fabsf(a.z - z) <= tol))
        fail_msg("(%g, %g, %g) != (%g, %g, %g)", a.x, a.y, a.z, x, y, z);
}

static struct rb_quat axis_angle(struct rb_vec3 axis, float rad)
{
    axis = rb_v3_normalize(axis);
    float s = sinf(0.5f * rad);
    return (struct rb_quat){axis.x * s, axis.y * s, axis.z * s, cosf(0.5f * rad)};
}

/* Clip-space point -> NDC. */
static struct rb_vec3 project(const struct rb_mat4 *m, struct rb_vec3 p)
{
    struct rb_vec4 c = rb_mat4_vec4(m, (struct rb_vec4){p.x, p.y, p.z, 1.0f});
    return rb_v3(c.x / c.w, c.y / c.w, c.z / c.w);
}

static void test_mul(void **state)
{
    (void)state;
    struct rb_mat4 a =
        rb_mat4_trs(rb_v3(1, 2, 3), axis_angle(rb_v3(0, 0, 1), RB_PI / 2), rb_v3(1, 1, 1));
    struct rb_mat4 b = rb_mat4_trs(rb_v3(5, 0, 0), rb_quat_identity(), rb_v3(2, 2, 2));
    struct rb_mat4 id = rb_mat4_identity(), ab = rb_mat4_mul(&a, &b);
    struct rb_mat4 ia = rb_mat4_mul(&id, &a);
    assert_mat_near(&ia, &a, 0.0f);
    /* (A B) p == A (B p): b scales by 2 and moves +5 x; a turns 90 degrees about Z, then moves */
    struct rb_vec3 p = rb_v3(1, 0, 0);
    assert_v3(rb_mat4_point(&ab, p), 1, 2 + 7, 3, 1e-5f);
    assert_v3(rb_mat4_point(&a, rb_mat4_point(&b, p)), 1, 9, 3, 1e-5f);
    /* column-major storage: translation lives in column 3 */
    assert_float_equal(a.m[3][0], 1.0f, 0.0f);
    assert_float_equal(a.m[3][2], 3.0f, 0.0f);
    /* directions ignore the translation */
    assert_v3(rb_mat4_dir(&a, rb_v3(1, 0, 0)), 0, 1, 0, 1e-6f);
}

static void test_trs(void **state)
{
    (void)state;
    struct rb_quat q = axis_angle(rb_v3(1, 1, 0), 1.1f);
    struct rb_mat4 m = rb_mat4_trs(rb_v3(-3, 4, 0.5f), q, rb_v3(2, 3, 0.5f));
    /* T * R * S applied to a point equals the three steps one by one */
    struct rb_vec3 p = rb_v3(0.3f, -1.2f, 2.0f);
    struct rb_vec3 want = rb_quat_rotate(q, rb_v3(p.x * 2, p.y * 3, p.z * 0.5f));
    want = rb_v3_add(want, rb_v3(-3, 4, 0.5f));
    assert_v3(rb_mat4_point(&m, p), want.x, want.y, want.z, 1e-5f);
    /* an unnormalized quaternion is normalized first */
    struct rb_quat q2 = {q.x * 3, q.y * 3, q.z * 3, q.w * 3};
    struct rb_mat4 m2 = rb_mat4_trs(rb_v3(-3, 4, 0.5f), q2, rb_v3(2, 3, 0.5f));
    assert_mat_near(&m, &m2, 1e-6f);
}

static void test_inverse(void **state)
{
    (void)state;
    struct rb_mat4 m =
        rb_mat4_trs(rb_v3(7, -2, 1), axis_angle(rb_v3(0.2f, 1, -0.4f), 2.0f), rb_v3(0.5f, 4, 1.5f));
    bool ok = false;
    struct rb_mat4 inv = rb_mat4_inverse(&m, &ok), id = rb_mat4_identity();
    assert_true(ok);
    struct rb_mat4 a = rb_mat4_mul(&m, &inv), b = rb_mat4_mul(&inv, &m);
    assert_mat_near(&a, &id, 1e-5f);
    assert_mat_near(&b, &id, 1e-5f);
    /* a projection (bottom row not 0 0 0 1) inverts too */
    struct rb_mat4 pr = rb_mat4_perspective(1.0f, 1.5f, 0.1f, 100.0f);
    struct rb_mat4 pinv = rb_mat4_inverse(&pr, &ok), pp = rb_mat4_mul(&pr, &pinv);
    assert_true(ok);
    assert_mat_near(&pp, &id, 1e-4f);
    /* singular: identity and ok == false */
    struct rb_mat4 z = rb_mat4_trs(rb_v3(1, 1, 1), rb_quat_identity(), rb_v3(1, 0, 1));
    struct rb_mat4 zi = rb_mat4_inverse(&z, &ok);
    assert_false(ok);
    assert_mat_near(&zi, &id, 0.0f);
    /* the transpose of a rotation is its inverse */
    struct rb_mat4 r =
        rb_mat4_trs(rb_v3(0, 0, 0), axis_angle(rb_v3(1, 2, 3), 0.7f), rb_v3(1, 1, 1));
    struct rb_mat4 rt = rb_mat4_transpose(&r), ri = rb_mat4_inverse(&r, NULL);
    assert_mat_near(&rt, &ri, 1e-6f);
}

static void test_slerp(void **state)
{
    (void)state;
    struct rb_quat a = rb_quat_identity(), b = axis_angle(rb_v3(0, 1, 0), RB_PI / 2);
    struct rb_quat h = rb_quat_slerp(a, b, 0.5f);
    float angle = 2.0f * acosf(fminf(fabsf(h.w), 1.0f));
    assert_float_equal(angle, RB_PI / 4, 1e-5f);
    assert_v3(rb_quat_rotate(h, rb_v3(1, 0, 0)), cosf(RB_PI / 4), 0, -sinf(RB_PI / 4), 1e-6f);
    struct rb_quat e0 = rb_quat_slerp(a, b, 0.0f), e1 = rb_quat_slerp(a, b, 1.0f);
    assert_float_equal(e0.w, 1.0f, 1e-6f);
    assert_float_equal(e1.y, b.y, 1e-6f);
    assert_float_equal(e1.w, b.w, 1e-6f);
    /* constant angular speed: a quarter of the way is a quarter of the angle */
    struct rb_quat q = rb_quat_slerp(a, b, 0.25f);
    assert_float_equal(2.0f * acosf(fminf(q.w, 1.0f)), RB_PI / 8, 1e-5f);
    /* -b is the same rotation: the short way round, not through 270 degrees */
    struct rb_quat nb = {-b.x, -b.y, -b.z, -b.w};
    struct rb_quat s = rb_quat_slerp(a, nb, 0.5f);
    assert_float_equal(2.0f * acosf(fminf(fabsf(s.w), 1.0f)), RB_PI / 4, 1e-5f);
    /* nearly equal inputs stay unit length */
    struct rb_quat c = axis_angle(rb_v3(0, 1, 0), 1e-4f), n = rb_quat_slerp(a, c, 0.3f);
    assert_float_equal(n.x * n.x + n.y * n.y + n.z * n.z + n.w * n.w, 1.0f, 1e-6f);
    /* composition: two 45-degree turns are one 90-degree turn */
    struct rb_quat m = rb_quat_mul(h, h);
    assert_v3(rb_quat_rotate(m, rb_v3(1, 0, 0)), 0, 0, -1, 1e-6f);
}

static void test_look_at(void **state)
{
    (void)state;
    struct rb_vec3 eye = rb_v3(3, 4, 5), target = rb_v3(3, 4, -5);
    struct rb_mat4 v = rb_mat4_look_at(eye, target, rb_v3(0, 1, 0));
    assert_v3(rb_mat4_point(&v, eye), 0, 0, 0, 1e-6f);
    assert_v3(rb_mat4_point(&v, target), 0, 0, -10, 1e-5f);       /* looks down -Z */
    assert_v3(rb_mat4_point(&v, rb_v3(3, 5, 5)), 0, 1, 0, 1e-6f); /* up stays up */
    assert_v3(rb_mat4_point(&v, rb_v3(4, 4, 5)), 1, 0, 0, 1e-6f); /* right is +X */
    /* looking straight down along the up vector still gives an orthonormal view */
    struct rb_mat4 d = rb_mat4_look_at(rb_v3(0, 10, 0), rb_v3(0, 0, 0), rb_v3(0, 1, 0));
    assert_v3(rb_mat4_point(&d, rb_v3(0, 0, 0)), 0, 0, -10, 1e-5f);
    for (int c = 0; c < 3; c++) {
        struct rb_vec3 col = rb_v3(d.m[c][0], d.m[c][1], d.m[c][2]);
        assert_float_equal(rb_v3_length(col), 1.0f, 1e-5f);
    }
}

static void test_perspective(void **state)
{
    (void)state;
    float n = 0.25f, f = 40.0f, fov = 1.0f, aspect = 2.0f;
    struct rb_mat4 p = rb_mat4_perspective(fov, aspect, n, f);
    assert_float_equal(project(&p, rb_v3(0, 0, -n)).z, 0.0f, 1e-6f);
    assert_float_equal(project(&p, rb_v3(0, 0, -f)).z, 1.0f, 1e-5f);
    float mid = project(&p, rb_v3(0, 0, -1)).z;
    assert_true(mid > 0.0f && mid < 1.0f);
    /* the top edge of the vertical fov lands on NDC y = -1 (Vulkan y points down) */
    float t = tanf(0.5f * fov);
    struct rb_vec3 top = project(&p, rb_v3(0, t * 5, -5));
    assert_float_equal(top.y, -1.0f, 1e-5f);
    struct rb_vec3 right = project(&p, rb_v3(t * aspect * 5, 0, -5));
    assert_float_equal(right.x, 1.0f, 1e-5f);
    /* orthographic: near -> 0, far -> 1, +Y up on screen */
    struct rb_mat4 o = rb_mat4_ortho(-2, 2, -1, 1, n, f);
    assert_float_equal(project(&o, rb_v3(0, 0, -n)).z, 0.0f, 1e-6f);
    assert_float_equal(project(&o, rb_v3(0, 0, -f)).z, 1.0f, 1e-5f);
    assert_float_equal(project(&o, rb_v3(0, 1, -1)).y, -1.0f, 1e-6f);
    assert_float_equal(project(&o, rb_v3(2, 0, -1)).x, 1.0f, 1e-6f);
}

static void test_vectors(void **state)
{
    (void)state;
    assert_v3(rb_v3_normalize(rb_v3(0, 0, 0)), 0, 0, 0, 0.0f);
    assert_v3(rb_v3_normalize(rb_v3(0, 3, 4)), 0, 0.6f, 0.8f, 1e-6f);
    assert_v3(rb_v3_cross(rb_v3(1, 0, 0), rb_v3(0, 1, 0)), 0, 0, 1, 0.0f);
    assert_v3(rb_v3_lerp(rb_v3(0, 2, 4), rb_v3(2, 4, 8), 0.25f), 0.5f, 2.5f, 5, 1e-6f);
    assert_v3(rb_v3_min(rb_v3(1, 5, -1), rb_v3(2, 3, -4)), 1, 3, -4, 0.0f);
    assert_float_equal(rb_clampf(7.0f, 0.0f, 1.0f), 1.0f, 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mul),     cmocka_unit_test(test_trs),
        cmocka_unit_test(test_inverse), cmocka_unit_test(test_slerp),
        cmocka_unit_test(test_look_at), cmocka_unit_test(test_perspective),
        cmocka_unit_test(test_vectors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
