/* lib/scene/simplify.c, with no device: the budget's split over meshes (proportional, floored,
 * the per-mesh minimum, 0 = whole), and the simplifier on meshes whose true shape is known in
 * closed form: a finely tessellated plane (seamed at every quad, so only the weld by position
 * lets it collapse) and a flat-shaded box keep their area and bounds under a budget far below
 * their triangle count; a sphere keeps its silhouette within a tolerance; a cloud of separate
 * boxes, which edge collapses cannot bring under the target, takes the sloppy fallback; every
 * corner of a flat-shaded result keeps its face's normal; the same input gives the same bits. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "scene/scene.h"

#define PI 3.14159265358979323846

/* A vertex as a scene might lay it out: the simplifier reads only position and normal. */
struct vtx {
    float p[3];
    float n[3];
    float uv[2];
};

struct mesh {
    struct vtx *v;
    uint32_t *idx;
    uint32_t vertex_count, index_count, vertex_cap, index_cap;
};

static void reserve(struct mesh *m, uint32_t vertices, uint32_t indices)
{
    if (m->vertex_count + vertices > m->vertex_cap) {
        m->vertex_cap = 2 * (m->vertex_count + vertices);
        m->v = realloc(m->v, sizeof(*m->v) * m->vertex_cap);
    }
    if (m->index_count + indices > m->index_cap) {
        m->index_cap = 2 * (m->index_count + indices);
        m->idx = realloc(m->idx, sizeof(*m->idx) * m->index_cap);
    }
    assert_non_null(m->v);
    assert_non_null(m->idx);
}

static void mesh_free(struct mesh *m)
{
    free(m->idx);
    free(m->v);
}

/* A quad with its own four vertices (so every quad edge is a UV/normal seam): corners c, c+u,
 * c+u+v, c+v, facing u x v, with normal n. */
static void add_quad(struct mesh *m, const float c[3], const float u[3], const float v[3],
                     const float n[3])
{
    reserve(m, 4, 6);
    uint32_t b = m->vertex_count;
    for (int k = 0; k < 4; k++) {
        float a = k == 1 || k == 2, d = k >= 2;
        struct vtx *o = &m->v[b + (uint32_t)k];
        for (int i = 0; i < 3; i++) {
            o->p[i] = c[i] + a * u[i] + d * v[i];
            o->n[i] = n[i];
        }
        o->uv[0] = a;
        o->uv[1] = d;
    }
    static const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++)
        m->idx[m->index_count++] = b + tri[k];
    m->vertex_count += 4;
}

/* The square [x0, x0 + size] x [y0, y0 + size] at height z, facing up, as n x n seamed quads. */
static void add_plane(struct mesh *m, float x0, float y0, float z, float size, int n)
{
    float s = size / (float)n, u[3] = {s, 0, 0}, v[3] = {0, s, 0}, up[3] = {0, 0, 1};
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            add_quad(m, (float[3]){x0 + (float)i * s, y0 + (float)j * s, z}, u, v, up);
}

/* An axis-aligned box from lo with edge size, each face n x n seamed quads with the face's
 * normal (flat shading: the normals differ across every edge of the box). */
static void add_box(struct mesh *m, const float lo[3], float size, int n)
{
    float s = size / (float)n;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int a = (axis + 1) % 3, b = (axis + 2) % 3;
            float u[3] = {0}, v[3] = {0}, nrm[3] = {0};
            /* u x v along +axis for a, b cyclic; swap them on the low side to face out */
            u[side ? a : b] = s;
            v[side ? b : a] = s;
            nrm[axis] = side ? 1.0f : -1.0f;
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    float c[3] = {lo[0], lo[1], lo[2]};
                    c[axis] += side ? size : 0.0f;
                    c[side ? a : b] += (float)i * s;
                    c[side ? b : a] += (float)j * s;
                    add_quad(m, c, u, v, nrm);
                }
        }
}

/* A UV sphere of radius r around the origin with smooth normals and a seam at longitude 0. */
static void add_sphere(struct mesh *m, float r, int rings, int segments)
{
    uint32_t b = m->vertex_count, row = (uint32_t)segments + 1;
    reserve(m, (uint32_t)(rings + 1) * row, 6u * (uint32_t)(rings * segments));
    for (int j = 0; j <= rings; j++)
        for (int i = 0; i <= segments; i++) {
            double th = PI * j / rings, ph = 2.0 * PI * (i % segments) / segments;
            struct vtx *o = &m->v[m->vertex_count++];
            o->n[0] = (float)(sin(th) * cos(ph));
            o->n[1] = (float)(sin(th) * sin(ph));
            o->n[2] = (float)cos(th);
            for (int k = 0; k < 3; k++)
                o->p[k] = r * o->n[k];
            o->uv[0] = (float)i / (float)segments;
            o->uv[1] = (float)j / (float)rings;
        }
    for (uint32_t j = 0; j < (uint32_t)rings; j++)
        for (uint32_t i = 0; i < (uint32_t)segments; i++) {
            uint32_t a = b + j * row + i, c = a + row;
            uint32_t t[6] = {a, c, a + 1, a + 1, c, c + 1};
            for (int k = 0; k < 6; k++)
                m->idx[m->index_count++] = t[k];
        }
}

static struct rb_scene_simplify_mesh view_of(const struct mesh *m, bool with_normals)
{
    return (struct rb_scene_simplify_mesh){.positions = m->v[0].p,
                                           .normals = with_normals ? m->v[0].n : NULL,
                                           .stride_bytes = sizeof(struct vtx),
                                           .vertex_count = m->vertex_count,
                                           .indices = m->idx,
                                           .index_count = m->index_count};
}

/* Simplifies m to target triangles into a new array (the caller frees it). */
static uint32_t *simplify(const struct mesh *m, bool with_normals, uint32_t target,
                          struct rb_scene_simplified *r)
{
    struct rb_err err = RB_ERR_INIT;
    uint32_t *out = malloc(sizeof(uint32_t) * m->index_count);
    assert_non_null(out);
    struct rb_scene_simplify_mesh in = view_of(m, with_normals);
    if (rb_scene_simplify(&in, target, out, r, &err))
        fail_msg("simplify: %s", err.msg);
    assert_int_equal(r->index_count % 3, 0);
    for (uint32_t i = 0; i < r->index_count; i++)
        assert_true(out[i] < m->vertex_count);
    return out;
}

struct measure {
    double area;
    double lo[3], hi[3];
};

/* The total area of the triangles and the bounds of their corners. */
static struct measure measure(const struct mesh *m, const uint32_t *idx, uint32_t count)
{
    struct measure s = {0, {INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (uint32_t t = 0; t + 2 < count; t += 3) {
        const float *a = m->v[idx[t]].p, *b = m->v[idx[t + 1]].p, *c = m->v[idx[t + 2]].p;
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)b[k] - a[k];
            e2[k] = (double)c[k] - a[k];
        }
        double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
               z = e1[0] * e2[1] - e1[1] * e2[0];
        s.area += 0.5 * sqrt(x * x + y * y + z * z);
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++) {
                double p = m->v[idx[t + (uint32_t)v]].p[k];
                s.lo[k] = p < s.lo[k] ? p : s.lo[k];
                s.hi[k] = p > s.hi[k] ? p : s.hi[k];
            }
    }
    return s;
}

/* got keeps want's area within rel_area and its bounds within tol (metres). */
static void assert_shape(struct measure got, struct measure want, double rel_area, double tol)
{
    if (!(fabs(got.area - want.area) <= rel_area * want.area))
        fail_msg("area %g, want %g within %g%%", got.area, want.area, 100.0 * rel_area);
    for (int k = 0; k < 3; k++)
        if (!(fabs(got.lo[k] - want.lo[k]) <= tol && fabs(got.hi[k] - want.hi[k]) <= tol))
            fail_msg("axis %d: bounds [%g, %g], want [%g, %g] within %g", k, got.lo[k], got.hi[k],
                     want.lo[k], want.hi[k], tol);
}

/* ---- the budget's split -------------------------------------------------------------------- */

static void test_targets(void **state)
{
    (void)state;
    const uint32_t tri[] = {30000, 10000, 7, 5000, 5000, 3};
    enum { N = sizeof(tri) / sizeof(tri[0]) };
    uint64_t total = 0;
    for (int i = 0; i < N; i++)
        total += tri[i];
    uint32_t targets[N];
    const uint64_t budgets[] = {1, 100, 1000, 4999, total - 1};
    for (size_t b = 0; b < sizeof(budgets) / sizeof(budgets[0]); b++) {
        uint64_t budget = budgets[b], extra = 0;
        uint64_t sum = rb_scene_simplify_targets(tri, N, budget, targets);
        uint64_t check = 0;
        for (int i = 0; i < N; i++) {
            /* floor(budget * t / total), raised to the minimum (or the whole mesh below it) */
            uint64_t share = budget * tri[i] / total;
            uint64_t least =
                tri[i] < RB_SCENE_SIMPLIFY_MIN_TRIANGLES ? tri[i] : RB_SCENE_SIMPLIFY_MIN_TRIANGLES;
            uint64_t want = share < least ? least : share;
            assert_int_equal(targets[i], want);
            assert_true(targets[i] <= tri[i]);
            extra += want - share;
            check += targets[i];
        }
        assert_int_equal(sum, check);
        /* proportional: equal meshes equal shares, three times the triangles three times the
         * share (to the floor), and never over budget but for what the minimum added */
        assert_int_equal(targets[3], targets[4]);
        if (targets[0] > RB_SCENE_SIMPLIFY_MIN_TRIANGLES) {
            assert_true(targets[0] >= 3 * targets[1] - 2 && targets[0] <= 3 * targets[1] + 2);
        }
        assert_true(sum <= budget + extra);
        assert_true(sum + N > budget || extra > 0);
    }
    /* 0 and a budget the meshes fit in keep every mesh whole */
    const uint64_t whole[] = {0, total, total + 1, UINT64_MAX};
    for (size_t b = 0; b < sizeof(whole) / sizeof(whole[0]); b++) {
        assert_int_equal(rb_scene_simplify_targets(tri, N, whole[b], targets), total);
        assert_memory_equal(targets, tri, sizeof(tri));
    }
}

/* ---- the simplifier ------------------------------------------------------------------------ */

static void test_plane(void **state)
{
    (void)state;
    enum { N = 64 }; /* 8192 triangles, 16384 vertices: every quad edge is a seam */
    struct mesh m = {0};
    add_plane(&m, -1.5f, 0.25f, 0.75f, 3.0f, N);
    struct measure want = measure(&m, m.idx, m.index_count);
    const uint32_t budgets[] = {1000, 100, 12, 2};
    for (size_t b = 0; b < sizeof(budgets) / sizeof(budgets[0]); b++) {
        struct rb_scene_simplified r;
        uint32_t *out = simplify(&m, true, budgets[b], &r);
        print_message("# plane of %u triangles, target %u: %u, error %g%s\n", m.index_count / 3,
                      budgets[b], r.index_count / 3, (double)r.error,
                      r.is_sloppy ? " (sloppy)" : "");
        assert_true(r.index_count / 3 <= budgets[b]);
        assert_true(r.index_count > 0);
        /* the weld by position lets edge collapses through the seams: no sloppy fallback */
        assert_false(r.is_sloppy);
        /* a plane collapses without error: the same square, up to float rounding */
        assert_shape(measure(&m, out, r.index_count), want, 1e-5, 1e-6);
        assert_true(r.error < 1e-4f);
        for (uint32_t t = 0; t < r.index_count; t += 3) {
            const float *p0 = m.v[out[t]].p, *p1 = m.v[out[t + 1]].p, *p2 = m.v[out[t + 2]].p;
            float z = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
            assert_true(z >= 0.0f); /* none folded over (collinear slivers may stay) */
        }
        free(out);
    }
    mesh_free(&m);
}

static void test_box_normals(void **state)
{
    (void)state;
    struct mesh m = {0};
    add_box(&m, (float[3]){-0.5f, 2.0f, 1.0f}, 1.25f, 16); /* 3072 triangles */
    struct measure want = measure(&m, m.idx, m.index_count);
    struct rb_scene_simplified r;
    uint32_t *out = simplify(&m, true, 200, &r);
    print_message("# box of %u triangles, target 200: %u, error %g%s\n", m.index_count / 3,
                  r.index_count / 3, (double)r.error, r.is_sloppy ? " (sloppy)" : "");
    assert_true(r.index_count / 3 <= 200);
    assert_shape(measure(&m, out, r.index_count), want, 1e-5, 1e-6);
    /* each corner is a vertex of its own face: the normal of the triangle's side of the edge */
    for (uint32_t t = 0; t < r.index_count; t += 3) {
        const float *p0 = m.v[out[t]].p, *p1 = m.v[out[t + 1]].p, *p2 = m.v[out[t + 2]].p;
        double e1[3], e2[3], f[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
        }
        f[0] = e1[1] * e2[2] - e1[2] * e2[1];
        f[1] = e1[2] * e2[0] - e1[0] * e2[2];
        f[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (len == 0.0)
            continue; /* a collinear sliver: it covers nothing, and has no side */
        for (int c = 0; c < 3; c++) {
            const float *n = m.v[out[t + (uint32_t)c]].n;
            double d = (n[0] * f[0] + n[1] * f[1] + n[2] * f[2]) / len;
            if (!(d > 0.999))
                fail_msg("triangle %u corner %d: normal (%g, %g, %g) against the face's %g", t / 3,
                         c, (double)n[0], (double)n[1], (double)n[2], d);
        }
    }
    /* without normals the corners are the first vertex at each position, whatever its face */
    struct rb_scene_simplified r2;
    uint32_t *out2 = simplify(&m, false, 200, &r2);
    assert_int_equal(r2.index_count, r.index_count);
    free(out2);
    free(out);
    mesh_free(&m);
}

static void test_sphere(void **state)
{
    (void)state;
    const float radius = 2.0f;
    struct mesh m = {0};
    add_sphere(&m, radius, 96, 192); /* 36864 triangles */
    struct measure want = measure(&m, m.idx, m.index_count);
    struct rb_scene_simplified r;
    uint32_t *out = simplify(&m, true, 500, &r);
    struct measure got = measure(&m, out, r.index_count);
    print_message("# sphere of %u triangles, target 500: %u, error %g%s, area %g of %g\n",
                  m.index_count / 3, r.index_count / 3, (double)r.error,
                  r.is_sloppy ? " (sloppy)" : "", got.area, want.area);
    assert_true(r.index_count / 3 <= 500);
    assert_false(r.is_sloppy);
    /* 500 triangles inscribed in the sphere: an edge of about 0.33 r sags by under 1.5% of r,
     * so the area shrinks by at most about 3%, and the bounds stay within that sag */
    assert_shape(got, want, 0.04, 0.015 * radius);
    assert_true(r.error > 0.0f && r.error < 0.05f);
    free(out);
    mesh_free(&m);
}

/* Crosses of four fins around a vertical spine, touching their neighbours at the fins' tips:
 * the spines and tips are non-manifold, so edge collapses stop far above a small target, and
 * the sloppy simplifier (a vertex grid) takes over. */
static void add_crosses(struct mesh *m, int n)
{
    float up[3] = {0, 0, 1};
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            for (int f = 0; f < 4; f++) {
                float u[3] = {0.5f * (float)((f + 1) % 2) * (f < 2 ? 1.0f : -1.0f),
                              0.5f * (float)(f % 2) * (f < 2 ? 1.0f : -1.0f), 0.0f};
                float nrm[3] = {-u[1], u[0], 0.0f};
                add_quad(m, (float[3]){(float)i, (float)j, 0.0f}, u, up, nrm);
            }
}

static void test_sloppy(void **state)
{
    (void)state;
    struct mesh m = {0};
    add_crosses(&m, 10); /* 800 triangles */
    struct measure want = measure(&m, m.idx, m.index_count);
    struct rb_scene_simplified r;
    uint32_t *out = simplify(&m, true, 200, &r);
    struct measure got = measure(&m, out, r.index_count);
    print_message("# crosses of %u triangles, target 200: %u, error %g%s\n", m.index_count / 3,
                  r.index_count / 3, (double)r.error, r.is_sloppy ? " (sloppy)" : "");
    assert_true(r.is_sloppy);
    assert_true(r.index_count > 0 && r.index_count / 3 <= 200);
    /* the grid keeps the cloud's extent to within a cell */
    assert_shape(got, want, 1.0, 0.5);
    free(out);
    /* a target so small that the grid would leave nothing: the edge collapses' result stands,
     * over the target, so the mesh does not vanish from the views */
    out = simplify(&m, true, 10, &r);
    print_message("# target 10: %u, error %g%s\n", r.index_count / 3, (double)r.error,
                  r.is_sloppy ? " (sloppy)" : "");
    assert_false(r.is_sloppy);
    assert_true(r.index_count / 3 > 10 && r.index_count < m.index_count);
    assert_shape(measure(&m, out, r.index_count), want, 1.0, 1e-6);
    free(out);
    mesh_free(&m);
}

static void test_deterministic(void **state)
{
    (void)state;
    struct mesh m = {0};
    add_sphere(&m, 1.0f, 48, 96);
    add_box(&m, (float[3]){1.5f, 0.0f, 0.0f}, 0.5f, 8);
    for (int sloppy = 0; sloppy < 2; sloppy++) {
        uint32_t target = sloppy ? 4 : 400;
        struct rb_scene_simplified r1, r2;
        uint32_t *a = simplify(&m, true, target, &r1);
        uint32_t *b = simplify(&m, true, target, &r2);
        assert_int_equal(r1.index_count, r2.index_count);
        assert_memory_equal(a, b, sizeof(uint32_t) * r1.index_count);
        assert_memory_equal(&r1.error, &r2.error, sizeof(float));
        assert_int_equal(r1.is_sloppy, r2.is_sloppy);
        free(b);
        free(a);
    }
    mesh_free(&m);
}

static void test_whole(void **state)
{
    (void)state;
    struct mesh m = {0};
    add_plane(&m, 0.0f, 0.0f, 0.0f, 1.0f, 8);
    /* a target of the mesh's count or more: the indices as they were */
    for (uint32_t extra = 0; extra < 2; extra++) {
        struct rb_scene_simplified r;
        uint32_t *out = simplify(&m, true, m.index_count / 3 + extra, &r);
        assert_int_equal(r.index_count, m.index_count);
        assert_memory_equal(out, m.idx, sizeof(uint32_t) * m.index_count);
        assert_false(r.is_sloppy);
        assert_true(r.error == 0.0f);
        free(out);
    }
    mesh_free(&m);
}

static void test_errors(void **state)
{
    (void)state;
    struct mesh m = {0};
    add_plane(&m, 0.0f, 0.0f, 0.0f, 1.0f, 2);
    uint32_t out[24];
    struct rb_err err = RB_ERR_INIT;
    struct rb_scene_simplified r;
    struct rb_scene_simplify_mesh in = view_of(&m, false);
    in.index_count = 22;
    assert_int_equal(rb_scene_simplify(&in, 2, out, &r, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "22 indices are not whole triangles");
    in = view_of(&m, false);
    m.idx[7] = m.vertex_count;
    assert_int_equal(rb_scene_simplify(&in, 2, out, &r, &err), RB_E_INVALID);
    assert_string_equal(err.msg, "index 7 is 16, past the 16 vertices");
    mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_targets),     cmocka_unit_test(test_plane),
        cmocka_unit_test(test_box_normals), cmocka_unit_test(test_sphere),
        cmocka_unit_test(test_sloppy),      cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_whole),       cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
