/* rb_camera_evaluate on hand-built scenes and poses: keyframe tracks (linear, Catmull-Rom,
 * clamped ends, fov), glTF camera nodes (and their errors), and the fitted default view. */
#include "scene/scene.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#define NONE RB_SCENE_NONE

/* Node 0 "Box" (no camera), node 1 "Eye" with camera 0 "Lens" at (1,2,3), turned 90 degrees
 * about Y and scaled by 2 (the scale must not reach the view matrix). Bounds [-1,1]^3. */
struct fixture {
    struct rb_scene s;
    struct rb_scene_node nodes[2];
    struct rb_scene_camera cam;
    struct rb_mat4 world[2];
    struct rb_scene_pose pose;
    struct rb_scene_setup setup;
    struct rb_job job;
};

static void build(struct fixture *f)
{
    memset(f, 0, sizeof(*f));
    f->nodes[0] = (struct rb_scene_node){.name = "Box",
                                         .parent = NONE,
                                         .rotation = {0, 0, 0, 1},
                                         .scale = {1, 1, 1},
                                         .mesh = NONE,
                                         .skin = NONE,
                                         .camera = NONE,
                                         .light = NONE,
                                         .in_scene = true};
    f->nodes[1] = f->nodes[0];
    f->nodes[1].name = "Eye";
    f->nodes[1].camera = 0;
    f->cam = (struct rb_scene_camera){
        .name = "Lens", .is_perspective = true, .yfov_rad = 0.7f, .znear = 0.05f};
    f->world[0] = rb_mat4_identity();
    float h = sqrtf(0.5f);
    f->world[1] = rb_mat4_trs(rb_v3(1, 2, 3), (struct rb_quat){0, h, 0, h}, rb_v3(2, 2, 2));
    f->pose = (struct rb_scene_pose){.node_world = f->world};
    f->setup = (struct rb_scene_setup){.bounds_min = {-1, -1, -1}, .bounds_max = {1, 1, 1}};
    f->s = (struct rb_scene){
        .nodes = f->nodes, .node_count = 2, .cameras = &f->cam, .camera_count = 1};
    f->job.width_px = 1600;
    f->job.height_px = 900;
}

static struct rb_camera eval(struct fixture *f, double t)
{
    struct rb_camera cam;
    struct rb_err err = RB_ERR_INIT;
    if (rb_camera_evaluate(&f->job, &f->s, &f->setup, &f->pose, t, &cam, &err))
        fail_msg("camera: %s", err.msg);
    return cam;
}

static void assert_v3(struct rb_vec3 a, float x, float y, float z, float tol)
{
    if (!(fabsf(a.x - x) <= tol && fabsf(a.y - y) <= tol && fabsf(a.z - z) <= tol))
        fail_msg("(%g, %g, %g) != (%g, %g, %g)", a.x, a.y, a.z, x, y, z);
}

static void set_key(struct rb_job_camera_key *k, double t, float px, float py, float pz, float ax,
                    float ay, float az, float fov)
{
    *k = (struct rb_job_camera_key){
        .t_s = t, .position = {px, py, pz}, .look_at = {ax, ay, az}, .fov_y_deg = fov};
}

static void test_linear_track(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    struct rb_job_camera_key keys[2];
    set_key(&keys[0], 0, 0, 0, 10, 0, 0, 0, 0);
    set_key(&keys[1], 2, 10, 0, 10, 10, 0, 0, 0);
    f.job.camera.keys = keys;
    f.job.camera.key_count = 2;
    f.job.camera.interpolation = RB_INTERP_LINEAR;
    f.job.camera.fov_y_deg = 30;
    struct rb_camera c = eval(&f, 1.0);
    assert_v3(c.position, 5, 0, 10, 1e-6f);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(5, 0, 0)), 0, 0, -10, 1e-5f);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(5, 1, 10)), 0, 1, 0, 1e-5f); /* +Y up */
    assert_float_equal(c.fov_y_rad, 30.0f * RB_PI / 180.0f, 1e-6f);
    assert_true(c.z_near > 0.0f && c.z_near < 9.0f && c.z_far > 11.0f);
    /* clamped at both ends */
    assert_v3(eval(&f, -4.0).position, 0, 0, 10, 0.0f);
    assert_v3(eval(&f, 40.0).position, 10, 0, 10, 0.0f);
}

static struct rb_vec3 cr_position(struct fixture *f, double t)
{
    return eval(f, t).position;
}

static void test_catmull_rom_track(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    /* unevenly spaced keys; Catmull-Rom is the default interpolation */
    struct rb_job_camera_key keys[4];
    set_key(&keys[0], 0, 0, 0, 0, 0, 0, -100, 0);
    set_key(&keys[1], 1, 1, 2, 0, 0, 0, -100, 0);
    set_key(&keys[2], 3, 3, 0, 1, 0, 0, -100, 0);
    set_key(&keys[3], 4, 4, 4, 4, 0, 0, -100, 0);
    f.job.camera.keys = keys;
    f.job.camera.key_count = 4;
    for (int k = 0; k < 4; k++) /* passes through every key */
        assert_v3(cr_position(&f, keys[k].t_s), keys[k].position[0], keys[k].position[1],
                  keys[k].position[2], 1e-5f);
    /* smooth: the velocity is the same on both sides of the inner keys */
    const double h = 1e-3;
    for (int k = 1; k < 3; k++) {
        double t = keys[k].t_s;
        struct rb_vec3 p = cr_position(&f, t);
        struct rb_vec3 vl = rb_v3_scale(rb_v3_sub(p, cr_position(&f, t - h)), (float)(1 / h));
        struct rb_vec3 vr = rb_v3_scale(rb_v3_sub(cr_position(&f, t + h), p), (float)(1 / h));
        assert_true(rb_v3_length(rb_v3_sub(vl, vr)) < 0.05f);
        assert_true(rb_v3_length(vl) > 0.5f);
    }
    /* not the straight line between the keys */
    struct rb_vec3 mid = cr_position(&f, 2.0);
    assert_true(rb_v3_length(rb_v3_sub(mid, rb_v3(2, 1, 0.5f))) > 0.05f);
    /* clamped ends */
    assert_v3(cr_position(&f, -1.0), 0, 0, 0, 0.0f);
    assert_v3(cr_position(&f, 9.0), 4, 4, 4, 0.0f);

    /* evenly spaced keys give the uniform Catmull-Rom spline */
    keys[2].t_s = 2;
    keys[3].t_s = 3;
    struct rb_vec3 p[4];
    for (int k = 0; k < 4; k++)
        p[k] = rb_v3(keys[k].position[0], keys[k].position[1], keys[k].position[2]);
    float u = 0.3f, u2 = u * u, u3 = u2 * u;
    struct rb_vec3 want = rb_v3_scale(
        rb_v3_add(
            rb_v3_add(rb_v3_scale(p[1], 2), rb_v3_scale(rb_v3_sub(p[2], p[0]), u)),
            rb_v3_add(rb_v3_scale(rb_v3_add(rb_v3_sub(rb_v3_scale(p[0], 2), rb_v3_scale(p[1], 5)),
                                            rb_v3_sub(rb_v3_scale(p[2], 4), p[3])),
                                  u2),
                      rb_v3_scale(rb_v3_add(rb_v3_sub(rb_v3_scale(p[1], 3), p[0]),
                                            rb_v3_sub(p[3], rb_v3_scale(p[2], 3))),
                                  u3))),
        0.5f);
    struct rb_vec3 got = cr_position(&f, 1.3);
    assert_v3(got, want.x, want.y, want.z, 1e-4f);
    /* the first segment uses the first key as its own (phantom) neighbour */
    u = 0.5f;
    struct rb_vec3 first = rb_v3_scale(
        rb_v3_add(
            rb_v3_add(rb_v3_scale(p[0], 2), rb_v3_scale(rb_v3_sub(p[1], p[0]), u)),
            rb_v3_add(rb_v3_scale(rb_v3_add(rb_v3_sub(rb_v3_scale(p[0], 2), rb_v3_scale(p[0], 5)),
                                            rb_v3_sub(rb_v3_scale(p[1], 4), p[2])),
                                  u * u),
                      rb_v3_scale(rb_v3_add(rb_v3_sub(rb_v3_scale(p[0], 3), p[0]),
                                            rb_v3_sub(p[2], rb_v3_scale(p[1], 3))),
                                  u * u * u))),
        0.5f);
    assert_v3(cr_position(&f, 0.5), first.x, first.y, first.z, 1e-4f);
}

static void test_fov_keys(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    struct rb_job_camera_key keys[3];
    set_key(&keys[0], 0, 0, 0, 5, 0, 0, 0, 30);
    set_key(&keys[1], 1, 0, 0, 5, 0, 0, 0, 50);
    set_key(&keys[2], 2, 0, 0, 5, 0, 0, 5, 0); /* fov 0: the track's; looks at itself */
    f.job.camera.keys = keys;
    f.job.camera.key_count = 3;
    f.job.camera.fov_y_deg = 20;
    const float deg = RB_PI / 180.0f;
    assert_float_equal(eval(&f, 0.5).fov_y_rad, 40 * deg, 1e-5f);
    assert_float_equal(eval(&f, 1.5).fov_y_rad, 35 * deg, 1e-5f);
    assert_float_equal(eval(&f, 2.0).fov_y_rad, 20 * deg, 1e-6f);
    f.job.camera.fov_y_deg = 0; /* and the track's 0 means 40 */
    assert_float_equal(eval(&f, 3.0).fov_y_rad, 40 * deg, 1e-6f);
    /* a key whose eye is its target still gives a finite view */
    struct rb_camera c = eval(&f, 3.0);
    for (int i = 0; i < 16; i++)
        assert_true(isfinite(c.world_to_camera.m[i / 4][i % 4]));
}

static void test_node_camera(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    f.job.camera.node = "Eye";
    f.job.camera.fov_y_deg = 25; /* the file's yfov wins for a node camera */
    struct rb_camera c = eval(&f, 0.0);
    assert_v3(c.position, 1, 2, 3, 1e-6f);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(1, 2, 3)), 0, 0, 0, 1e-5f);
    /* looks down its -Z, which the 90-degree turn about Y maps to world -X; no scale */
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(-4, 2, 3)), 0, 0, -5, 1e-5f);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(1, 3, 3)), 0, 1, 0, 1e-5f);
    assert_float_equal(c.fov_y_rad, 0.7f, 1e-6f);
    assert_float_equal(c.z_near, 0.05f, 1e-7f);
    /* zfar 0 (infinite) in the file: derived, past the farthest corner of the bounds */
    float far_corner = rb_v3_length(rb_v3_sub(rb_v3(1, 2, 3), rb_v3(-1, -1, -1)));
    assert_true(c.z_far > far_corner);
    f.cam.zfar = 77;
    assert_float_equal(eval(&f, 0.0).z_far, 77.0f, 0.0f);
    /* the job's planes win over the file's */
    f.job.camera.near_m = 0.5f;
    f.job.camera.far_m = 50;
    c = eval(&f, 0.0);
    assert_float_equal(c.z_near, 0.5f, 0.0f);
    assert_float_equal(c.z_far, 50.0f, 0.0f);

    /* without a node or keys, the scene's first camera node */
    f.job = (struct rb_job){.width_px = 16, .height_px = 9};
    assert_v3(eval(&f, 0.0).position, 1, 2, 3, 1e-6f);
}

static void test_node_camera_errors(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    struct rb_camera c;
    struct rb_err err = RB_ERR_INIT;
    f.job.camera.node = "Nope";
    assert_int_equal(rb_camera_evaluate(&f.job, &f.s, &f.setup, &f.pose, 0, &c, &err),
                     RB_E_INVALID);
    assert_string_equal(err.msg, "camera node 'Nope' not found in the scene");
    f.job.camera.node = "Box";
    assert_int_equal(rb_camera_evaluate(&f.job, &f.s, &f.setup, &f.pose, 0, &c, &err),
                     RB_E_INVALID);
    assert_string_equal(err.msg, "camera node 'Box' has no camera");
    /* Where the job set the key, the message starts there. */
    char at[] = "shot.yaml:7:11";
    f.job.at.camera_node = at;
    assert_int_equal(rb_camera_evaluate(&f.job, &f.s, &f.setup, &f.pose, 0, &c, &err),
                     RB_E_INVALID);
    assert_string_equal(err.msg, "shot.yaml:7:11: camera node 'Box' has no camera");
    f.job.at.camera_node = NULL;
}

/* Every corner of the bounds lies inside the view frustum and between the clip planes. */
static void assert_fits(const struct rb_camera *c, struct rb_vec3 lo, struct rb_vec3 hi,
                        float aspect)
{
    float ty = tanf(0.5f * c->fov_y_rad), tx = ty * aspect;
    for (int i = 0; i < 8; i++) {
        struct rb_vec3 w = rb_v3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
        struct rb_vec3 v = rb_mat4_point(&c->world_to_camera, w);
        assert_true(v.z < 0.0f);
        assert_true(fabsf(v.y / v.z) <= ty);
        assert_true(fabsf(v.x / v.z) <= tx);
        assert_true(-v.z > c->z_near && -v.z < c->z_far);
    }
}

static void test_fit(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    f.nodes[1].in_scene = false; /* no usable scene camera: fit the bounds */
    struct rb_camera c = eval(&f, 0.0);
    float fov = 40.0f * RB_PI / 180.0f, d = sqrtf(3.0f) / sinf(0.5f * fov) * 1.1f;
    struct rb_vec3 dir = rb_v3_normalize(rb_v3(0, 0.35f, 1));
    assert_float_equal(c.fov_y_rad, fov, 1e-6f);
    assert_v3(c.position, dir.x * d, dir.y * d, dir.z * d, 1e-4f);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(0, 0, 0)), 0, 0, -d, 1e-4f);
    assert_fits(&c, f.setup.bounds_min, f.setup.bounds_max, 16.0f / 9.0f);

    /* off-center, flat bounds and a portrait image: still all in view */
    f.setup.bounds_min = rb_v3(95, -1, -20);
    f.setup.bounds_max = rb_v3(105, 1, 20);
    f.job.width_px = 600;
    f.job.height_px = 1000;
    f.job.camera.fov_y_deg = 60;
    c = eval(&f, 0.0);
    assert_v3(rb_mat4_point(&c.world_to_camera, rb_v3(100, 0, 0)), 0, 0,
              -rb_v3_length(rb_v3_sub(c.position, rb_v3(100, 0, 0))), 1e-3f);
    assert_fits(&c, f.setup.bounds_min, f.setup.bounds_max, 0.6f);

    /* empty bounds at the origin: a finite camera with sane planes */
    f.setup.bounds_min = f.setup.bounds_max = rb_v3(0, 0, 0);
    c = eval(&f, 0.0);
    assert_true(isfinite(c.position.x) && c.z_near > 0.0f && c.z_far > c.z_near);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_linear_track),       cmocka_unit_test(test_catmull_rom_track),
        cmocka_unit_test(test_fov_keys),           cmocka_unit_test(test_node_camera),
        cmocka_unit_test(test_node_camera_errors), cmocka_unit_test(test_fit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
