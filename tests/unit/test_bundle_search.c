/* Bundle search against Embree: from points the camera sees, the surface bdpt's search finds in
 * a ray-bundle's per-pixel lists (Program 1 of seed 000: shaders/common/bundle_search.glsl, the
 * connect pass's own code) is the one Embree finds along the same line. Real scenes: the demo
 * job's room at frame 10 (the box turned, the column bent) and
 * $RB_SCENES/cornell-box/CornellBox.glb (skipped when absent). On lavapipe, validation on.
 * - The bundles are bdpt's own: the bdpt integrator renders a frame (160 x 90, one VPL, the
 *   job's other bdpt settings but view_triangles 0, so that its lists hold the full mesh, the
 *   one Embree gets, and one sub-image and one cache, so that they are there for every pixel) with
 * k + 1 bundles, for k < BUNDLES: its last bundle's lists are left for bundle_probe.comp
 * (rb_integrator_bdpt_frame), which starts the search from every G-buffer point x1 as connect does
 * (x1's texel and depth, s the side of x1's geometric normal, d the bundle's direction: bdpt's
 * k-th), with s and with -s. Every k + 1 renders the same first k bundles: k is the new direction.
 * - Embree casts the line the lists sampled for x1: through its texel's centre (the rasterizer's
 *   sample), along s d, from x1's depth plus half a texel (where the search starts), against the
 *   same posed triangles (rb_scene_deform), keeping the nearest that faces the line's origin, as
 * the search keeps the nodes that face x1.
 * - A sample agrees when both miss, or both hit at distances within one texel of the grid with
 *   interpolated normals within NORMAL_COS (the same surface). For each direction, s = +1
 *   (along d: front nodes) and s = -1 (against d: back nodes), at least 99% of the samples agree.
 * - The search with the wrong sign (-s, against Embree's s d) agrees with under half of them: the
 *   comparison can fail. x1's own line (up to half a texel's diagonal beside the sampled one, so
 *   the distance may also differ by that times the slope of the surface it meets) is printed, not
 *   asserted: it differs where a texel straddles an edge or seam.
 * - connect's distance (rb_bundle_on_own_line: the node's plane met on x1's own line) agrees
 *   with Embree's along x1's own line within OWN_TOLERANCE of a texel for at least OWN_MIN of the
 *   samples, and more often than the node's depth does. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "bindings_shared.h"
#include "bundle_probe.comp.h"
#include "integrators/integrators_int.h"
#include "reference/reference_int.h"
#include "testutil.h"

#define BUNDLES 8
#define WIDTH 160
#define HEIGHT 90
#define AGREE_MIN 0.99 /* of the samples, in each direction */
#define WRONG_MAX 0.5  /* with the wrong sign */
/* Along x1's own line through the node's plane: within a tenth of a texel for 97% of the
 * samples (measured 98.0% and 98.4%; the node's depth: 38% and 40%); edges, seams and planes
 * nearly along d differ. */
#define OWN_TOLERANCE 0.1
#define OWN_MIN 0.97
#define NORMAL_COS 0.999 /* about 2.6 degrees between the normals: the same surface */
#define PI 3.14159265358979323846

/* bundle_probe.comp's output: the bundle's view, then an entry per pixel. */
struct probe_entry {
    float origin[4];  /* x1, s (0: no surface) */
    float t[4];       /* along s d, along -s d (-1: none) */
    uint32_t node[4]; /* normal words along s d, -s d; node indices */
};
struct probe_out {
    struct rb_gpu_view view;
    struct probe_entry entries[];
};
_Static_assert(sizeof(struct probe_entry) == 48, "bundle_probe.comp's entry");
_Static_assert(offsetof(struct probe_out, entries) == 96, "bundle_probe.comp's output");

/* ---- the probe: the search on the device ------------------------------------------------- */

struct probe {
    struct rb_gpu *gpu;
    struct rb_gpu_layout layout;
    VkPipeline pipeline;
    struct rb_gpu_buffer out; /* struct probe_out, host-visible */
};

static void probe_init(struct probe *p, struct rb_gpu *gpu, size_t pixels)
{
    static const VkDescriptorType types[RB_BIND_BUNDLE_PROBE_COUNT] = {
        [RB_BIND_BUNDLE_PROBE_POSITION] = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
        [RB_BIND_BUNDLE_PROBE_MOTION] = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
        [RB_BIND_BUNDLE_PROBE_VIEWS] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        [RB_BIND_BUNDLE_PROBE_HEADS] = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
        [RB_BIND_BUNDLE_PROBE_NODES] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        [RB_BIND_BUNDLE_PROBE_OUT] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    };
    struct rb_err err = RB_ERR_INIT;
    *p = (struct probe){.gpu = gpu};
    if (rb_gpu_layout_init(gpu, types, RB_BIND_BUNDLE_PROBE_COUNT, 3 * sizeof(uint32_t), &p->layout,
                           &err) ||
        rb_gpu_compute_pipeline(gpu, rb_spv_bundle_probe_comp, sizeof(rb_spv_bundle_probe_comp),
                                p->layout.pipeline_layout, "bundle_probe", &p->pipeline, &err) ||
        rb_gpu_buffer_init(
            gpu,
            &(struct rb_gpu_buffer_desc){.size_bytes = sizeof(struct probe_out) +
                                                       pixels * sizeof(struct probe_entry),
                                         .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                         .is_host_visible = true,
                                         .debug_name = "probe.out"},
            &p->out, &err))
        fail_msg("%s", err.msg);
}

static void probe_release(struct probe *p)
{
    rb_gpu_buffer_release(p->gpu, &p->out);
    vkDestroyPipeline(p->gpu->device, p->pipeline, NULL);
    rb_gpu_layout_release(p->gpu, &p->layout);
}

/* Searches bundle k's lists, as the bdpt frame just rendered left them, from every pixel of
 * its G-buffer. */
static const struct probe_out *probe_run(struct probe *p, const struct rb_integrator *it,
                                         uint32_t k)
{
    const struct rb_bdpt_frame *b = rb_integrator_bdpt_frame(it);
    const struct rb_frame *frame = &it->frame;
    assert_non_null(b);
    struct rb_err err = RB_ERR_INIT;
    VkCommandBuffer cmd;
    if (rb_gpu_oneshot_begin(p->gpu, &cmd, &err))
        fail_msg("%s", err.msg);
    rb_gpu_barrier(cmd); /* after the frame's passes */
    struct rb_gpu_bindings bind = {0};
    const VkDescriptorType image = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    const VkDescriptorType buffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    const VkImageLayout general = VK_IMAGE_LAYOUT_GENERAL;
    rb_gpu_bindings_set_image(&bind, RB_BIND_BUNDLE_PROBE_POSITION, image,
                              frame->gbuffer[RB_GB_POSITION].view, VK_NULL_HANDLE, general);
    rb_gpu_bindings_set_image(&bind, RB_BIND_BUNDLE_PROBE_MOTION, image,
                              frame->gbuffer[RB_GB_MOTION].view, VK_NULL_HANDLE, general);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BUNDLE_PROBE_VIEWS, buffer, &b->bundle_views);
    rb_gpu_bindings_set_image(&bind, RB_BIND_BUNDLE_PROBE_HEADS, image, b->bundle.heads.view,
                              VK_NULL_HANDLE, general);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BUNDLE_PROBE_NODES, buffer, &b->bundle.nodes);
    rb_gpu_bindings_set_buffer(&bind, RB_BIND_BUNDLE_PROBE_OUT, buffer, &p->out);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->pipeline);
    rb_gpu_push_bindings(p->gpu, cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p->layout.pipeline_layout,
                         &bind);
    uint32_t push[3] = {k, b->bundle_size_px, b->bundle.capacity_nodes};
    vkCmdPushConstants(cmd, p->layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(push), push);
    vkCmdDispatch(cmd, (frame->width_px + 7) / 8, (frame->height_px + 7) / 8, 1);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
    if (rb_gpu_oneshot_end(p->gpu, cmd, &err))
        fail_msg("%s", err.msg);
    return p->out.mapped;
}

/* ---- Embree on the same posed mesh ------------------------------------------------------- */

struct mesh {
    float *pos; /* 4 per vertex (Embree's stride) */
    float *nrm; /* 3 per vertex */
    uint32_t *tris;
    uint32_t vertex_count, tri_count;
    RTCDevice device;
    struct rb_ref_world world; /* just its Embree scene, for rb_ref_intersect */
};

/* The normal of triangle prim by its winding, (p1 - p0) x (p2 - p0): glTF's front side. */
static void winding_normal(const struct mesh *m, uint32_t prim, double out[3])
{
    const uint32_t *tri = &m->tris[(size_t)prim * 3];
    const float *p0 = &m->pos[tri[0] * 4], *p1 = &m->pos[tri[1] * 4], *p2 = &m->pos[tri[2] * 4];
    double e1[3], e2[3];
    for (int c = 0; c < 3; c++) {
        e1[c] = (double)p1[c] - p0[c];
        e2[c] = (double)p2[c] - p0[c];
    }
    out[0] = e1[1] * e2[2] - e1[2] * e2[1];
    out[1] = e1[2] * e2[0] - e1[0] * e2[2];
    out[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* Keeps only the triangles that face the ray's origin, as the search keeps only the nodes whose
 * face points back along its way. */
static void facing_filter(const struct RTCFilterFunctionNArguments *args)
{
    const struct mesh *m = args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; i++) {
        if (!args->valid[i])
            continue;
        double ng[3], dot = 0.0;
        winding_normal(m, ((const unsigned *)args->hit)[5 * args->N + i], ng);
        for (unsigned c = 0; c < 3; c++)
            dot += ng[c] * ((const float *)args->ray)[(4 + c) * args->N + i];
        if (!(dot < 0.0))
            args->valid[i] = 0;
    }
}

/* The triangles of the frame's pose, laid out as frame.c lays out the index buffer. */
static void mesh_init(struct mesh *m, const struct rb_scene *scene,
                      const struct rb_scene_pose *pose)
{
    uint64_t verts = 0, tris = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        verts += p->vertex_count;
        tris += p->index_count / 3;
    }
    *m = (struct mesh){.vertex_count = (uint32_t)verts, .tri_count = (uint32_t)tris};
    m->pos = malloc((verts + 1) * 4 * sizeof(float)); /* Embree reads 16 bytes a vertex */
    m->nrm = malloc((verts + 1) * 3 * sizeof(float));
    m->tris = malloc((tris + 1) * 3 * sizeof(uint32_t));
    assert_true(m->pos && m->nrm && m->tris);
    rb_scene_deform(scene, pose, m->pos, 4, m->nrm, NULL, NULL);
    uint32_t dst = 0, t = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        for (uint32_t j = 0; j < p->index_count / 3 * 3; j++)
            m->tris[t++] = dst + scene->indices[p->first_index + j];
        dst += p->vertex_count;
    }
    m->device = rtcNewDevice(NULL);
    assert_non_null(m->device);
    RTCScene rtc = rtcNewScene(m->device);
    rtcSetSceneFlags(rtc, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(m->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m->pos, 0,
                               4 * sizeof(float), m->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->tris, 0,
                               3 * sizeof(uint32_t), m->tri_count);
    rtcSetGeometryUserData(g, m);
    rtcSetGeometryIntersectFilterFunction(g, facing_filter);
    rtcCommitGeometry(g);
    rtcAttachGeometry(rtc, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(rtc);
    assert_int_equal(rtcGetDeviceError(m->device), RTC_ERROR_NONE);
    m->world.rtc = rtc;
}

static void mesh_release(struct mesh *m)
{
    rtcReleaseScene(m->world.rtc);
    rtcReleaseDevice(m->device);
    free(m->tris);
    free(m->nrm);
    free(m->pos);
}

struct hit {
    bool found;
    float t;
    double n[3];  /* the interpolated vertex normal, unit */
    double cos_d; /* |cos| between the triangle and the line */
};

/* The nearest triangle facing org along dir (unit) beyond tnear. */
static struct hit embree_hit(const struct mesh *m, const float org[3], const float dir[3],
                             float tnear)
{
    struct rb_ref_hit rh;
    rb_ref_intersect(&m->world, false, org, dir, tnear, INFINITY, &rh);
    struct hit h = {.found = rh.prim != RB_REF_NONE, .t = rh.t};
    if (!h.found)
        return h;
    const uint32_t *tri = &m->tris[(size_t)rh.prim * 3];
    double w[3] = {1.0 - rh.u - rh.v, rh.u, rh.v}, len = 0.0, ng[3], ng_len = 0.0, dot = 0.0;
    winding_normal(m, rh.prim, ng);
    for (int c = 0; c < 3; c++) {
        h.n[c] = 0.0;
        for (int k = 0; k < 3; k++)
            h.n[c] += w[k] * m->nrm[tri[k] * 3 + (uint32_t)c];
        len += h.n[c] * h.n[c];
        ng_len += ng[c] * ng[c];
        dot += ng[c] * dir[c];
    }
    for (int c = 0; c < 3; c++)
        h.n[c] /= sqrt(len);
    h.cos_d = fabs(dot) / sqrt(ng_len);
    return h;
}

/* A node's normal word back to a unit vector: rb_view_polar_decode of shaders/common/view.glsl. */
static void polar_decode(uint32_t w, double n[3])
{
    double theta = (double)(w & 0xffffu) / 65535.0 * PI;
    double phi = ((double)(w >> 16) / 65535.0 - 0.5) * 2.0 * PI;
    n[0] = sin(theta) * cos(phi);
    n[1] = sin(theta) * sin(phi);
    n[2] = cos(theta);
}

/* ---- the comparison ---------------------------------------------------------------------- */

/* The start of the line the lists sampled for x1: x1 moved, within its depth plane, onto the
 * centre of its texel, where the rasterizer sampled every surface of the texel's list. From the
 * view's documented projection (an orthographic transform whose first two rows are right and up
 * over the half size; a texel's centre at NDC (2 i + 1) / size - 1), in double precision.
 * Returns how far x1 is from that line. */
static double texel_line(const struct rb_gpu_view *v, uint32_t size, const float x1[3],
                         float out[3])
{
    const float *m = v->transform; /* column-major */
    double shift[3] = {0.0, 0.0, 0.0};
    for (int r = 0; r < 2; r++) {
        double row[3] = {m[r], m[4 + r], m[8 + r]}, ndc = m[12 + r], len2 = 0.0;
        for (int c = 0; c < 3; c++) {
            ndc += row[c] * x1[c];
            len2 += row[c] * row[c];
        }
        double centre = (floor((ndc * 0.5 + 0.5) * size) + 0.5) / size * 2.0 - 1.0;
        for (int c = 0; c < 3; c++)
            shift[c] += row[c] * (centre - ndc) / len2;
    }
    for (int c = 0; c < 3; c++)
        out[c] = (float)(x1[c] + shift[c]);
    return sqrt(shift[0] * shift[0] + shift[1] * shift[1] + shift[2] * shift[2]);
}

enum outcome { AGREE, SEARCH_MISSED, SEARCH_EXTRA, DISTANCE, NORMAL, OUTCOME_COUNT };

struct tally {
    uint32_t count[OUTCOME_COUNT];
    uint32_t samples;
    double worst_t;   /* of the samples that agree: the largest distance difference over its
                       * tolerance (1 == at the limit) */
    double worst_cos; /* and the least cosine between the normals */
};

static double share(const struct tally *t)
{
    return t->samples ? (double)t->count[AGREE] / t->samples : 0.0;
}

/* The search's hit (t < 0: none; its node's normal word) against Embree's, e, with a distance
 * tolerance. */
static void compare(struct tally *tally, float t, uint32_t normal, const struct hit *e,
                    double tolerance)
{
    bool found = t >= 0.0f;
    enum outcome o = AGREE;
    double dt = 0.0, cos = 1.0;
    if (!found || !e->found) {
        o = found == e->found ? AGREE : found ? SEARCH_EXTRA : SEARCH_MISSED;
    } else {
        double n[3];
        polar_decode(normal, n);
        dt = fabs((double)t - e->t);
        cos = n[0] * e->n[0] + n[1] * e->n[1] + n[2] * e->n[2];
        o = !(dt <= tolerance) ? DISTANCE : cos < NORMAL_COS ? NORMAL : AGREE;
    }
    tally->samples++;
    tally->count[o]++;
    if (o == AGREE) {
        tally->worst_t = fmax(tally->worst_t, dt / tolerance);
        tally->worst_cos = fmin(tally->worst_cos, cos);
    }
}

static void report(const char *scene, const char *what, const struct tally *t)
{
    print_message("# %s: %s: %u of %u samples agree (%.3f%%); the search missed %u, found one "
                  "Embree did not %u, distance off %u, normal off %u; of those that agree, the "
                  "worst distance / tolerance %.3g, the least cosine between normals %.6f\n",
                  scene, what, t->count[AGREE], t->samples, 100.0 * share(t),
                  t->count[SEARCH_MISSED], t->count[SEARCH_EXTRA], t->count[DISTANCE],
                  t->count[NORMAL], t->worst_t, t->worst_cos);
}

/* The tallies of one scene: along the lines the lists sampled, by direction; with the wrong
 * sign; along x1's own line, by direction, for the record; and along it within OWN_TOLERANCE,
 * with the node's depth and through its plane. */
struct tallies {
    struct tally right[2], wrong, own[2], centre_depth, plane;
};

static void compare_bundle(const struct probe_out *out, size_t pixels, uint32_t size,
                           const struct mesh *m, struct tallies *t)
{
    const float *d = out->view.axis, texel = out->view.axis[3];
    for (size_t i = 0; i < pixels; i++) {
        const struct probe_entry *e = &out->entries[i];
        float s = e->origin[3], line[3];
        if (s == 0.0f)
            continue;
        double aside = texel_line(&out->view, size, e->origin, line);
        assert_true(aside <= sqrt(0.5) * texel * 1.001); /* generate's texel size is its grid's */
        float dir[3] = {s * d[0], s * d[1], s * d[2]};
        /* Both start where the search starts: half a texel beyond x1's depth. */
        struct hit sampled = embree_hit(m, line, dir, 0.5f * texel);
        struct hit own = embree_hit(m, e->origin, dir, 0.5f * texel);
        compare(&t->right[s < 0.0f], e->t[0], e->node[0], &sampled, texel);
        compare(&t->wrong, e->t[1], e->node[1], &sampled, texel);
        /* Beside the sampled line, x1's meets a surface at angle theta to the grid up to
         * sqrt(1/2) texel tan(theta) nearer or farther. */
        double c = own.found ? fmax(own.cos_d, 1e-6) : 1.0;
        double slope = sqrt(0.5) * sqrt(fmax(0.0, 1.0 - c * c)) / c;
        compare(&t->own[s < 0.0f], e->t[0], e->node[0], &own, texel * (1.0 + slope));
        /* What connect takes: the node's plane met on x1's own line, held closer than the node's
         * depth there. */
        compare(&t->centre_depth, e->t[0], e->node[0], &own, OWN_TOLERANCE * texel);
        compare(&t->plane, e->t[2], e->node[0], &own, OWN_TOLERANCE * texel);
    }
}

static void check_scene(const char *name, const char *path, int frame_index)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = NULL;
    struct rb_job *job = NULL;
    struct rb_scene *scene = NULL;
    char resolution[32];
    snprintf(resolution, sizeof(resolution), "[%d, %d]", WIDTH, HEIGHT);
    const struct rb_job_override o[] = {
        {"resolution", resolution, NULL},
        {"integrator.name", "bdpt", NULL},
        {"integrator.bdpt.vpls", "1", NULL},
        {"integrator.bdpt.view_triangles", "0", NULL},
        /* bdpt lists a bundle only at the texels its connect pass searches (bdpt_mark.comp):
         * one sub-image of the G-buffer the caches share, so that it lists them for every
         * point of the frame's own G-buffer, where the probe searches */
        {"integrator.bdpt.interleave", "1", NULL},
        {"integrator.bdpt.caches", "1", NULL},
    };
    if (rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err) ||
        rb_job_load(path, o, COUNT(o), &job, &err) ||
        rb_scene_load(job->scene_path, 0, &scene, &err))
        fail_msg("%s: %s", name, err.msg);
    /* The lists drop alpha-masked texels; this Embree scene has no alpha test. */
    for (uint32_t i = 0; i < scene->material_count; i++)
        assert_false(scene->materials[i].alpha_mode == RB_ALPHA_MASK);
    size_t pixels = (size_t)WIDTH * HEIGHT;
    struct probe probe;
    probe_init(&probe, gpu, pixels);
    struct mesh m = {0};
    struct tallies t;
    memset(&t, 0, sizeof(t));
    struct tally *all[] = {&t.right[0], &t.right[1], &t.wrong,       &t.own[0],
                           &t.own[1],   &t.plane,    &t.centre_depth};
    for (size_t i = 0; i < COUNT(all); i++)
        all[i]->worst_cos = 1.0;
    for (uint32_t k = 0; k < BUNDLES; k++) {
        job->integrator.bdpt.bundles = k + 1;
        rb_job_rehash(job);
        struct rb_integrator *it = NULL;
        struct rb_frame_result r;
        if (rb_integrator_create(
                &(struct rb_integrator_desc){.job = job, .scene = scene, .gpu = gpu}, &it, &err) ||
            rb_integrator_render(it, frame_index, &r, &err))
            fail_msg("%s: bundle %u: %s", name, k, err.msg);
        assert_null(it->frame.view_indices.buffer); /* the full mesh */
        assert_int_equal(r.bundle_nodes_dropped, 0);
        if (k == 0) {
            mesh_init(&m, scene, it->cur.pose);
            assert_int_equal((uint64_t)m.tri_count * 3, it->frame.index_count);
        }
        const struct probe_out *out = probe_run(&probe, it, k);
        compare_bundle(out, pixels, rb_integrator_bdpt_frame(it)->bundle_size_px, &m, &t);
        rb_integrator_destroy(it);
    }
    report(name, "along d (s = +1)", &t.right[0]);
    report(name, "against d (s = -1)", &t.right[1]);
    report(name, "the wrong sign", &t.wrong);
    report(name, "x1's own line, along d (not asserted)", &t.own[0]);
    report(name, "x1's own line, against d (not asserted)", &t.own[1]);
    report(name, "x1's own line, the node's depth within a tenth of a texel", &t.centre_depth);
    report(name, "x1's own line, through the node's plane, within a tenth of a texel", &t.plane);
    mesh_release(&m);
    probe_release(&probe);
    rb_scene_destroy(scene);
    rb_job_destroy(job);
    rb_gpu_destroy(gpu);

    for (int i = 0; i < 2; i++) {
        assert_true(t.right[i].samples >= pixels * BUNDLES / 8);
        assert_true(share(&t.right[i]) >= AGREE_MIN);
    }
    assert_true(share(&t.wrong) < WRONG_MAX);
    assert_true(share(&t.plane) >= OWN_MIN);
    assert_true(share(&t.plane) > share(&t.centre_depth));
}

static void test_demo(void **state)
{
    (void)state;
    check_scene("demo", "jobs/demo.yaml", 10);
}

static void test_cornell_box(void **state)
{
    (void)state;
    char path[4096];
    if (rb_test_scene(path, sizeof(path), "cornell-box/CornellBox.glb")) {
        print_message("# cornell box: skipped: %s is absent (set RB_SCENES)\n", path);
        skip(); /* a checkout without the external sample scenes */
    }
    check_scene("cornell box", path, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_demo),
        cmocka_unit_test(test_cornell_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
