/* simplify: a coarser copy of a triangle mesh for the many small views of an integrator (RSM
 * faces, VPL maps, ray-bundles), each of which pays lavapipe's single-threaded vertex front end
 * again (about 7 ms per 100k triangles, LAVAPIPE.md). meshoptimizer does the collapsing; this
 * file decides how a budget is split, welds vertices by position first, falls back to the
 * sloppy simplifier, keeps every mesh from vanishing and puts hard edges' normals back. It knows
 * nothing of instances or the GPU (lib/integrators/frame.c builds the frame's buffer from it).
 * Everything here is integer arithmetic, plain float arithmetic (never contracted) or
 * meshoptimizer's own single-threaded code, so the same mesh and target give the same indices
 * on every run. */
#include "scene/scene.h"

#include <float.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

uint64_t rb_scene_simplify_targets(const uint32_t *triangles, uint32_t count,
                                   uint64_t budget_triangles, uint32_t *targets)
{
    uint64_t total = 0, sum = 0;
    for (uint32_t i = 0; i < count; i++)
        total += triangles[i];
    bool is_whole = budget_triangles == 0 || budget_triangles >= total;
    /* budget < total, so budget * triangles[i] < total * 2^32: no overflow while total < 2^32 */
    if (!is_whole && total > UINT32_MAX)
        RB_BUG("a simplification budget over %llu triangles", (unsigned long long)total);
    for (uint32_t i = 0; i < count; i++) {
        uint32_t t = triangles[i];
        if (!is_whole) {
            uint32_t least =
                t < RB_SCENE_SIMPLIFY_MIN_TRIANGLES ? t : RB_SCENE_SIMPLIFY_MIN_TRIANGLES;
            t = (uint32_t)(budget_triangles * t / total);
            t = t < least ? least : t;
        }
        targets[i] = t;
        sum += t;
    }
    return sum;
}

static const float *vec_at(const float *base, size_t stride_bytes, uint32_t i)
{
    return (const float *)((const char *)base + stride_bytes * i);
}

/* The mesh welded by position: one vertex per distinct position. meshoptimizer's simplifier
 * treats several vertices at one position as a seam it may only collapse along, and it locks
 * any such vertex in place when some of them are named by no triangle (as a shadow index
 * buffer leaves them), so the welded mesh gets its own compact vertices. */
struct weld {
    uint32_t unique;   /* distinct positions */
    uint32_t *remap;   /* [vertex_count]: the welded vertex, ~0u for one no index names */
    uint32_t *first;   /* [unique + 1]: members[first[w] .. first[w + 1]) are welded to w */
    uint32_t *members; /* [vertex_count], each welded vertex's in increasing order */
    float *positions;  /* [unique][3] */
    uint32_t *indices; /* [index_count] into positions */
};

static void weld_release(struct weld *w)
{
    free(w->indices);
    free(w->positions);
    free(w->members);
    free(w->first);
    free(w->remap);
}

static enum rb_status weld_init(const struct rb_scene_simplify_mesh *mesh, struct weld *w,
                                struct rb_err *err)
{
    uint32_t n = mesh->vertex_count, count = mesh->index_count;
    *w = (struct weld){0};
    w->remap = malloc(sizeof(uint32_t) * n);
    w->members = malloc(sizeof(uint32_t) * n);
    w->indices = malloc(sizeof(uint32_t) * count);
    if (!w->remap || !w->members || !w->indices)
        goto nomem;
    const struct meshopt_Stream stream = {mesh->positions, 3 * sizeof(float), mesh->stride_bytes};
    w->unique =
        (uint32_t)meshopt_generateVertexRemapMulti(w->remap, mesh->indices, count, n, &stream, 1);
    meshopt_remapIndexBuffer(w->indices, mesh->indices, count, w->remap);
    w->first = calloc((size_t)w->unique + 1, sizeof(uint32_t));
    w->positions = malloc(sizeof(float) * 3 * ((size_t)w->unique + 1));
    if (!w->first || !w->positions)
        goto nomem;
    /* a counting sort of the vertices by their welded vertex; all of one share its position */
    for (uint32_t v = 0; v < n; v++)
        if (w->remap[v] != ~0u)
            w->first[w->remap[v] + 1]++;
    for (uint32_t u = 0; u < w->unique; u++)
        w->first[u + 1] += w->first[u];
    for (uint32_t v = 0; v < n; v++) /* first[u] runs to the end of u's members */
        if (w->remap[v] != ~0u)
            w->members[w->first[w->remap[v]]++] = v;
    for (uint32_t u = w->unique; u > 0; u--)
        w->first[u] = w->first[u - 1];
    w->first[0] = 0;
    for (uint32_t u = 0; u < w->unique; u++)
        memcpy(&w->positions[3 * u],
               vec_at(mesh->positions, mesh->stride_bytes, w->members[w->first[u]]),
               3 * sizeof(float));
    return RB_OK;
nomem:
    weld_release(w);
    return rb_errf(err, RB_E_NOMEM, "out of memory for %u vertices", n);
}

/* Turns out's indices into the welded mesh back into the mesh's own vertices: of the vertices
 * at a corner's position, the one whose normal is closest to its triangle's (so a corner on a
 * hard edge or a flat-shaded face keeps the normal of its side), or without normals the
 * lowest-numbered; the lowest-numbered on a tie. */
static void unweld(const struct rb_scene_simplify_mesh *mesh, const struct weld *w, uint32_t *out,
                   uint32_t out_count)
{
    for (uint32_t t = 0; t + 2 < out_count; t += 3) {
        const float *a = &w->positions[3 * out[t]], *b = &w->positions[3 * out[t + 1]];
        const float *c = &w->positions[3 * out[t + 2]];
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float face[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
        for (uint32_t k = t; k < t + 3; k++) {
            uint32_t u = out[k], best = w->members[w->first[u]];
            float best_dot = -FLT_MAX;
            for (uint32_t m = w->first[u]; mesh->normals && m < w->first[u + 1]; m++) {
                const float *nm = vec_at(mesh->normals, mesh->stride_bytes, w->members[m]);
                float d = nm[0] * face[0] + nm[1] * face[1] + nm[2] * face[2];
                if (d > best_dot) {
                    best_dot = d;
                    best = w->members[m];
                }
            }
            out[k] = best;
        }
    }
}

enum rb_status rb_scene_simplify(const struct rb_scene_simplify_mesh *mesh,
                                 uint32_t target_triangles, uint32_t *out,
                                 struct rb_scene_simplified *result, struct rb_err *err)
{
    uint32_t count = mesh->index_count;
    *result = (struct rb_scene_simplified){0};
    if (count % 3)
        return rb_errf(err, RB_E_INVALID, "%u indices are not whole triangles", count);
    if (mesh->stride_bytes < 12 || mesh->stride_bytes % 4 || mesh->stride_bytes > 256)
        return rb_errf(err, RB_E_INVALID, "a vertex stride of %zu bytes", mesh->stride_bytes);
    for (uint32_t i = 0; i < count; i++)
        if (mesh->indices[i] >= mesh->vertex_count)
            return rb_errf(err, RB_E_INVALID, "index %u is %u, past the %u vertices", i,
                           mesh->indices[i], mesh->vertex_count);
    if (target_triangles >= count / 3) {
        memcpy(out, mesh->indices, sizeof(uint32_t) * count);
        result->index_count = count;
        return RB_OK;
    }

    struct weld w;
    enum rb_status st = weld_init(mesh, &w, err);
    if (st)
        return st;
    uint32_t *scratch = malloc(sizeof(uint32_t) * count);
    if (!scratch) {
        weld_release(&w);
        return rb_errf(err, RB_E_NOMEM, "out of memory for %u indices", count);
    }
    size_t target = (size_t)target_triangles * 3, stride = 3 * sizeof(float);
    /* No bound on the error: the budget alone decides, and the error is reported. */
    float error = 0.0f;
    size_t n = meshopt_simplify(out, w.indices, count, w.positions, w.unique, stride, target,
                                FLT_MAX, 0, &error);
    bool is_sloppy = false;
    if (n > target) {
        float sloppy_error = 0.0f;
        size_t m = meshopt_simplifySloppy(scratch, w.indices, count, w.positions, w.unique, stride,
                                          target, FLT_MAX, &sloppy_error);
        if (m > 0 && m < n) {
            memcpy(out, scratch, sizeof(uint32_t) * m);
            n = m;
            error = sloppy_error;
            is_sloppy = true;
        }
    }
    if (n == 0) { /* kept whole rather than lost */
        memcpy(out, mesh->indices, sizeof(uint32_t) * count);
        n = count;
        error = 0.0f;
    } else {
        unweld(mesh, &w, out, (uint32_t)n);
        /* The collapses leave the triangles in no useful order; lavapipe's vertex front end
         * shades a vertex again whenever it has left its small cache. */
        memcpy(scratch, out, sizeof(uint32_t) * n);
        meshopt_optimizeVertexCache(out, scratch, n, mesh->vertex_count);
    }
    free(scratch);
    weld_release(&w);
    *result = (struct rb_scene_simplified){
        .index_count = (uint32_t)n, .error = error, .is_sloppy = is_sloppy};
    return RB_OK;
}
