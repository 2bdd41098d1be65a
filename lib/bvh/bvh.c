/* The hybrid integrator's BVH (seed 003, "BVH for the rays that fail in screen space"): objects
 * chosen under a triangle budget by occlusion relevance over traversal cost, built by Embree's
 * rtcBuildBVH (binned SAH, binary, at most RB_BVH_MAX_LEAF_SIZE triangles a leaf, depth bounded
 * by RB_BVH_MAX_DEPTH) into a temporary tree in Embree's thread-local memory, then flattened into
 * bvh_shared.h's arrays. Determinism: Embree's splits come from the primitives' bounds, but its
 * threads may leave a node's primitives in another order; the flattening numbers nodes depth-
 * first from the root (child 0 first) and sorts each leaf by triangle id, so that order cannot
 * reach the bytes (tests/unit/test_bvh.c compares builds on 1, 2, 4 and 8 threads, a million
 * triangles and thousands with one centroid included). Not done here: refitting, instancing,
 * simplified objects. */
#include "bvh/bvh.h"

#include <embree3/rtcore.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The temporary tree: inner nodes and leaves in Embree's allocator, told apart by count. */
struct tmp_inner {
    uint32_t count; /* 0 */
    const void *child[2];
    struct RTCBounds box[2];
};

struct tmp_leaf {
    uint32_t count; /* >= 1 */
    uint32_t ids[]; /* count pairs: global triangle id, object index */
};

static void *create_node(RTCThreadLocalAllocator alloc, unsigned child_count, void *user)
{
    (void)user;
    (void)child_count;
    struct tmp_inner *n = rtcThreadLocalAlloc(alloc, sizeof(*n), 16);
    if (n)
        memset(n, 0, sizeof(*n));
    return n;
}

static void set_children(void *node, void **children, unsigned child_count, void *user)
{
    (void)user;
    struct tmp_inner *n = node;
    for (unsigned i = 0; i < child_count && i < 2; i++)
        n->child[i] = children[i];
}

static void set_bounds(void *node, const struct RTCBounds **bounds, unsigned child_count,
                       void *user)
{
    (void)user;
    struct tmp_inner *n = node;
    for (unsigned i = 0; i < child_count && i < 2; i++)
        n->box[i] = *bounds[i];
}

static void *create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *prims,
                         size_t count, void *user)
{
    (void)user;
    struct tmp_leaf *l = rtcThreadLocalAlloc(alloc, sizeof(*l) + count * 2 * sizeof(uint32_t), 16);
    if (!l)
        return NULL;
    l->count = (uint32_t)count;
    for (size_t i = 0; i < count; i++) {
        l->ids[2 * i] = prims[i].primID;
        l->ids[2 * i + 1] = prims[i].geomID;
    }
    return l;
}

static void set_word(float *f, uint32_t word)
{
    memcpy(f, &word, sizeof(word));
}

static const float *vertex(const struct rb_bvh_mesh *m, uint32_t t, int k)
{
    return &m->positions[(size_t)m->indices[(size_t)t * 3 + (size_t)k] * m->stride_floats];
}

/* Twice triangle t's area in double precision, or 0 when it is degenerate (zero area, or a
 * coordinate that is not finite). */
static double double_area(const struct rb_bvh_mesh *m, uint32_t t)
{
    const float *p[3] = {vertex(m, t, 0), vertex(m, t, 1), vertex(m, t, 2)};
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++)
            if (!isfinite(p[k][c]))
                return 0.0;
    double e1[3], e2[3];
    for (int c = 0; c < 3; c++) {
        e1[c] = (double)p[1][c] - p[0][c];
        e2[c] = (double)p[2][c] - p[0][c];
    }
    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2];
    double z = e1[0] * e2[1] - e1[1] * e2[0];
    return sqrt(x * x + y * y + z * z);
}

/* Per object while choosing: its usable triangles (whole and coarser), its relevance and
 * score, whether it is in and by which version. */
struct pick {
    uint32_t object, valid, lod_valid;
    double relevance, score;
    bool is_included, is_lod;
};

static int by_score(const void *a, const void *b)
{
    const struct pick *x = a, *y = b;
    if (x->score != y->score)
        return x->score > y->score ? -1 : 1;
    return x->object < y->object ? -1 : x->object > y->object;
}

static int by_id(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* The flattening: nodes in depth-first order, leaves' triangles in that order. */
struct flat {
    const struct rb_bvh_mesh *mesh;
    struct rb_gpu_bvh_node *nodes;
    uint32_t node_count, node_cap;
    struct rb_gpu_bvh_triangle *tris;
    uint32_t tri_count;
    uint32_t depth;
};

/* Widens a box outward so a flat one keeps a volume and rounding in the slab test cannot cut
 * off a triangle on its face: by 2^-20 of the larger magnitude along each axis. */
static void pad_box(const float lo[3], const float hi[3], float *out_lo, float *out_hi)
{
    for (int c = 0; c < 3; c++) {
        float pad = fmaxf(fabsf(lo[c]), fabsf(hi[c])) * 0x1p-20f + FLT_MIN;
        out_lo[c] = lo[c] - pad;
        out_hi[c] = hi[c] + pad;
    }
}

static void emit_leaf(struct flat *f, struct tmp_leaf *l, float *index_word, float *leaf_word)
{
    qsort(l->ids, l->count, 2 * sizeof(uint32_t), by_id);
    set_word(index_word, f->tri_count);
    set_word(leaf_word, RB_BVH_LEAF_BIT | l->count);
    for (uint32_t i = 0; i < l->count; i++) {
        struct rb_gpu_bvh_triangle *t = &f->tris[f->tri_count++];
        memset(t, 0, sizeof(*t));
        float *v[3] = {t->v0, t->v1, t->v2};
        for (int k = 0; k < 3; k++)
            memcpy(v[k], vertex(f->mesh, l->ids[2 * i], k), 3 * sizeof(float));
        set_word(&t->v0[3], l->ids[2 * i]);
        set_word(&t->v1[3], l->ids[2 * i + 1]);
    }
}

/* Emits inner node n (at depth) and its subtrees; returns its index. */
static uint32_t emit_inner(struct flat *f, const struct tmp_inner *n, uint32_t depth)
{
    if (f->node_count == f->node_cap)
        RB_BUG("more BVH nodes than triangles");
    uint32_t index = f->node_count++;
    float lo[2][3], hi[2][3], words[2][2];
    for (int i = 0; i < 2; i++) {
        const struct RTCBounds *b = &n->box[i];
        const float blo[3] = {b->lower_x, b->lower_y, b->lower_z};
        const float bhi[3] = {b->upper_x, b->upper_y, b->upper_z};
        pad_box(blo, bhi, lo[i], hi[i]);
        const uint32_t *count = n->child[i];
        if (*count) {
            f->depth = depth + 1 > f->depth ? depth + 1 : f->depth;
            emit_leaf(f, (struct tmp_leaf *)n->child[i], &words[i][0], &words[i][1]);
        } else {
            set_word(&words[i][0], emit_inner(f, n->child[i], depth + 1));
            set_word(&words[i][1], 0);
        }
    }
    struct rb_gpu_bvh_node *out = &f->nodes[index];
    float *box[4] = {out->box0_min, out->box0_max, out->box1_min, out->box1_max};
    for (int i = 0; i < 2; i++) {
        memcpy(box[2 * i], lo[i], sizeof(lo[i]));
        memcpy(box[2 * i + 1], hi[i], sizeof(hi[i]));
        box[2 * i][3] = words[i][0];
        box[2 * i + 1][3] = words[i][1];
    }
    return index;
}

struct embree_status {
    enum RTCError code;
    char msg[256];
};

static void embree_error(void *user, enum RTCError code, const char *str)
{
    struct embree_status *s = user;
    if (s->code == RTC_ERROR_NONE) {
        s->code = code;
        snprintf(s->msg, sizeof(s->msg), "%s", str ? str : "no message");
    }
}

/* Embree's progress monitor: false (stop) once the caller's cancel flag is set. */
static bool progress(void *user, double done)
{
    (void)done;
    const atomic_bool *cancel = user;
    return !cancel || !atomic_load(cancel);
}

/* Builds prims (count of them) with Embree and flattens the tree into f. */
static enum rb_status build_tree(struct flat *f, struct RTCBuildPrimitive *prims, size_t count,
                                 uint32_t thread_count, const atomic_bool *cancel,
                                 struct rb_err *err)
{
    char config[64] = "";
    if (thread_count)
        snprintf(config, sizeof(config), "threads=%u", thread_count);
    RTCDevice device = rtcNewDevice(config);
    if (!device)
        return rb_errf(err, RB_E_EXTERNAL, "embree: cannot create a device (error %d)",
                       (int)rtcGetDeviceError(NULL));
    struct embree_status status = {RTC_ERROR_NONE, ""};
    rtcSetDeviceErrorFunction(device, embree_error, &status);
    enum rb_status st = RB_OK;
    RTCBVH bvh = rtcNewBVH(device);
    struct RTCBuildArguments args = rtcDefaultBuildArguments();
    args.buildQuality = RTC_BUILD_QUALITY_MEDIUM; /* HIGH adds spatial splits: a triangle in
                                                   * several leaves */
    args.maxBranchingFactor = 2;
    args.maxDepth = RB_BVH_MAX_DEPTH;
    args.sahBlockSize = 1;
    args.minLeafSize = 1;
    args.maxLeafSize = RB_BVH_MAX_LEAF_SIZE;
    args.traversalCost = 1.0f;
    args.intersectionCost = 1.0f;
    args.bvh = bvh;
    args.primitives = prims;
    args.primitiveCount = count;
    args.primitiveArrayCapacity = count;
    args.createNode = create_node;
    args.setNodeChildren = set_children;
    args.setNodeBounds = set_bounds;
    args.createLeaf = create_leaf;
    args.buildProgress = progress;
    args.userPtr = (void *)cancel; /* read only, by progress */
    void *root = bvh ? rtcBuildBVH(&args) : NULL;
    if (status.code == RTC_ERROR_CANCELLED || (cancel && atomic_load(cancel))) {
        st = rb_errf(err, RB_E_INTERRUPTED, "embree: the BVH of %zu triangles: cancelled", count);
        goto out;
    }
    if (!root || status.code != RTC_ERROR_NONE) {
        st = rb_errf(err, RB_E_EXTERNAL, "embree: building the BVH of %zu triangles: %s (%d)",
                     count, status.code ? status.msg : "no tree", (int)status.code);
        goto out;
    }
    if (*(const uint32_t *)root) {
        /* One leaf: under a root whose other child is empty. */
        struct RTCBounds b = {FLT_MAX, FLT_MAX, FLT_MAX, 0.0f, -FLT_MAX, -FLT_MAX, -FLT_MAX, 0.0f};
        for (size_t i = 0; i < count; i++) {
            b.lower_x = fminf(b.lower_x, prims[i].lower_x);
            b.lower_y = fminf(b.lower_y, prims[i].lower_y);
            b.lower_z = fminf(b.lower_z, prims[i].lower_z);
            b.upper_x = fmaxf(b.upper_x, prims[i].upper_x);
            b.upper_y = fmaxf(b.upper_y, prims[i].upper_y);
            b.upper_z = fmaxf(b.upper_z, prims[i].upper_z);
        }
        f->node_count = 1;
        f->depth = 1;
        struct rb_gpu_bvh_node *n = &f->nodes[0];
        memset(n, 0, sizeof(*n));
        const float lo[3] = {b.lower_x, b.lower_y, b.lower_z};
        const float hi[3] = {b.upper_x, b.upper_y, b.upper_z};
        pad_box(lo, hi, n->box0_min, n->box0_max);
        emit_leaf(f, (struct tmp_leaf *)root, &n->box0_min[3], &n->box0_max[3]);
        set_word(&n->box1_max[3], RB_BVH_LEAF_BIT);
    } else {
        emit_inner(f, root, 0);
    }
    if (f->depth > RB_BVH_STACK_SIZE)
        st = rb_errf(err, RB_E_UNSUPPORTED,
                     "BVH of %zu triangles is %u levels deep, more than the traversal's stack "
                     "of %d",
                     count, f->depth, RB_BVH_STACK_SIZE);
out:
    if (bvh)
        rtcReleaseBVH(bvh);
    rtcReleaseDevice(device);
    return st;
}

/* The objects of desc (the whole mesh as one when it has none), or an error for bad input. */
static enum rb_status check_desc(const struct rb_bvh_desc *desc, struct rb_bvh_object *whole,
                                 const struct rb_bvh_object **objects, uint32_t *object_count,
                                 struct rb_err *err)
{
    const struct rb_bvh_mesh *m = desc->mesh;
    if (!m || (m->triangle_count && (!m->positions || !m->indices)) || m->stride_floats < 3)
        return rb_errf(err, RB_E_INVALID, "BVH: no mesh, or a stride under 3 floats");
    *whole = (struct rb_bvh_object){.first_triangle = 0, .triangle_count = m->triangle_count};
    *objects = desc->objects ? desc->objects : whole;
    *object_count = desc->objects ? desc->object_count : 1;
    const struct rb_bvh_object *o = *objects;
    for (uint32_t i = 0; i < *object_count; i++)
        if ((uint64_t)o[i].first_triangle + o[i].triangle_count > m->triangle_count ||
            (uint64_t)o[i].lod_first + o[i].lod_count > m->triangle_count)
            return rb_errf(
                err, RB_E_INVALID,
                "BVH: object %u: triangles %u to %llu or its coarser %u to %llu past the mesh's %u",
                i, o[i].first_triangle,
                (unsigned long long)o[i].first_triangle + o[i].triangle_count, o[i].lod_first,
                (unsigned long long)o[i].lod_first + o[i].lod_count, m->triangle_count);
    for (uint64_t i = 0; i < (uint64_t)m->triangle_count * 3; i++)
        if (m->indices[i] >= m->vertex_count)
            return rb_errf(err, RB_E_INVALID,
                           "BVH: triangle %llu: index %u out of range (%u vertices)",
                           (unsigned long long)(i / 3), m->indices[i], m->vertex_count);
    if (desc->cancel && atomic_load(desc->cancel))
        return rb_errf(err, RB_E_INTERRUPTED, "BVH of %u triangles: cancelled", m->triangle_count);
    return RB_OK;
}

static int by_relevance(const void *a, const void *b)
{
    const struct pick *x = a, *y = b;
    if (x->relevance != y->relevance)
        return x->relevance > y->relevance ? -1 : 1;
    return x->object < y->object ? -1 : x->object > y->object;
}

/* Chooses the objects (rb_bvh_select's rule) into choice (object_count of them) and the counts
 * of stats; returns the triangles chosen. picks has room for object_count. */
static uint64_t choose(const struct rb_bvh_desc *desc, const struct rb_bvh_object *objects,
                       uint32_t object_count, struct pick *picks, uint8_t *choice,
                       struct rb_bvh *stats)
{
    const struct rb_bvh_mesh *m = desc->mesh;
    bool is_area = desc->score == RB_BVH_SCORE_AREA;
    uint64_t all_valid = 0;
    double total_relevance = 0.0;
    for (uint32_t i = 0; i < object_count; i++) {
        double area = 0.0, lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX},
               hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
        uint32_t valid = 0;
        for (uint32_t t = 0; t < objects[i].triangle_count; t++) {
            uint32_t id = objects[i].first_triangle + t;
            double a = double_area(m, id);
            if (!(a > 0.0))
                continue;
            valid++;
            area += 0.5 * a;
            for (int k = 0; k < 3; k++)
                for (int c = 0; c < 3; c++) {
                    lo[c] = fmin(lo[c], vertex(m, id, k)[c]);
                    hi[c] = fmax(hi[c], vertex(m, id, k)[c]);
                }
        }
        stats->triangles_degenerate += objects[i].triangle_count - valid;
        uint32_t lod_valid = 0;
        for (uint32_t t = 0; t < objects[i].lod_count; t++)
            lod_valid += double_area(m, objects[i].lod_first + t) > 0.0;
        /* Relevance: the object's area over its squared distance from the eye, the distance
         * taken to its bounds' centre and widened by their half diagonal, so an object around
         * the eye stays finite: about four times the solid angle it covers when far. */
        double relevance = 0.0;
        if (valid) {
            double d2 = 0.0, r2 = 0.0;
            for (int c = 0; c < 3; c++) {
                double mid = 0.5 * (lo[c] + hi[c]) - (double)desc->eye[c];
                d2 += mid * mid;
                r2 += 0.25 * (hi[c] - lo[c]) * (hi[c] - lo[c]);
            }
            relevance = area / (d2 + r2);
        }
        picks[i] = (struct pick){.object = i,
                                 .valid = valid,
                                 .lod_valid = lod_valid,
                                 .relevance = relevance,
                                 .score = valid ? (is_area ? area : relevance) / valid : 0.0};
        all_valid += valid;
        total_relevance += relevance;
    }
    uint64_t budget = desc->triangle_budget ? desc->triangle_budget : UINT64_MAX;
    /* Seed 003's shares: each object's part of the budget in proportion to its relevance; an
     * object over its share enters by its coarser version, and its score is its relevance per
     * triangle of that version. */
    if (!is_area && all_valid > budget && total_relevance > 0.0)
        for (uint32_t i = 0; i < object_count; i++) {
            struct pick *p = &picks[i];
            double share = (double)budget * (p->relevance / total_relevance);
            if (p->lod_valid > 0 && p->lod_valid < p->valid && (double)p->valid > share) {
                p->is_lod = true;
                p->score = p->relevance / p->lod_valid;
            }
        }
    /* The best score first, greedily under the budget: an object that no longer fits enters by
     * its coarser version if that fits, or is left out, and later ones are still tried. */
    qsort(picks, object_count, sizeof(*picks), by_score);
    uint64_t left = budget;
    for (uint32_t i = 0; i < object_count; i++) {
        struct pick *p = &picks[i];
        if ((p->is_lod ? p->lod_valid : p->valid) <= left) {
            p->is_included = true;
        } else if (!p->is_lod && p->lod_valid > 0 && p->lod_valid <= left) {
            p->is_included = p->is_lod = true;
        } else {
            p->is_lod = false;
            stats->triangles_left_out += p->valid;
            continue;
        }
        left -= p->is_lod ? p->lod_valid : p->valid;
    }
    /* What the budget has left makes coarser objects whole again, the most relevant first
     * (none can let a left-out object in: each was tried with more room than is left). */
    if (!is_area) {
        qsort(picks, object_count, sizeof(*picks), by_relevance);
        for (uint32_t i = 0; i < object_count; i++) {
            struct pick *p = &picks[i];
            if (p->is_included && p->is_lod && p->valid - p->lod_valid <= left) {
                left -= p->valid - p->lod_valid;
                p->is_lod = false;
            }
        }
    }
    uint64_t total = 0;
    for (uint32_t i = 0; i < object_count; i++) {
        const struct pick *p = &picks[i];
        choice[p->object] = !p->is_included ? RB_BVH_LEFT_OUT
                            : p->is_lod     ? RB_BVH_COARSER
                                            : RB_BVH_WHOLE;
        if (!p->is_included)
            continue;
        stats->objects_included++;
        stats->objects_simplified += p->is_lod;
        total += p->is_lod ? p->lod_valid : p->valid;
    }
    return total;
}

enum rb_status rb_bvh_select(const struct rb_bvh_desc *desc, uint8_t *choice, struct rb_err *err)
{
    struct rb_bvh_object whole;
    const struct rb_bvh_object *objects;
    uint32_t object_count;
    enum rb_status st = check_desc(desc, &whole, &objects, &object_count, err);
    if (st)
        return st;
    /* Every object fits, degenerate triangles and all: every object whole, as choose would
     * find (the common case, without an area computed). */
    uint64_t all = 0;
    for (uint32_t i = 0; i < object_count; i++)
        all += objects[i].triangle_count;
    if (!desc->triangle_budget || all <= desc->triangle_budget) {
        memset(choice, RB_BVH_WHOLE, object_count);
        return RB_OK;
    }
    struct pick *picks = calloc(object_count ? object_count : 1, sizeof(*picks));
    if (!picks)
        return rb_errf(err, RB_E_NOMEM, "BVH: out of memory for %u objects", object_count);
    struct rb_bvh stats = {0};
    choose(desc, objects, object_count, picks, choice, &stats);
    free(picks);
    return RB_OK;
}

enum rb_status rb_bvh_build(const struct rb_bvh_desc *desc, struct rb_bvh *out, struct rb_err *err)
{
    const struct rb_bvh_mesh *m = desc->mesh;
    struct rb_bvh_object whole;
    const struct rb_bvh_object *objects;
    uint32_t object_count;
    enum rb_status st = check_desc(desc, &whole, &objects, &object_count, err);
    if (st)
        return st;
    struct rb_bvh bvh = {.object_count = object_count};
    struct pick *picks = calloc(object_count ? object_count : 1, sizeof(*picks));
    uint8_t *choice = calloc(object_count ? object_count : 1, sizeof(*choice));
    struct RTCBuildPrimitive *prims = NULL;
    struct flat f = {.mesh = m};
    if (!picks || !choice) {
        st = rb_errf(err, RB_E_NOMEM, "BVH: out of memory for %u objects", object_count);
        goto out;
    }
    uint64_t valid_total = choose(desc, objects, object_count, picks, choice, &bvh);

    size_t n = (size_t)valid_total;
    prims = aligned_alloc(32, (n ? n : 1) * sizeof(*prims));
    f.node_cap = n > 1 ? (uint32_t)n : 1;
    f.nodes = calloc(f.node_cap, sizeof(*f.nodes));
    f.tris = calloc(n ? n : 1, sizeof(*f.tris));
    if (!prims || !f.nodes || !f.tris) {
        st = rb_errf(err, RB_E_NOMEM, "BVH: out of memory for %zu triangles", n);
        goto out;
    }
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    size_t k = 0;
    for (uint32_t i = 0; i < object_count; i++) {
        if (choice[i] == RB_BVH_LEFT_OUT)
            continue;
        bool lod = choice[i] == RB_BVH_COARSER;
        uint32_t first = lod ? objects[i].lod_first : objects[i].first_triangle;
        uint32_t count = lod ? objects[i].lod_count : objects[i].triangle_count;
        for (uint32_t j = 0; j < count; j++) {
            uint32_t t = first + j;
            if (!(double_area(m, t) > 0.0))
                continue;
            float tlo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, thi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
            for (int v = 0; v < 3; v++)
                for (int c = 0; c < 3; c++) {
                    tlo[c] = fminf(tlo[c], vertex(m, t, v)[c]);
                    thi[c] = fmaxf(thi[c], vertex(m, t, v)[c]);
                }
            for (int c = 0; c < 3; c++) {
                lo[c] = fminf(lo[c], tlo[c]);
                hi[c] = fmaxf(hi[c], thi[c]);
            }
            prims[k++] = (struct RTCBuildPrimitive){.lower_x = tlo[0],
                                                    .lower_y = tlo[1],
                                                    .lower_z = tlo[2],
                                                    .geomID = i,
                                                    .upper_x = thi[0],
                                                    .upper_y = thi[1],
                                                    .upper_z = thi[2],
                                                    .primID = t};
        }
    }
    if (k != n)
        RB_BUG("counted %zu triangles, found %zu", n, k);
    memcpy(bvh.bounds_min, lo, sizeof(lo));
    memcpy(bvh.bounds_max, hi, sizeof(hi));

    if (n == 0) {
        /* Nothing to hit: a root with two empty leaves. */
        f.node_count = 1;
        set_word(&f.nodes[0].box0_max[3], RB_BVH_LEAF_BIT);
        set_word(&f.nodes[0].box1_max[3], RB_BVH_LEAF_BIT);
    } else if ((st = build_tree(&f, prims, n, desc->thread_count, desc->cancel, err))) {
        goto out;
    }
    if (f.tri_count != n)
        RB_BUG("the BVH's leaves hold %u of %zu triangles", f.tri_count, n);
    bvh.nodes = f.nodes;
    bvh.node_count = f.node_count;
    bvh.triangles = f.tris;
    bvh.triangle_count = f.tri_count;
    bvh.depth = f.depth;
    bvh.choice = choice;
    f.nodes = NULL;
    f.tris = NULL;
    choice = NULL;
    *out = bvh;
out:
    free(f.tris);
    free(f.nodes);
    free(prims);
    free(choice);
    free(picks);
    return st;
}

void rb_bvh_release(struct rb_bvh *bvh)
{
    free(bvh->nodes);
    free(bvh->triangles);
    free(bvh->choice);
    memset(bvh, 0, sizeof(*bvh));
}
