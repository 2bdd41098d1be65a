/* Raster views (lib/passes/view.c), each kind and output alone, on lavapipe with the validation
 * layer on. The oracle casts rays in double precision through each pixel centre against the same
 * rectangles the GPU draws (its own ray-rectangle test, its own reading of the views' documented
 * projections), so every expected value is a closed form, not the renderer's output.
 * - orthographic depth: three views in one batch of a floor and a floating box; every pixel
 *   whose centre is not within 1e-3 texel of an edge holds the distance along the view axis.
 * - simplified mesh: a finely tiled plane simplified with rb_scene_simplify and drawn through
 *   the batch's use_simplified gives the full mesh's orthographic depths off its outline.
 * - paraboloid depth: a dual paraboloid (two hemispheres, one batch) in a room with a box; the
 *   depth is the distance to the first surface along the pixel centre's direction, and
 *   coverage is right for every pixel farther from an edge than the tessellation's bound,
 *   C^2 / (2 size) texels (derived in view.c; 1/32 texel at 256^2), while the geometry keeps
 *   every edge's level under the cap that bound assumes (checked here).
 * - reflective shadow map of a floor from a point light's cube face and from the sun: each
 *   texel's position, normal, depth, and flux (I albedo times the texel's solid angle, or E
 *   albedo times its area), which add up to the closed forms for the whole view.
 * - linked list: two stacked planes facing each other, seen from above and below in one batch:
 *   every pixel holds exactly its fragments, with their depths, face signs and normals, and the
 *   pool's count is the number of fragments; with a tiny pool the dropped count is exact, the
 *   nodes past the capacity stay untouched, and rb_view_list_check reports it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "passes/passes.h"

#define FAR_CLEAR 3.0e38f
#define MAX_QUADS 256
#define PI 3.14159265358979323846

/* ---- the scene: rectangles, drawn by the GPU and intersected by the oracle ------------------ */

struct quad {
    double c[3], u[3], v[3]; /* corners c, c+u, c+u+v, c+v; u perpendicular to v; u x v faces out */
    double normal[3];        /* the vertex normal of all four corners */
    int plane;               /* rectangles in one plane share an id */
};

struct scene {
    struct quad q[MAX_QUADS];
    int count;
};

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(double v[3])
{
    double l = sqrt(dot3(v, v));
    for (int i = 0; i < 3; i++)
        v[i] /= l;
}

static void add_quad(struct scene *s, const double c[3], const double u[3], const double v[3],
                     const double *normal, int plane)
{
    assert_true(s->count < MAX_QUADS);
    struct quad *q = &s->q[s->count++];
    memcpy(q->c, c, sizeof(q->c));
    memcpy(q->u, u, sizeof(q->u));
    memcpy(q->v, v, sizeof(q->v));
    if (normal)
        memcpy(q->normal, normal, sizeof(q->normal));
    else
        cross3(u, v, q->normal);
    normalize3(q->normal);
    q->plane = plane;
}

/* An n x n grid of 1 m tiles centred on the z axis at height z, facing up or down. */
static void add_grid(struct scene *s, int n, double z, bool up, int plane)
{
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double c[3] = {i - n / 2.0, j - n / 2.0, z};
            double x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
            add_quad(s, c, up ? x : y, up ? y : x, NULL, plane);
        }
}

/* A box with outward faces, planes first_plane .. first_plane + 5. */
static void add_box(struct scene *s, const double lo[3], const double hi[3], int first_plane)
{
    double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    double dx[3] = {d[0], 0, 0}, dy[3] = {0, d[1], 0}, dz[3] = {0, 0, d[2]};
    double top[3] = {lo[0], lo[1], hi[2]}, px[3] = {hi[0], lo[1], lo[2]};
    double py[3] = {lo[0], hi[1], lo[2]};
    add_quad(s, lo, dy, dx, NULL, first_plane);      /* -z */
    add_quad(s, top, dx, dy, NULL, first_plane + 1); /* +z */
    add_quad(s, lo, dz, dy, NULL, first_plane + 2);  /* -x */
    add_quad(s, px, dy, dz, NULL, first_plane + 3);  /* +x */
    add_quad(s, lo, dx, dz, NULL, first_plane + 4);  /* -y */
    add_quad(s, py, dz, dx, NULL, first_plane + 5);  /* +y */
}

/* The ray o + t d meets quad q at t (> 0), or not. */
static bool hit_quad(const struct quad *q, const double o[3], const double d[3], double *t)
{
    double n[3];
    cross3(q->u, q->v, n);
    double den = dot3(n, d);
    if (fabs(den) < 1e-12)
        return false;
    double co[3] = {q->c[0] - o[0], q->c[1] - o[1], q->c[2] - o[2]};
    double tt = dot3(n, co) / den;
    if (!(tt > 1e-9))
        return false;
    double h[3] = {o[0] + tt * d[0] - q->c[0], o[1] + tt * d[1] - q->c[1],
                   o[2] + tt * d[2] - q->c[2]};
    double a = dot3(h, q->u) / dot3(q->u, q->u), b = dot3(h, q->v) / dot3(q->v, q->v);
    if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0)
        return false;
    *t = tt;
    return true;
}

/* The first surface along the ray within max_t: its plane id (-1: none) and distance. */
static int first_hit(const struct scene *s, const double o[3], const double d[3], double max_t,
                     double *t_out)
{
    int plane = -1;
    double best = max_t;
    for (int i = 0; i < s->count; i++) {
        double t;
        if (hit_quad(&s->q[i], o, d, &t) && t < best) {
            best = t;
            plane = s->q[i].plane;
        }
    }
    *t_out = best;
    return plane;
}

/* ---- the GPU side -------------------------------------------------------------------------- */

struct gpu_scene {
    struct rb_gpu *gpu;
    struct rb_frame frame;
    struct rb_frame_slot slot; /* the frame's one slot */
};

static void check_ok(enum rb_status st, const struct rb_err *err)
{
    if (st)
        fail_msg("%s", err->msg);
}

/* A host-visible buffer; addressed ones are read by device address (geometry_shared.h). */
static void make_buffer_at(struct rb_gpu *gpu, VkDeviceSize size, VkBufferUsageFlags usage,
                           bool is_addressed, const char *name, struct rb_gpu_buffer *out)
{
    struct rb_err err = RB_ERR_INIT;
    check_ok(rb_gpu_buffer_init(gpu,
                                &(struct rb_gpu_buffer_desc){.size_bytes = size,
                                                             .usage = usage,
                                                             .is_host_visible = true,
                                                             .is_addressed = is_addressed,
                                                             .debug_name = name},
                                out, &err),
             &err);
}

static void make_buffer(struct rb_gpu *gpu, VkDeviceSize size, VkBufferUsageFlags usage,
                        const char *name, struct rb_gpu_buffer *out)
{
    make_buffer_at(gpu, size, usage, false, name, out);
}

static void image_to_general(struct rb_gpu *gpu, struct rb_gpu_image *img)
{
    struct rb_err err = RB_ERR_INIT;
    VkCommandBuffer cmd;
    check_ok(rb_gpu_oneshot_begin(gpu, &cmd, &err), &err);
    rb_gpu_image_barrier(gpu, cmd, img, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
    check_ok(rb_gpu_oneshot_end(gpu, cmd, &err), &err);
}

static void make_image(struct rb_gpu *gpu, uint32_t w, uint32_t h, uint32_t layers, VkFormat format,
                       VkImageUsageFlags usage, bool layer_views, const char *name,
                       struct rb_gpu_image *out)
{
    struct rb_err err = RB_ERR_INIT;
    check_ok(rb_gpu_image_init(gpu,
                               &(struct rb_gpu_image_desc){.width_px = w,
                                                           .height_px = h,
                                                           .layer_count = layers,
                                                           .format = format,
                                                           .usage = usage,
                                                           .is_array = true,
                                                           .has_layer_views = layer_views,
                                                           .debug_name = name},
                               out, &err),
             &err);
    image_to_general(gpu, out);
}

/* Uploads the scene as slot 0's world vertices, indices, and one diffuse material (albedo). */
static void upload(struct gpu_scene *g, const struct scene *s, float albedo)
{
    struct rb_gpu *gpu = g->gpu;
    struct rb_frame *f = &g->frame;
    memset(f, 0, sizeof(*f));
    memset(&g->slot, 0, sizeof(g->slot));
    f->slots = &g->slot;
    f->slot_count = 1;
    uint32_t nv = 4 * (uint32_t)s->count, ni = 6 * (uint32_t)s->count;
    make_buffer_at(gpu, nv * sizeof(struct rb_gpu_vertex), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true,
                   "vertices", &f->slots[0].vertices);
    make_buffer_at(gpu, ni * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT, true, "indices",
                   &f->indices);
    make_buffer(gpu, sizeof(struct rb_gpu_geometry), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "geometry",
                &f->slots[0].geometry);
    memcpy(f->slots[0].geometry.mapped,
           &(struct rb_gpu_geometry){.vertices = f->slots[0].vertices.address,
                                     .indices = f->indices.address},
           sizeof(struct rb_gpu_geometry));
    struct rb_gpu_vertex *v = f->slots[0].vertices.mapped;
    uint32_t *idx = f->indices.mapped;
    uint32_t material = 0;
    float material_bits;
    memcpy(&material_bits, &material, sizeof(material_bits));
    for (int i = 0; i < s->count; i++) {
        const struct quad *q = &s->q[i];
        for (int k = 0; k < 4; k++) {
            double a = k == 1 || k == 2, b = k >= 2;
            struct rb_gpu_vertex *o = &v[4 * i + k];
            memset(o, 0, sizeof(*o));
            for (int c = 0; c < 3; c++) {
                o->position[c] = (float)(q->c[c] + a * q->u[c] + b * q->v[c]);
                o->normal[c] = (float)q->normal[c];
            }
            o->uv[0] = (float)a;
            o->uv[1] = (float)b;
            o->uv[2] = material_bits;
        }
        static const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++)
            idx[6 * i + k] = 4 * (uint32_t)i + tri[k];
    }
    f->index_count = ni;
    f->vertex_count = nv;

    make_buffer(gpu, sizeof(struct rb_gpu_material), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                "materials", &f->materials);
    struct rb_gpu_material *m = f->materials.mapped;
    memset(m, 0, sizeof(*m));
    m->base_color[0] = m->base_color[1] = m->base_color[2] = albedo;
    m->base_color[3] = 1.0f;
    m->params[1] = 1.0f;         /* roughness */
    m->specular_color[3] = 1.0f; /* double-sided */
    for (int k = 0; k < 4; k++)
        m->textures[k] = -1;
    make_image(gpu, 1, 1, 1, VK_FORMAT_R8G8B8A8_SRGB, VK_IMAGE_USAGE_SAMPLED_BIT, false, "srgb",
               &f->srgb_textures);
    make_image(gpu, 1, 1, 1, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT, false, "linear",
               &f->linear_textures);
}

static void release(struct gpu_scene *g)
{
    struct rb_frame *f = &g->frame;
    rb_gpu_image_release(g->gpu, &f->linear_textures);
    rb_gpu_image_release(g->gpu, &f->srgb_textures);
    rb_gpu_buffer_release(g->gpu, &f->materials);
    rb_gpu_buffer_release(g->gpu, &f->indices);
    rb_gpu_buffer_release(g->gpu, &f->slots[0].geometry);
    rb_gpu_buffer_release(g->gpu, &f->slots[0].vertices);
}

static struct rb_gpu *make_gpu(void)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = NULL;
    if (rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err))
        fail_msg("no device: %s", err.msg);
    return gpu;
}

static struct rb_pass_view *make_pass(struct rb_gpu *gpu, enum rb_view_kind kind,
                                      enum rb_view_output output)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_pass_view *p = NULL;
    struct rb_view_variant v = {kind, output};
    check_ok(rb_pass_view_create(
                 gpu, &(struct rb_pass_view_desc){.variants = &v, .variant_count = 1}, &p, &err),
             &err);
    return p;
}

/* Records the copy of every layer of img into buf (tightly packed, layer after layer). */
static void record_copy(VkCommandBuffer cmd, const struct rb_gpu_image *img,
                        const struct rb_gpu_buffer *buf)
{
    rb_gpu_barrier(cmd);
    VkBufferImageCopy r = {
        .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, img->layer_count},
        .imageExtent = {img->width_px, img->height_px, 1},
    };
    vkCmdCopyImageToBuffer(cmd, img->image, VK_IMAGE_LAYOUT_GENERAL, buf->buffer, 1, &r);
    rb_gpu_barrier(cmd);
}

/* Draws one batch and reads the listed images back into host buffers. */
static void run_batch(struct gpu_scene *g, struct rb_pass_view *p, const struct rb_view_batch *b,
                      const struct rb_gpu_image *const *images, const struct rb_gpu_buffer *outs,
                      int image_count)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = g->gpu;
    check_ok(rb_gpu_begin(gpu, &err), &err);
    rb_gpu_pass_begin(gpu, gpu->cmd, "views");
    rb_pass_view_record(p, gpu->cmd, &g->frame, &g->frame.slots[0], b);
    rb_gpu_pass_end(gpu, gpu->cmd);
    for (int i = 0; i < image_count; i++)
        record_copy(gpu->cmd, images[i], &outs[i]);
    check_ok(rb_gpu_submit_wait(gpu, &err), &err);
    assert_int_equal(gpu->validation_messages, 0);
}

/* The eight points at radius r around (0, 0), and the centre. */
static const double ring[9][2] = {{0, 0},
                                  {1, 0},
                                  {-1, 0},
                                  {0, 1},
                                  {0, -1},
                                  {0.7071, 0.7071},
                                  {-0.7071, 0.7071},
                                  {0.7071, -0.7071},
                                  {-0.7071, -0.7071}};

/* ---- orthographic depth -------------------------------------------------------------------- */

struct ortho {
    double origin[3], dir[3], up[3];
};

static void view_basis(const double dir[3], const double up[3], double s[3], double u[3])
{
    cross3(dir, up, s);
    normalize3(s);
    cross3(s, dir, u);
}

/* Normalizes each view's direction and writes the views as the GPU reads them. */
static void set_ortho_views(struct rb_gpu_view *gv, struct ortho *views, int count, double half_w,
                            double half_h, double depth_m)
{
    for (int i = 0; i < count; i++) {
        struct ortho *o = &views[i];
        normalize3(o->dir);
        rb_view_orthographic(&gv[i],
                             rb_v3((float)o->origin[0], (float)o->origin[1], (float)o->origin[2]),
                             rb_v3((float)o->dir[0], (float)o->dir[1], (float)o->dir[2]),
                             rb_v3((float)o->up[0], (float)o->up[1], (float)o->up[2]),
                             (float)half_w, (float)half_h, (float)depth_m);
    }
}

/* The first surface through pixel (x, y) of a w x h orthographic view v (basis sv, uv) of
 * half-extents and depth lim[0..2]: its plane id (-1: none) and distance t; -2 when a point
 * within lim[3] texels of the pixel centre sees another plane (the pixel is on an edge). */
static int ortho_hit(const struct scene *s, const struct ortho *v, const double sv[3],
                     const double uv[3], const double lim[4], int w, int h, int x, int y, double *t)
{
    int plane = -2;
    for (int k = 0; k < 9; k++) {
        /* NDC y grows down the image: view up is -y. */
        double px = x + 0.5 + lim[3] * ring[k][0], py = y + 0.5 + lim[3] * ring[k][1];
        double a = (px / w * 2.0 - 1.0) * lim[0], b = -(py / h * 2.0 - 1.0) * lim[1];
        double o[3], tk;
        for (int c = 0; c < 3; c++)
            o[c] = v->origin[c] + a * sv[c] + b * uv[c];
        int pk = first_hit(s, o, v->dir, lim[2], &tk);
        if (k == 0) {
            plane = pk;
            *t = tk;
        } else if (pk != plane) {
            return -2;
        }
    }
    return plane;
}

static void test_orthographic_depth(void **state)
{
    (void)state;
    enum { W = 96, H = 80, VIEWS = 3 };
    const double half_w = 2.4, half_h = 2.0, depth_m = 10.0, margin_px = 1e-3;
    static struct scene s;
    s.count = 0;
    add_grid(&s, 8, 0.0, true, 0);
    add_box(&s, (double[3]){0.6, -1.0, 0.3}, (double[3]){1.4, -0.2, 0.8}, 1);

    struct ortho views[VIEWS] = {
        {{0.2, 0.1, 5.0}, {0, 0, -1}, {0, 1, 0}},
        {{-1.0, 1.2, 4.0}, {0.3, -0.2, -1}, {0, 1, 0}},
        {{1.5, 0.5, 3.0}, {-0.25, -0.3, -1}, {1, 1, 0}},
    };
    struct gpu_scene g = {.gpu = make_gpu()};
    upload(&g, &s, 0.5f);
    struct rb_gpu_buffer view_buf = {0}, out = {0};
    make_buffer(g.gpu, sizeof(struct rb_gpu_view) * VIEWS, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                "views", &view_buf);
    set_ortho_views(view_buf.mapped, views, VIEWS, half_w, half_h, depth_m);
    struct rb_gpu_image target = {0}, depth = {0};
    make_image(g.gpu, W, H, VIEWS, VK_FORMAT_R32_SFLOAT,
               VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, true,
               "ortho depth", &target);
    make_image(g.gpu, W, H, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
               false, "scratch depth", &depth);
    make_buffer(g.gpu, (VkDeviceSize)W * H * VIEWS * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                "readback", &out);
    struct rb_pass_view *p = make_pass(g.gpu, RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_DEPTH);
    run_batch(&g, p,
              &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                      .output = RB_VIEW_OUTPUT_DEPTH,
                                      .views = &view_buf,
                                      .view_count = VIEWS,
                                      .targets = {&target},
                                      .depth = &depth},
              (const struct rb_gpu_image *[]){&target}, &out, 1);

    const float *got = out.mapped;
    int checked = 0, skipped = 0, bad = 0, box_pixels = 0;
    double worst = 0.0;
    for (int l = 0; l < VIEWS; l++) {
        double sv[3], uv[3];
        view_basis(views[l].dir, views[l].up, sv, uv);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double t = 0.0;
                int plane =
                    ortho_hit(&s, &views[l], sv, uv,
                              (double[4]){half_w, half_h, depth_m, margin_px}, W, H, x, y, &t);
                if (plane == -2) {
                    skipped++;
                    continue;
                }
                checked++;
                box_pixels += plane > 0;
                float v = got[(size_t)l * W * H + (size_t)y * W + x];
                double want = plane < 0 ? FAR_CLEAR : t;
                double e = plane < 0 ? (v == FAR_CLEAR ? 0.0 : 1.0) : fabs(v - want);
                if (e > worst)
                    worst = e;
                if (e > 1e-4 && bad++ < 8)
                    print_message("view %d pixel (%d, %d): %.7g, want %.7g (plane %d)\n", l, x, y,
                                  v, want, plane);
            }
    }
    print_message("orthographic: %d pixels checked, %d on an edge, %d on the box, worst %.3g m\n",
                  checked, skipped, box_pixels, worst);
    assert_int_equal(bad, 0);
    assert_true(checked > 0.97 * W * H * VIEWS);
    assert_true(box_pixels > 300);

    /* The same batch with indirect draws from rb_view_draws_init, the middle view's instance
     * count set to 0 as a shader would: the others draw the same bits, it stays cleared. */
    float *direct = malloc((size_t)W * H * VIEWS * sizeof(float));
    assert_non_null(direct);
    memcpy(direct, got, (size_t)W * H * VIEWS * sizeof(float));
    struct rb_gpu_buffer draws = {0};
    struct rb_err err = RB_ERR_INIT;
    make_buffer(g.gpu, VIEWS * sizeof(VkDrawIndexedIndirectCommand),
                VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, "draws",
                &draws);
    check_ok(rb_view_draws_init(g.gpu, &g.frame, false, VIEWS, &draws, &err), &err);
    VkDrawIndexedIndirectCommand *cmds = draws.mapped;
    assert_int_equal(cmds[2].indexCount, g.frame.index_count);
    assert_int_equal(cmds[2].instanceCount, 1);
    cmds[1].instanceCount = 0;
    run_batch(&g, p,
              &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                      .output = RB_VIEW_OUTPUT_DEPTH,
                                      .views = &view_buf,
                                      .view_count = VIEWS,
                                      .targets = {&target},
                                      .depth = &depth,
                                      .draws = &draws},
              (const struct rb_gpu_image *[]){&target}, &out, 1);
    size_t layer = (size_t)W * H, same = 0, cleared = 0;
    for (size_t i = 0; i < layer * VIEWS; i++) {
        if (i / layer == 1)
            cleared += got[i] == FAR_CLEAR;
        else
            same += memcmp(&got[i], &direct[i], sizeof(float)) == 0;
    }
    assert_int_equal(same, 2 * layer);
    assert_int_equal(cleared, layer);
    free(direct);
    rb_gpu_buffer_release(g.gpu, &draws);

    rb_pass_view_destroy(p);
    rb_gpu_buffer_release(g.gpu, &out);
    rb_gpu_image_release(g.gpu, &depth);
    rb_gpu_image_release(g.gpu, &target);
    rb_gpu_buffer_release(g.gpu, &view_buf);
    release(&g);
    rb_gpu_destroy(g.gpu);
}

/* ---- the simplified mesh ------------------------------------------------------------------- */

/* Simplifies the uploaded scene to target triangles with rb_scene_simplify, as the frame does
 * for the bdpt integrator's small views, into frame->view_indices. */
static void upload_simplified(struct gpu_scene *g, uint32_t target)
{
    struct rb_frame *f = &g->frame;
    const struct rb_gpu_vertex *v = f->slots[0].vertices.mapped;
    struct rb_err err = RB_ERR_INIT;
    struct rb_scene_simplified r;
    make_buffer(g->gpu, f->index_count * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                "indices.view", &f->view_indices);
    check_ok(rb_scene_simplify(&(struct rb_scene_simplify_mesh){.positions = v->position,
                                                                .normals = v->normal,
                                                                .stride_bytes = sizeof(*v),
                                                                .vertex_count = f->vertex_count,
                                                                .indices = f->indices.mapped,
                                                                .index_count = f->index_count},
                               target, f->view_indices.mapped, &r, &err),
             &err);
    f->view_index_count = r.index_count;
}

/* A plane of 16 x 16 tiles (512 triangles, a seam at every tile edge) simplifies without error,
 * so three oblique orthographic depth views of the simplified mesh, drawn with the batch's
 * use_simplified, match the full mesh's depths at every pixel off the plane's outline; and
 * use_simplified does choose view_indices: one tile's worth of them covers one tile. */
static void test_simplified_depth(void **state)
{
    (void)state;
    enum { W = 96, H = 80, VIEWS = 3, TARGET = 8 };
    const double lim[4] = {10.0, 9.0, 30.0, 1e-3}; /* half width, half height, depth, margin */
    static struct scene s;
    s.count = 0;
    add_grid(&s, 16, 0.25, true, 0);
    struct ortho views[VIEWS] = {
        {{0.5, -0.3, 12.0}, {0, 0, -1}, {0, 1, 0}},
        {{-3.0, 4.0, 10.0}, {0.3, -0.4, -1}, {0, 1, 0}},
        {{2.0, 1.0, 8.0}, {-0.2, -0.1, -1}, {1, 1, 0}},
    };
    struct gpu_scene g = {.gpu = make_gpu()};
    upload(&g, &s, 0.5f);
    upload_simplified(&g, TARGET);
    print_message("simplified: %u of %u triangles\n", g.frame.view_index_count / 3,
                  g.frame.index_count / 3);
    assert_true(g.frame.view_index_count > 0 && g.frame.view_index_count / 3 <= TARGET);

    struct rb_gpu_buffer view_buf = {0}, out[3] = {0};
    make_buffer(g.gpu, sizeof(struct rb_gpu_view) * VIEWS, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                "views", &view_buf);
    set_ortho_views(view_buf.mapped, views, VIEWS, lim[0], lim[1], lim[2]);
    struct rb_gpu_image target = {0}, depth = {0};
    make_image(g.gpu, W, H, VIEWS, VK_FORMAT_R32_SFLOAT,
               VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, true,
               "ortho depth", &target);
    make_image(g.gpu, W, H, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
               false, "scratch depth", &depth);
    struct rb_pass_view *p = make_pass(g.gpu, RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_DEPTH);
    /* out[0]: the full mesh; out[1]: the simplified one; out[2]: view_indices cut to a tile */
    for (int i = 0; i < 3; i++) {
        make_buffer(g.gpu, (VkDeviceSize)W * H * VIEWS * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    "readback", &out[i]);
        if (i == 2) { /* the full mesh's first tile */
            memcpy(g.frame.view_indices.mapped, g.frame.indices.mapped, 6 * sizeof(uint32_t));
            g.frame.view_index_count = 6;
        }
        run_batch(&g, p,
                  &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                          .output = RB_VIEW_OUTPUT_DEPTH,
                                          .views = &view_buf,
                                          .view_count = VIEWS,
                                          .targets = {&target},
                                          .depth = &depth,
                                          .use_simplified = i > 0},
                  (const struct rb_gpu_image *[]){&target}, &out[i], 1);
    }

    const float *full = out[0].mapped, *simple = out[1].mapped, *tile = out[2].mapped;
    int checked = 0, skipped = 0, bad = 0, covered = 0, tile_covered = 0;
    double worst = 0.0;
    for (int l = 0; l < VIEWS; l++) {
        double sv[3], uv[3];
        view_basis(views[l].dir, views[l].up, sv, uv);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                size_t i = (size_t)l * W * H + (size_t)y * W + x;
                tile_covered += tile[i] != FAR_CLEAR;
                double t;
                if (ortho_hit(&s, &views[l], sv, uv, lim, W, H, x, y, &t) == -2) {
                    skipped++;
                    continue;
                }
                checked++;
                covered += full[i] != FAR_CLEAR;
                double e = full[i] == FAR_CLEAR || simple[i] == FAR_CLEAR
                               ? (full[i] == simple[i] ? 0.0 : 1.0)
                               : fabs((double)simple[i] - full[i]);
                worst = e > worst ? e : worst;
                if (e > 1e-4 && bad++ < 8)
                    print_message("view %d pixel (%d, %d): %.7g, full mesh %.7g\n", l, x, y,
                                  (double)simple[i], (double)full[i]);
            }
    }
    print_message("simplified: %d pixels checked, %d on the outline, %d covered, worst %.3g m; "
                  "one tile covers %d\n",
                  checked, skipped, covered, worst, tile_covered);
    assert_int_equal(bad, 0);
    assert_true(covered > W * H && covered < checked);
    /* a 1 m tile of a 16 m plane: about 1/256 of the plane's pixels, and some */
    assert_true(tile_covered > 0 && tile_covered < covered / 64);

    rb_pass_view_destroy(p);
    for (int i = 0; i < 3; i++)
        rb_gpu_buffer_release(g.gpu, &out[i]);
    rb_gpu_image_release(g.gpu, &depth);
    rb_gpu_image_release(g.gpu, &target);
    rb_gpu_buffer_release(g.gpu, &view_buf);
    rb_gpu_buffer_release(g.gpu, &g.frame.view_indices);
    release(&g);
    rb_gpu_destroy(g.gpu);
}

/* ---- paraboloid depth ---------------------------------------------------------------------- */

struct para {
    double eye[3], axis[3], right[3];
};

/* The direction of NDC point q in the paraboloid view's frame, as rb_view_paraboloid documents:
 * d lands at (d.x, d.y) / (1 + d.z), so d = (2q, 1 - |q|^2) / (1 + |q|^2). */
static void para_dir(const struct para *v, double qx, double qy, double out[3])
{
    double r2 = qx * qx + qy * qy;
    double l[3] = {2 * qx / (1 + r2), 2 * qy / (1 + r2), (1 - r2) / (1 + r2)};
    double y[3];
    cross3(v->axis, v->right, y);
    for (int c = 0; c < 3; c++)
        out[c] = l[0] * v->right[c] + l[1] * y[c] + l[2] * v->axis[c];
}

/* The level view.tesc would need for edge a-b so that its pieces stay within C texels:
 * ceil(L size / (2 d_min C)) with d_min the eye's distance to the edge. */
static double needed_level(const double eye[3], const double a[3], const double b[3], int size)
{
    double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ao[3] = {a[0] - eye[0], a[1] - eye[1], a[2] - eye[2]};
    double s = fmin(fmax(-dot3(ao, e) / dot3(e, e), 0.0), 1.0);
    double p[3] = {ao[0] + s * e[0], ao[1] + s * e[1], ao[2] + s * e[2]};
    return ceil(sqrt(dot3(e, e)) * size / (2.0 * sqrt(dot3(p, p)) * RB_VIEW_TESS_CHORD_PX));
}

static void test_paraboloid_depth(void **state)
{
    (void)state;
    enum { SIZE = 256, VIEWS = 2 };
    const double far_m = 10.0;
    /* The edge bound, C^2 / (2 size) texels, and a little for rounding. */
    const double bound_px = RB_VIEW_TESS_CHORD_PX * RB_VIEW_TESS_CHORD_PX / (2.0 * SIZE);
    const double margin_px = bound_px + 2e-3;
    static struct scene s;
    s.count = 0;
    add_grid(&s, 8, 0.0, true, 0);  /* floor */
    add_grid(&s, 8, 3.0, false, 1); /* ceiling */
    add_box(&s, (double[3]){0.6, -1.0, 0.3}, (double[3]){1.4, -0.2, 0.8}, 2);
    /* A VPL's pair of hemispheres, down to the floor and up to the ceiling. */
    struct para views[VIEWS] = {
        {{0.3, -0.2, 1.2}, {0, 0, -1}, {1, 0, 0}},
        {{0.3, -0.2, 1.2}, {0, 0, 1}, {0, 1, 0}},
    };

    /* The bound holds while no edge in front of a view needs more than the level cap. */
    double worst_level = 0.0;
    for (int l = 0; l < VIEWS; l++)
        for (int i = 0; i < s.count; i++) {
            const struct quad *q = &s.q[i];
            double p[4][3];
            bool in_front = false;
            for (int k = 0; k < 4; k++) {
                double a = k == 1 || k == 2, b = k >= 2;
                for (int c = 0; c < 3; c++)
                    p[k][c] = q->c[c] + a * q->u[c] + b * q->v[c];
                double rel[3] = {p[k][0] - views[l].eye[0], p[k][1] - views[l].eye[1],
                                 p[k][2] - views[l].eye[2]};
                in_front |= dot3(rel, views[l].axis) >= 0.0;
            }
            if (!in_front)
                continue;
            static const int edges[5][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}};
            for (int e = 0; e < 5; e++)
                worst_level = fmax(
                    worst_level, needed_level(views[l].eye, p[edges[e][0]], p[edges[e][1]], SIZE));
        }
    print_message("paraboloid: edge bound %.4f texels; highest level needed %g (cap %g)\n",
                  bound_px, worst_level, RB_VIEW_TESS_MAX_LEVEL);
    assert_true(worst_level <= RB_VIEW_TESS_MAX_LEVEL);

    struct gpu_scene g = {.gpu = make_gpu()};
    upload(&g, &s, 0.5f);
    struct rb_gpu_buffer view_buf = {0}, out = {0};
    make_buffer(g.gpu, sizeof(struct rb_gpu_view) * VIEWS, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                "views", &view_buf);
    struct rb_gpu_view *gv = view_buf.mapped;
    for (int i = 0; i < VIEWS; i++) {
        const struct para *v = &views[i];
        rb_view_paraboloid(&gv[i], rb_v3((float)v->eye[0], (float)v->eye[1], (float)v->eye[2]),
                           rb_v3((float)v->axis[0], (float)v->axis[1], (float)v->axis[2]),
                           rb_v3((float)v->right[0], (float)v->right[1], (float)v->right[2]),
                           (float)far_m);
    }
    struct rb_gpu_image target = {0}, depth = {0};
    make_image(g.gpu, SIZE, SIZE, VIEWS, VK_FORMAT_R32_SFLOAT,
               VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, true,
               "paraboloid depth", &target);
    make_image(g.gpu, SIZE, SIZE, 1, VK_FORMAT_D32_SFLOAT,
               VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "scratch depth", &depth);
    make_buffer(g.gpu, (VkDeviceSize)SIZE * SIZE * VIEWS * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                "readback", &out);
    struct rb_pass_view *p = make_pass(g.gpu, RB_VIEW_KIND_PARABOLOID, RB_VIEW_OUTPUT_DEPTH);
    run_batch(&g, p,
              &(struct rb_view_batch){.kind = RB_VIEW_KIND_PARABOLOID,
                                      .output = RB_VIEW_OUTPUT_DEPTH,
                                      .views = &view_buf,
                                      .view_count = VIEWS,
                                      .targets = {&target},
                                      .depth = &depth},
              (const struct rb_gpu_image *[]){&target}, &out, 1);

    const float *got = out.mapped;
    int checked = 0, skipped = 0, bad = 0, box_pixels = 0, disk = 0;
    double worst = 0.0;
    for (int l = 0; l < VIEWS; l++)
        for (int y = 0; y < SIZE; y++)
            for (int x = 0; x < SIZE; x++) {
                float v = got[(size_t)l * SIZE * SIZE + (size_t)y * SIZE + x];
                double qx = (x + 0.5) / SIZE * 2.0 - 1.0, qy = (y + 0.5) / SIZE * 2.0 - 1.0;
                if (qx * qx + qy * qy > 1.0) { /* off the map: never drawn */
                    checked++;
                    if (v != FAR_CLEAR && bad++ < 8)
                        print_message("view %d pixel (%d, %d) off the disk: %g\n", l, x, y, v);
                    continue;
                }
                disk++;
                int plane = -2;
                double t = 0.0;
                bool robust = true;
                for (int k = 0; k < 9 && robust; k++) {
                    double d[3];
                    para_dir(&views[l], qx + margin_px * ring[k][0] * 2.0 / SIZE,
                             qy + margin_px * ring[k][1] * 2.0 / SIZE, d);
                    double tk;
                    int pk = first_hit(&s, views[l].eye, d, far_m, &tk);
                    if (k == 0) {
                        plane = pk;
                        t = tk;
                    } else if (pk != plane) {
                        robust = false;
                    }
                }
                if (!robust) {
                    skipped++;
                    continue;
                }
                checked++;
                box_pixels += plane >= 2;
                double e;
                if (plane < 0)
                    e = v == FAR_CLEAR ? 0.0 : 1.0;
                else
                    e = fabs(v - t) / t;
                if (e > worst)
                    worst = e;
                if (e > 1e-5 && bad++ < 8)
                    print_message("view %d pixel (%d, %d): %.7g, want %.7g (plane %d)\n", l, x, y,
                                  v, plane < 0 ? FAR_CLEAR : t, plane);
            }
    print_message("paraboloid: %d texels checked, %d within %.4f texels of an edge, %d on the "
                  "box, worst relative error %.3g\n",
                  checked, skipped, margin_px, box_pixels, worst);
    assert_int_equal(bad, 0);
    /* Most of the disk is checked: the texels within the edge bound of an edge of the grids'
     * cells are 5.6% of it at 2 texels (C = 32), 1.5% at half a texel. */
    assert_true(skipped < disk / 10);
    assert_true(box_pixels > 500);

    rb_pass_view_destroy(p);
    rb_gpu_buffer_release(g.gpu, &out);
    rb_gpu_image_release(g.gpu, &depth);
    rb_gpu_image_release(g.gpu, &target);
    rb_gpu_buffer_release(g.gpu, &view_buf);
    release(&g);
    rb_gpu_destroy(g.gpu);
}

/* ---- reflective shadow map ----------------------------------------------------------------- */

static void test_rsm(void **state)
{
    (void)state;
    enum { SIZE = 64 };
    const float albedo = 0.5f, intensity = 3.0f, irradiance = 2.0f;
    const double height = 2.0, half = 1.5;
    static struct scene s;
    s.count = 0;
    add_grid(&s, 16, 0.0, true, 0); /* wider than either view sees */

    struct gpu_scene g = {.gpu = make_gpu()};
    upload(&g, &s, albedo);
    struct rb_gpu_buffer view_buf = {0};
    make_buffer(g.gpu, sizeof(struct rb_gpu_view) * 2, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "views",
                &view_buf);
    struct rb_gpu_view *gv = view_buf.mapped;
    /* A point light's cube face straight down, and a sun's orthographic beam. */
    rb_view_perspective(&gv[0], rb_v3(0.2f, 0.1f, (float)height), rb_v3(0, 0, -1), rb_v3(0, 1, 0),
                        (float)(PI / 2), 1.0f, 0.01f, 10.0f);
    rb_view_orthographic(&gv[1], rb_v3(-0.3f, 0.4f, (float)height), rb_v3(0, 0, -1), rb_v3(0, 1, 0),
                         (float)half, (float)half, 10.0f);
    struct rb_gpu_image targets[RB_VIEW_RSM_TARGETS] = {{0}}, depth = {0};
    struct rb_gpu_buffer outs[RB_VIEW_RSM_TARGETS] = {{0}};
    for (int i = 0; i < RB_VIEW_RSM_TARGETS; i++) {
        make_image(g.gpu, SIZE, SIZE, 2, rb_view_rsm_formats[i],
                   VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, true,
                   "rsm", &targets[i]);
        make_buffer(g.gpu, (VkDeviceSize)SIZE * SIZE * 2 * 16, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    "readback", &outs[i]);
    }
    make_image(g.gpu, SIZE, SIZE, 1, VK_FORMAT_D32_SFLOAT,
               VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "scratch depth", &depth);
    struct rb_err err = RB_ERR_INIT;
    struct rb_pass_view *p = NULL;
    static const struct rb_view_variant variants[] = {
        {RB_VIEW_KIND_PERSPECTIVE, RB_VIEW_OUTPUT_RSM},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_RSM},
    };
    check_ok(
        rb_pass_view_create(
            g.gpu, &(struct rb_pass_view_desc){.variants = variants, .variant_count = 2}, &p, &err),
        &err);
    check_ok(rb_gpu_begin(g.gpu, &err), &err);
    for (int v = 0; v < 2; v++) {
        float e = v == 0 ? intensity : irradiance;
        rb_pass_view_record(
            p, g.gpu->cmd, &g.frame, &g.frame.slots[0],
            &(struct rb_view_batch){
                .kind = v == 0 ? RB_VIEW_KIND_PERSPECTIVE : RB_VIEW_KIND_ORTHOGRAPHIC,
                .output = RB_VIEW_OUTPUT_RSM,
                .views = &view_buf,
                .first_view = (uint32_t)v,
                .first_layer = (uint32_t)v,
                .view_count = 1,
                .targets = {&targets[0], &targets[1], &targets[2], &targets[3]},
                .depth = &depth,
                .intensity = {e, e, e},
            });
    }
    for (int i = 0; i < RB_VIEW_RSM_TARGETS; i++)
        record_copy(g.gpu->cmd, &targets[i], &outs[i]);
    check_ok(rb_gpu_submit_wait(g.gpu, &err), &err);
    assert_int_equal(g.gpu->validation_messages, 0);

    /* Every texel sees the floor (z = 0) facing up, through its centre at NDC (x, y): from the
     * light at (0.2, 0.1, h) along (x, -y, -1) (a 90-degree face), from the sun's near plane at
     * (-0.3 + 1.5 x, 0.4 - 1.5 y, h) straight down. Its flux is I albedo times its solid angle,
     * (2 / size)^2 / (1 + x^2 + y^2)^1.5, or E albedo times its area, (3 / size)^2; over the
     * whole map they add up to I albedo times 4 asin(sin 45 deg sin 45 deg) = 2 pi / 3 (within
     * the midpoint rule's error, 1e-4 at 64^2), and to E albedo times the beam's area. */
    const float *pos = outs[0].mapped, *nrm = outs[1].mapped, *flux = outs[2].mapped;
    const uint32_t *mat = outs[3].mapped; /* RG32UI: albedo and gloss words */
    uint32_t want_albedo = (uint32_t)lround(albedo * 255.0) * 0x010101u;
    double want_total[2] = {intensity * albedo * 2.0 * PI / 3.0,
                            irradiance * albedo * 4.0 * half * half};
    int bad = 0;
    double worst = 0.0;
    for (int v = 0; v < 2; v++) {
        double total = 0.0;
        for (int y = 0; y < SIZE; y++)
            for (int x = 0; x < SIZE; x++) {
                size_t k = (((size_t)v * SIZE + (size_t)y) * SIZE + (size_t)x) * 4;
                double nx = (x + 0.5) / SIZE * 2.0 - 1.0, ny = (y + 0.5) / SIZE * 2.0 - 1.0;
                double want_pos[3], want_flux, want_depth;
                if (v == 0) {
                    want_pos[0] = 0.2 + height * nx;
                    want_pos[1] = 0.1 - height * ny;
                    want_flux = intensity * albedo * (2.0 / SIZE) * (2.0 / SIZE) /
                                pow(1.0 + nx * nx + ny * ny, 1.5);
                    want_depth = height * sqrt(1.0 + nx * nx + ny * ny);
                } else {
                    want_pos[0] = -0.3 + half * nx;
                    want_pos[1] = 0.4 - half * ny;
                    want_flux = irradiance * albedo * (2.0 * half / SIZE) * (2.0 * half / SIZE);
                    want_depth = height;
                }
                want_pos[2] = 0.0;
                double e = fabs(flux[k] - want_flux) / want_flux;
                worst = fmax(worst, e);
                bool ok = pos[k + 3] == 1.0f && nrm[k + 2] > 0.99999f && nrm[k + 3] == 1.0f &&
                          flux[k] == flux[k + 1] && flux[k] == flux[k + 2] && e < 1e-5 &&
                          fabs(flux[k + 3] - want_depth) < 1e-5;
                /* The material as a bundle node holds it: diffuse RGB bytes (the specular byte
                 * and roughness depend on the default material's F0), no emission. */
                size_t km = (((size_t)v * SIZE + (size_t)y) * SIZE + (size_t)x) * 2;
                ok = ok && (mat[km] & 0xffffffu) == want_albedo && (mat[km + 1] >> 8) == 0;
                for (int c = 0; c < 3; c++)
                    ok = ok && fabs(pos[k + c] - want_pos[c]) < 1e-5;
                if (!ok && bad++ < 8)
                    print_message("rsm view %d texel (%d, %d): position %g %g %g %g normal %g %g "
                                  "%g %g flux %g depth %g; want %g %g 0, flux %g, depth %g\n",
                                  v, x, y, pos[k], pos[k + 1], pos[k + 2], pos[k + 3], nrm[k],
                                  nrm[k + 1], nrm[k + 2], nrm[k + 3], flux[k], flux[k + 3],
                                  want_pos[0], want_pos[1], want_flux, want_depth);
                total += flux[k];
            }
        double rel = fabs(total - want_total[v]) / want_total[v];
        print_message("rsm view %d: flux %.7g W, closed form %.7g W (relative %.2g)\n", v, total,
                      want_total[v], rel);
        assert_true(rel < 1e-4);
    }
    print_message("rsm: worst relative error of a texel's flux %.3g\n", worst);
    assert_int_equal(bad, 0);

    rb_pass_view_destroy(p);
    rb_gpu_image_release(g.gpu, &depth);
    for (int i = 0; i < RB_VIEW_RSM_TARGETS; i++) {
        rb_gpu_buffer_release(g.gpu, &outs[i]);
        rb_gpu_image_release(g.gpu, &targets[i]);
    }
    rb_gpu_buffer_release(g.gpu, &view_buf);
    release(&g);
    rb_gpu_destroy(g.gpu);
}

/* ---- linked lists -------------------------------------------------------------------------- */

enum { LW = 64, LH = 48, LVIEWS = 2 };

/* Two planes facing each other: A at z = 2 facing down, B at z = 1 facing up, with slanted
 * vertex normals; their edges fall on texel edges (multiples of 1/32 m), never on a centre. */
static void list_scene(struct scene *s)
{
    s->count = 0;
    double na[3] = {-0.1, 0.4, -1.0}, nb[3] = {0.3, -0.2, 1.0};
    normalize3(na);
    normalize3(nb);
    add_quad(s, (double[3]){-0.5, -0.625, 2.0}, (double[3]){0, 1.125, 0}, (double[3]){1.25, 0, 0},
             na, 0);
    add_quad(s, (double[3]){-0.75, -0.25, 1.0}, (double[3]){1.25, 0, 0}, (double[3]){0, 0.96875, 0},
             nb, 1);
}

static const struct ortho list_views[LVIEWS] = {
    {{0, 0, 5.0}, {0, 0, -1}, {0, 1, 0}}, /* from above: A is a back face, B a front face */
    {{0, 0, -2.0}, {0, 0, 1}, {0, 1, 0}}, /* from below: B is a back face, A a front face */
};

struct list_run {
    struct rb_gpu_buffer heads, nodes; /* host copies */
    struct rb_gpu_list_counter usage;
};

/* Draws both views into list l (its pool lowered to capacity nodes when non-zero) and reads it
 * back; the node buffer starts as 0xAB bytes, so untouched nodes show. */
static void run_list(struct gpu_scene *g, struct rb_pass_view *p, struct rb_view_list *l,
                     const struct rb_gpu_buffer *views, struct list_run *out)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = g->gpu;
    make_buffer(gpu, (VkDeviceSize)LW * LH * LVIEWS * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, "heads",
                &out->heads);
    make_buffer(gpu, l->nodes.size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, "nodes", &out->nodes);
    check_ok(rb_gpu_begin(gpu, &err), &err);
    vkCmdFillBuffer(gpu->cmd, l->nodes.buffer, 0, VK_WHOLE_SIZE, 0xABABABABu);
    rb_gpu_barrier(gpu->cmd);
    rb_pass_view_record(p, gpu->cmd, &g->frame, &g->frame.slots[0],
                        &(struct rb_view_batch){.kind = RB_VIEW_KIND_ORTHOGRAPHIC,
                                                .output = RB_VIEW_OUTPUT_LIST,
                                                .views = views,
                                                .view_count = LVIEWS,
                                                .list = l});
    record_copy(gpu->cmd, &l->heads, &out->heads);
    vkCmdCopyBuffer(gpu->cmd, l->nodes.buffer, out->nodes.buffer, 1,
                    &(VkBufferCopy){0, 0, l->nodes.size});
    rb_gpu_barrier(gpu->cmd);
    check_ok(rb_gpu_submit_wait(gpu, &err), &err);
    assert_int_equal(gpu->validation_messages, 0);
    out->usage = rb_view_list_usage(l);
}

static void decode_polar(uint32_t bits, double n[3])
{
    double theta = (bits & 0xffffu) / 65535.0 * PI;
    double phi = ((bits >> 16) / 65535.0 - 0.5) * 2.0 * PI;
    n[0] = sin(theta) * cos(phi);
    n[1] = sin(theta) * sin(phi);
    n[2] = cos(theta);
}

struct expected {
    double depth; /* signed: + front, - back */
    double normal[3];
};

/* The fragments the oracle expects at a pixel of a list view, nearest first. */
static int expected_fragments(const struct scene *s, int view, int x, int y, struct expected *e)
{
    const struct ortho *v = &list_views[view];
    double sv[3], uv[3];
    view_basis(v->dir, v->up, sv, uv);
    double a = ((x + 0.5) / LW * 2.0 - 1.0) * 1.0, b = -((y + 0.5) / LH * 2.0 - 1.0) * 0.75;
    double o[3];
    for (int c = 0; c < 3; c++)
        o[c] = v->origin[c] + a * sv[c] + b * uv[c];
    int n = 0;
    for (int i = 0; i < s->count; i++) {
        double t;
        if (!hit_quad(&s->q[i], o, v->dir, &t))
            continue;
        double ng[3];
        cross3(s->q[i].u, s->q[i].v, ng);
        e[n].depth = dot3(ng, v->dir) < 0.0 ? t : -t;
        memcpy(e[n].normal, s->q[i].normal, sizeof(e[n].normal));
        n++;
    }
    if (n == 2 && fabs(e[1].depth) < fabs(e[0].depth)) {
        struct expected tmp = e[0];
        e[0] = e[1];
        e[1] = tmp;
    }
    return n;
}

static void test_linked_list(void **state)
{
    (void)state;
    static struct scene s;
    list_scene(&s);
    struct gpu_scene g = {.gpu = make_gpu()};
    upload(&g, &s, 0.5f);
    struct rb_gpu_buffer view_buf = {0};
    make_buffer(g.gpu, sizeof(struct rb_gpu_view) * LVIEWS, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                "views", &view_buf);
    struct rb_gpu_view *gv = view_buf.mapped;
    for (int i = 0; i < LVIEWS; i++) {
        const struct ortho *o = &list_views[i];
        rb_view_orthographic(
            &gv[i], rb_v3((float)o->origin[0], (float)o->origin[1], (float)o->origin[2]),
            rb_v3((float)o->dir[0], (float)o->dir[1], (float)o->dir[2]),
            rb_v3((float)o->up[0], (float)o->up[1], (float)o->up[2]), 1.0f, 0.75f, 10.0f);
    }
    /* The expected fragments: their number sizes the pools. */
    uint32_t total = 0;
    int twice = 0;
    struct expected e[2];
    for (int v = 0; v < LVIEWS; v++)
        for (int y = 0; y < LH; y++)
            for (int x = 0; x < LW; x++) {
                int n = expected_fragments(&s, v, x, y, e);
                total += (uint32_t)n;
                twice += n == 2;
            }
    assert_true(twice > 500);

    struct rb_err err = RB_ERR_INIT;
    struct rb_pass_view *p = make_pass(g.gpu, RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_LIST);
    for (int pass = 0; pass < 2; pass++) {
        /* First a pool with room to spare, then one that holds a third of the fragments, with
         * guard nodes past its capacity. */
        bool tiny = pass == 1;
        uint32_t capacity = tiny ? total / 3 : total + 100, guard = 64;
        struct rb_view_list list = {0};
        check_ok(rb_view_list_init(g.gpu,
                                   &(struct rb_view_list_desc){.width_px = LW,
                                                               .height_px = LH,
                                                               .layer_count = LVIEWS,
                                                               .capacity_nodes = capacity + guard,
                                                               .debug_name = "bundle"},
                                   &list, &err),
                 &err);
        list.capacity_nodes = capacity; /* the guard nodes are past what the pass may write */
        struct list_run run = {0};
        run_list(&g, p, &list, &view_buf, &run);
        print_message("list (%s pool): %u fragments, %u requested, %u dropped, capacity %u\n",
                      tiny ? "tiny" : "ample", total, run.usage.requested, run.usage.dropped,
                      capacity);
        assert_int_equal(run.usage.requested, total);
        assert_int_equal(run.usage.dropped, tiny ? total - capacity : 0);

        const uint32_t *heads = run.heads.mapped;
        const struct rb_gpu_list_node *nodes = run.nodes.mapped;
        uint8_t *seen = calloc(capacity + guard, 1);
        assert_non_null(seen);
        uint32_t listed = 0;
        int bad = 0;
        for (int v = 0; v < LVIEWS; v++)
            for (int y = 0; y < LH; y++)
                for (int x = 0; x < LW; x++) {
                    int want = expected_fragments(&s, v, x, y, e);
                    struct rb_gpu_list_node got[4];
                    int n = 0;
                    uint32_t i = heads[((size_t)v * LH + (size_t)y) * LW + (size_t)x];
                    while (i != RB_NONE && n < 4) {
                        if (i >= capacity || seen[i]) {
                            if (bad++ < 8)
                                print_message("view %d pixel (%d, %d): node %u %s\n", v, x, y, i,
                                              i >= capacity ? "past the capacity" : "on two lists");
                            break;
                        }
                        seen[i] = 1;
                        got[n++] = nodes[i];
                        i = nodes[i].next;
                    }
                    listed += (uint32_t)n;
                    if (tiny) {
                        /* Which fragments found room is a race; what is there must be right. */
                        if (n > want && bad++ < 8)
                            print_message("view %d pixel (%d, %d): %d nodes for %d fragments\n", v,
                                          x, y, n, want);
                        continue;
                    }
                    if (n != want) {
                        if (bad++ < 8)
                            print_message("view %d pixel (%d, %d): %d nodes, want %d\n", v, x, y, n,
                                          want);
                        continue;
                    }
                    if (n == 2 && fabsf(got[1].depth) < fabsf(got[0].depth)) {
                        struct rb_gpu_list_node t = got[0];
                        got[0] = got[1];
                        got[1] = t;
                    }
                    for (int k = 0; k < n; k++) {
                        double nn[3];
                        decode_polar(got[k].normal, nn);
                        double dn = sqrt((nn[0] - e[k].normal[0]) * (nn[0] - e[k].normal[0]) +
                                         (nn[1] - e[k].normal[1]) * (nn[1] - e[k].normal[1]) +
                                         (nn[2] - e[k].normal[2]) * (nn[2] - e[k].normal[2]));
                        if ((fabs(got[k].depth - e[k].depth) > 1e-5 || dn > 1e-4) && bad++ < 8)
                            print_message("view %d pixel (%d, %d) node %d: depth %.7g normal "
                                          "%.5f %.5f %.5f, want %.7g and %.5f %.5f %.5f\n",
                                          v, x, y, k, got[k].depth, nn[0], nn[1], nn[2], e[k].depth,
                                          e[k].normal[0], e[k].normal[1], e[k].normal[2]);
                    }
                }
        assert_int_equal(bad, 0);
        /* Every node within the capacity is on exactly one list; none past it was written. */
        assert_int_equal(listed, tiny ? capacity : total);
        const uint32_t *raw = run.nodes.mapped;
        uint32_t first_guard = capacity * (uint32_t)(sizeof(struct rb_gpu_list_node) / 4);
        uint32_t words = (capacity + guard) * (uint32_t)(sizeof(struct rb_gpu_list_node) / 4);
        for (uint32_t w = first_guard; w < words; w++)
            if (raw[w] != 0xABABABABu && bad++ < 8)
                print_message("guard word %u written: 0x%08x\n", w, raw[w]);
        assert_int_equal(bad, 0);

        enum rb_status st = rb_view_list_check(&list, "bundle nodes", &err);
        if (tiny) {
            char want[128];
            snprintf(want, sizeof(want), "%u of %u fragments dropped", total - capacity, total);
            print_message("%s\n", err.msg);
            assert_int_equal(st, RB_E_NOMEM);
            assert_non_null(strstr(err.msg, want));
            assert_non_null(strstr(err.msg, "'bundle nodes'"));
        } else {
            assert_int_equal(st, RB_OK);
        }
        free(seen);
        rb_gpu_buffer_release(g.gpu, &run.nodes);
        rb_gpu_buffer_release(g.gpu, &run.heads);
        rb_view_list_release(g.gpu, &list);
    }
    rb_pass_view_destroy(p);
    rb_gpu_buffer_release(g.gpu, &view_buf);
    release(&g);
    rb_gpu_destroy(g.gpu);
}

/* A paraboloid view draws depth only so far: asking for more fails at create, with the reason. */
static void test_unsupported_variant(void **state)
{
    (void)state;
    struct rb_gpu *gpu = make_gpu();
    struct rb_err err = RB_ERR_INIT;
    struct rb_pass_view *p = NULL;
    struct rb_view_variant v = {RB_VIEW_KIND_PARABOLOID, RB_VIEW_OUTPUT_LIST};
    assert_int_equal(
        rb_pass_view_create(
            gpu,
            &(struct rb_pass_view_desc){.variants = &v, .variant_count = 1, .debug_name = "vpl"},
            &p, &err),
        RB_E_UNSUPPORTED);
    assert_null(p);
    assert_string_equal(err.msg, "raster view 'vpl': paraboloid views have no 'list' output");
    rb_gpu_destroy(gpu);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orthographic_depth), cmocka_unit_test(test_simplified_depth),
        cmocka_unit_test(test_paraboloid_depth),   cmocka_unit_test(test_rsm),
        cmocka_unit_test(test_linked_list),        cmocka_unit_test(test_unsupported_variant),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
