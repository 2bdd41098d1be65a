/* Animation: keyframe sampling (STEP, LINEAR, CUBICSPLINE, rotation slerp, clamping) on
 * hand-built samplers, and rb_scene_evaluate on hand-built scenes (hierarchy in any node order,
 * clip time mapping, morph weights, skin joint matrices, bounds). */
#include "scene/scene.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#define NONE RB_SCENE_NONE

static struct rb_scene_anim_sampler sampler(enum rb_anim_interp interp, float *times, uint32_t keys,
                                            float *values, uint32_t comps)
{
    return (struct rb_scene_anim_sampler){.interpolation = interp,
                                          .times = times,
                                          .values = values,
                                          .key_count = keys,
                                          .components = comps};
}

static float quat_angle_deg(const float *q)
{
    float w = fminf(fabsf(q[3]), 1.0f);
    return 2.0f * acosf(w) * 180.0f / RB_PI;
}

/* ---- sampling ------------------------------------------------------------------------------- */

static void test_step(void **state)
{
    (void)state;
    float times[3] = {0, 1, 2}, values[3] = {1, 2, 3}, out = 0;
    struct rb_scene_anim_sampler s = sampler(RB_ANIM_STEP, times, 3, values, 1);
    rb_scene_sample(&s, 0.5f, &out);
    assert_float_equal(out, 1.0f, 0.0f); /* the left key */
    rb_scene_sample(&s, 1.0f, &out);
    assert_float_equal(out, 2.0f, 0.0f);
    rb_scene_sample(&s, 1.999f, &out);
    assert_float_equal(out, 2.0f, 0.0f);
    rb_scene_sample(&s, -3.0f, &out);
    assert_float_equal(out, 1.0f, 0.0f);
    rb_scene_sample(&s, 9.0f, &out);
    assert_float_equal(out, 3.0f, 0.0f);
}

static void test_linear(void **state)
{
    (void)state;
    float times[2] = {0, 2}, values[6] = {0, 10, 0, 4, 20, 2}, out[3];
    struct rb_scene_anim_sampler s = sampler(RB_ANIM_LINEAR, times, 2, values, 3);
    rb_scene_sample(&s, 1.0f, out);
    assert_float_equal(out[0], 2.0f, 1e-6f);
    assert_float_equal(out[1], 15.0f, 1e-6f);
    assert_float_equal(out[2], 1.0f, 1e-6f);
    rb_scene_sample(&s, 0.5f, out);
    assert_float_equal(out[1], 12.5f, 1e-6f);
    /* clamped on both sides */
    rb_scene_sample(&s, -1.0f, out);
    assert_float_equal(out[1], 10.0f, 0.0f);
    rb_scene_sample(&s, 2.5f, out);
    assert_float_equal(out[1], 20.0f, 0.0f);
    rb_scene_sample(&s, NAN, out);
    assert_float_equal(out[1], 10.0f, 0.0f);
}

static void test_single_key(void **state)
{
    (void)state;
    float times[1] = {0.5f}, values[2] = {7, 8}, out[2];
    struct rb_scene_anim_sampler s = sampler(RB_ANIM_LINEAR, times, 1, values, 2);
    rb_scene_sample(&s, 0.0f, out);
    assert_float_equal(out[1], 8.0f, 0.0f);
    rb_scene_sample(&s, 3.0f, out);
    assert_float_equal(out[0], 7.0f, 0.0f);
}

static void test_cubic_spline(void **state)
{
    (void)state;
    /* keys at 0 and 2 (interval 2): v0 = 1 with out-tangent 0.5, v1 = 3 with in-tangent -1.
     * At u = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875, so
     * p = 0.84375 * 1 + 2 * 0.140625 * 0.5 + 0.15625 * 3 + 2 * -0.046875 * -1 = 1.546875. */
    float times[2] = {0, 2};
    float values[6] = {/* key 0: in, value, out */ 9,
                       1,
                       0.5f,
                       /* key 1 */ -1,
                       3,
                       9};
    struct rb_scene_anim_sampler s = sampler(RB_ANIM_CUBICSPLINE, times, 2, values, 1);
    float out;
    rb_scene_sample(&s, 0.5f, &out);
    assert_float_equal(out, 1.546875f, 1e-6f);
    rb_scene_sample(&s, 0.0f, &out);
    assert_float_equal(out, 1.0f, 1e-6f);
    rb_scene_sample(&s, 2.0f, &out);
    assert_float_equal(out, 3.0f, 1e-6f);
    rb_scene_sample(&s, 5.0f, &out); /* clamped: the value, not a tangent */
    assert_float_equal(out, 3.0f, 0.0f);
    rb_scene_sample(&s, -5.0f, &out);
    assert_float_equal(out, 1.0f, 0.0f);
    /* three keys: the second interval uses its own tangents */
    float t3[3] = {0, 1, 3};
    float v3[9] = {0, 0, 0, 0, 2, 1, 4, 6, 0};
    s = sampler(RB_ANIM_CUBICSPLINE, t3, 3, v3, 1);
    rb_scene_sample(&s, 2.0f, &out); /* u = 0.5, td = 2: 0.5*2 + 2*0.125*1 + 0.5*6 + 2*-0.125*4 */
    assert_float_equal(out, 3.25f, 1e-6f);
}

static void test_rotation_slerp(void **state)
{
    (void)state;
    float h = sqrtf(0.5f);
    float times[2] = {0, 1}, values[8] = {0, 0, 0, 1, 0, h, 0, h}, q[4];
    struct rb_scene_anim_sampler s = sampler(RB_ANIM_LINEAR, times, 2, values, 4);
    rb_scene_sample_path(&s, RB_ANIM_ROTATION, 0.5f, q);
    assert_float_equal(quat_angle_deg(q), 45.0f, 1e-3f);
    assert_float_equal(q[1], sinf(RB_PI / 8), 1e-6f);
    assert_float_equal(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0f, 1e-6f);
    /* slerp is uniform in angle (nlerp would give 21.6 degrees here) */
    rb_scene_sample_path(&s, RB_ANIM_ROTATION, 0.25f, q);
    assert_float_equal(quat_angle_deg(q), 22.5f, 1e-3f);
    /* the plain sampler interpolates component-wise, unnormalized */
    rb_scene_sample(&s, 0.5f, q);
    assert_float_equal(q[3], 0.5f * (1.0f + h), 1e-6f);
    /* a negated second key is the same rotation: slerp takes the short way */
    for (int k = 4; k < 8; k++)
        values[k] = -values[k];
    rb_scene_sample_path(&s, RB_ANIM_ROTATION, 0.5f, q);
    assert_float_equal(quat_angle_deg(q), 45.0f, 1e-3f);
    /* CUBICSPLINE rotations come out normalized */
    float cv[24] = {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, h, 0, h, 0, 0, 0, 0};
    s = sampler(RB_ANIM_CUBICSPLINE, times, 2, cv, 4);
    rb_scene_sample_path(&s, RB_ANIM_ROTATION, 0.5f, q);
    assert_float_equal(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0f, 1e-6f);
    assert_float_equal(quat_angle_deg(q), 45.0f, 1e-3f); /* symmetric Hermite, zero tangents */
}

/* ---- evaluation on a hand-built scene ------------------------------------------------------- */

/* Node 0 "Child" (mesh 0, a morphed triangle) under node 1 "Parent"; the child comes first to
 * check that evaluation does not assume parents precede children. Clip 0 "Move" (2 s):
 * Parent translation (0,0,0) -> (4,0,0), Child rotation 0 -> 90 degrees about Y. */
struct fixture {
    struct rb_scene s;
    struct rb_scene_node nodes[2];
    struct rb_scene_vertex verts[3];
    uint32_t idx[3];
    struct rb_scene_primitive prim;
    struct rb_scene_mesh mesh;
    struct rb_scene_morph_delta deltas[6];
    float weights[2];
    struct rb_scene_animation anim;
    struct rb_scene_anim_sampler samplers[2];
    struct rb_scene_anim_channel channels[2];
    float times[2], move[6], turn[8];
};

static void build(struct fixture *f)
{
    memset(f, 0, sizeof(*f));
    float h = sqrtf(0.5f);
    const float pos[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 3; i++) {
        memcpy(f->verts[i].position, pos[i], sizeof(pos[i]));
        f->verts[i].normal[2] = 1;
        f->idx[i] = (uint32_t)i;
    }
    f->deltas[0].position[2] = 2;  /* target 0 moves vertex 0 up to z = 2 */
    f->deltas[4].position[2] = -1; /* target 1 moves vertex 1 down to z = -1 */
    f->prim =
        (struct rb_scene_primitive){.vertex_count = 3, .index_count = 3, .morph_target_count = 2};
    f->weights[0] = 0.5f;
    f->mesh = (struct rb_scene_mesh){
        .name = "Tri", .primitive_count = 1, .default_weights = f->weights, .weight_count = 2};
    f->nodes[0] = (struct rb_scene_node){.name = "Child",
                                         .parent = 1,
                                         .translation = {0, 1, 0},
                                         .rotation = {0, 0, 0, 1},
                                         .scale = {1, 1, 1},
                                         .mesh = 0,
                                         .skin = NONE,
                                         .camera = NONE,
                                         .light = NONE,
                                         .in_scene = true};
    f->nodes[1] = (struct rb_scene_node){.name = "Parent",
                                         .parent = NONE,
                                         .translation = {10, 0, 0},
                                         .rotation = {0, 0, 0, 1},
                                         .scale = {1, 1, 1},
                                         .mesh = NONE,
                                         .skin = NONE,
                                         .camera = NONE,
                                         .light = NONE,
                                         .in_scene = true};
    f->times[0] = 0, f->times[1] = 2;
    const float move[6] = {0, 0, 0, 4, 0, 0}, turn[8] = {0, 0, 0, 1, 0, h, 0, h};
    memcpy(f->move, move, sizeof(move));
    memcpy(f->turn, turn, sizeof(turn));
    f->samplers[0] = sampler(RB_ANIM_LINEAR, f->times, 2, f->move, 3);
    f->samplers[1] = sampler(RB_ANIM_LINEAR, f->times, 2, f->turn, 4);
    f->channels[0] = (struct rb_scene_anim_channel){0, 1, RB_ANIM_TRANSLATION};
    f->channels[1] = (struct rb_scene_anim_channel){1, 0, RB_ANIM_ROTATION};
    f->anim = (struct rb_scene_animation){.name = "Move",
                                          .samplers = f->samplers,
                                          .sampler_count = 2,
                                          .channels = f->channels,
                                          .channel_count = 2,
                                          .duration_s = 2};
    f->s = (struct rb_scene){.vertices = f->verts,
                             .vertex_count = 3,
                             .indices = f->idx,
                             .index_count = 3,
                             .morph_deltas = f->deltas,
                             .morph_delta_count = 6,
                             .primitives = &f->prim,
                             .primitive_count = 1,
                             .meshes = &f->mesh,
                             .mesh_count = 1,
                             .nodes = f->nodes,
                             .node_count = 2,
                             .animations = &f->anim,
                             .animation_count = 1};
}

static struct rb_scene_pose *pose_of(const struct rb_scene *s)
{
    struct rb_scene_pose *p = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_scene_pose_create(s, &p, &err))
        fail_msg("pose: %s", err.msg);
    return p;
}

static struct rb_vec3 translation(const struct rb_mat4 *m)
{
    return rb_v3(m->m[3][0], m->m[3][1], m->m[3][2]);
}

static void test_evaluate_hierarchy(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    struct rb_scene_pose *p = pose_of(&f.s);
    assert_int_equal(p->instance_count, 1);
    assert_int_equal(p->instances[0].node, 0);
    assert_int_equal(p->instances[0].first_joint, NONE);
    assert_int_equal(p->instances[0].first_weight, 0);

    /* rest pose (no selection) */
    rb_scene_evaluate(&f.s, NULL, 5.0, p);
    struct rb_vec3 t = translation(&p->node_world[0]);
    assert_float_equal(t.x, 10.0f, 1e-6f);
    assert_float_equal(t.y, 1.0f, 1e-6f);

    /* at t = 1 the clip replaces the rest translation: parent at (2,0,0), child turned 45 deg */
    uint32_t clip = 0;
    struct rb_anim_selection sel = {.clips = &clip, .clip_count = 1, .speed = 1.0};
    rb_scene_evaluate(&f.s, &sel, 1.0, p);
    t = translation(&p->node_world[0]);
    assert_float_equal(t.x, 2.0f, 1e-6f);
    assert_float_equal(t.y, 1.0f, 1e-6f);
    struct rb_vec3 x = rb_mat4_dir(&p->node_world[0], rb_v3(1, 0, 0));
    assert_float_equal(x.x, cosf(RB_PI / 4), 1e-6f);
    assert_float_equal(x.z, -sinf(RB_PI / 4), 1e-6f);

    /* not looping: clamped at the end */
    rb_scene_evaluate(&f.s, &sel, 3.0, p);
    assert_float_equal(translation(&p->node_world[1]).x, 4.0f, 1e-6f);
    /* looping: 3 s wraps to 1 s, -0.5 s to 1.5 s */
    sel.loop = true;
    rb_scene_evaluate(&f.s, &sel, 3.0, p);
    assert_float_equal(translation(&p->node_world[1]).x, 2.0f, 1e-5f);
    rb_scene_evaluate(&f.s, &sel, -0.5, p);
    assert_float_equal(translation(&p->node_world[1]).x, 3.0f, 1e-5f);
    /* offset and speed: 0.5 + 0.25 * 2 = 1 */
    sel.offset_s = 0.5;
    sel.speed = 2.0;
    rb_scene_evaluate(&f.s, &sel, 0.25, p);
    assert_float_equal(translation(&p->node_world[1]).x, 2.0f, 1e-5f);
    /* an out-of-range clip index is ignored */
    clip = 7;
    rb_scene_evaluate(&f.s, &sel, 0.25, p);
    assert_float_equal(translation(&p->node_world[1]).x, 10.0f, 0.0f);
    rb_scene_pose_destroy(p);
}

static void test_evaluate_morph_bounds(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    struct rb_scene_pose *p = pose_of(&f.s);
    rb_scene_evaluate(&f.s, NULL, 0.0, p);
    /* mesh default weights (0.5, 0): vertex 0 rises to z = 1 */
    assert_float_equal(p->morph_weights[0], 0.5f, 0.0f);
    assert_float_equal(p->morph_weights[1], 0.0f, 0.0f);
    assert_float_equal(p->bounds_min.x, 10.0f, 1e-6f);
    assert_float_equal(p->bounds_max.x, 11.0f, 1e-6f);
    assert_float_equal(p->bounds_min.y, 1.0f, 1e-6f);
    assert_float_equal(p->bounds_max.y, 2.0f, 1e-6f);
    assert_float_equal(p->bounds_min.z, 0.0f, 1e-6f);
    assert_float_equal(p->bounds_max.z, 1.0f, 1e-6f);
    rb_scene_pose_destroy(p);

    /* node weights override the mesh's: (0, 1) lowers vertex 1 to z = -1 */
    float nw[2] = {0, 1};
    f.nodes[0].weights = nw;
    p = pose_of(&f.s);
    assert_float_equal(p->morph_weights[1], 1.0f, 0.0f);
    assert_float_equal(p->bounds_min.z, -1.0f, 1e-6f);
    assert_float_equal(p->bounds_max.z, 0.0f, 1e-6f);

    /* an animated weights channel beats both */
    float wv[4] = {1, 0, 1, 0};
    f.samplers[0] = sampler(RB_ANIM_LINEAR, f.times, 2, wv, 2);
    f.channels[0] = (struct rb_scene_anim_channel){0, 0, RB_ANIM_WEIGHTS};
    f.anim.channel_count = 1; /* without the rotation */
    uint32_t clip = 0;
    struct rb_anim_selection sel = {.clips = &clip, .clip_count = 1, .speed = 1.0};
    rb_scene_evaluate(&f.s, &sel, 1.0, p);
    assert_float_equal(p->morph_weights[0], 1.0f, 0.0f);
    assert_float_equal(p->morph_weights[1], 0.0f, 0.0f);
    assert_float_equal(p->bounds_max.z, 2.0f, 1e-6f);
    rb_scene_pose_destroy(p);
}

static void test_evaluate_skin(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    /* Node 0 gets a skin of joints {1, 2}; node 2 is a child of 1 at (0,5,0). Vertex 0 follows
     * joint 0, vertex 1 joint 1, vertex 2 half and half. The skinned mesh ignores its own
     * node's transform (glTF 3.7.3.3). */
    struct rb_scene_node nodes[3] = {f.nodes[0], f.nodes[1], f.nodes[1]};
    nodes[0].parent = NONE;
    nodes[0].translation = rb_v3(100, 0, 0);
    nodes[0].skin = 0;
    nodes[2].name = "Tip";
    nodes[2].parent = 1;
    nodes[2].translation = rb_v3(0, 5, 0);
    f.s.nodes = nodes;
    f.s.node_count = 3;
    f.s.animation_count = 0;
    f.prim.morph_target_count = 0;
    f.mesh.weight_count = 0;
    f.verts[0].weights[0] = 1;
    f.verts[1].joints[0] = 1;
    f.verts[1].weights[0] = 1;
    f.verts[2].joints[1] = 1;
    f.verts[2].weights[0] = 0.5f;
    f.verts[2].weights[1] = 0.5f;
    uint32_t joints[2] = {1, 2};
    struct rb_mat4 ibm[2] = {rb_mat4_identity(), rb_mat4_identity()};
    ibm[1].m[3][1] = -5; /* bind pose: the tip joint sat at y = 5 */
    struct rb_scene_skin skin = {
        .name = "Rig", .joints = joints, .inverse_bind = ibm, .joint_count = 2};
    f.s.skins = &skin;
    f.s.skin_count = 1;

    struct rb_scene_pose *p = pose_of(&f.s);
    assert_int_equal(p->joint_matrix_count, 2);
    assert_int_equal(p->instances[0].first_joint, 0);
    assert_int_equal(p->instances[0].first_weight, NONE);
    /* joint matrix = joint world * inverse bind: the tip moved with its parent (10,0,0) */
    struct rb_vec3 j1 = translation(&p->joint_matrices[1]);
    assert_float_equal(j1.x, 10.0f, 1e-6f);
    assert_float_equal(j1.y, 0.0f, 1e-6f);
    /* every vertex lands at x in [10, 11]; the mesh node's x = 100 plays no part */
    assert_float_equal(p->bounds_min.x, 10.0f, 1e-6f);
    assert_float_equal(p->bounds_max.x, 11.0f, 1e-6f);
    assert_float_equal(p->bounds_max.y, 1.0f, 1e-6f);

    /* the tip joint bends up: bounds follow the joint's box */
    nodes[2].translation = rb_v3(0, 8, 0);
    rb_scene_evaluate(&f.s, NULL, 0.0, p);
    /* vertex 2 (0,1,0) leans on joint 1, whose box goes through (10,3,0): y up to 4 */
    assert_float_equal(p->bounds_max.y, 4.0f, 1e-5f);
    assert_float_equal(p->bounds_min.y, 0.0f, 1e-6f);
    rb_scene_pose_destroy(p);
}

static void test_pose_errors(void **state)
{
    (void)state;
    struct fixture f;
    build(&f);
    f.nodes[1].parent = 0; /* a cycle: 0 -> 1 -> 0 */
    struct rb_scene_pose *p = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_scene_pose_create(&f.s, &p, &err), RB_E_INVALID);
    assert_null(p);
    assert_non_null(strstr(err.msg, "cycle"));
    build(&f);
    f.nodes[0].parent = 9;
    assert_int_equal(rb_scene_pose_create(&f.s, &p, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "parent 9"));
    rb_scene_pose_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_step),
        cmocka_unit_test(test_linear),
        cmocka_unit_test(test_single_key),
        cmocka_unit_test(test_cubic_spline),
        cmocka_unit_test(test_rotation_slerp),
        cmocka_unit_test(test_evaluate_hierarchy),
        cmocka_unit_test(test_evaluate_morph_bounds),
        cmocka_unit_test(test_evaluate_skin),
        cmocka_unit_test(test_pose_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
