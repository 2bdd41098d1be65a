/* The hybrid integrator's BVH (lib/bvh, shaders/common/bvh.glsl): the builder's choices under a
 * budget, degenerate and empty input, bytes that do not depend on Embree's threads, and the GPU
 * traversal (bvh_trace.comp, on lavapipe with validation) on small hand-built cases and, against
 * Embree's rtcIntersect1 on the same triangles, on random rays over every shared scene
 * ($RB_SCENES; skipped when absent): the same closest triangle (or both none) with the distance
 * within DIST_REL, for at least AGREE_MIN of the rays. */
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>

#include "bvh/bvh.h"
#include "bvh_trace.comp.h"
#include "gpu/gpu.h"
#include "reference/reference_int.h"
#include "testutil.h"

#define AGREE_MIN 0.999
#define DIST_REL 1e-4
#define SCENE_RAYS 20000
#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* ---- the tracer: bvh_trace.comp on the device -------------------------------------------- */

struct tracer {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
    double gpu_s; /* of the last closest-hit-only dispatch, submit to wait */
};

static struct tracer tracer;

static int setup(void **state)
{
    (void)state;
    static const VkDescriptorType types[RB_BIND_BVH_TRACE_COUNT] = {
        [RB_BIND_BVH_TRACE_NODES] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        [RB_BIND_BVH_TRACE_TRIS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        [RB_BIND_BVH_TRACE_RAYS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        [RB_BIND_BVH_TRACE_HITS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    };
    struct rb_err err = RB_ERR_INIT;
    if (rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &tracer.gpu, &err) ||
        rb_gpu_layout_init(tracer.gpu, types, RB_BIND_BVH_TRACE_COUNT, 2 * sizeof(uint32_t),
                           &tracer.layout, &err) ||
        rb_gpu_compute_pipeline(tracer.gpu, rb_spv_bvh_trace_comp, sizeof(rb_spv_bvh_trace_comp),
                                tracer.layout.pipeline_layout, "bvh_trace", &tracer.pipeline,
                                &err)) {
        print_error("%s\n", err.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    if (tracer.gpu) {
        vkDestroyPipeline(tracer.gpu->device, tracer.pipeline, NULL);
        rb_gpu_layout_release(tracer.gpu, &tracer.layout);
    }
    rb_gpu_destroy(tracer.gpu);
    return 0;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void buffer(struct rb_gpu_buffer *b, const void *data, size_t size, const char *name)
{
    struct rb_err err = RB_ERR_INIT;
    if (rb_gpu_buffer_init(tracer.gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = size ? size : 16,
                                                        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = name},
                           b, &err))
        fail_msg("%s", err.msg);
    if (data)
        memcpy(b->mapped, data, size);
}

/* Traces rays (count of them) through bvh into hits; occlusion queries too when asked. */
static void trace(const struct rb_bvh *bvh, const struct rb_gpu_bvh_ray *rays, uint32_t count,
                  bool has_occlusion, struct rb_gpu_bvh_trace_hit *hits)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu_buffer nodes, tris, ray_buf, hit_buf;
    buffer(&nodes, bvh->nodes, bvh->node_count * sizeof(*bvh->nodes), "bvh.nodes");
    buffer(&tris, bvh->triangles, bvh->triangle_count * sizeof(*bvh->triangles), "bvh.tris");
    buffer(&ray_buf, rays, count * sizeof(*rays), "bvh.rays");
    buffer(&hit_buf, NULL, count * sizeof(*hits), "bvh.hits");
    VkCommandBuffer cmd;
    if (rb_gpu_oneshot_begin(tracer.gpu, &cmd, &err))
        fail_msg("%s", err.msg);
    struct rb_gpu_bindings bind = {0};
    const VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BVH_TRACE_NODES, storage, &nodes);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BVH_TRACE_TRIS, storage, &tris);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BVH_TRACE_RAYS, storage, &ray_buf);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BVH_TRACE_HITS, storage, &hit_buf);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, tracer.pipeline);
    rb_gpu_push_bindings(tracer.gpu, cmd, VK_PIPELINE_BIND_POINT_COMPUTE,
                         tracer.layout.pipeline_layout, &bind);
    uint32_t push[2] = {count, has_occlusion};
    vkCmdPushConstants(cmd, tracer.layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(push),
                       push);
    vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
    double start = now_s();
    if (rb_gpu_oneshot_end(tracer.gpu, cmd, &err) || rb_gpu_check_validation(tracer.gpu, &err))
        fail_msg("%s", err.msg);
    if (!has_occlusion)
        tracer.gpu_s = now_s() - start;
    memcpy(hits, hit_buf.mapped, count * sizeof(*hits));
    rb_gpu_buffer_release(tracer.gpu, &hit_buf);
    rb_gpu_buffer_release(tracer.gpu, &ray_buf);
    rb_gpu_buffer_release(tracer.gpu, &tris);
    rb_gpu_buffer_release(tracer.gpu, &nodes);
}

static uint32_t word(float f)
{
    uint32_t w;
    memcpy(&w, &f, sizeof(w));
    return w;
}

static struct rb_gpu_bvh_ray ray(float ox, float oy, float oz, float dx, float dy, float dz,
                                 float tmin, float tmax)
{
    return (struct rb_gpu_bvh_ray){{ox, oy, oz, tmin}, {dx, dy, dz, tmax}};
}

/* Traces one ray with the occlusion queries; checks they agree with the closest hit. */
static struct rb_gpu_bvh_trace_hit trace1(const struct rb_bvh *bvh, struct rb_gpu_bvh_ray r)
{
    struct rb_gpu_bvh_trace_hit h;
    trace(bvh, &r, 1, true, &h);
    assert_int_equal(h.occluded[0], h.hit[0] >= 0.0f);
    assert_int_equal(h.occluded[1], 0);
    return h;
}

static void build(const struct rb_bvh_desc *desc, struct rb_bvh *out)
{
    struct rb_err err = RB_ERR_INIT;
    if (rb_bvh_build(desc, out, &err))
        fail_msg("%s", err.msg);
}

static struct rb_bvh_mesh soup(const float *pos, uint32_t vertex_count, const uint32_t *idx,
                               uint32_t triangle_count)
{
    return (struct rb_bvh_mesh){.positions = pos,
                                .stride_floats = 3,
                                .vertex_count = vertex_count,
                                .indices = idx,
                                .triangle_count = triangle_count};
}

/* ---- small cases -------------------------------------------------------------------------- */

static void test_one_triangle(void **state)
{
    (void)state;
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[] = {0, 1, 2};
    struct rb_bvh_mesh m = soup(pos, 3, idx, 1);
    struct rb_bvh bvh;
    build(&(struct rb_bvh_desc){.mesh = &m}, &bvh);
    assert_int_equal(bvh.node_count, 1);
    assert_int_equal(bvh.triangle_count, 1);
    assert_int_equal(bvh.objects_included, 1);
    assert_int_equal(word(bvh.triangles[0].v0[3]), 0);

    struct rb_gpu_bvh_trace_hit h = trace1(&bvh, ray(0.25f, 0.5f, 1, 0, 0, -1, 0, INFINITY));
    assert_float_equal(h.hit[0], 1.0f, 1e-6f);
    assert_int_equal(word(h.hit[1]), 0);
    assert_float_equal(h.hit[2], 0.25f, 1e-6f); /* the second vertex's weight: x */
    assert_float_equal(h.hit[3], 0.5f, 1e-6f);
    /* The back face, and a direction that is not unit: t in its units. */
    h = trace1(&bvh, ray(0.25f, 0.25f, -2, 0, 0, 4, 0, INFINITY));
    assert_float_equal(h.hit[0], 0.5f, 1e-6f);
    /* Outside the triangle; beyond tmax; before tmin. */
    assert_true(trace1(&bvh, ray(0.75f, 0.75f, 1, 0, 0, -1, 0, INFINITY)).hit[0] < 0.0f);
    assert_true(trace1(&bvh, ray(0.25f, 0.25f, 1, 0, 0, -1, 0, 0.99f)).hit[0] < 0.0f);
    assert_true(trace1(&bvh, ray(0.25f, 0.25f, 1, 0, 0, -1, 1.01f, INFINITY)).hit[0] < 0.0f);
    rb_bvh_release(&bvh);
    assert_null(bvh.nodes);
}

static void test_edges_and_ties(void **state)
{
    (void)state;
    /* The unit square as two triangles sharing the diagonal from (1,0) to (0,1), then the first
     * again, on its own vertices: an exact tie with triangle 0. */
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[] = {1, 3, 2, 4, 5, 6, 0, 1, 2};
    struct rb_bvh_mesh m = soup(pos, 7, idx, 3);
    struct rb_bvh bvh;
    build(&(struct rb_bvh_desc){.mesh = &m}, &bvh);
    assert_int_equal(bvh.triangle_count, 3);
    /* Through points of the shared edge, from both sides: no crack between the two. */
    for (int i = 1; i < 16; i++) {
        float x = (float)i / 16.0f;
        for (float s = -1.0f; s <= 1.0f; s += 2.0f) {
            struct rb_gpu_bvh_trace_hit h = trace1(&bvh, ray(x, 1.0f - x, s, 0, 0, -s, 0, 10));
            assert_float_equal(h.hit[0], 1.0f, 1e-6f);
        }
    }
    /* The tie: triangles 1 and 2 are the same, and 1 is the lower id. */
    struct rb_gpu_bvh_trace_hit h = trace1(&bvh, ray(0.2f, 0.3f, 1, 0, 0, -1, 0, 10));
    assert_int_equal(word(h.hit[1]), 1);
    assert_int_equal(word(trace1(&bvh, ray(0.8f, 0.7f, 1, 0, 0, -1, 0, 10)).hit[1]), 0);
    /* Along an edge, in the triangles' plane: nothing to hit, and no NaN on the way. */
    assert_true(trace1(&bvh, ray(-1, 0, 0, 1, 0, 0, 0, 10)).hit[0] < 0.0f);
    assert_true(trace1(&bvh, ray(2, -1, 0, -1, 1, 0, 0, 10)).hit[0] < 0.0f);
    rb_bvh_release(&bvh);
}

static void test_empty_and_degenerate(void **state)
{
    (void)state;
    struct rb_bvh_mesh empty = soup(NULL, 0, NULL, 0);
    struct rb_bvh bvh;
    build(&(struct rb_bvh_desc){.mesh = &empty}, &bvh);
    assert_int_equal(bvh.node_count, 1);
    assert_int_equal(bvh.triangle_count, 0);
    assert_true(bvh.bounds_min[0] > bvh.bounds_max[0]);
    assert_true(trace1(&bvh, ray(0, 0, 0, 0, 0, 1, 0, INFINITY)).hit[0] < 0.0f);
    rb_bvh_release(&bvh);

    /* One good triangle among a collinear one, one with a repeated corner and one with NaN. */
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, NAN, 0.5f, 0, 0, 0, 0.5f};
    const uint32_t idx[] = {0, 1, 3, 0, 1, 1, 0, 4, 2, 0, 1, 2, 0, 1, 5};
    struct rb_bvh_mesh m = soup(pos, 6, idx, 5);
    build(&(struct rb_bvh_desc){.mesh = &m,
                                .objects = (struct rb_bvh_object[]){{0, 4, 0, 0}, {4, 1, 0, 0}},
                                .object_count = 2,
                                .triangle_budget = 1},
          &bvh);
    assert_int_equal(bvh.triangles_degenerate, 3);
    assert_int_equal(bvh.triangle_count, 1);
    assert_int_equal(word(bvh.triangles[0].v0[3]), 3);
    assert_int_equal(bvh.objects_included, 1);
    assert_int_equal(bvh.triangles_left_out, 1); /* the other object's one */
    assert_int_equal(word(trace1(&bvh, ray(0.1f, 0.1f, 1, 0, 0, -1, 0, 10)).hit[1]), 3);
    rb_bvh_release(&bvh);

    /* All degenerate: empty, and still a tree to trace. */
    build(&(struct rb_bvh_desc){.mesh = &m,
                                .objects = (struct rb_bvh_object[]){{0, 3, 0, 0}},
                                .object_count = 1},
          &bvh);
    assert_int_equal(bvh.triangle_count, 0);
    assert_true(trace1(&bvh, ray(0.1f, 0.1f, 1, 0, 0, -1, 0, 10)).hit[0] < 0.0f);
    rb_bvh_release(&bvh);
}

static void test_bad_input(void **state)
{
    (void)state;
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[] = {0, 1, 3};
    struct rb_bvh_mesh m = soup(pos, 3, idx, 1);
    struct rb_bvh bvh = {.node_count = 7};
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_bvh_build(&(struct rb_bvh_desc){.mesh = &m}, &bvh, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "BVH: triangle 0: index 3 out of range (3 vertices)");
    m.vertex_count = 4;
    assert_int_equal(
        rb_bvh_build(&(struct rb_bvh_desc){.mesh = &m,
                                           .objects = (struct rb_bvh_object[]){{1, 1, 0, 0}},
                                           .object_count = 1},
                     &bvh, &err),
        RB_E_INVALID);
    assert_non_null(strstr(err.msg, "object 0"));
    assert_int_equal(bvh.node_count, 7); /* untouched */
}

/* Adds a right triangle with legs a (along x) and b (along y) at height z. */
static void right_triangle(float *pos, uint32_t *idx, uint32_t t, float a, float b, float z)
{
    const float v[9] = {0, 0, z, a, 0, z, 0, b, z};
    memcpy(&pos[t * 9], v, sizeof(v));
    for (uint32_t k = 0; k < 3; k++)
        idx[t * 3 + k] = t * 3 + k;
}

/* test_budget's and test_lod's triangles: right triangles of these legs, one a plane z = t;
 * the last is object 0's coarser version in test_lod and unused in test_budget. */
#define BUDGET_TRIANGLES 7
static struct rb_bvh_mesh budget_mesh(float pos[BUDGET_TRIANGLES * 9],
                                      uint32_t idx[BUDGET_TRIANGLES * 3])
{
    static const float legs[BUDGET_TRIANGLES][2] = {{2, 1}, {1, 2}, {2, 1}, {4, 2},
                                                    {1, 1}, {2, 4}, {3, 2}};
    for (uint32_t t = 0; t < BUDGET_TRIANGLES; t++)
        right_triangle(pos, idx, t, legs[t][0], legs[t][1], (float)t);
    return soup(pos, BUDGET_TRIANGLES * 3, idx, BUDGET_TRIANGLES);
}

static void test_budget(void **state)
{
    (void)state;
    /* Scores (area / triangles): object 0, three of area 1: 1; object 1, one of area 4: 4;
     * object 2, one of area 0.5: 0.5; object 3, one of area 4: 4 (a tie with object 1). */
    float pos[BUDGET_TRIANGLES * 9];
    uint32_t idx[BUDGET_TRIANGLES * 3];
    struct rb_bvh_mesh m = budget_mesh(pos, idx);
    const struct rb_bvh_object objects[] = {{0, 3, 0, 0}, {3, 1, 0, 0}, {4, 1, 0, 0}, {5, 1, 0, 0}};
    static const struct {
        uint64_t budget;
        uint32_t included; /* bits by object */
        uint64_t left_out;
    } cases[] = {
        {0, 0xf, 0},
        {1, 1u << 1, 5},                     /* the tie goes to the lower index */
        {4, 1u << 1 | 1u << 3 | 1u << 2, 3}, /* object 0 no longer fits; 2 still does */
        {5, 1u << 1 | 1u << 3 | 1u << 0, 1}, /* the best three, then 2 does not fit */
        {6, 0xf, 0},
    };
    for (size_t c = 0; c < COUNT(cases); c++) {
        struct rb_bvh bvh;
        build(&(struct rb_bvh_desc){.mesh = &m,
                                    .objects = objects,
                                    .object_count = 4,
                                    .triangle_budget = cases[c].budget,
                                    .score = RB_BVH_SCORE_AREA},
              &bvh);
        uint32_t seen = 0, count = 0;
        for (uint32_t i = 0; i < bvh.triangle_count; i++)
            seen |= 1u << word(bvh.triangles[i].v1[3]);
        for (uint32_t o = 0; o < 4; o++)
            count += cases[c].included >> o & 1u ? objects[o].triangle_count : 0;
        print_message("# budget %llu: objects 0x%x, %llu triangles left out\n",
                      (unsigned long long)cases[c].budget, seen,
                      (unsigned long long)bvh.triangles_left_out);
        assert_int_equal(seen, cases[c].included);
        assert_int_equal(bvh.triangle_count, count);
        assert_int_equal(bvh.objects_included, __builtin_popcount(cases[c].included));
        assert_int_equal(bvh.object_count, 4);
        assert_int_equal(bvh.triangles_left_out, cases[c].left_out);
        rb_bvh_release(&bvh);
    }
}

/* A coarser version enters in place of an object that does not fit whole: test_budget's objects,
 * object 0 (three triangles) with a coarser version of one (triangle 6). Budget 4: objects 1
 * and 3 (one each), then object 0 by its coarser triangle, then object 2; without the coarser
 * version object 0 is left out. A coarser version that does not fit either leaves it out. */
static void test_lod(void **state)
{
    (void)state;
    float pos[BUDGET_TRIANGLES * 9];
    uint32_t idx[BUDGET_TRIANGLES * 3];
    struct rb_bvh_mesh m = budget_mesh(pos, idx);
    const struct rb_bvh_object objects[] = {{0, 3, 6, 1}, {3, 1, 0, 0}, {4, 1, 0, 0}, {5, 1, 0, 0}};
    static const struct {
        uint64_t budget;
        uint32_t triangles; /* bits by triangle */
        uint32_t simplified;
        uint64_t left_out;
    } cases[] = {
        {0, 0x3f, 0, 0}, /* everything whole */
        {4, 0x78, 1, 0}, /* 3, 5, then 0 by triangle 6, then 4 */
        {2, 0x28, 0, 4}, /* 3 and 5; nothing left for 0's coarser version or 2 */
        {6, 0x3f, 0, 0}, /* whole again */
    };
    for (size_t c = 0; c < COUNT(cases); c++) {
        struct rb_bvh bvh;
        build(&(struct rb_bvh_desc){.mesh = &m,
                                    .objects = objects,
                                    .object_count = 4,
                                    .triangle_budget = cases[c].budget,
                                    .score = RB_BVH_SCORE_AREA},
              &bvh);
        uint32_t seen = 0;
        for (uint32_t i = 0; i < bvh.triangle_count; i++)
            seen |= 1u << word(bvh.triangles[i].v0[3]);
        print_message("# budget %llu: triangles 0x%x, %u simplified\n",
                      (unsigned long long)cases[c].budget, seen, bvh.objects_simplified);
        assert_int_equal(seen, cases[c].triangles);
        assert_int_equal(bvh.objects_simplified, cases[c].simplified);
        assert_int_equal(bvh.triangles_left_out, cases[c].left_out);
        rb_bvh_release(&bvh);
    }
}

/* Relevance from the eye (rb_bvh_select): two objects alike, four unit right triangles (area 2)
 * with a coarser version of one, at x 0 and x 100; the eye 3 m from one of them. Its share of
 * the budget is nearly all of it, the other's nearly none. The area score cannot tell them
 * apart and takes object 0 first wherever the eye is. */
static void test_relevance(void **state)
{
    (void)state;
    float pos[10 * 9];
    uint32_t idx[10 * 3];
    for (uint32_t o = 0; o < 2; o++)
        for (uint32_t k = 0; k < 5; k++) {
            uint32_t t = o * 5 + k;
            float x = 100.0f * (float)o + 2.0f * (float)k, leg = k < 4 ? 1.0f : 2.0f;
            const float v[9] = {x, 0, 0, x + leg, 0, 0, x, leg, 0};
            memcpy(&pos[t * 9], v, sizeof(v));
            for (uint32_t j = 0; j < 3; j++)
                idx[t * 3 + j] = t * 3 + j;
        }
    struct rb_bvh_mesh m = soup(pos, 30, idx, 10);
    const struct rb_bvh_object objects[] = {{0, 4, 4, 1}, {5, 4, 9, 1}};
    enum { O = RB_BVH_LEFT_OUT, W = RB_BVH_WHOLE, C = RB_BVH_COARSER };
    static const struct {
        enum rb_bvh_score score;
        float eye_x;
        uint64_t budget;
        uint8_t want[2];
    } cases[] = {
        /* the near one whole, the far one by its coarser version */
        {RB_BVH_SCORE_RELEVANCE, 2, 6, {W, C}},
        {RB_BVH_SCORE_RELEVANCE, 102, 6, {C, W}},
        /* both over their share: both coarser; what is left (2) cannot make one whole (3) */
        {RB_BVH_SCORE_RELEVANCE, 2, 4, {C, C}},
        {RB_BVH_SCORE_RELEVANCE, 102, 1, {O, C}},
        {RB_BVH_SCORE_RELEVANCE, 2, 8, {W, W}},   /* everything fits: everything whole */
        {RB_BVH_SCORE_RELEVANCE, 102, 0, {W, W}}, /* no budget */
        {RB_BVH_SCORE_AREA, 102, 6, {W, C}},
        {RB_BVH_SCORE_AREA, 102, 4, {W, O}},
        {RB_BVH_SCORE_AREA, 102, 1, {C, O}},
        {RB_BVH_SCORE_AREA, 2, 8, {W, W}},
    };
    for (size_t c = 0; c < COUNT(cases); c++) {
        struct rb_bvh_desc desc = {.mesh = &m,
                                   .objects = objects,
                                   .object_count = 2,
                                   .triangle_budget = cases[c].budget,
                                   .score = cases[c].score,
                                   .eye = {cases[c].eye_x, 0.5f, 3.0f}};
        uint8_t choice[2] = {0xff, 0xff};
        struct rb_err err = RB_ERR_INIT;
        assert_int_equal(rb_bvh_select(&desc, choice, &err), RB_OK);
        print_message("# %s, eye at x %g, budget %llu: %u %u\n",
                      cases[c].score == RB_BVH_SCORE_AREA ? "area" : "relevance", cases[c].eye_x,
                      (unsigned long long)cases[c].budget, choice[0], choice[1]);
        assert_memory_equal(choice, cases[c].want, 2);
        /* the build holds what the selection chose */
        struct rb_bvh bvh;
        build(&desc, &bvh);
        assert_memory_equal(bvh.choice, choice, 2);
        uint32_t want_tris = 0;
        for (uint32_t o = 0; o < 2; o++)
            want_tris += choice[o] == W ? 4 : choice[o] == C ? 1 : 0;
        assert_int_equal(bvh.triangle_count, want_tris);
        rb_bvh_release(&bvh);
    }
}

/* ---- determinism --------------------------------------------------------------------------- */

/* A bumpy grid of side x side quads, then dup copies of one triangle: identical centroids,
 * which Embree can only split by the order of its primitive array. */
static struct rb_bvh_mesh grid_mesh(uint32_t side, uint32_t dup, float **pos, uint32_t **idx)
{
    uint32_t verts = (side + 1) * (side + 1), tris = 2 * side * side + dup;
    *pos = malloc(verts * 3 * sizeof(float));
    *idx = malloc(tris * 3 * sizeof(uint32_t));
    assert_true(*pos && *idx);
    for (uint32_t y = 0, v = 0; y <= side; y++)
        for (uint32_t x = 0; x <= side; x++, v++) {
            (*pos)[v * 3] = (float)x;
            (*pos)[v * 3 + 1] = (float)y;
            (*pos)[v * 3 + 2] = sinf(0.37f * (float)x) * cosf(0.23f * (float)y) * 3.0f;
        }
    uint32_t t = 0;
    for (uint32_t y = 0; y < side; y++)
        for (uint32_t x = 0; x < side; x++) {
            uint32_t a = y * (side + 1) + x, b = a + 1, c = a + side + 1, d = c + 1;
            const uint32_t q[6] = {a, b, c, b, d, c};
            memcpy(&(*idx)[t * 3], q, sizeof(q));
            t += 2;
        }
    for (uint32_t i = 0; i < dup; i++, t++)
        memcpy(&(*idx)[t * 3], &(*idx)[0], 3 * sizeof(uint32_t));
    return soup(*pos, verts, *idx, tris);
}

static void expect_same_build(const struct rb_bvh_desc *desc, const char *name)
{
    struct rb_bvh one, many;
    struct rb_bvh_desc d = *desc;
    d.thread_count = 1;
    build(&d, &one);
    const uint32_t threads[] = {2, 4, 8};
    for (size_t i = 0; i < COUNT(threads); i++) {
        d.thread_count = threads[i];
        build(&d, &many);
        print_message("# %s: %u nodes, %u triangles, depth %u; 1 and %u threads: %s\n", name,
                      one.node_count, one.triangle_count, one.depth, threads[i],
                      one.node_count == many.node_count &&
                              !memcmp(one.nodes, many.nodes, one.node_count * sizeof(*one.nodes))
                          ? "same nodes"
                          : "different nodes");
        assert_int_equal(one.node_count, many.node_count);
        assert_int_equal(one.triangle_count, many.triangle_count);
        assert_memory_equal(one.nodes, many.nodes, one.node_count * sizeof(*one.nodes));
        assert_memory_equal(one.triangles, many.triangles,
                            one.triangle_count * sizeof(*one.triangles));
        rb_bvh_release(&many);
    }
    rb_bvh_release(&one);
}

static void test_threads(void **state)
{
    (void)state;
    float *pos;
    uint32_t *idx;
    struct rb_bvh_mesh m = grid_mesh(120, 3000, &pos, &idx);
    expect_same_build(&(struct rb_bvh_desc){.mesh = &m}, "grid");
    free(idx);
    free(pos);
}

/* The hybrid's thread cancels a build it no longer wants: a set flag stops it with
 * RB_E_INTERRUPTED and *out untouched; a clear one changes nothing. */
static void test_cancel(void **state)
{
    (void)state;
    float *pos;
    uint32_t *idx;
    struct rb_bvh_mesh m = grid_mesh(120, 0, &pos, &idx);
    atomic_bool cancel;
    atomic_init(&cancel, true);
    struct rb_bvh out = {.node_count = 12345}, plain, flagged;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_bvh_build(&(struct rb_bvh_desc){.mesh = &m, .cancel = &cancel}, &out, &err),
                     RB_E_INTERRUPTED);
    print_message("# a set flag: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_int_equal(out.node_count, 12345);
    atomic_store(&cancel, false);
    build(&(struct rb_bvh_desc){.mesh = &m}, &plain);
    build(&(struct rb_bvh_desc){.mesh = &m, .cancel = &cancel}, &flagged);
    assert_int_equal(plain.node_count, flagged.node_count);
    assert_memory_equal(plain.nodes, flagged.nodes, plain.node_count * sizeof(*plain.nodes));
    assert_memory_equal(plain.triangles, flagged.triangles,
                        plain.triangle_count * sizeof(*plain.triangles));
    rb_bvh_release(&plain);
    rb_bvh_release(&flagged);
    free(idx);
    free(pos);
}

/* ---- against Embree on the shared scenes --------------------------------------------------- */

/* One scene's world triangles at time 0, laid out as frame.c lays them out. */
struct world {
    float *pos; /* 4 per vertex (Embree's stride) */
    uint32_t *tris;
    uint32_t vertex_count, tri_count;
    struct rb_bvh_object *objects; /* one per instance */
    uint32_t object_count;
};

static bool world_load(const char *path, struct world *w)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_scene *scene = NULL;
    struct rb_scene_pose *pose = NULL;
    if (rb_scene_load(path, 0, &scene, &err)) {
        print_message("# %s: not loaded: %s\n", path, err.msg);
        return false;
    }
    if (rb_scene_pose_create(scene, &pose, &err))
        fail_msg("%s: %s", path, err.msg);
    uint32_t clip = 0; /* the first animation, if any, as a job that names none */
    rb_scene_evaluate(scene,
                      &(struct rb_anim_selection){.clips = &clip,
                                                  .clip_count = scene->animation_count ? 1 : 0,
                                                  .speed = 1.0,
                                                  .loop = true},
                      0.0, pose);
    uint64_t verts = 0, tris = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        verts += p->vertex_count;
        tris += p->index_count / 3;
    }
    *w = (struct world){.vertex_count = (uint32_t)verts,
                        .tri_count = (uint32_t)tris,
                        .object_count = pose->instance_count};
    w->pos = malloc((verts + 1) * 4 * sizeof(float));
    w->tris = malloc((tris + 1) * 3 * sizeof(uint32_t));
    w->objects = malloc((pose->instance_count + 1) * sizeof(*w->objects));
    assert_true(w->pos && w->tris && w->objects);
    rb_scene_deform(scene, pose, w->pos, 4, NULL, NULL, NULL);
    uint32_t dst = 0, t = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        w->objects[i] =
            (struct rb_bvh_object){.first_triangle = t / 3, .triangle_count = p->index_count / 3};
        for (uint32_t j = 0; j < p->index_count / 3 * 3; j++)
            w->tris[t++] = dst + scene->indices[p->first_index + j];
        dst += p->vertex_count;
    }
    rb_scene_pose_destroy(pose);
    rb_scene_destroy(scene);
    return true;
}

static struct rb_bvh_mesh world_mesh(const struct world *w)
{
    return (struct rb_bvh_mesh){.positions = w->pos,
                                .stride_floats = 4,
                                .vertex_count = w->vertex_count,
                                .indices = w->tris,
                                .triangle_count = w->tri_count};
}

static void world_release(struct world *w)
{
    free(w->objects);
    free(w->tris);
    free(w->pos);
}

/* PCG32 (O'Neill), fixed seed: the same rays every run. */
struct pcg {
    uint64_t state;
};

static float pcg_float(struct pcg *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + 1442695040888963407ull;
    uint32_t x = (uint32_t)(((old >> 18u) ^ old) >> 27u), rot = (uint32_t)(old >> 59u);
    x = (x >> rot) | (x << ((32u - rot) & 31u));
    return (float)(x >> 8) * 0x1p-24f;
}

/* Even rays start anywhere in the scene's box (a little larger), odd ones on a random triangle,
 * moved off it along its normal to the side the ray leaves by; directions uniform on the
 * sphere. */
static void scene_rays(const struct world *w, const struct rb_bvh *bvh, struct rb_gpu_bvh_ray *rays,
                       uint32_t count)
{
    struct pcg rng = {0x853c49e6748fea9bull};
    float ext[3], diag = 0.0f;
    for (int c = 0; c < 3; c++) {
        ext[c] = bvh->bounds_max[c] - bvh->bounds_min[c];
        diag += ext[c] * ext[c];
    }
    diag = sqrtf(diag);
    for (uint32_t i = 0; i < count; i++) {
        float z = 1.0f - 2.0f * pcg_float(&rng), phi = 6.2831853f * pcg_float(&rng);
        float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        float d[3] = {s * cosf(phi), s * sinf(phi), z}, o[3];
        if (i % 2 == 0 || w->tri_count == 0) {
            for (int c = 0; c < 3; c++)
                o[c] = bvh->bounds_min[c] + ext[c] * (1.2f * pcg_float(&rng) - 0.1f);
        } else {
            uint32_t t = (uint32_t)(pcg_float(&rng) * (float)w->tri_count) % w->tri_count;
            const float *p[3];
            for (int k = 0; k < 3; k++)
                p[k] = &w->pos[w->tris[t * 3 + (uint32_t)k] * 4];
            float a = sqrtf(pcg_float(&rng)), b = pcg_float(&rng);
            float e1[3], e2[3], n[3];
            for (int c = 0; c < 3; c++) {
                e1[c] = p[1][c] - p[0][c];
                e2[c] = p[2][c] - p[0][c];
            }
            rb_f3_cross(e1, e2, n);
            float len = sqrtf(rb_f3_dot(n, n)), side = rb_f3_dot(n, d) < 0.0f ? -1.0f : 1.0f;
            for (int c = 0; c < 3; c++)
                o[c] = (1.0f - a) * p[0][c] + a * (1.0f - b) * p[1][c] + a * b * p[2][c] +
                       (len > 0.0f ? side * 1e-4f * diag * n[c] / len : 0.0f);
        }
        rays[i] = ray(o[0], o[1], o[2], d[0], d[1], d[2], 0.0f, INFINITY);
    }
}

struct embree {
    RTCDevice device;
    RTCScene scene;
};

static void embree_init(struct embree *e, const struct world *w)
{
    e->device = rtcNewDevice(NULL);
    assert_non_null(e->device);
    e->scene = rtcNewScene(e->device);
    rtcSetSceneFlags(e->scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, w->pos, 0,
                               4 * sizeof(float), w->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, w->tris, 0,
                               3 * sizeof(uint32_t), w->tri_count);
    rtcCommitGeometry(g);
    rtcAttachGeometry(e->scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(e->scene);
    assert_int_equal(rtcGetDeviceError(e->device), RTC_ERROR_NONE);
}

static void embree_release(struct embree *e)
{
    rtcReleaseScene(e->scene);
    rtcReleaseDevice(e->device);
}

/* Embree's closest hit: the triangle (RB_NONE: none) and t. */
static uint32_t embree_hit(const struct embree *e, const struct rb_gpu_bvh_ray *r, float *t)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof(rh));
    rh.ray.org_x = r->origin[0];
    rh.ray.org_y = r->origin[1];
    rh.ray.org_z = r->origin[2];
    rh.ray.tnear = r->origin[3];
    rh.ray.dir_x = r->direction[0];
    rh.ray.dir_y = r->direction[1];
    rh.ray.dir_z = r->direction[2];
    rh.ray.tfar = r->direction[3];
    rh.ray.mask = UINT32_MAX;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(e->scene, &ctx, &rh);
    *t = rh.ray.tfar;
    return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? RB_NONE : rh.hit.primID;
}

/* Whether triangle tri of w meets r, in double precision and with a margin of 1e-6 in the
 * barycentrics; then its distance in *t. */
static bool exact_hit(const struct world *w, uint32_t tri, const struct rb_gpu_bvh_ray *r,
                      double *t)
{
    double p[3][3], o[3], d[3], e1[3], e2[3], s[3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++)
            p[k][c] = w->pos[w->tris[tri * 3 + (uint32_t)k] * 4 + (uint32_t)c];
    for (int c = 0; c < 3; c++) {
        o[c] = r->origin[c];
        d[c] = r->direction[c];
        e1[c] = p[1][c] - p[0][c];
        e2[c] = p[2][c] - p[0][c];
        s[c] = o[c] - p[0][c];
    }
    double q[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                   d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * q[0] + e1[1] * q[1] + e1[2] * q[2];
    if (det == 0.0)
        return false;
    double u = (s[0] * q[0] + s[1] * q[1] + s[2] * q[2]) / det;
    double x[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
                   s[0] * e1[1] - s[1] * e1[0]};
    double v = (d[0] * x[0] + d[1] * x[1] + d[2] * x[2]) / det;
    *t = (e2[0] * x[0] + e2[1] * x[1] + e2[2] * x[2]) / det;
    return u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6;
}

/* How one scene's rays came out; agree: both miss, or the same triangle at the same distance. */
struct agreement {
    uint32_t rays, agree;
    uint32_t tie;      /* another triangle, but as near in double precision: overlapping ones */
    uint32_t other;    /* another triangle, nearer or farther */
    uint32_t missed;   /* only Embree hit */
    uint32_t extra;    /* only the BVH hit */
    uint32_t distance; /* the same triangle, a distance off by more than DIST_REL */
    double worst_rel;  /* of the rays on the same triangle */
};

static bool compare_scene(const char *name, const char *path)
{
    struct world w;
    if (!world_load(path, &w))
        return false;
    struct rb_bvh_mesh m = world_mesh(&w);
    struct rb_bvh bvh;
    double start = now_s();
    build(&(struct rb_bvh_desc){.mesh = &m, .objects = w.objects, .object_count = w.object_count},
          &bvh);
    double build_ms = 1e3 * (now_s() - start);

    struct rb_gpu_bvh_ray *rays = malloc(SCENE_RAYS * sizeof(*rays));
    struct rb_gpu_bvh_trace_hit *hits = malloc(SCENE_RAYS * sizeof(*hits));
    struct rb_gpu_bvh_trace_hit *closest = malloc(SCENE_RAYS * sizeof(*hits));
    assert_true(rays && hits && closest);
    scene_rays(&w, &bvh, rays, SCENE_RAYS);
    trace(&bvh, rays, SCENE_RAYS, false, closest);
    double rays_per_s = SCENE_RAYS / tracer.gpu_s;
    trace(&bvh, rays, SCENE_RAYS, true, hits);

    struct embree e;
    embree_init(&e, &w);
    struct agreement a = {0};
    for (uint32_t i = 0; i < SCENE_RAYS; i++) {
        const struct rb_gpu_bvh_trace_hit *h = &hits[i];
        /* The closest hit is the same with or without the occlusion queries, which agree. */
        assert_memory_equal(h->hit, closest[i].hit, sizeof(h->hit));
        assert_int_equal(h->occluded[0], h->hit[0] >= 0.0f);
        assert_int_equal(h->occluded[1], 0);
        float te;
        uint32_t ref = embree_hit(&e, &rays[i], &te), got = word(h->hit[1]);
        double rel = fabs((double)h->hit[0] - te) / te, t_exact;
        a.rays++;
        if (ref == RB_NONE || got == RB_NONE) {
            a.agree += ref == got;
            a.missed += got == RB_NONE && ref != RB_NONE;
            a.extra += got != RB_NONE && ref == RB_NONE;
        } else if (ref != got) {
            bool is_tie = rel <= DIST_REL && exact_hit(&w, got, &rays[i], &t_exact) &&
                          fabs(t_exact - te) <= DIST_REL * te;
            a.tie += is_tie;
            a.other += !is_tie;
        } else {
            a.worst_rel = fmax(a.worst_rel, rel);
            a.agree += rel <= DIST_REL;
            a.distance += rel > DIST_REL;
        }
    }
    print_message("# %s: %u triangles (%llu degenerate), %u objects: build %.1f ms, %u nodes, "
                  "depth %u; %u of %u rays agree with Embree (%.3f%%), and %u more hit another "
                  "triangle at the same distance (%.3f%% in all); other triangle %u, missed %u, "
                  "extra %u, distance %u; worst relative distance %.2g; %.0f rays/s (closest "
                  "hit, lavapipe)\n",
                  name, bvh.triangle_count, (unsigned long long)bvh.triangles_degenerate,
                  bvh.object_count, build_ms, bvh.node_count, bvh.depth, a.agree, a.rays,
                  100.0 * a.agree / a.rays, a.tie, 100.0 * (a.agree + a.tie) / a.rays, a.other,
                  a.missed, a.extra, a.distance, a.worst_rel, rays_per_s);
    assert_int_equal(bvh.objects_included, w.object_count);
    assert_true((double)(a.agree + a.tie) >= AGREE_MIN * a.rays);
    embree_release(&e);
    free(closest);
    free(hits);
    free(rays);
    rb_bvh_release(&bvh);
    world_release(&w);
    return true;
}

/* The same bytes on one thread and several, on the largest shared scene. */
static void test_threads_scene(void **state)
{
    (void)state;
    char path[4096];
    struct world w;
    if (rb_test_scene(path, sizeof(path),
                      "MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb")) {
        print_message("# skipped: %s is absent (set RB_SCENES)\n", path);
        skip(); /* a checkout without the external sample scenes */
    }
    assert_true(world_load(path, &w));
    struct rb_bvh_mesh m = world_mesh(&w);
    expect_same_build(
        &(struct rb_bvh_desc){.mesh = &m, .objects = w.objects, .object_count = w.object_count},
        "MetalRoughSpheresNoTextures");
    world_release(&w);
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && !strcmp(s + n - k, suffix);
}

static void test_scenes_against_embree(void **state)
{
    (void)state;
    char dir[4096];
    if (rb_test_scene(dir, sizeof(dir), "cornell-box/CornellBox.glb")) {
        print_message("# skipped: %s is absent (set RB_SCENES)\n", dir);
        skip(); /* a checkout without the external sample scenes */
    }
    rb_test_scene(dir, sizeof(dir), "");
    struct dirent **subs = NULL;
    int n = scandir(dir, &subs, NULL, alphasort);
    assert_true(n > 0);
    unsigned traced = 0;
    for (int i = 0; i < n; i++) {
        char sub[4608];
        snprintf(sub, sizeof(sub), "%s/%s", dir, subs[i]->d_name);
        struct dirent **files = NULL;
        int k = subs[i]->d_name[0] == '.' ? -1 : scandir(sub, &files, NULL, alphasort);
        for (int j = 0; j < k; j++) {
            const char *f = files[j]->d_name;
            if (has_suffix(f, ".glb") || has_suffix(f, ".gltf")) {
                char path[4992];
                snprintf(path, sizeof(path), "%s/%s", sub, f);
                traced += compare_scene(f, path);
            }
            free(files[j]);
        }
        free(files);
        free(subs[i]);
    }
    free(subs);
    assert_true(traced >= 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_triangle),
        cmocka_unit_test(test_edges_and_ties),
        cmocka_unit_test(test_empty_and_degenerate),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_budget),
        cmocka_unit_test(test_lod),
        cmocka_unit_test(test_relevance),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_threads_scene),
        cmocka_unit_test(test_scenes_against_embree),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
