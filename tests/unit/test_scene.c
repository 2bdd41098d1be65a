/* Scene loading: the shared sample scenes (counts, skins, animation, textures), the hand-made
 * tests/unit/scenes/features.gltf (every conversion feature), world lights, clip selection,
 * and files that must fail with a message naming the culprit. */
#include "scene/scene.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "testutil.h"

#define FEATURES "tests/unit/scenes/features.gltf"

/* ---- helpers -------------------------------------------------------------------------------- */

static char log_text[16384];

static void capture(enum rb_log_level level, const char *msg, void *user)
{
    (void)level;
    (void)user;
    size_t n = strlen(log_text);
    snprintf(log_text + n, sizeof(log_text) - n, "%s\n", msg);
}

static int setup_log(void **state)
{
    (void)state;
    log_text[0] = '\0';
    rb_log_set_sink(capture, NULL);
    rb_log_set_level(RB_LOG_INFO);
    return 0;
}

static int teardown_log(void **state)
{
    (void)state;
    rb_log_set_sink(NULL, NULL);
    rb_log_set_level(RB_LOG_WARN);
    return 0;
}

static struct rb_scene *load(const char *path)
{
    struct rb_scene *s = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_scene_load(path, 0, &s, &err);
    if (st)
        fail_msg("loading '%s' failed: %s", path, err.msg);
    return s;
}

static struct rb_scene *load_shared(const char *rel)
{
    char path[1024];
    if (rb_test_scene(path, sizeof(path), rel))
        skip(); /* a checkout without the external sample scenes */
    return load(path);
}

static struct rb_scene_pose *pose_of(const struct rb_scene *s)
{
    struct rb_scene_pose *p = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_scene_pose_create(s, &p, &err))
        fail_msg("pose: %s", err.msg);
    return p;
}

static size_t instanced_triangles(const struct rb_scene *s, const struct rb_scene_pose *p)
{
    size_t n = 0;
    for (uint32_t i = 0; i < p->instance_count; i++)
        n += s->primitives[p->instances[i].primitive].index_count / 3;
    return n;
}

static struct rb_anim_selection clip(const uint32_t *index)
{
    return (struct rb_anim_selection){.clips = index, .clip_count = 1, .speed = 1.0, .loop = true};
}

static struct rb_vec3 translation(const struct rb_mat4 *m)
{
    return rb_v3(m->m[3][0], m->m[3][1], m->m[3][2]);
}

static char tmpdir[256];

static int setup_tmp(void **state)
{
    const char *base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof(tmpdir), "%s/rb_scene_XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir))
        return -1;
    return setup_log(state);
}

static int teardown_tmp(void **state)
{
    char cmd[400];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0)
        return -1;
    return teardown_log(state);
}

static void write_file(const char *name, const void *data, size_t size, char *path, size_t cap)
{
    snprintf(path, cap, "%s/%s", tmpdir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* A one-triangle glTF with an embedded buffer; %s slots: extra top-level members, then extra
 * primitive members. Positions (0,0,0) (1,0,0) (0,1,0), then u16 indices 0 1 2 (+ pad). */
static const char *const tiny_gltf =
    "{\"asset\":{\"version\":\"2.0\"},%s"
    "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0%s}],"
    "\"meshes\":[{\"name\":\"Body\",\"primitives\":[{\"attributes\":{\"POSITION\":0}%s}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"type\":\"VEC3\",\"count\":%s,"
    "\"min\":[0,0,0],\"max\":[1,1,0]},"
    "{\"bufferView\":1,\"componentType\":5123,\"type\":\"SCALAR\",\"count\":3}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
    "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
    "\"buffers\":[{\"byteLength\":44,\"uri\":\"data:application/octet-stream;base64,"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=\"}]}";

/* Writes tiny_gltf with the given parts to name and tries to load it. */
static enum rb_status load_tiny(const char *name, const char *top, const char *node,
                                const char *prim, const char *count, struct rb_err *err, char *path,
                                size_t cap)
{
    char json[4096];
    snprintf(json, sizeof(json), tiny_gltf, top, node, prim, count);
    write_file(name, json, strlen(json), path, cap);
    struct rb_scene *s = NULL;
    enum rb_status st = rb_scene_load(path, 0, &s, err);
    rb_scene_destroy(s);
    return st;
}

/* ---- shared scenes -------------------------------------------------------------------------- */

static void test_shared_triangle_counts(void **state)
{
    (void)state;
    static const struct {
        const char *file;
        size_t triangles;
    } cases[] = {
        {"cornell-box/CornellBox.glb", 36},
        {"cornell-box-suzanne/cornell-box.glb", 1040},
        {"Fox/Fox.glb", 576},
        {"CesiumMan/CesiumMan.glb", 4672},
        {"BoxAnimated/BoxAnimated.gltf", 254},
        {"AnimatedMorphCube/AnimatedMorphCube.glb", 12},
        {"MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb", 1040409},
        {"WaterBottle/WaterBottle.gltf", 4510},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        struct rb_scene *s = load_shared(cases[i].file);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        struct rb_scene_pose *p = pose_of(s);
        size_t tris = instanced_triangles(s, p);
        if (tris != cases[i].triangles)
            fail_msg("%s: %zu triangles, expected %zu", cases[i].file, tris, cases[i].triangles);
        /* every index stays inside its primitive, every primitive inside the arrays */
        for (uint32_t k = 0; k < s->primitive_count; k++) {
            const struct rb_scene_primitive *pr = &s->primitives[k];
            assert_true((uint64_t)pr->first_vertex + pr->vertex_count <= s->vertex_count);
            assert_true((uint64_t)pr->first_index + pr->index_count <= s->index_count);
            assert_true(pr->material < s->material_count);
            for (uint32_t j = 0; j < pr->index_count; j++)
                assert_true(s->indices[pr->first_index + j] < pr->vertex_count);
        }
        const struct rb_scene_material *def = &s->materials[s->material_count - 1];
        assert_float_equal(def->roughness, 1.0f, 0.0f);
        assert_float_equal(def->metallic, 0.0f, 0.0f);
        printf("# %s: %zu triangles, loaded in %.1f ms\n", cases[i].file, tris,
               (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6);
        rb_scene_pose_destroy(p);
        rb_scene_destroy(s);
    }
}

static void test_cornell_emissive_strength(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("cornell-box/CornellBox.glb");
    float best = 0.0f;
    for (uint32_t i = 0; i < s->material_count; i++)
        best = fmaxf(best, s->materials[i].emissive[0]);
    assert_float_equal(best, 100.0f, 1e-3f); /* emissiveFactor 1 x emissiveStrength 100 */
    rb_scene_destroy(s);
}

static void test_fox_skin_and_clips(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("Fox/Fox.glb");
    assert_int_equal(s->skin_count, 1);
    assert_int_equal(s->skins[0].joint_count, 24);
    assert_int_equal(s->animation_count, 3);
    uint32_t walk = rb_scene_find_animation(s, "Walk");
    assert_int_equal(walk, 1);
    assert_int_equal(rb_scene_find_animation(s, "Fly"), RB_SCENE_NONE);
    assert_float_equal(s->animations[walk].duration_s, 0.708f, 1e-3f);
    assert_int_equal(s->animations[walk].channel_count, 21);

    struct rb_scene_pose *p = pose_of(s);
    assert_int_equal(p->instance_count, 1);
    assert_int_equal(p->instances[0].first_joint, 0);
    assert_int_equal(p->joint_matrix_count, 24);
    uint32_t survey = rb_scene_find_animation(s, "Survey");
    struct rb_anim_selection sel = clip(&survey);
    struct rb_vec3 lo[3], hi[3];
    struct rb_mat4 first[3];
    const double times[3] = {0.0, 1.0, 2.2};
    for (int t = 0; t < 3; t++) {
        rb_scene_evaluate(s, &sel, times[t], p);
        for (uint32_t j = 0; j < p->joint_matrix_count; j++)
            for (int c = 0; c < 16; c++)
                assert_true(isfinite(p->joint_matrices[j].m[c / 4][c % 4]));
        lo[t] = p->bounds_min;
        hi[t] = p->bounds_max;
        first[t] = p->joint_matrices[5];
        assert_true(hi[t].y - lo[t].y > 50.0f && hi[t].y - lo[t].y < 120.0f);
    }
    /* the fox moves: bounds and joints differ between times */
    bool moved = false;
    for (int t = 1; t < 3; t++)
        moved |= fabsf(lo[t].x - lo[0].x) + fabsf(hi[t].x - hi[0].x) + fabsf(lo[t].z - lo[0].z) +
                     fabsf(hi[t].z - hi[0].z) >
                 0.5f;
    assert_true(moved);
    assert_true(memcmp(&first[0], &first[1], sizeof(first[0])) != 0);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_cesium_man(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("CesiumMan/CesiumMan.glb");
    assert_int_equal(s->skin_count, 1);
    assert_int_equal(s->skins[0].joint_count, 19);
    assert_int_equal(s->animation_count, 1);
    assert_int_equal(s->texture_count, 1);
    struct rb_scene_pose *p = pose_of(s);
    uint32_t a = 0;
    struct rb_anim_selection sel = clip(&a);
    rb_scene_evaluate(s, &sel, 0.5, p);
    /* a 1.5 m tall figure standing on y = 0 */
    assert_true(p->bounds_max.y - p->bounds_min.y > 1.0f && p->bounds_max.y < 2.5f);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_box_animated_moves(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("BoxAnimated/BoxAnimated.gltf");
    assert_int_equal(s->animation_count, 1);
    assert_float_equal(s->animations[0].duration_s, 3.708f, 1e-3f);
    struct rb_scene_pose *p = pose_of(s);
    uint32_t a = 0;
    struct rb_anim_selection sel = clip(&a);
    struct rb_mat4 w1[8], w2[8];
    assert_true(s->node_count <= 8);
    rb_scene_evaluate(s, &sel, 1.0, p);
    memcpy(w1, p->node_world, s->node_count * sizeof(struct rb_mat4));
    rb_scene_evaluate(s, &sel, 2.0, p);
    memcpy(w2, p->node_world, s->node_count * sizeof(struct rb_mat4));
    int moved = 0;
    for (uint32_t i = 0; i < s->node_count; i++) {
        float d = 0.0f;
        for (int c = 0; c < 16; c++)
            d += fabsf(w1[i].m[c / 4][c % 4] - w2[i].m[c / 4][c % 4]);
        moved += d > 1e-3f;
    }
    assert_true(moved >= 1);
    /* deterministic: the same time gives the same bits */
    rb_scene_evaluate(s, &sel, 1.0, p);
    assert_memory_equal(w1, p->node_world, s->node_count * sizeof(struct rb_mat4));
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_morph_cube_weights(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("AnimatedMorphCube/AnimatedMorphCube.glb");
    assert_int_equal(s->primitives[0].morph_target_count, 2);
    assert_int_equal(s->morph_delta_count, 2 * s->primitives[0].vertex_count);
    struct rb_scene_pose *p = pose_of(s);
    assert_int_equal(p->morph_weight_count, 2);
    assert_int_equal(p->instances[0].first_weight, 0);
    uint32_t a = rb_scene_find_animation(s, "Square");
    assert_int_not_equal(a, RB_SCENE_NONE);
    struct rb_anim_selection sel = clip(&a);
    float w[4][2];
    const double times[4] = {0.0, 1.0, 2.0, 3.0};
    for (int t = 0; t < 4; t++) {
        rb_scene_evaluate(s, &sel, times[t], p);
        memcpy(w[t], p->morph_weights, sizeof(w[t]));
        for (int k = 0; k < 2; k++)
            assert_true(w[t][k] >= -1e-3f && w[t][k] <= 1.001f);
    }
    float change = 0.0f;
    for (int t = 1; t < 4; t++)
        change += fabsf(w[t][0] - w[0][0]) + fabsf(w[t][1] - w[0][1]);
    assert_true(change > 0.1f);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_water_bottle_textures(void **state)
{
    (void)state;
    struct rb_scene *s = load_shared("WaterBottle/WaterBottle.gltf");
    assert_int_equal(s->texture_count, 4);
    for (uint32_t i = 0; i < s->texture_count; i++) {
        const struct rb_scene_texture *t = &s->textures[i];
        assert_true(t->width_px > 0 && t->height_px > 0);
        assert_non_null(t->rgba8);
        assert_non_null(t->name);
        /* not all black: the image really decoded */
        uint64_t sum = 0;
        for (size_t k = 0; k < (size_t)t->width_px * t->height_px * 4; k += 4097)
            sum += t->rgba8[k];
        assert_true(sum > 0);
    }
    const struct rb_scene_material *m = &s->materials[0];
    assert_true(m->base_color_tex < 4 && m->normal_tex < 4 && m->metallic_roughness_tex < 4 &&
                m->emissive_tex < 4);
    assert_true(strstr(s->textures[m->normal_tex].name, "normal") != NULL);
    assert_int_equal(s->primitives[0].material, 0);
    rb_scene_destroy(s);
}

/* ---- features.gltf -------------------------------------------------------------------------- */

static void test_features_geometry(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    assert_non_null(strstr(log_text, "mesh 'Mixed' primitive 1: points"));
    assert_non_null(strstr(log_text, "TEXCOORD_1"));
    assert_int_equal(s->mesh_count, 4);

    /* Strip: 4 vertices, triangles (0 1 2) (1 3 2) */
    const struct rb_scene_mesh *m = &s->meshes[0];
    assert_int_equal(m->primitive_count, 1);
    const struct rb_scene_primitive *p = &s->primitives[m->first_primitive];
    assert_int_equal(p->vertex_count, 4);
    assert_int_equal(p->index_count, 6);
    const uint32_t strip[6] = {0, 1, 2, 1, 3, 2};
    assert_memory_equal(s->indices + p->first_index, strip, sizeof(strip));
    assert_int_equal(p->material, s->material_count - 1); /* the default material */

    /* Fan: 3 triangles, no normals: flat normals on 9 unshared vertices */
    p = &s->primitives[s->meshes[1].first_primitive];
    assert_int_equal(p->index_count, 9);
    assert_int_equal(p->vertex_count, 9);
    const struct rb_scene_vertex *v = s->vertices + p->first_vertex;
    const float fan_first[3][3] = {{1, 0, 0}, {1, 1, 0}, {0, 0, 0}}; /* (v1, v2, v0) */
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++)
            assert_float_equal(v[k].position[c], fan_first[k][c], 0.0f);
    for (uint32_t k = 0; k < 9; k++) {
        assert_float_equal(v[k].normal[2], 1.0f, 1e-6f);
        assert_int_equal(s->indices[p->first_index + k], k);
    }

    /* Mixed: the points primitive is gone; the triangle got tangents from its UVs */
    assert_int_equal(s->meshes[2].primitive_count, 1);
    p = &s->primitives[s->meshes[2].first_primitive];
    assert_int_equal(p->material, 0);
    v = s->vertices + p->first_vertex;
    assert_float_equal(v[1].uv[0], 1.0f, 0.0f); /* normalized u8 255 */
    for (int k = 0; k < 3; k++) {
        assert_float_equal(v[k].tangent[0], 1.0f, 1e-6f);
        assert_float_equal(v[k].tangent[1], 0.0f, 1e-6f);
        assert_float_equal(v[k].tangent[3], 1.0f, 0.0f);
    }

    /* Morph: one target, sparse delta (0, 0, 3) on vertex 2 only */
    m = &s->meshes[3];
    assert_int_equal(m->weight_count, 1);
    assert_float_equal(m->default_weights[0], 0.5f, 0.0f);
    p = &s->primitives[m->first_primitive];
    assert_int_equal(p->morph_target_count, 1);
    const struct rb_scene_morph_delta *d = s->morph_deltas + p->first_morph;
    assert_float_equal(d[2].position[2], 3.0f, 0.0f);
    assert_float_equal(d[0].position[2], 0.0f, 0.0f);
    assert_float_equal(d[1].position[2], 0.0f, 0.0f);
    rb_scene_destroy(s);
}

static void test_features_material_texture(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    assert_int_equal(s->material_count, 2);
    const struct rb_scene_material *m = &s->materials[0];
    assert_string_equal(m->name, "Bumpy");
    assert_float_equal(m->base_color[1], 0.25f, 0.0f);
    assert_float_equal(m->metallic, 0.75f, 0.0f);
    assert_float_equal(m->roughness, 0.125f, 0.0f);
    assert_float_equal(m->normal_scale, 0.5f, 0.0f);
    assert_float_equal(m->emissive[0], 4.0f, 0.0f); /* x emissiveStrength 4 */
    assert_float_equal(m->emissive[1], 2.0f, 0.0f);
    assert_float_equal(m->emissive[2], 1.0f, 0.0f);
    assert_int_equal(m->alpha_mode, RB_ALPHA_MASK);
    assert_float_equal(m->alpha_cutoff, 0.3f, 1e-6f);
    assert_true(m->double_sided);
    assert_int_equal(m->base_color_tex, 0);
    assert_int_equal(m->normal_tex, 0);
    assert_int_equal(m->metallic_roughness_tex, RB_SCENE_NONE);
    assert_int_equal(m->emissive_tex, RB_SCENE_NONE);
    const struct rb_scene_material *def = &s->materials[1];
    assert_float_equal(def->base_color[0], 1.0f, 0.0f);
    assert_int_equal(def->base_color_tex, RB_SCENE_NONE);

    /* 16-bit grey + alpha PNG: (0xffff, 0x8000) (0, 0xffff) -> RGBA8 */
    assert_int_equal(s->texture_count, 1);
    const struct rb_scene_texture *t = &s->textures[0];
    assert_string_equal(t->name, "grey16");
    assert_int_equal(t->width_px, 2);
    assert_int_equal(t->height_px, 1);
    const uint8_t want[8] = {255, 255, 255, 128, 0, 0, 0, 255};
    assert_memory_equal(t->rgba8, want, sizeof(want));
    rb_scene_destroy(s);
}

static void test_features_nodes(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    assert_int_equal(s->node_count, 10);
    uint32_t strip = rb_scene_find_node(s, "StripNode");
    assert_int_equal(strip, 1);
    assert_int_equal(rb_scene_find_node(s, "Nobody"), RB_SCENE_NONE);
    const struct rb_scene_node *n = &s->nodes[strip];
    assert_int_equal(n->parent, 0);
    /* matrix T(0,2,0) * Ry(90) * S(2) decomposed */
    assert_float_equal(n->translation.y, 2.0f, 1e-6f);
    assert_float_equal(n->scale.x, 2.0f, 1e-5f);
    assert_float_equal(n->scale.y, 2.0f, 1e-5f);
    assert_float_equal(n->scale.z, 2.0f, 1e-5f);
    float sign = n->rotation.w < 0 ? -1.0f : 1.0f;
    assert_float_equal(sign * n->rotation.y, sqrtf(0.5f), 1e-5f);
    assert_float_equal(sign * n->rotation.w, sqrtf(0.5f), 1e-5f);
    assert_float_equal(n->rotation.x, 0.0f, 1e-6f);

    for (uint32_t i = 0; i < 9; i++)
        assert_true(s->nodes[i].in_scene);
    assert_false(s->nodes[9].in_scene); /* Orphan */
    assert_int_equal(s->nodes[4].weights[0], 0.25f);

    assert_int_equal(s->camera_count, 1);
    assert_true(s->cameras[0].is_perspective);
    assert_float_equal(s->cameras[0].yfov_rad, 0.8f, 1e-6f);
    assert_float_equal(s->cameras[0].zfar, 100.0f, 0.0f);

    assert_int_equal(s->light_count, 3);
    assert_int_equal(s->lights[0].type, RB_LIGHT_POINT);
    assert_float_equal(s->lights[0].range, 5.0f, 0.0f);
    assert_int_equal(s->lights[1].type, RB_LIGHT_SPOT);
    assert_float_equal(s->lights[1].inner_cone_rad, 0.0f, 0.0f);
    assert_float_equal(s->lights[1].outer_cone_rad, RB_PI / 4, 1e-6f);
    assert_float_equal(s->lights[1].color[1], 1.0f, 0.0f); /* default white */
    assert_int_equal(s->lights[2].type, RB_LIGHT_DIRECTIONAL);

    /* instances in node order: Strip, Fan, Mixed, Morph; the orphan has none */
    struct rb_scene_pose *p = pose_of(s);
    assert_int_equal(p->instance_count, 4);
    const uint32_t nodes[4] = {1, 2, 3, 4};
    for (int i = 0; i < 4; i++)
        assert_int_equal(p->instances[i].node, nodes[i]);
    assert_int_equal(instanced_triangles(s, p), 2 + 3 + 1 + 1);
    assert_int_equal(p->instances[3].first_weight, 0);
    assert_float_equal(p->morph_weights[0], 0.25f, 0.0f); /* node.weights beat mesh.weights */
    struct rb_vec3 t = translation(&p->node_world[strip]);
    assert_float_equal(t.x, 1.0f, 1e-6f); /* Root's translation */
    assert_float_equal(t.y, 2.0f, 1e-6f);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_features_animation(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    struct rb_scene_pose *p = pose_of(s);
    uint32_t steps = rb_scene_find_animation(s, "Steps");
    uint32_t cubic = rb_scene_find_animation(s, "Cubic");
    uint32_t turn = rb_scene_find_animation(s, "Turn");
    assert_int_equal(steps, 0);
    assert_int_equal(s->animations[cubic].samplers[0].interpolation, RB_ANIM_CUBICSPLINE);
    struct rb_anim_selection sel = clip(&steps);
    sel.loop = false;
    rb_scene_evaluate(s, &sel, 0.5, p);
    assert_float_equal(translation(&p->node_world[1]).x, 1.0f, 1e-6f); /* STEP holds key 0 */
    rb_scene_evaluate(s, &sel, 1.5, p);
    assert_float_equal(translation(&p->node_world[1]).x, 6.0f, 1e-6f);
    rb_scene_evaluate(s, &sel, 7.0, p); /* clamped past the end */
    assert_float_equal(translation(&p->node_world[1]).x, 10.0f, 1e-6f);

    /* CUBICSPLINE weights, keys (0: v 0, out 2) (1: in 0, v 1): p(0.5) = 0.75 */
    sel.clips = &cubic;
    rb_scene_evaluate(s, &sel, 0.5, p);
    assert_float_equal(p->morph_weights[0], 0.75f, 1e-6f);
    /* the morphed vertex (delta z 3) widens the bounds as the weight grows */
    float z_half = p->bounds_max.z;
    rb_scene_evaluate(s, &sel, 1.0, p);
    assert_float_equal(p->morph_weights[0], 1.0f, 1e-6f);
    assert_true(p->bounds_max.z > z_half);
    assert_float_equal(p->bounds_max.z, 3.0f, 1e-5f);

    /* two clips at once: slerped rotation of FanNode plus the step translation */
    uint32_t both[2] = {turn, steps};
    sel = (struct rb_anim_selection){.clips = both, .clip_count = 2, .speed = 1.0};
    rb_scene_evaluate(s, &sel, 0.5, p);
    struct rb_vec3 x = rb_mat4_dir(&p->node_world[2], rb_v3(1, 0, 0));
    assert_float_equal(x.x, cosf(RB_PI / 4), 1e-5f);
    assert_float_equal(x.z, -sinf(RB_PI / 4), 1e-5f);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_features_lights(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    struct rb_scene_pose *p = pose_of(s);
    struct rb_job_light jl = {.type = RB_LIGHT_SPOT,
                              .position = {1, 2, 3},
                              .direction = {0, 0, -2},
                              .color = {1, 0.5f, 1},
                              .intensity = 4};
    struct rb_job job = {0};
    job.use_scene_lights = true;
    job.lights = &jl;
    job.light_count = 1;
    struct rb_world_light out[5];
    struct rb_scene_setup setup = {0}; /* no default light */
    memset(out, 0x5a, sizeof(out));
    assert_int_equal(rb_scene_world_lights(&job, s, &setup, p, out, 5), 4);
    /* SunNode rotated -90 degrees about X: light travels down */
    assert_int_equal(out[0].type, RB_LIGHT_DIRECTIONAL);
    assert_float_equal(out[0].direction.y, -1.0f, 1e-6f);
    assert_float_equal(out[0].color[0], 3.0f, 1e-6f);
    assert_int_equal(out[1].type, RB_LIGHT_SPOT);
    assert_float_equal(out[1].position.y, 3.0f, 1e-6f);
    assert_float_equal(out[1].outer_cone_rad, RB_PI / 4, 1e-6f);
    assert_int_equal(out[2].type, RB_LIGHT_POINT);
    assert_float_equal(out[2].position.x, 1.0f, 1e-6f); /* Root (1,0,0) + (0,0,2) */
    assert_float_equal(out[2].position.z, 2.0f, 1e-6f);
    assert_float_equal(out[2].color[0], 2.0f, 1e-6f);
    assert_float_equal(out[2].color[1], 0.0f, 0.0f);
    assert_float_equal(out[2].range, 5.0f, 0.0f);
    /* the job light: direction normalized, color x intensity, default outer cone 45 deg */
    assert_float_equal(out[3].direction.z, -1.0f, 1e-6f);
    assert_float_equal(out[3].color[1], 2.0f, 1e-6f);
    assert_float_equal(out[3].outer_cone_rad, RB_PI / 4, 1e-6f);
    assert_float_equal(out[3].inner_cone_rad, 0.0f, 0.0f);

    /* a short list: the count says how many there are, only cap are written */
    struct rb_world_light few[2];
    memset(few, 0x5a, sizeof(few));
    assert_int_equal(rb_scene_world_lights(&job, s, &setup, p, few, 1), 4);
    unsigned char pattern[sizeof(few[1])];
    memset(pattern, 0x5a, sizeof(pattern));
    assert_memory_equal(&few[1], pattern, sizeof(pattern));

    /* no lights at all, default_light on: one default point light above, right of and in front
     * of the job's bounds, two bounding radii from the center, irradiance ~1 at the center,
     * after the other lights; logged at info level */
    job = (struct rb_job){.default_light = RB_DEFAULT_LIGHT_ON, .rate_fps = 24};
    log_text[0] = '\0';
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_scene_setup_init(&job, s, NULL, 0, 0, &setup, &err), RB_OK);
    assert_true(setup.has_default_light);
    assert_int_equal(rb_scene_world_lights(&job, s, &setup, p, out, 5), 1);
    assert_int_equal(out[0].type, RB_LIGHT_POINT);
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(setup.bounds_min, setup.bounds_max), 0.5f);
    float radius = 0.5f * rb_v3_length(rb_v3_sub(setup.bounds_max, setup.bounds_min));
    struct rb_vec3 off = rb_v3_sub(out[0].position, c);
    float dist = rb_v3_length(off);
    assert_float_equal(dist, 2.0f * radius, 1e-4f * radius);
    assert_true(off.x > 0.0f && off.y > 0.0f && off.z > 0.0f);
    assert_true(off.y > off.x && off.y > off.z);
    assert_float_equal(out[0].color[0] / (dist * dist), 1.0f, 1e-4f);
    assert_non_null(strstr(log_text, "default light"));
    /* off: none, even with nothing else */
    job.default_light = RB_DEFAULT_LIGHT_OFF;
    assert_int_equal(rb_scene_setup_init(&job, s, NULL, 0, 0, &setup, &err), RB_OK);
    assert_false(setup.has_default_light);
    assert_int_equal(rb_scene_world_lights(&job, s, &setup, p, out, 5), 0);
    rb_scene_pose_destroy(p);
    rb_scene_destroy(s);
}

static void test_select_clips(void **state)
{
    (void)state;
    struct rb_scene *s = load(FEATURES);
    struct rb_err err = RB_ERR_INIT;
    uint32_t idx[4], count = 99;
    struct rb_job job = {0};
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 4, &count, &err), RB_OK);
    assert_int_equal(count, 1); /* none named: the first animation */
    assert_int_equal(idx[0], 0);
    char *names[2] = {"Turn", "Cubic"};
    job.animation.clips = names;
    job.animation.clip_count = 2;
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 4, &count, &err), RB_OK);
    assert_int_equal(count, 2);
    assert_int_equal(idx[0], 2);
    assert_int_equal(idx[1], 1);
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 1, &count, &err), RB_E_OVERFLOW);
    names[1] = "Dance";
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 4, &count, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "animation clip 'Dance' not found (scene has: Steps, Cubic, "
                                 "Turn)");
    rb_scene_destroy(s);

    s = load_shared("cornell-box/CornellBox.glb");
    job = (struct rb_job){0};
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 4, &count, &err), RB_OK);
    assert_int_equal(count, 0);
    job.animation.clips = names;
    job.animation.clip_count = 1;
    assert_int_equal(rb_scene_select_clips(s, &job, idx, 4, &count, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "(scene has: none)"));
    rb_scene_destroy(s);
}

/* ---- failures ------------------------------------------------------------------------------- */

static void test_missing_file(void **state)
{
    (void)state;
    struct rb_scene *s = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_scene_load("tests/unit/scenes/no-such-scene.glb", 0, &s, &err), RB_E_IO);
    assert_null(s);
    assert_non_null(strstr(err.msg, "no-such-scene.glb"));
}

static void test_corrupt_glb(void **state)
{
    (void)state;
    char path[512];
    unsigned char junk[300];
    for (size_t i = 0; i < sizeof(junk); i++)
        junk[i] = (unsigned char)(i * 37 + 11);
    write_file("junk.glb", junk, sizeof(junk), path, sizeof(path));
    struct rb_scene *s = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
    assert_null(s);
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "cannot load"));

    /* a valid header around a truncated JSON chunk */
    unsigned char glb[64] = "glTF";
    uint32_t words[4] = {2, sizeof(glb), 40, 0x4E4F534A};
    memcpy(glb + 4, words, sizeof(words));
    memcpy(glb + 20, "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{", 38);
    write_file("cut.glb", glb, sizeof(glb), path, sizeof(path));
    assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, path));

    write_file("junk.gltf", "{ \"asset\": ", 11, path, sizeof(path));
    assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, path));
}

static void test_missing_texture(void **state)
{
    (void)state;
    char path[512], top[512];
    snprintf(top, sizeof(top),
             "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
             "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"missing.png\"}],");
    struct rb_err err = RB_ERR_INIT;
    assert_int_not_equal(
        load_tiny("missing.gltf", top, "", ",\"material\":0", "3", &err, path, sizeof(path)),
        RB_OK);
    assert_non_null(strstr(err.msg, "image 'missing.png'"));

    /* without a material using it, the image does not matter */
    snprintf(top, sizeof(top), "\"images\":[{\"uri\":\"missing.png\"}],");
    assert_int_equal(load_tiny("unused.gltf", top, "", "", "3", &err, path, sizeof(path)), RB_OK);
}

static void test_unsupported_extension(void **state)
{
    (void)state;
    char path[512];
    struct rb_err err = RB_ERR_INIT;
    const char *top = "\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],"
                      "\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],";
    assert_int_equal(load_tiny("draco.gltf", top, "", "", "3", &err, path, sizeof(path)),
                     RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "'KHR_draco_mesh_compression'"));

    /* the extensions we know are fine, KHR_texture_transform with a warning */
    top = "\"extensionsUsed\":[\"KHR_lights_punctual\",\"KHR_texture_transform\"],"
          "\"extensionsRequired\":[\"KHR_lights_punctual\",\"KHR_texture_transform\"],";
    log_text[0] = '\0';
    assert_int_equal(load_tiny("known.gltf", top, "", "", "3", &err, path, sizeof(path)), RB_OK);
    assert_non_null(strstr(log_text, "KHR_texture_transform"));
}

static void test_bad_references(void **state)
{
    (void)state;
    char path[512];
    struct rb_err err = RB_ERR_INIT;
    /* sanity: the template loads */
    assert_int_equal(load_tiny("ok.gltf", "", "", ",\"indices\":1", "3", &err, path, sizeof(path)),
                     RB_OK);
    static const struct {
        const char *top, *node, *prim, *count, *want;
    } cases[] = {
        /* 4 VEC3 floats do not fit the 36-byte view */
        {"", "", "", "4", "accessor 0: bytes"},
        {"", "", ",\"indices\":0", "3", "mesh 'Body' primitive 0: accessor 0: expected SCALAR"},
        {"", "", ",\"indices\":7", "3", "cannot load"}, /* tinygltf's own check */
        {"", "", ",\"material\":3", "3", "material 3 does not exist"},
        {"", ",\"children\":[5]", "", "3", "child 5 does not exist"},
        {"", ",\"children\":[0]", "", "3", "lists itself among its children"},
        {"", ",\"skin\":2", "", "3", "skin 2 does not exist"},
        {"", "", ",\"mode\":9", "3", "unknown mode 9"},
        {"", "", ",\"targets\":[{\"POSITION\":1}]", "3", "expected VEC3, found SCALAR"},
        {"\"animations\":[{\"samplers\":[{\"input\":1,\"output\":0}],\"channels\":"
         "[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"rotation\"}}]}],",
         "", "", "3", "rotation needs 4 values per key"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        err = (struct rb_err)RB_ERR_INIT;
        enum rb_status st = load_tiny("bad.gltf", cases[i].top, cases[i].node, cases[i].prim,
                                      cases[i].count, &err, path, sizeof(path));
        if (st == RB_OK || !strstr(err.msg, cases[i].want))
            fail_msg("case %zu: status %d, message '%s', expected '%s'", i, st, err.msg,
                     cases[i].want);
    }
    /* an index past the vertices */
    err = (struct rb_err)RB_ERR_INIT;
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"name\":\"Body\",\"primitives\":[{\"attributes\":{\"POSITION\":0},"
        "\"indices\":1}]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
        "\"type\":\"VEC3\",\"count\":2},{\"bufferView\":1,\"componentType\":5123,"
        "\"type\":\"SCALAR\",\"count\":3}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":24},"
        "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],\"buffers\":[{\"byteLength\":44,"
        "\"uri\":\"data:application/octet-stream;base64,"
        "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=\"}]}";
    write_file("index.gltf", json, strlen(json), path, sizeof(path));
    struct rb_scene *s = NULL;
    assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, "mesh 'Body' primitive 0: index 2 out of range"));
}

/* ---- glTF JSON types ------------------------------------------------------------------------ */

/* Every issue rb_scene_json_check reports, one "pointer: problem" line each. */
static char issues[16384];

static bool collect(void *user, const char *pointer, const char *problem)
{
    (void)user;
    size_t n = strlen(issues);
    snprintf(issues + n, sizeof(issues) - n, "%s: %s\n", pointer, problem);
    return true;
}

static enum rb_status check_json(const char *json, const struct rb_scene_json_rule *rules,
                                 size_t rule_count, struct rb_err *err)
{
    issues[0] = '\0';
    return rb_scene_json_check(json, strlen(json), rules, rule_count, collect, NULL, err);
}

/* The walker on a table of its own: wildcards over arrays and objects, required members, the
 * types and their messages, table-then-document order, and stopping at the first issue. */
static void test_json_walker(void **state)
{
    (void)state;
    static const struct rb_scene_json_rule rules[] = {
        {"/list", RB_SCENE_JSON_ARRAY, 0, true},
        {"/list/*", RB_SCENE_JSON_OBJECT, 0, false},
        {"/list/*/i", RB_SCENE_JSON_UINT, 0, false},
        {"/list/*/v", RB_SCENE_JSON_NUMBERS, 3, false},
        {"/list/*/map", RB_SCENE_JSON_OBJECT, 0, false},
        {"/list/*/map/*", RB_SCENE_JSON_UINT, 0, false},
        {"/list/*/need", RB_SCENE_JSON_STRING, 0, true},
        {"/size", RB_SCENE_JSON_SIZE, 0, false},
        {"/flag", RB_SCENE_JSON_BOOLEAN, 0, false},
        {"/names", RB_SCENE_JSON_STRINGS, 0, false},
        {"/ids", RB_SCENE_JSON_UINTS, 0, false},
    };
    static const struct {
        const char *json, *issues;
    } cases[] = {
        {"{\"list\":[{\"i\":0,\"v\":[1,2.5,-3e2],\"map\":{\"A\":1},\"need\":\"x\"}],"
         "\"size\":8589934592,\"flag\":true,\"names\":[\"a\"],\"ids\":[0,2147483647]}",
         ""},
        {"{}", "/list: expected array, found nothing\n"},
        /* a parent of the wrong type is reported once, and nothing below it */
        {"{\"list\":{\"a\":{\"i\":-1}}}", "/list: expected array, found object\n"},
        {"{\"list\":[5]}", "/list/0: expected object, found 5\n"},
        {"{\"list\":[{\"need\":\"x\",\"i\":-1},{\"need\":\"x\",\"i\":1.0},"
         "{\"need\":\"x\",\"i\":2147483648},{\"need\":\"x\",\"i\":\"0\"}]}",
         "/list/0/i: expected non-negative integer, found -1\n"
         "/list/1/i: expected non-negative integer, found 1.0\n"
         "/list/2/i: expected non-negative integer, found 2147483648 (more than 2147483647)\n"
         "/list/3/i: expected non-negative integer, found string\n"},
        {"{\"list\":[{\"need\":\"x\",\"v\":[1,2]},{\"need\":\"x\",\"v\":[1,\"2\",3]},"
         "{\"need\":\"x\",\"v\":\"1,2,3\"}]}",
         "/list/0/v: expected array of 3 numbers, found array of 2\n"
         "/list/1/v/1: expected number, found string\n"
         "/list/2/v: expected array of 3 numbers, found string\n"},
        /* members in key order, escaped as RFC 6901 says; the table's order comes first */
        {"{\"list\":[{\"map\":{\"e\":null,\"a/b\":\"1\",\"c~d\":2}},{\"map\":[]}]}",
         "/list/1/map: expected object, found array\n"
         "/list/0/map/a~1b: expected non-negative integer, found string\n"
         "/list/0/map/e: expected non-negative integer, found null\n"
         "/list/0/need: expected string, found nothing\n"
         "/list/1/need: expected string, found nothing\n"},
        {"{\"size\":-1,\"flag\":\"yes\",\"names\":[\"a\",1],\"ids\":[0,-4]}",
         "/list: expected array, found nothing\n"
         "/size: expected non-negative integer, found -1\n"
         "/flag: expected boolean, found string\n"
         "/names/1: expected string, found 1\n"
         "/ids/1: expected non-negative integer, found -4\n"},
    };
    struct rb_err err = RB_ERR_INIT;
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        assert_int_equal(check_json(cases[i].json, rules, sizeof(rules) / sizeof(rules[0]), &err),
                         RB_OK);
        if (strcmp(issues, cases[i].issues))
            fail_msg("case %zu: issues\n%s\nexpected\n%s", i, issues, cases[i].issues);
    }

    /* without a callback the first issue stops the walk and is the error */
    const char *json = "{\"list\":[{\"i\":\"0\"}]}";
    assert_int_equal(rb_scene_json_check(json, strlen(json), rules,
                                         sizeof(rules) / sizeof(rules[0]), NULL, NULL, &err),
                     RB_E_PARSE);
    assert_string_equal(err.msg, "/list/0/i: expected non-negative integer, found string");
    /* the text's size counts, not a terminator */
    assert_int_equal(rb_scene_json_check("{}garbage", 2, rules, 1, collect, NULL, &err), RB_OK);

    assert_int_equal(check_json("{\"list\":[", rules, 1, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, "invalid JSON: "));
    assert_int_equal(check_json("[1]", rules, 1, &err), RB_E_PARSE);
    assert_string_equal(err.msg, "not a glTF document: the top level is array, not an object");
}

/* The rule for exactly the first len characters of pointer, or NULL. */
static const struct rb_scene_json_rule *rule_for(const char *pointer, size_t len)
{
    for (size_t i = 0; i < rb_scene_json_rule_count; i++)
        if (strlen(rb_scene_json_rules[i].pointer) == len &&
            !strncmp(rb_scene_json_rules[i].pointer, pointer, len))
            return &rb_scene_json_rules[i];
    return NULL;
}

/* The table itself: real types, pointers that start with '/', no rule twice, and every parent
 * with a rule of its own earlier in the table (an object before a name, an array or object before
 * a "*"), so the walker never looks into an unchecked value and parents are reported first. */
static void test_json_rules_table(void **state)
{
    (void)state;
    assert_true(rb_scene_json_rule_count > 100);
    for (size_t i = 0; i < rb_scene_json_rule_count; i++) {
        const struct rb_scene_json_rule *r = &rb_scene_json_rules[i];
        if (r->type <= RB_SCENE_JSON_INVALID || r->type > RB_SCENE_JSON_STRINGS ||
            r->pointer[0] != '/' || (r->count && r->type != RB_SCENE_JSON_NUMBERS))
            fail_msg("rule %zu '%s' is malformed", i, r->pointer);
        for (size_t k = 0; k < i; k++)
            if (!strcmp(rb_scene_json_rules[k].pointer, r->pointer))
                fail_msg("'%s' has two rules", r->pointer);
        for (const char *slash = strchr(r->pointer + 1, '/'); slash;
             slash = strchr(slash + 1, '/')) {
            const struct rb_scene_json_rule *parent =
                rule_for(r->pointer, (size_t)(slash - r->pointer));
            bool wild = slash[1] == '*' && (slash[2] == '/' || !slash[2]);
            if (!parent || parent > r ||
                !(parent->type == RB_SCENE_JSON_OBJECT ||
                  (wild && parent->type == RB_SCENE_JSON_ARRAY)))
                fail_msg("'%s': its parent '%.*s' has no rule before it, or not an %s one",
                         r->pointer, (int)(slash - r->pointer), r->pointer,
                         wild ? "array or object" : "object");
        }
    }
}

/* JSON that holds the path of pointer with value at its end, each "*" as element 0 of an array
 * or member "K" of an object (as the parent's rule says); value NULL leaves the last member out
 * of its parent. Writes the concrete pointer into where. */
static void instantiate(const char *pointer, const char *value, char *json, size_t cap, char *where,
                        size_t where_cap)
{
    char closers[64] = "";
    size_t n = 0, w = 0;
    json[0] = where[0] = '\0';
    for (const char *p = pointer; *p == '/';) {
        const char *end = strchr(p + 1, '/');
        size_t len = end ? (size_t)(end - p - 1) : strlen(p + 1);
        bool last = !end;
        if (len == 1 && p[1] == '*') {
            const struct rb_scene_json_rule *parent = rule_for(pointer, (size_t)(p - pointer));
            bool array = parent->type == RB_SCENE_JSON_ARRAY;
            n += (size_t)snprintf(json + n, cap - n, array ? "[" : "{\"K\":");
            w += (size_t)snprintf(where + w, where_cap - w, array ? "/0" : "/K");
            closers[strlen(closers)] = array ? ']' : '}';
        } else if (last && !value) {
            n += (size_t)snprintf(json + n, cap - n, "{}");
            w += (size_t)snprintf(where + w, where_cap - w, "/%.*s", (int)len, p + 1);
        } else {
            n += (size_t)snprintf(json + n, cap - n, "{\"%.*s\":", (int)len, p + 1);
            w += (size_t)snprintf(where + w, where_cap - w, "/%.*s", (int)len, p + 1);
            closers[strlen(closers)] = '}';
        }
        p += len + 1;
    }
    if (value)
        n += (size_t)snprintf(json + n, cap - n, "%s", value);
    for (size_t k = strlen(closers); k-- > 0;)
        n += (size_t)snprintf(json + n, cap - n, "%c", closers[k]);
}

/* Whether issues has a line for exactly this pointer that ends in found. */
static bool has_issue(const char *where, const char *found)
{
    char head[512];
    snprintf(head, sizeof(head), "%s: expected ", where);
    for (const char *line = issues; *line;) {
        const char *nl = strchr(line, '\n');
        size_t len = (size_t)(nl - line), flen = strlen(found);
        if (!strncmp(line, head, strlen(head)) && len >= flen &&
            !strncmp(line + len - flen, found, flen))
            return true;
        line = nl + 1;
    }
    return false;
}

/* Every rule of the real table, in a document of its own: a null there is reported at its
 * pointer, a value of the right type is not, and a missing one only when the rule requires it. */
static void test_json_rules_each(void **state)
{
    (void)state;
    static const char *const good[] = {
        [RB_SCENE_JSON_OBJECT] = "{}",       [RB_SCENE_JSON_ARRAY] = "[]",
        [RB_SCENE_JSON_STRING] = "\"s\"",    [RB_SCENE_JSON_BOOLEAN] = "false",
        [RB_SCENE_JSON_NUMBER] = "-0.5",     [RB_SCENE_JSON_UINT] = "3",
        [RB_SCENE_JSON_SIZE] = "4294967296", [RB_SCENE_JSON_UINTS] = "[0,1]",
        [RB_SCENE_JSON_STRINGS] = "[\"s\"]",
    };
    struct rb_err err = RB_ERR_INIT;
    char json[2048], where[512];
    for (size_t i = 0; i < rb_scene_json_rule_count; i++) {
        const struct rb_scene_json_rule *r = &rb_scene_json_rules[i];
        instantiate(r->pointer, "null", json, sizeof(json), where, sizeof(where));
        assert_int_equal(check_json(json, rb_scene_json_rules, rb_scene_json_rule_count, &err),
                         RB_OK);
        if (!has_issue(where, ", found null"))
            fail_msg("%s: null not reported in %s\n%s", r->pointer, json, issues);

        char numbers[80] = "[0";
        for (uint32_t k = 1; k < (r->count ? r->count : 2); k++)
            strcat(numbers, ",0");
        strcat(numbers, "]");
        instantiate(r->pointer, r->type == RB_SCENE_JSON_NUMBERS ? numbers : good[r->type], json,
                    sizeof(json), where, sizeof(where));
        check_json(json, rb_scene_json_rules, rb_scene_json_rule_count, &err);
        if (has_issue(where, ""))
            fail_msg("%s: a good value is reported in %s\n%s", r->pointer, json, issues);

        if (where[strlen(where) - 2] == '/' && strchr("0K", where[strlen(where) - 1]))
            continue; /* the member of a wildcard cannot be missing */
        instantiate(r->pointer, NULL, json, sizeof(json), where, sizeof(where));
        check_json(json, rb_scene_json_rules, rb_scene_json_rule_count, &err);
        if (has_issue(where, ", found nothing") != r->is_required)
            fail_msg("%s: missing from %s is %sreported\n%s", r->pointer, json,
                     r->is_required ? "not " : "", issues);
    }
}

/* A glTF from the parts of tiny_gltf's document, as path (a .glb when name says so). */
static void write_gltf(const char *name, const char *json, char *path, size_t cap)
{
    size_t n = strlen(json);
    if (!strstr(name, ".glb")) {
        write_file(name, json, n, path, cap);
        return;
    }
    size_t padded = (n + 3) & ~(size_t)3;
    unsigned char glb[4096] = "glTF";
    assert_true(20 + padded <= sizeof(glb));
    uint32_t words[4] = {2, (uint32_t)(20 + padded), (uint32_t)padded, 0x4E4F534A};
    memcpy(glb + 4, words, sizeof(words));
    memcpy(glb + 20, json, n);
    memset(glb + 20 + n, ' ', padded - n);
    write_file(name, glb, 20 + padded, path, cap);
}

/* The types through rb_scene_load: strict by default (one error naming the file and the pointer,
 * .gltf and .glb alike), lenient on request (warnings; tinygltf skips what does not fit). */
static void test_scene_load_strict_and_lenient(void **state)
{
    (void)state;
    static const struct {
        const char *name, *node, *prim, *pointer_problem;
    } cases[] = {
        {"prims.gltf", "\"mesh\":0", "{}", "/meshes/0/primitives: expected array, found object"},
        {"scale.gltf", "\"mesh\":0,\"scale\":\"not a number\"",
         "[{\"attributes\":{\"POSITION\":0}}]",
         "/nodes/0/scale: expected array of 3 numbers, found string"},
        {"mesh.glb", "\"mesh\":\"0\"", "[{\"attributes\":{\"POSITION\":0}}]",
         "/nodes/0/mesh: expected non-negative integer, found string"},
        {"attributes.glb", "\"mesh\":0", "[{\"mode\":4}]",
         "/meshes/0/primitives/0/attributes: expected object, found nothing"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        char json[2048], path[512], want[1024];
        snprintf(json, sizeof(json),
                 "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],"
                 "\"nodes\":[{%s}],\"meshes\":[{\"primitives\":%s}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"type\":\"VEC3\","
                 "\"count\":3}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                 "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;"
                 "base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}",
                 cases[i].node, cases[i].prim);
        write_gltf(cases[i].name, json, path, sizeof(path));
        struct rb_scene *s = NULL;
        struct rb_err err = RB_ERR_INIT;
        snprintf(want, sizeof(want), "scene '%s': %s", path, cases[i].pointer_problem);
        log_text[0] = '\0';
        assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
        assert_null(s);
        assert_string_equal(err.msg, want);
        assert_string_equal(log_text, "");

        assert_int_equal(rb_scene_load(path, RB_SCENE_LOAD_LENIENT, &s, &err), RB_OK);
        assert_non_null(strstr(log_text, want));
        if (i == 2) /* the string is no mesh index to tinygltf */
            assert_int_equal(s->nodes[0].mesh, RB_SCENE_NONE);
        if (i == 0 || i == 3) /* no primitive survives */
            assert_int_equal(s->primitive_count, 0);
        if (i == 1) { /* the scale is the default */
            assert_int_equal(s->primitive_count, 1);
            assert_float_equal(s->nodes[0].scale.x, 1.0f, 0.0f);
        }
        rb_scene_destroy(s);
    }
}

/* tinygltf's own complaints: errors when they mean the file is broken (strict), and not at all
 * for the valid files it complains about. */
static void test_scene_load_tinygltf_errors(void **state)
{
    (void)state;
    char path[512];
    struct rb_err err = RB_ERR_INIT;
    struct rb_scene *s = NULL;

    /* a .glb whose JSON chunk ends off a 4-byte boundary */
    char json[2048];
    snprintf(json, sizeof(json), tiny_gltf, "", "", "", "3");
    size_t n = strlen(json);
    while (n % 4 != 1)
        json[n++] = ' ';
    json[n] = '\0';
    unsigned char glb[4096] = "glTF";
    uint32_t words[4] = {2, (uint32_t)(20 + n), (uint32_t)n, 0x4E4F534A};
    memcpy(glb + 4, words, sizeof(words));
    memcpy(glb + 20, json, n);
    write_file("misaligned.glb", glb, 20 + n, path, sizeof(path));
    assert_int_equal(rb_scene_load(path, 0, &s, &err), RB_E_PARSE);
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "4-byte boundary"));
    log_text[0] = '\0';
    assert_int_equal(rb_scene_load(path, RB_SCENE_LOAD_LENIENT, &s, &err), RB_OK);
    assert_non_null(strstr(log_text, "4-byte boundary"));
    rb_scene_destroy(s);

    /* valid: a skin without inverseBindMatrices, a channel whose target node is left to an
     * extension (dropped, with a warning) */
    log_text[0] = '\0';
    assert_int_equal(load_tiny("valid.gltf",
                               "\"skins\":[{\"joints\":[0]}],\"animations\":[{\"samplers\":"
                               "[{\"input\":1,\"output\":0}],\"channels\":[{\"sampler\":0,"
                               "\"target\":{\"path\":\"translation\"}}]}],",
                               "", "", "3", &err, path, sizeof(path)),
                     RB_OK);
    assert_null(strstr(log_text, "inverseBindMatrices"));
    assert_non_null(strstr(log_text, "animation.channels.target"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_shared_triangle_counts, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_cornell_emissive_strength, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_fox_skin_and_clips, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_cesium_man, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_box_animated_moves, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_morph_cube_weights, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_water_bottle_textures, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_features_geometry, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_features_material_texture, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_features_nodes, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_features_animation, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_features_lights, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_select_clips, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_missing_file, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_corrupt_glb, setup_tmp, teardown_tmp),
        cmocka_unit_test_setup_teardown(test_missing_texture, setup_tmp, teardown_tmp),
        cmocka_unit_test_setup_teardown(test_unsupported_extension, setup_tmp, teardown_tmp),
        cmocka_unit_test_setup_teardown(test_bad_references, setup_tmp, teardown_tmp),
        cmocka_unit_test_setup_teardown(test_json_walker, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_json_rules_table, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_json_rules_each, setup_log, teardown_log),
        cmocka_unit_test_setup_teardown(test_scene_load_strict_and_lenient, setup_tmp,
                                        teardown_tmp),
        cmocka_unit_test_setup_teardown(test_scene_load_tinygltf_errors, setup_tmp, teardown_tmp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
