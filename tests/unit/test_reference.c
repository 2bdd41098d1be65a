/* Unit tests for lib/reference, the CPU ground truth, on scenes built in memory: its random
 * numbers; the BRDF (energy, reciprocity); furnaces (a white Lambertian sphere, GGX metal
 * spheres down to a mirror, a closed emissive box for emitter sampling, MIS and Russian
 * roulette); the environment map (lookup, importance sampling); the direct path space against
 * closed forms (point light with a range, spot and directional lights, shadows, single-sided
 * culling for camera rays only, alpha masks, textures, normal maps, KHR_materials_specular,
 * back faces); area lights against Lambert's polygon formula (a ceiling beside its light
 * panel); skins, morph targets and motion vectors; the box pixel filter; the path spaces
 * against each other, BDPT's emitters against a point light and in the Cornell box; determinism
 * across thread counts and runs; convergence (1/sqrt(spp) with hashed numbers, faster with the
 * Sobol sampler); passes and callbacks. */
#include "reference/reference.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "shared.h"
#include "testutil.h"

#define NONE RB_SCENE_NONE
#define PI_D 3.14159265358979323846

/* ---- scenes in memory ----------------------------------------------------------------------- */

static void *grow(void *p, size_t count, size_t size)
{
    void *q = realloc(p, (count ? count : 1) * size);
    assert_non_null(q);
    return q;
}

static struct rb_scene *scene_new(void)
{
    struct rb_scene *s = calloc(1, sizeof(*s));
    assert_non_null(s);
    return s;
}

/* A metallic-roughness material without textures or the specular extension. */
static struct rb_scene_material material(float r, float g, float b, float metallic, float roughness)
{
    return (struct rb_scene_material){
        .base_color = {r, g, b, 1.0f},
        .base_color_tex = NONE,
        .metallic = metallic,
        .roughness = roughness,
        .metallic_roughness_tex = NONE,
        .normal_tex = NONE,
        .normal_scale = 1.0f,
        .emissive_tex = NONE,
        .specular_factor = 1.0f,
        .specular_color = {1.0f, 1.0f, 1.0f},
    };
}

static uint32_t add_material(struct rb_scene *s, struct rb_scene_material m)
{
    s->materials = grow(s->materials, s->material_count + 1, sizeof(m));
    s->materials[s->material_count] = m;
    return s->material_count++;
}

static uint32_t add_texture(struct rb_scene *s, uint32_t w, uint32_t h, const uint8_t *rgba)
{
    s->textures = grow(s->textures, s->texture_count + 1, sizeof(*s->textures));
    struct rb_scene_texture *t = &s->textures[s->texture_count];
    *t = (struct rb_scene_texture){.width_px = w, .height_px = h};
    t->rgba8 = malloc((size_t)w * h * 4);
    assert_non_null(t->rgba8);
    memcpy(t->rgba8, rgba, (size_t)w * h * 4);
    return s->texture_count++;
}

/* Appends one primitive as a new mesh, instanced by a new root node at translation t. */
static uint32_t add_mesh(struct rb_scene *s, const struct rb_scene_vertex *v, uint32_t nv,
                         const uint32_t *idx, uint32_t ni, uint32_t mat, struct rb_vec3 t)
{
    s->vertices = grow(s->vertices, s->vertex_count + nv, sizeof(*v));
    memcpy(s->vertices + s->vertex_count, v, nv * sizeof(*v));
    s->indices = grow(s->indices, s->index_count + ni, sizeof(*idx));
    memcpy(s->indices + s->index_count, idx, ni * sizeof(*idx));
    s->primitives = grow(s->primitives, s->primitive_count + 1, sizeof(*s->primitives));
    s->primitives[s->primitive_count] = (struct rb_scene_primitive){
        .material = mat,
        .first_vertex = s->vertex_count,
        .vertex_count = nv,
        .first_index = s->index_count,
        .index_count = ni,
    };
    s->vertex_count += nv;
    s->index_count += ni;
    s->meshes = grow(s->meshes, s->mesh_count + 1, sizeof(*s->meshes));
    s->meshes[s->mesh_count] =
        (struct rb_scene_mesh){.first_primitive = s->primitive_count++, .primitive_count = 1};
    s->nodes = grow(s->nodes, s->node_count + 1, sizeof(*s->nodes));
    s->nodes[s->node_count] = (struct rb_scene_node){
        .parent = NONE,
        .translation = t,
        .rotation = {0, 0, 0, 1},
        .scale = {1, 1, 1},
        .mesh = s->mesh_count++,
        .skin = NONE,
        .camera = NONE,
        .light = NONE,
        .in_scene = true,
    };
    return s->node_count++;
}

/* The default material at the end, as the loader leaves every scene. */
static void scene_finish(struct rb_scene *s)
{
    add_material(s, material(1, 1, 1, 0, 1));
}

static struct rb_scene_vertex vert(float px, float py, float pz, float nx, float ny, float nz,
                                   float u, float v)
{
    return (struct rb_scene_vertex){
        .position = {px, py, pz}, .normal = {nx, ny, nz}, .tangent = {1, 0, 0, 1}, .uv = {u, v}};
}

/* A parallelogram c +- u +- v, front (counter-clockwise) side along u x v. */
static uint32_t add_quad(struct rb_scene *s, struct rb_vec3 c, struct rb_vec3 u, struct rb_vec3 v,
                         uint32_t mat)
{
    struct rb_vec3 n = rb_v3_normalize(rb_v3_cross(u, v));
    struct rb_scene_vertex q[4];
    static const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (int i = 0; i < 4; i++) {
        struct rb_vec3 p = rb_v3_add(rb_v3_scale(u, su[i]), rb_v3_scale(v, sv[i]));
        q[i] = vert(p.x, p.y, p.z, n.x, n.y, n.z, 0.5f + 0.5f * su[i], 0.5f - 0.5f * sv[i]);
    }
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    return add_mesh(s, q, 4, idx, 6, mat, c);
}

/* A UV sphere with smooth (exact) normals, triangles wound outwards; poles' degenerate
 * triangles are left out. stacks = slices = 32 gives 1984 triangles. */
static uint32_t add_sphere(struct rb_scene *s, struct rb_vec3 c, float r, int stacks, int slices,
                           uint32_t mat)
{
    uint32_t nv = (uint32_t)((stacks + 1) * (slices + 1));
    struct rb_scene_vertex *v = malloc(nv * sizeof(*v));
    uint32_t *idx = malloc((size_t)stacks * slices * 6 * sizeof(uint32_t));
    assert_non_null(v);
    assert_non_null(idx);
    for (int i = 0; i <= stacks; i++)
        for (int j = 0; j <= slices; j++) {
            double th = PI_D * i / stacks, ph = 2.0 * PI_D * j / slices;
            float n[3] = {(float)(sin(th) * cos(ph)), (float)cos(th), (float)(-sin(th) * sin(ph))};
            v[i * (slices + 1) + j] = vert(r * n[0], r * n[1], r * n[2], n[0], n[1], n[2],
                                           (float)j / slices, (float)i / stacks);
        }
    uint32_t ni = 0;
    for (int i = 0; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            uint32_t a = (uint32_t)(i * (slices + 1) + j), b = a + 1;
            uint32_t c2 = a + (uint32_t)slices + 1, d = c2 + 1;
            uint32_t tris[2][3] = {{a, c2, d}, {a, d, b}};
            for (int k = 0; k < 2; k++) {
                const float *p0 = v[tris[k][0]].position, *p1 = v[tris[k][1]].position;
                const float *p2 = v[tris[k][2]].position;
                struct rb_vec3 e1 = rb_v3(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]);
                struct rb_vec3 e2 = rb_v3(p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]);
                struct rb_vec3 fn = rb_v3_cross(e1, e2);
                if (rb_v3_length(fn) < 1e-9f)
                    continue; /* a pole */
                struct rb_vec3 mid =
                    rb_v3(p0[0] + p1[0] + p2[0], p0[1] + p1[1] + p2[1], p0[2] + p1[2] + p2[2]);
                bool out = rb_v3_dot(fn, mid) > 0.0f;
                idx[ni++] = tris[k][0];
                idx[ni++] = out ? tris[k][1] : tris[k][2];
                idx[ni++] = out ? tris[k][2] : tris[k][1];
            }
        }
    uint32_t node = add_mesh(s, v, nv, idx, ni, mat, c);
    free(idx);
    free(v);
    return node;
}

/* ---- jobs and renders ----------------------------------------------------------------------- */

/* A job from YAML text (the scene key must name an existing file; the scene itself is the one
 * built in memory). */
static struct rb_job *job_new(const char *fmt, ...)
{
    char text[4096];
    int n = snprintf(text, sizeof(text), "scene: scenes/features.gltf\noutput: out.####.exr\n");
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text + n, sizeof(text) - (size_t)n, fmt, ap);
    va_end(ap);
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_job_parse("test.yaml", text, strlen(text), "tests/unit", NULL, 0, &job, &err))
        fail_msg("job: %s\n%s", err.msg, text);
    return job;
}

static struct rb_reference *ref_new_sampler(const struct rb_job *job, const struct rb_scene *scene,
                                            uint32_t threads, enum rb_reference_sampler sampler)
{
    struct rb_reference *ref = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_reference_create(
            &(struct rb_reference_desc){
                .job = job, .scene = scene, .thread_count = threads, .sampler = sampler},
            &ref, &err))
        fail_msg("reference: %s", err.msg);
    return ref;
}

static struct rb_reference *ref_new(const struct rb_job *job, const struct rb_scene *scene,
                                    uint32_t threads)
{
    return ref_new_sampler(job, scene, threads, RB_REFERENCE_SAMPLER_DEFAULT);
}

/* Renders frame and returns a copy of the pixels (free it). */
static float *render(struct rb_reference *ref, int frame, struct rb_frame_result *res)
{
    struct rb_err err = RB_ERR_INIT;
    if (rb_reference_render(ref, frame, res, &err))
        fail_msg("render: %s", err.msg);
    size_t n = (size_t)res->width_px * res->height_px * RB_OUT_FLOATS;
    float *copy = malloc(n * sizeof(float));
    assert_non_null(copy);
    memcpy(copy, res->pixels, n * sizeof(float));
    return copy;
}

/* The camera ray through the point (sx, sy) of the image, in pixels (pixel x spans [x, x + 1)). */
static void image_ray(const struct rb_frame_result *r, float sx, float sy, struct rb_vec3 *org,
                      struct rb_vec3 *dir)
{
    struct rb_mat4 inv = rb_mat4_inverse(&r->world_to_ndc, NULL);
    struct rb_mat4 cam = rb_mat4_inverse(&r->world_to_camera, NULL);
    *org = rb_v3(cam.m[3][0], cam.m[3][1], cam.m[3][2]);
    struct rb_vec4 f =
        rb_mat4_vec4(&inv, (struct rb_vec4){sx / (float)r->width_px * 2.0f - 1.0f,
                                            sy / (float)r->height_px * 2.0f - 1.0f, 1, 1});
    *dir = rb_v3_normalize(rb_v3_sub(rb_v3(f.x / f.w, f.y / f.w, f.z / f.w), *org));
}

/* The camera ray through the centre of pixel (x, y), as the reference defines it. */
static void pixel_ray(const struct rb_frame_result *r, uint32_t x, uint32_t y, struct rb_vec3 *org,
                      struct rb_vec3 *dir)
{
    image_ray(r, (float)x + 0.5f, (float)y + 0.5f, org, dir);
}

static const float *px_at(const float *pixels, const struct rb_frame_result *r, uint32_t x,
                          uint32_t y)
{
    return pixels + ((size_t)y * r->width_px + x) * RB_OUT_FLOATS;
}

/* Mean and standard error per pixel and channel over K frames of a static scene (each frame
 * draws independent random numbers). */
struct stats {
    double *mean, *sem; /* width * height * 3 */
    float *first;       /* frame 0's pixels, for the AOVs */
    struct rb_frame_result r;
};

static void frame_stats(struct rb_reference *ref, int frames, struct stats *st)
{
    double *sum = NULL, *sum2 = NULL;
    size_t n = 0;
    for (int f = 0; f < frames; f++) {
        struct rb_frame_result r;
        float *p = render(ref, f, &r);
        if (f == 0) {
            n = (size_t)r.width_px * r.height_px * 3;
            sum = calloc(n, sizeof(double));
            sum2 = calloc(n, sizeof(double));
            assert_non_null(sum);
            assert_non_null(sum2);
            st->r = r;
            st->first = p;
        }
        for (size_t i = 0; i < n; i++) {
            double v = p[(i / 3) * RB_OUT_FLOATS + RB_OUT_BEAUTY + i % 3];
            sum[i] += v;
            sum2[i] += v * v;
        }
        if (f)
            free(p);
    }
    for (size_t i = 0; i < n; i++) {
        double m = sum[i] / frames;
        double var = (sum2[i] - frames * m * m) / (frames - 1);
        sum[i] = m;
        sum2[i] = sqrt(var > 0.0 ? var / frames : 0.0);
    }
    st->mean = sum;
    st->sem = sum2;
}

static void stats_release(struct stats *st)
{
    free(st->mean);
    free(st->sem);
    free(st->first);
}

/* ---- random numbers ------------------------------------------------------------------------- */

static double chi_square_16(const uint32_t counts[16], uint32_t n)
{
    double e = n / 16.0, chi = 0.0;
    for (int i = 0; i < 16; i++)
        chi += (counts[i] - e) * (counts[i] - e) / e;
    return chi;
}

static void test_random(void **state)
{
    (void)state;
    /* Uniform over all four inputs together. */
    uint32_t counts[16] = {0}, n = 0;
    double sum = 0.0;
    for (uint32_t p = 0; p < 64; p++)
        for (uint32_t s = 0; s < 32; s++)
            for (uint32_t d = 0; d < 32; d++) {
                float u = rb_reference_random(p % 3, p, s, d);
                assert_true(u >= 0.0f && u < 1.0f);
                sum += u;
                counts[(int)(u * 16.0f)]++;
                n++;
            }
    /* mean of n uniforms: sd 1/sqrt(12 n) ~ 0.001; 15 degrees of freedom: P(chi2 > 40) < 5e-4 */
    assert_true(fabs(sum / n - 0.5) < 0.005);
    assert_true(chi_square_16(counts, n) < 40.0);
    /* Uniform along each input alone, the others fixed. */
    for (int which = 0; which < 4; which++) {
        uint32_t c[16] = {0};
        for (uint32_t i = 0; i < 16384; i++) {
            uint32_t a[4] = {7, 1234, 5, 3};
            a[which] = i;
            c[(int)(rb_reference_random(a[0], a[1], a[2], a[3]) * 16.0f)]++;
        }
        double chi = chi_square_16(c, 16384);
        if (!(chi < 40.0))
            fail_msg("input %d alone: chi-square %g", which, chi);
    }
    /* Dimensions 2k and 2k + 1 of one pixel's samples are a (0,2)-sequence: every aligned run
     * of 16 samples puts exactly one point in each cell of the 16 x 1, 8 x 2, ..., 1 x 16 grids. */
    for (uint32_t pair = 0; pair < 8; pair++)
        for (uint32_t s0 = 0; s0 < 64; s0 += 16)
            for (int a = 0; a <= 4; a++) {
                uint32_t cells[16] = {0};
                for (uint32_t s = s0; s < s0 + 16; s++) {
                    float u = rb_reference_random(3, 77, s, 2 * pair);
                    float v = rb_reference_random(3, 77, s, 2 * pair + 1);
                    cells[(int)(u * (float)(1 << a)) * (1 << (4 - a)) +
                          (int)(v * (float)(1 << (4 - a)))]++;
                }
                for (int c = 0; c < 16; c++)
                    if (cells[c] != 1)
                        fail_msg("pair %u, samples %u-%u, %d x %d grid: cell %d has %u points",
                                 pair, s0, s0 + 15, 1 << a, 1 << (4 - a), c, cells[c]);
            }
    /* Every input changes the number. */
    for (uint32_t i = 0; i < 1000; i++) {
        uint32_t a[4] = {i % 7, i * 31 + 5, i % 64, i % 40};
        float u = rb_reference_random(a[0], a[1], a[2], a[3]);
        assert_true(u == rb_reference_random(a[0], a[1], a[2], a[3]));
        for (int k = 0; k < 4; k++) {
            uint32_t b[4] = {a[0], a[1], a[2], a[3]};
            b[k]++;
            if (u == rb_reference_random(b[0], b[1], b[2], b[3]))
                fail_msg("input %d does not change the number at %u", k, i);
        }
    }
}

/* ---- the BRDF -------------------------------------------------------------------------------- */

static void onb(struct rb_vec3 n, struct rb_vec3 *t, struct rb_vec3 *b)
{
    struct rb_vec3 a = fabsf(n.x) > 0.9f ? rb_v3(0, 1, 0) : rb_v3(1, 0, 0);
    *t = rb_v3_normalize(rb_v3_cross(a, n));
    *b = rb_v3_cross(n, *t);
}

/* E = integral of f(n, v, l) (n.l) [ng.l > 0] over l, by two deterministic quadratures
 * combined with the balance heuristic: a grid over GGX's half vectors (the shape of the
 * specular lobe) and a cosine-weighted grid (the diffuse lobe). ng NULL: no cut. */
static double albedo(struct rb_vec3 n, struct rb_vec3 v, const struct rb_vec3 *ng,
                     const float c_diff[3], const float f0[3], float f90, float roughness,
                     int channel)
{
    double a = fmax((double)roughness * roughness, 1e-4), a2 = a * a;
    struct rb_vec3 t, b;
    onb(n, &t, &b);
    enum { N1X = 512, N1Y = 128, N2X = 256, N2Y = 128 };
    const double n1 = N1X * N1Y, n2 = N2X * N2Y;
    double sum = 0.0;
    for (int tech = 0; tech < 2; tech++) {
        int nx = tech ? N2X : N1X, ny = tech ? N2Y : N1Y;
        for (int i = 0; i < nx; i++)
            for (int j = 0; j < ny; j++) {
                double x = (i + 0.5) / nx, y = (j + 0.5) / ny, phi = 2.0 * PI_D * y;
                struct rb_vec3 l;
                if (tech == 0) {
                    double ct = 1.0 / sqrt(1.0 + a2 * x / (1.0 - x)), st = sqrt(1.0 - ct * ct);
                    struct rb_vec3 h = rb_v3_add(rb_v3_add(rb_v3_scale(t, (float)(st * cos(phi))),
                                                           rb_v3_scale(b, (float)(st * sin(phi)))),
                                                 rb_v3_scale(n, (float)ct));
                    float vdh = rb_v3_dot(v, h);
                    if (vdh <= 0.0f)
                        continue;
                    l = rb_v3_sub(rb_v3_scale(h, 2.0f * vdh), v);
                } else {
                    double r = sqrt(x);
                    l = rb_v3_add(rb_v3_add(rb_v3_scale(t, (float)(r * cos(phi))),
                                            rb_v3_scale(b, (float)(r * sin(phi)))),
                                  rb_v3_scale(n, (float)sqrt(1.0 - x)));
                }
                l = rb_v3_normalize(l);
                double ndl = rb_v3_dot(n, l);
                if (ndl <= 0.0 || (ng && rb_v3_dot(*ng, l) <= 0.0f))
                    continue;
                float f[3];
                rb_reference_brdf((float[3]){n.x, n.y, n.z}, (float[3]){v.x, v.y, v.z},
                                  (float[3]){l.x, l.y, l.z}, c_diff, f0, f90, roughness, f);
                /* both densities of l */
                struct rb_vec3 h = rb_v3_normalize(rb_v3_add(v, l));
                double ndh = rb_v3_dot(n, h), vdh = rb_v3_dot(v, h), p1 = 0.0;
                if (ndh > 0.0 && vdh > 0.0) {
                    double d = ndh * ndh * (a2 - 1.0) + 1.0;
                    p1 = a2 / (PI_D * d * d) * ndh / (4.0 * vdh);
                }
                double p2 = ndl / PI_D;
                sum += f[channel] * ndl / (n1 * p1 + n2 * p2);
            }
    }
    return sum;
}

/* The model's directional albedo E(mu) stays at or below 1 for metals at every angle and for
 * dielectrics away from grazing. (Near grazing a white dielectric reflects more than it gets:
 * glTF weights the diffuse lobe by 1 - F(v.h), not by what the specular lobe took; E reaches
 * 1.15 at mu = 0.3 and 1.7 at mu = 0.05 for smooth surfaces. That is the model the GPU
 * evaluates, so the reference keeps it.) */
static void test_brdf_energy(void **state)
{
    (void)state;
    const float zero[3] = {0, 0, 0}, one[3] = {1, 1, 1}, white[3] = {1, 1, 1};
    const float f0_d[3] = {0.04f, 0.04f, 0.04f};
    const float roughness[] = {0.05f, 0.1f, 0.3f, 0.6f, 1.0f};
    const float mu[] = {0.05f, 0.3f, 0.7f, 1.0f};
    struct rb_vec3 n = rb_v3(0, 0, 1);
    for (size_t i = 0; i < sizeof(roughness) / sizeof(roughness[0]); i++)
        for (size_t j = 0; j < sizeof(mu) / sizeof(mu[0]); j++) {
            struct rb_vec3 v = rb_v3(sqrtf(1.0f - mu[j] * mu[j]), 0, mu[j]);
            double metal = albedo(n, v, NULL, zero, one, 1.0f, roughness[i], 0);
            if (!(metal <= 1.0 + 2e-3 && metal > 0.25))
                fail_msg("roughness %g mu %g: metal E %g", roughness[i], mu[j], metal);
            /* a smooth mirror keeps nearly everything where it is not grazing */
            if (roughness[i] <= 0.1f && mu[j] >= 0.3f && !(metal > 0.97))
                fail_msg("roughness %g mu %g: metal E %g", roughness[i], mu[j], metal);
            if (mu[j] < 0.7f)
                continue;
            double dielectric = albedo(n, v, NULL, white, f0_d, 1.0f, roughness[i], 0);
            if (!(dielectric <= 1.0 + 2e-3 && dielectric > 0.9))
                fail_msg("roughness %g mu %g: dielectric E %g", roughness[i], mu[j], dielectric);
        }
    /* Pure Lambert integrates to its albedo. */
    struct rb_vec3 v = rb_v3(0.6f, 0, 0.8f);
    double lambert = albedo(n, v, NULL, white, zero, 0.0f, 1.0f, 0);
    assert_true(fabs(lambert - 1.0) < 1e-3);
}

static void test_brdf_reciprocity(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < 2000; i++) {
        float r[6];
        for (int k = 0; k < 6; k++)
            r[k] = rb_reference_random(99, i, 0, (uint32_t)k);
        struct rb_vec3 n = rb_v3(0, 0, 1);
        float ct1 = 0.02f + 0.98f * r[0], ct2 = 0.02f + 0.98f * r[1];
        float p1 = 2.0f * RB_PI * r[2], p2 = 2.0f * RB_PI * r[3];
        float s1 = sqrtf(1 - ct1 * ct1), s2 = sqrtf(1 - ct2 * ct2);
        float v[3] = {s1 * cosf(p1), s1 * sinf(p1), ct1},
              l[3] = {s2 * cosf(p2), s2 * sinf(p2), ct2};
        float g = 0.02f + 0.98f * r[4], rough = r[5];
        float f0[3] = {g, g, g}, c_diff[3] = {0, 0, 0}, a[3], b[3];
        rb_reference_brdf((float[3]){n.x, n.y, n.z}, v, l, c_diff, f0, 1.0f, rough, a);
        rb_reference_brdf((float[3]){n.x, n.y, n.z}, l, v, c_diff, f0, 1.0f, rough, b);
        for (int c = 0; c < 3; c++)
            if (!(fabsf(a[c] - b[c]) <= 1e-5f * fmaxf(fabsf(a[c]), 1.0f)))
                fail_msg("f(v,l) %g != f(l,v) %g (roughness %g, g %g)", a[c], b[c], rough, g);
    }
    /* below the horizon there is no light */
    float out[3];
    rb_reference_brdf((float[3]){0, 0, 1}, (float[3]){0, 0, 1}, (float[3]){0, 0.6f, -0.8f},
                      (float[3]){1, 1, 1}, (float[3]){0.04f, 0.04f, 0.04f}, 1.0f, 0.5f, out);
    assert_true(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f);
}

/* ---- furnaces ------------------------------------------------------------------------------- */

/* A sphere of radius 1 at the origin, seen from +Z in a uniform white environment (which lights
 * the scene, so no default light is added). */
#define FURNACE_JOB                                                                                \
    "resolution: [32, 32]\n"                                                                       \
    "frames: {start: 0, end: 0, rate: 24}\n"                                                       \
    "camera: {fov_y_deg: 40, keys: [{t: 0, position: [0, 0, 4], look_at: [0, 0, 0]}]}\n"           \
    "environment: {color: [1, 1, 1], intensity: 1}\n"                                              \
    "integrator: {name: reference, reference: {spp: %d, max_bounces: 16, rr_depth: 1}}\n"

/* The largest angle between a triangle's face normal and one of its vertex normals. */
static double max_normal_tilt(const struct rb_scene *s)
{
    double worst = 0.0;
    for (uint32_t t = 0; t + 2 < s->index_count; t += 3) {
        const struct rb_scene_vertex *v[3] = {&s->vertices[s->indices[t]],
                                              &s->vertices[s->indices[t + 1]],
                                              &s->vertices[s->indices[t + 2]]};
        struct rb_vec3 p[3], fn;
        for (int k = 0; k < 3; k++)
            p[k] = rb_v3(v[k]->position[0], v[k]->position[1], v[k]->position[2]);
        fn = rb_v3_normalize(rb_v3_cross(rb_v3_sub(p[1], p[0]), rb_v3_sub(p[2], p[0])));
        for (int k = 0; k < 3; k++) {
            struct rb_vec3 n = rb_v3(v[k]->normal[0], v[k]->normal[1], v[k]->normal[2]);
            worst = fmax(worst, acos(fmin(1.0, rb_v3_dot(fn, rb_v3_normalize(n)))));
        }
    }
    return worst;
}

static void test_white_furnace(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    struct rb_scene_material m = material(1, 1, 1, 0, 1);
    m.specular_factor = 0.0f; /* pure Lambert, albedo 1 */
    add_sphere(s, rb_v3(0, 0, 0), 1.0f, 32, 32, add_material(s, m));
    scene_finish(s);
    struct rb_job *job = job_new(FURNACE_JOB, 16);
    struct rb_reference *ref = ref_new(job, s, 2);
    struct stats st;
    frame_stats(ref, 16, &st);
    /* Light toward directions below the triangle's plane (though above the smooth normal) is
     * cut off, as on the GPU: for a tilt d between the two normals that loses at most
     * tan^2(d) / 4 of the cosine-weighted hemisphere. */
    double tilt = max_normal_tilt(s), allowance = tan(tilt) * tan(tilt) / 4.0 + 1e-4;
    uint32_t hits = 0;
    for (uint32_t y = 0; y < st.r.height_px; y++)
        for (uint32_t x = 0; x < st.r.width_px; x++) {
            const float *p = px_at(st.first, &st.r, x, y);
            size_t i = ((size_t)y * st.r.width_px + x) * 3;
            if (p[RB_OUT_BEAUTY + 3] == 0.0f) {
                assert_true(p[RB_OUT_BEAUTY] == 1.0f && p[RB_OUT_DEPTH] == 0.0f);
                continue;
            }
            hits++;
            for (int c = 0; c < 3; c++)
                if (!(fabs(st.mean[i + c] - 1.0) <= 4.0 * st.sem[i + c] + allowance))
                    fail_msg("pixel %u,%u: %g +- %g, not 1 (allowance %g)", x, y, st.mean[i + c],
                             st.sem[i + c], allowance);
            assert_true(fabsf(p[RB_OUT_ALBEDO] - 1.0f) < 1e-6f);
        }
    assert_true(hits > 200); /* the sphere covers a good part of the frame */
    stats_release(&st);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* Brute force: the first triangle of s along the ray (node translations only). */
static bool oracle_hit(const struct rb_scene *s, struct rb_vec3 o, struct rb_vec3 d, float *t_out,
                       struct rb_vec3 *ng, struct rb_vec3 *n)
{
    float best = INFINITY;
    for (uint32_t ni = 0; ni < s->node_count; ni++) {
        const struct rb_scene_node *node = &s->nodes[ni];
        const struct rb_scene_primitive *pr = &s->primitives[s->meshes[node->mesh].first_primitive];
        for (uint32_t k = 0; k + 2 < pr->index_count; k += 3) {
            const struct rb_scene_vertex *v[3];
            struct rb_vec3 p[3];
            for (int c = 0; c < 3; c++) {
                v[c] = &s->vertices[pr->first_vertex + s->indices[pr->first_index + k + c]];
                p[c] = rb_v3_add(rb_v3(v[c]->position[0], v[c]->position[1], v[c]->position[2]),
                                 node->translation);
            }
            struct rb_vec3 e1 = rb_v3_sub(p[1], p[0]), e2 = rb_v3_sub(p[2], p[0]);
            struct rb_vec3 q = rb_v3_cross(d, e2);
            float det = rb_v3_dot(e1, q);
            if (fabsf(det) < 1e-12f)
                continue;
            struct rb_vec3 sv = rb_v3_sub(o, p[0]);
            float b1 = rb_v3_dot(sv, q) / det;
            struct rb_vec3 r = rb_v3_cross(sv, e1);
            float b2 = rb_v3_dot(d, r) / det, t = rb_v3_dot(e2, r) / det;
            if (b1 < 0 || b2 < 0 || b1 + b2 > 1 || t <= 0 || t >= best)
                continue;
            best = t;
            *ng = rb_v3_normalize(rb_v3_cross(e1, e2));
            struct rb_vec3 nn = rb_v3(0, 0, 0);
            float b[3] = {1 - b1 - b2, b1, b2};
            for (int c = 0; c < 3; c++)
                nn = rb_v3_add(
                    nn,
                    rb_v3_scale(rb_v3(v[c]->normal[0], v[c]->normal[1], v[c]->normal[2]), b[c]));
            *n = rb_v3_normalize(nn);
        }
    }
    *t_out = best;
    return best < INFINITY;
}

static void test_ggx_furnace(void **state)
{
    (void)state;
    /* 0: a mirror (alpha at the BRDF's floor, 1e-4), which reflects everything at f0 = 1 */
    const float roughness[] = {0.0f, 0.1f, 0.3f, 0.6f, 1.0f};
    for (size_t ri = 0; ri < sizeof(roughness) / sizeof(roughness[0]); ri++) {
        struct rb_scene *s = scene_new();
        add_sphere(s, rb_v3(0, 0, 0), 1.0f, 32, 32,
                   add_material(s, material(1, 1, 1, 1, roughness[ri])));
        scene_finish(s);
        struct rb_job *job = job_new(FURNACE_JOB, 16);
        struct rb_reference *ref = ref_new(job, s, 2);
        struct stats st;
        frame_stats(ref, 16, &st);
        /* pixels along the middle row, from the centre toward the rim */
        const uint32_t xs[] = {16, 18, 20, 21, 22};
        for (size_t k = 0; k < sizeof(xs) / sizeof(xs[0]); k++) {
            uint32_t x = xs[k], y = 16;
            const float *p = px_at(st.first, &st.r, x, y);
            assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
            struct rb_vec3 o, d, ng, n;
            float t;
            pixel_ray(&st.r, x, y, &o, &d);
            assert_true(oracle_hit(s, o, d, &t, &ng, &n));
            /* the AOVs are the oracle's hit */
            struct rb_vec3 aov_n =
                rb_v3(p[RB_OUT_NORMAL], p[RB_OUT_NORMAL + 1], p[RB_OUT_NORMAL + 2]);
            assert_true(rb_v3_length(rb_v3_sub(aov_n, n)) < 1e-4f);
            struct rb_vec3 hp = rb_v3_add(o, rb_v3_scale(d, t));
            float depth = -rb_mat4_point(&st.r.world_to_camera, hp).z;
            assert_true(fabsf(p[RB_OUT_DEPTH] - depth) < 1e-4f * depth);
            struct rb_vec3 v = rb_v3_scale(d, -1.0f);
            float mu = rb_v3_dot(n, v);
            const float zero[3] = {0, 0, 0}, one[3] = {1, 1, 1};
            double e = 1.0, e_cut = 1.0 - 1e-3;
            if (roughness[ri] > 0.0f) {
                e = albedo(n, v, NULL, zero, one, 1.0f, roughness[ri], 0);
                e_cut = albedo(n, v, &ng, zero, one, 1.0f, roughness[ri], 0);
            }
            size_t i = ((size_t)y * st.r.width_px + x) * 3;
            for (int c = 0; c < 3; c++) {
                double m = st.mean[i + c], sem = st.sem[i + c];
                /* Single scattering is all a convex sphere gets: no more than E(mu), no more
                 * lost than the facets' cut (light from under the triangle's plane). The 1e-4
                 * is single precision: at alpha 1e-4 the GGX peak gives rare outliers of a few
                 * 1e-4 that 16 frames cannot put a standard error on. */
                if (!(m >= e_cut - 4.0 * sem && m <= 1.0 + 4.0 * sem + 1e-4 &&
                      m <= e + 4.0 * sem + 1e-4))
                    fail_msg("roughness %g, pixel %u (mu %.3f): %g +- %g, E(mu) %g, with the "
                             "facet cut %g",
                             roughness[ri], x, mu, m, sem, e, e_cut);
            }
        }
        stats_release(&st);
        rb_reference_destroy(ref);
        rb_job_destroy(job);
        rb_scene_destroy(s);
    }
}

/* Inside a closed cube whose walls all emit Le and reflect albedo a (Lambert), the radiance is
 * Le / (1 - a) everywhere: every path bounces until it dies. Flat faces (vertex normals = face
 * normals) so nothing is cut. This exercises emitter sampling by power, MIS against BSDF hits,
 * many bounces and Russian roulette. */
static void add_box_inside(struct rb_scene *s, float half, uint32_t mat)
{
    /* six faces, each seen from inside: front side toward the centre */
    static const float axes[6][3][3] = {
        {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}}, {{0, -1, 0}, {0, 0, 1}, {1, 0, 0}},
        {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}}, {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}},
    };
    for (int f = 0; f < 6; f++) {
        struct rb_vec3 n = rb_v3(axes[f][0][0], axes[f][0][1], axes[f][0][2]);
        struct rb_vec3 u = rb_v3_scale(rb_v3(axes[f][1][0], axes[f][1][1], axes[f][1][2]), half);
        struct rb_vec3 v = rb_v3_scale(rb_v3(axes[f][2][0], axes[f][2][1], axes[f][2][2]), half);
        /* the wall sits at +half along n; its front (u x v) must face -n, the inside */
        if (rb_v3_dot(rb_v3_cross(u, v), n) > 0.0f)
            v = rb_v3_scale(v, -1.0f);
        add_quad(s, rb_v3_scale(n, half), u, v, mat);
    }
}

static void test_emissive_furnace(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    struct rb_scene_material m = material(0.5f, 0.5f, 0.5f, 0, 1);
    m.specular_factor = 0.0f;
    m.emissive[0] = m.emissive[1] = m.emissive[2] = 0.5f;
    add_box_inside(s, 1.0f, add_material(s, m));
    scene_finish(s);
    struct rb_job *job = job_new(
        "resolution: [24, 24]\n"
        "frames: {start: 0, end: 0, rate: 24}\n"
        "camera: {fov_y_deg: 70, keys: [{t: 0, position: [0.2, 0.1, 0.3], "
        "look_at: [-1, -0.5, -1]}]}\n"
        "integrator: {name: reference, reference: {spp: 16, max_bounces: 24, rr_depth: 1}}\n");
    struct rb_reference *ref = ref_new(job, s, 2);
    struct stats st;
    frame_stats(ref, 16, &st);
    /* paths of at most 25 scatterings: Le (1 - a^26) / (1 - a), a hair under 1 */
    double want = 0.5 * (1.0 - pow(0.5, 26)) / 0.5;
    /* Every pixel sees the same distribution, and 16 frames underestimate a skewed one's
     * spread, so each pixel's standard error is at least the pooled one. */
    size_t nc = (size_t)st.r.width_px * st.r.height_px * 3;
    double pooled = 0.0, mean = 0.0;
    for (size_t i = 0; i < nc; i++) {
        pooled += st.sem[i] * st.sem[i] / nc;
        mean += st.mean[i] / nc;
    }
    pooled = sqrt(pooled);
    for (size_t i = 0; i < nc; i++) {
        assert_true(st.first[(i / 3) * RB_OUT_FLOATS + RB_OUT_BEAUTY + 3] == 1.0f);
        double sem = fmax(st.sem[i], pooled);
        if (!(fabs(st.mean[i] - want) <= 5.0 * sem))
            fail_msg("pixel %zu: %g +- %g, want %g", i / 3, st.mean[i], sem, want);
    }
    /* the whole image: pixels are independent, channels are not */
    double sem_all = pooled / sqrt(nc / 3.0);
    if (!(fabs(mean - want) <= 4.0 * sem_all))
        fail_msg("image mean %g +- %g, want %g", mean, sem_all, want);
    /* the layers: emission at x1 and one scattering are direct, the rest indirect (a^2 / (1-a)
     * of Le in expectation); beauty is their sum */
    double direct = 0.0, indirect = 0.0;
    size_t n = (size_t)st.r.width_px * st.r.height_px;
    for (size_t i = 0; i < n; i++) {
        const float *p = st.first + i * RB_OUT_FLOATS;
        direct += p[RB_OUT_DIRECT];
        indirect += p[RB_OUT_INDIRECT];
        assert_true(fabsf(p[RB_OUT_BEAUTY] - p[RB_OUT_DIRECT] - p[RB_OUT_INDIRECT]) < 1e-5f);
        /* no specular lobe (specular_factor 0): the indirect light is all diffuse */
        assert_true(p[RB_OUT_INDIRECT_SPECULAR] == 0.0f);
        assert_true(fabsf(p[RB_OUT_INDIRECT_DIFFUSE] - p[RB_OUT_INDIRECT]) <=
                    1e-6f * p[RB_OUT_INDIRECT]);
    }
    direct /= n;
    indirect /= n;
    if (!(fabs(direct - 0.75) < 0.03 && fabs(indirect - 0.25) < 0.03))
        fail_msg("direct %g (want 0.75), indirect %g (want 0.25)", direct, indirect);
    stats_release(&st);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* ---- the environment map -------------------------------------------------------------------- */

/* rb_equirect_uv of shaders/common/lights.glsl and a bilinear read (u repeats, v clamps). */
static void env_lookup(const float *rgba, int w, int h, float rot, struct rb_vec3 d, float out[3])
{
    float c = cosf(-rot), s = sinf(-rot);
    struct rb_vec3 r = rb_v3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
    double u = atan2(r.x, -r.z) / (2.0 * PI_D) + 0.5, v = acos(fmax(-1, fmin(1, r.y))) / PI_D;
    double x = u * w - 0.5, y = v * h - 0.5, fx = floor(x), fy = floor(y);
    for (int k = 0; k < 3; k++) {
        double acc = 0.0;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                int xi = (((int)fx + i) % w + w) % w, yi = (int)fy + j;
                yi = yi < 0 ? 0 : (yi >= h ? h - 1 : yi);
                double wgt = (i ? x - fx : 1 - (x - fx)) * (j ? y - fy : 1 - (y - fy));
                acc += wgt * rgba[((size_t)yi * w + xi) * 4 + k];
            }
        out[k] = (float)acc;
    }
}

static void test_environment_map(void **state)
{
    (void)state;
    enum { W = 32, H = 16 };
    float *map = malloc(W * H * 4 * sizeof(float));
    assert_non_null(map);
    /* a patterned map, to check the lookup seen directly; and a sky over a black ground with a
     * bright sun patch, to check the importance sampling under a white Lambertian sphere */
    float *sky = malloc(W * H * 4 * sizeof(float));
    assert_non_null(sky);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = map + (y * W + x) * 4, *q = sky + (y * W + x) * 4;
            p[0] = (float)x / W, p[1] = (float)y / H, p[2] = (x + y) % 3 ? 0.25f : 1.0f;
            p[3] = 1.0f;
            bool sun = y == 3 && (x == 5 || x == 6);
            q[0] = q[1] = q[2] = sun ? 40.0f : (y < H / 2 ? 1.0f : 0.0f);
            q[3] = 1.0f;
        }
    struct rb_scene *s = scene_new();
    struct rb_scene_material m = material(1, 1, 1, 0, 1);
    m.specular_factor = 0.0f;
    add_sphere(s, rb_v3(0, 0, 0), 1.0f, 32, 32, add_material(s, m));
    scene_finish(s);
    struct rb_job *job = job_new(
        "resolution: [32, 32]\n"
        "frames: {start: 0, end: 0, rate: 24}\n"
        "camera: {fov_y_deg: 50, keys: [{t: 0, position: [0.5, 1.5, 3.5], look_at: [0, 0, 0]}]}\n"
        "environment: {intensity: 1.5, rotation_deg: 30}\n"
        "integrator: {name: reference, reference: {spp: 16, max_bounces: 4}}\n");
    float rot = 30.0f * RB_PI / 180.0f;

    /* seen directly */
    struct rb_reference *ref = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(
        rb_reference_create(
            &(struct rb_reference_desc){
                .job = job, .scene = s, .env_rgba = map, .env_width_px = W, .env_height_px = H},
            &ref, &err),
        RB_OK);
    struct rb_frame_result r;
    float *px = render(ref, 0, &r);
    uint32_t misses = 0;
    for (uint32_t y = 0; y < r.height_px; y++)
        for (uint32_t x = 0; x < r.width_px; x++) {
            const float *p = px_at(px, &r, x, y);
            if (p[RB_OUT_BEAUTY + 3] != 0.0f)
                continue;
            struct rb_vec3 o, d;
            pixel_ray(&r, x, y, &o, &d);
            float want[3];
            env_lookup(map, W, H, rot, d, want);
            for (int c = 0; c < 3; c++)
                if (!(fabsf(p[RB_OUT_BEAUTY + c] - 1.5f * want[c]) < 1e-4f))
                    fail_msg("pixel %u,%u: %g, want %g", x, y, p[RB_OUT_BEAUTY + c],
                             1.5f * want[c]);
            misses++;
        }
    assert_true(misses > 200);
    free(px);
    rb_reference_destroy(ref);

    /* lighting a white sphere: E = integral of L(l) (n.l) / pi [ng.l > 0], by a
     * cosine-weighted midpoint grid around the pixel's normal */
    assert_int_equal(rb_reference_create(&(struct rb_reference_desc){.job = job,
                                                                     .scene = s,
                                                                     .thread_count = 2,
                                                                     .env_rgba = sky,
                                                                     .env_width_px = W,
                                                                     .env_height_px = H},
                                         &ref, &err),
                     RB_OK);
    struct stats st;
    frame_stats(ref, 16, &st);
    uint32_t checked = 0;
    for (uint32_t y = 1; y < st.r.height_px; y += 2)
        for (uint32_t x = 1; x < st.r.width_px; x += 2) {
            const float *p = px_at(st.first, &st.r, x, y);
            if (p[RB_OUT_BEAUTY + 3] == 0.0f)
                continue;
            struct rb_vec3 o, d, ng, n, t, b;
            float th;
            pixel_ray(&st.r, x, y, &o, &d);
            assert_true(oracle_hit(s, o, d, &th, &ng, &n));
            if (rb_v3_dot(ng, n) < 0.0f)
                ng = rb_v3_scale(ng, -1.0f);
            onb(n, &t, &b);
            enum { NX = 256, NY = 256 };
            double e = 0.0;
            for (int i = 0; i < NX; i++)
                for (int j = 0; j < NY; j++) {
                    double u = (i + 0.5) / NX, rr = sqrt(u), ph = 2.0 * PI_D * (j + 0.5) / NY;
                    struct rb_vec3 l = rb_v3_add(rb_v3_add(rb_v3_scale(t, (float)(rr * cos(ph))),
                                                           rb_v3_scale(b, (float)(rr * sin(ph)))),
                                                 rb_v3_scale(n, (float)sqrt(1.0 - u)));
                    if (rb_v3_dot(ng, l) <= 0.0f)
                        continue;
                    float le[3];
                    env_lookup(sky, W, H, rot, rb_v3_normalize(l), le);
                    e += le[0];
                }
            e *= 1.5 / (NX * NY);
            size_t i = ((size_t)y * st.r.width_px + x) * 3;
            /* the grid's error: a sun of a few texels over 256^2 points, well under 1% */
            if (!(fabs(st.mean[i] - e) <= 4.0 * st.sem[i] + 0.01 * e + 1e-3))
                fail_msg("pixel %u,%u: %g +- %g, want %g", x, y, st.mean[i], st.sem[i], e);
            checked++;
        }
    assert_true(checked > 40);
    stats_release(&st);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
    free(sky);
    free(map);
}

/* ---- the direct path space against closed forms --------------------------------------------- */

/* A 4 x 4 m Lambertian floor (albedo 0.8) at y = 0; a single-sided occluder 0.2 m wide at
 * y = 0.5 facing down (the camera above sees its back, so camera rays pass through it; shadow
 * rays do not); a masked quad (alpha 0) at y = 0.7 that nothing sees; and an opaque quad of the
 * same texture off to the side, seen and casting shadows, to show that the texture's alpha does
 * not hide opaque materials. */
struct direct_scene {
    struct rb_scene *s;
    float occ_c[3], occ_half; /* occluder: centre, half size */
    float opaque_c[3], opaque_half;
};

static void direct_scene_build(struct direct_scene *d)
{
    struct rb_scene *s = d->s = scene_new();
    struct rb_scene_material floor = material(0.8f, 0.8f, 0.8f, 0, 1);
    floor.specular_factor = 0.0f;
    add_quad(s, rb_v3(0, 0, 0), rb_v3(2, 0, 0), rb_v3(0, 0, -2), add_material(s, floor));
    d->occ_c[0] = 0.3f, d->occ_c[1] = 0.5f, d->occ_c[2] = 0.3f, d->occ_half = 0.1f;
    add_quad(s, rb_v3(d->occ_c[0], d->occ_c[1], d->occ_c[2]), rb_v3(0.1f, 0, 0), rb_v3(0, 0, 0.1f),
             add_material(s, material(0.5f, 0.5f, 0.5f, 0, 1)));
    static const uint8_t clear[2 * 2 * 4] = {255, 0, 0, 0, 255, 0, 0, 0,
                                             255, 0, 0, 0, 255, 0, 0, 0};
    uint32_t tex = add_texture(s, 2, 2, clear);
    struct rb_scene_material masked = material(1, 1, 1, 0, 1);
    masked.base_color_tex = tex;
    masked.alpha_mode = RB_ALPHA_MASK;
    masked.alpha_cutoff = 0.5f;
    add_quad(s, rb_v3(-0.4f, 0.7f, -0.2f), rb_v3(0.3f, 0, 0), rb_v3(0, 0, -0.3f),
             add_material(s, masked));
    struct rb_scene_material opaque = masked;
    opaque.alpha_mode = RB_ALPHA_OPAQUE;
    d->opaque_c[0] = -1.2f, d->opaque_c[1] = 0.3f, d->opaque_c[2] = 1.0f, d->opaque_half = 0.2f;
    add_quad(s, rb_v3(d->opaque_c[0], d->opaque_c[1], d->opaque_c[2]), rb_v3(0.2f, 0, 0),
             rb_v3(0, 0, -0.2f), add_material(s, opaque));
    scene_finish(s);
}

/* Where segment a -> b crosses the plane y = c[1], inside the square of half size h around c:
 * 1; clearly outside: 0; within eps of its border: -1 (too close to call). */
static int crosses_square(struct rb_vec3 a, struct rb_vec3 b, const float c[3], float h, float eps)
{
    if ((a.y - c[1]) * (b.y - c[1]) >= 0.0f)
        return 0;
    float t = (c[1] - a.y) / (b.y - a.y);
    float x = a.x + t * (b.x - a.x) - c[0], z = a.z + t * (b.z - a.z) - c[2];
    float m = fmaxf(fabsf(x), fabsf(z));
    return m < h - eps ? 1 : (m > h + eps ? 0 : -1);
}

struct test_light {
    int type; /* RB_LIGHT_* */
    struct rb_vec3 pos, dir;
    float intensity, range, inner_deg, outer_deg;
};

static double light_at(const struct test_light *l, struct rb_vec3 p, struct rb_vec3 *to_light)
{
    if (l->type == RB_LIGHT_DIRECTIONAL) {
        *to_light = rb_v3_scale(l->dir, -1.0f);
        return l->intensity * fmax(0.0, to_light->y);
    }
    struct rb_vec3 d = rb_v3_sub(l->pos, p);
    double dist = rb_v3_length(d);
    *to_light = rb_v3_scale(d, (float)(1.0 / dist));
    double att = 1.0 / (dist * dist);
    if (l->range > 0.0f) {
        double r = dist / l->range;
        att *= fmin(fmax(1.0 - r * r * r * r, 0.0), 1.0);
    }
    if (l->type == RB_LIGHT_SPOT) {
        double ci = cos(l->inner_deg * PI_D / 180.0), co = cos(l->outer_deg * PI_D / 180.0);
        double cd = -rb_v3_dot(l->dir, *to_light);
        double t = fmin(fmax((cd - co) / fmax(1e-3, ci - co), 0.0), 1.0);
        att *= t * t;
    }
    return l->intensity * att * fmax(0.0, to_light->y);
}

static void check_direct(const char *lights_yaml, const struct test_light *lights, int nl)
{
    struct direct_scene ds;
    direct_scene_build(&ds);
    struct rb_job *job = job_new(
        "resolution: [40, 30]\n"
        "frames: {start: 0, end: 0, rate: 24}\n"
        "camera: {fov_y_deg: 60, keys: [{t: 0, position: [0, 2.5, 2.5], look_at: [0, 0, 0]}]}\n"
        "lights: %s\n"
        "environment: {color: [0.1, 0.2, 0.3], intensity: 2}\n"
        "integrator: {name: reference, reference: {spp: 2, paths: direct}}\n",
        lights_yaml);
    struct rb_reference *ref = ref_new(job, ds.s, 2);
    struct rb_frame_result r;
    float *px = render(ref, 0, &r);
    uint32_t lit = 0, shadowed = 0, misses = 0, opaque = 0;
    for (uint32_t y = 0; y < r.height_px; y++)
        for (uint32_t x = 0; x < r.width_px; x++) {
            const float *p = px_at(px, &r, x, y);
            struct rb_vec3 o, d;
            pixel_ray(&r, x, y, &o, &d);
            float t = -o.y / d.y;
            struct rb_vec3 hit = rb_v3_add(o, rb_v3_scale(d, t));
            float edge = fmaxf(fabsf(hit.x), fabsf(hit.z));
            int opq = crosses_square(o, hit, ds.opaque_c, ds.opaque_half, 1e-3f);
            if (opq != 0) {
                if (opq == 1) { /* the opaque textured quad: base colour x texel (1, 0, 0) */
                    assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
                    assert_true(fabsf(p[RB_OUT_ALBEDO] - 1.0f) < 1e-5f &&
                                p[RB_OUT_ALBEDO + 1] == 0.0f);
                    opaque++;
                }
                continue;
            }
            if (!(d.y < 0.0f) || edge > 2.0f + 1e-3f) { /* the environment, alpha 0 */
                const float env[3] = {0.2f, 0.4f, 0.6f};
                for (int c = 0; c < 3; c++)
                    assert_true(fabsf(p[RB_OUT_BEAUTY + c] - env[c]) < 1e-6f &&
                                p[RB_OUT_DIRECT + c] == p[RB_OUT_BEAUTY + c] &&
                                p[RB_OUT_INDIRECT + c] == 0.0f);
                assert_true(p[RB_OUT_BEAUTY + 3] == 0.0f && p[RB_OUT_DEPTH] == 0.0f);
                misses++;
                continue;
            }
            if (edge > 2.0f - 1e-3f)
                continue;
            double want = 0.0;
            bool unsure = false;
            for (int i = 0; i < nl; i++) {
                struct rb_vec3 tl;
                double e = light_at(&lights[i], hit, &tl);
                struct rb_vec3 far = lights[i].type == RB_LIGHT_DIRECTIONAL
                                         ? rb_v3_add(hit, rb_v3_scale(tl, 100.0f))
                                         : lights[i].pos;
                int b1 = crosses_square(hit, far, ds.occ_c, ds.occ_half, 2e-3f);
                int b2 = crosses_square(hit, far, ds.opaque_c, ds.opaque_half, 2e-3f);
                int blocked = b1 == 1 || b2 == 1 ? 1 : (b1 < 0 || b2 < 0 ? -1 : 0);
                unsure |= blocked < 0;
                if (blocked == 0)
                    want += e;
                else if (e > 0.0)
                    shadowed++;
            }
            if (unsure)
                continue;
            want *= 0.8 / PI_D;
            assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
            for (int c = 0; c < 3; c++) {
                if (!(fabs(p[RB_OUT_BEAUTY + c] - want) <= 2e-4 * want + 1e-7))
                    fail_msg("pixel %u,%u: %g, want %g", x, y, p[RB_OUT_BEAUTY + c], want);
                assert_true(p[RB_OUT_INDIRECT + c] == 0.0f);
                assert_true(p[RB_OUT_DIRECT + c] == p[RB_OUT_BEAUTY + c]);
                assert_true(fabsf(p[RB_OUT_ALBEDO + c] - 0.8f) < 1e-6f);
            }
            assert_true(fabsf(p[RB_OUT_NORMAL + 1] - 1.0f) < 1e-6f);
            float depth = -rb_mat4_point(&r.world_to_camera, hit).z;
            assert_true(fabsf(p[RB_OUT_DEPTH] - depth) < 1e-4f * depth);
            assert_true(fabsf(p[RB_OUT_MOTION]) < 1e-3f && fabsf(p[RB_OUT_MOTION + 1]) < 1e-3f);
            if (want > 0.0)
                lit++;
        }
    if (!(lit > 100 && shadowed > 3 && misses > 10 && opaque > 3))
        fail_msg("lit %u shadowed %u misses %u opaque %u", lit, shadowed, misses, opaque);
    free(px);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(ds.s);
}

static void test_direct_point(void **state)
{
    (void)state;
    struct test_light l = {.type = RB_LIGHT_POINT, .pos = {0, 1, 0}, .intensity = 2, .range = 2.5f};
    check_direct("[{type: point, position: [0, 1, 0], intensity: 2, range: 2.5}]", &l, 1);
}

static void test_direct_spot_directional(void **state)
{
    (void)state;
    struct test_light l[2] = {
        {.type = RB_LIGHT_SPOT,
         .pos = {0.2f, 1.2f, 0},
         .dir = {0, -1, 0},
         .intensity = 3,
         .inner_deg = 15,
         .outer_deg = 40},
        {.type = RB_LIGHT_DIRECTIONAL, .dir = {-0.6f, -0.8f, 0}, .intensity = 0.5f},
    };
    check_direct("[{type: spot, position: [0.2, 1.2, 0], direction: [0, -1, 0], intensity: 3, "
                 "inner_cone_deg: 15, outer_cone_deg: 40}, "
                 "{type: directional, direction: [-0.6, -0.8, 0], intensity: 0.5}]",
                 l, 2);
}

/* ---- area lights against Lambert's polygon formula ------------------------------------------ */

/* The irradiance at x (unit normal n) from a polygon (count corners, 3 doubles each) of
 * uniform radiance L wholly above x's horizon, in closed form (Lambert 1760):
 * E = L/2 sum_i angle(v_i, v_i+1) (n . unit(v_i x v_i+1)), with v_i = P_i - x; the winding
 * sets the sign, hence the absolute value. */
static double polygon_irradiance(const double *poly, int count, const double x[3],
                                 const double n[3], double radiance)
{
    double sum = 0.0;
    for (int i = 0; i < count; i++) {
        const double *a = poly + 3 * i, *b = poly + 3 * ((i + 1) % count);
        double va[3] = {a[0] - x[0], a[1] - x[1], a[2] - x[2]};
        double vb[3] = {b[0] - x[0], b[1] - x[1], b[2] - x[2]};
        double c[3] = {va[1] * vb[2] - va[2] * vb[1], va[2] * vb[0] - va[0] * vb[2],
                       va[0] * vb[1] - va[1] * vb[0]};
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double dot = va[0] * vb[0] + va[1] * vb[1] + va[2] * vb[2];
        if (len > 0.0) /* atan2: accurate for small angles too, unlike acos */
            sum += atan2(len, dot) * (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / len;
    }
    return 0.5 * radiance * fabs(sum);
}

static struct rb_scene_material lambert(float albedo)
{
    struct rb_scene_material m = material(albedo, albedo, albedo, 0, 1);
    m.specular_factor = 0.0f; /* pure Lambert */
    return m;
}

/* An emitter of radiance le that reflects nothing. */
static struct rb_scene_material lamp(float le)
{
    struct rb_scene_material m = lambert(0.0f);
    m.emissive[0] = m.emissive[1] = m.emissive[2] = le;
    return m;
}

/* As the Cornell box's: a Lambertian ceiling (albedo 0.8, 3 x 3 m, facing down) at y = 1 and an
 * emissive panel (0.7 x 0.6 m, radiance 5, black) hung CEIL_GAP below it; panel gets the
 * panel's corners as the renderer stores them. */
#define CEIL_Y 1.0f
#define CEIL_GAP 0.02f
#define PANEL_HX 0.35f
#define PANEL_HZ 0.3f
#define PANEL_LE 5.0f
static struct rb_scene *ceiling_scene(double panel[4][3])
{
    struct rb_scene *s = scene_new();
    add_quad(s, rb_v3(0, CEIL_Y, 0), rb_v3(1.5f, 0, 0), rb_v3(0, 0, 1.5f),
             add_material(s, lambert(0.8f)));
    add_quad(s, rb_v3(0, CEIL_Y - CEIL_GAP, 0), rb_v3(PANEL_HX, 0, 0), rb_v3(0, 0, PANEL_HZ),
             add_material(s, lamp(PANEL_LE)));
    scene_finish(s);
    static const float sx[4] = {-1, 1, 1, -1}, sz[4] = {-1, -1, 1, 1};
    for (int i = 0; i < 4; i++) {
        panel[i][0] = sx[i] * PANEL_HX;
        panel[i][1] = CEIL_Y - CEIL_GAP;
        panel[i][2] = sz[i] * PANEL_HZ;
    }
    return s;
}

/* The ceiling's radiance (0.8 / pi x E) at every pixel that sees it, seen from below beside the
 * panel, against the closed form. Shadow rays from there toward the panel run nearly parallel
 * to it: one aimed from the surface point but started off the surface passes the panel's plane
 * before its end, and the panel shadows its own light. Only direct light (max_bounces 0): the
 * ceiling is flat and the panel black, so there is no other. */
static void test_area_light_ceiling(void **state)
{
    (void)state;
    double panel[4][3];
    struct rb_scene *s = ceiling_scene(panel);
    struct rb_job *job = job_new(
        "resolution: [32, 24]\n"
        "frames: {start: 0, end: 0, rate: 24}\n"
        "camera: {fov_y_deg: 40, keys: [{t: 0, position: [0, 0, 1.2], look_at: [0, 1, 0]}]}\n"
        "integrator: {name: reference, reference: {spp: 128, max_bounces: 0}}\n");
    struct rb_reference *ref = ref_new(job, s, 2);
    struct stats st;
    frame_stats(ref, 16, &st);
    const double down[3] = {0, -1, 0};
    uint32_t checked = 0, near = 0, off = 0, on_panel = 0, low_x = 0, low_y = 0;
    double ratio_sum = 0.0, low = INFINITY, low_m = 0.0, low_want = 0.0;
    for (uint32_t y = 0; y < st.r.height_px; y++)
        for (uint32_t x = 0; x < st.r.width_px; x++) {
            struct rb_vec3 o, d;
            pixel_ray(&st.r, x, y, &o, &d);
            const float *p = px_at(st.first, &st.r, x, y);
            size_t i = ((size_t)y * st.r.width_px + x) * 3;
            if (!(d.y > 0.0f))
                continue;
            /* where the ray crosses the panel's plane, then the ceiling */
            double tp = (panel[0][1] - o.y) / d.y, tc = (CEIL_Y - o.y) / d.y;
            double px = o.x + tp * d.x, pz = o.z + tp * d.z;
            double h[3] = {o.x + tc * d.x, CEIL_Y, o.z + tc * d.z};
            double edge = fmax(fabs(px) - PANEL_HX, fabs(pz) - PANEL_HZ);
            if (edge < -1e-3) { /* the panel itself */
                for (int c = 0; c < 3; c++)
                    assert_true(p[RB_OUT_BEAUTY + c] == PANEL_LE);
                on_panel++;
                continue;
            }
            if (edge < 1e-3 || fmax(fabs(h[0]), fabs(h[2])) > 1.5 - 1e-3)
                continue;
            assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
            double want = 0.8 / PI_D * polygon_irradiance(&panel[0][0], 4, h, down, PANEL_LE);
            for (int c = 0; c < 3; c++)
                if (!(fabs(st.mean[i + c] - want) <= 5.0 * st.sem[i + c] + 0.03 * want))
                    off++;
            double ratio = st.mean[i] / want;
            ratio_sum += ratio;
            if (ratio < low)
                low = ratio, low_m = st.mean[i], low_want = want, low_x = x, low_y = y;
            checked++;
            if (fmax(fabs(h[0]) - PANEL_HX, fabs(h[2]) - PANEL_HZ) < 0.1)
                near++;
        }
    double mean_ratio = ratio_sum / checked;
    print_message("# ceiling beside the panel: %u pixels, mean ratio to the closed form %.4f, "
                  "lowest %.3f\n",
                  checked, mean_ratio, low);
    if (off || !(fabs(mean_ratio - 1.0) < 0.01) || checked < 300 || near < 20 || on_panel < 50)
        fail_msg("%u of %u ceiling pixels (%u within 0.1 m of the panel) off the closed form by "
                 "more than 5 standard errors + 3%%; mean ratio %g; lowest %g at pixel %u,%u "
                 "(%g, want %g); %u panel pixels",
                 off / 3, checked, near, mean_ratio, low, low_x, low_y, low_m, low_want, on_panel);
    stats_release(&st);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* rb_reference_bake: the panel's light on a floor 1 m below it, at points across the floor's two
 * triangles (by their world vertices), on both sides. The front (up, toward the panel) holds the
 * closed form's E / pi within 2% (Sobol light samples); the back sees nothing. The same bits with 1
 * and 3 threads; a triangle out of range is refused, and a reference made for baking renders no
 * frame. */
static void test_bake(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    add_quad(s, rb_v3(0, 0, 0), rb_v3(1, 0, 0), rb_v3(0, 0, -1), add_material(s, lambert(0.5f)));
    add_quad(s, rb_v3(0, 1, 0), rb_v3(PANEL_HX, 0, 0), rb_v3(0, 0, PANEL_HZ),
             add_material(s, lamp(PANEL_LE)));
    scene_finish(s);
    double panel[4][3];
    static const float sx[4] = {-1, 1, 1, -1}, sz[4] = {-1, -1, 1, 1};
    for (int i = 0; i < 4; i++) {
        panel[i][0] = sx[i] * PANEL_HX;
        panel[i][1] = 1.0;
        panel[i][2] = sz[i] * PANEL_HZ;
    }
    struct rb_job *job =
        job_new("resolution: [8, 8]\n"
                "frames: {start: 0, end: 0, rate: 24}\n"
                "camera: {keys: [{t: 0, position: [0, 0.5, 3], look_at: [0, 0.5, 0]}]}\n");
    enum { N = 2 * 2 * 15 };
    struct rb_reference_bake_point pts[N];
    /* the floor's corners: triangle 0 is (-1, 0, 1), (1, 0, 1), (1, 0, -1); 1 is the first,
     * the third and (-1, 0, -1) */
    static const double q[2][3][3] = {{{-1, 0, 1}, {1, 0, 1}, {1, 0, -1}},
                                      {{-1, 0, 1}, {1, 0, -1}, {-1, 0, -1}}};
    uint32_t n = 0;
    for (uint32_t t = 0; t < 2; t++)
        for (uint32_t k = 0; k < 15; k++)
            for (uint32_t side = 0; side < 2; side++) {
                float u = (float)(k % 5) / 5.0f + 0.05f, v = (float)(k / 5) / 4.0f + 0.05f;
                if (u + v > 0.95f)
                    u = 0.95f - v;
                pts[n++] = (struct rb_reference_bake_point){
                    .vertex = {0, t + 1, t + 2}, .u = u, .v = v, .is_back = side == 1};
            }
    float out1[N * 3], out3[N * 3];
    struct rb_err err = RB_ERR_INIT;
    struct rb_reference *ref1 = NULL, *ref3 = NULL;
    struct rb_reference_desc desc = {
        .job = job, .scene = s, .thread_count = 1, .is_bake_only = true};
    assert_int_equal(rb_reference_create(&desc, &ref1, &err), RB_OK);
    desc.thread_count = 3;
    assert_int_equal(rb_reference_create(&desc, &ref3, &err), RB_OK);
    uint64_t rays = 0;
    assert_int_equal(rb_reference_bake(ref1, 0, pts, N, 1024, out1, &rays, &err), RB_OK);
    assert_int_equal(rb_reference_bake(ref3, 0, pts, N, 1024, out3, NULL, &err), RB_OK);
    assert_memory_equal(out1, out3, sizeof(out1));
    assert_true(rays > 0);
    const double up[3] = {0, 1, 0};
    double worst = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        const double(*c)[3] = q[pts[i].vertex[1] - 1];
        double b0 = 1.0 - pts[i].u - pts[i].v, x[3];
        for (int a = 0; a < 3; a++)
            x[a] = b0 * c[0][a] + pts[i].u * c[1][a] + pts[i].v * c[2][a];
        double want =
            pts[i].is_back ? 0.0 : polygon_irradiance(&panel[0][0], 4, x, up, PANEL_LE) / PI_D;
        for (int a = 0; a < 3; a++) {
            double got = out1[i * 3 + a];
            if (pts[i].is_back)
                assert_true(got == 0.0);
            else
                worst = fmax(worst, fabs(got / want - 1.0));
        }
    }
    print_message("# baked floor: worst relative error %.4f against the closed form\n", worst);
    assert_true(worst < 0.02);
    pts[0].vertex[2] = 8;
    assert_int_equal(rb_reference_bake(ref1, 0, pts, N, 4, out1, NULL, &err), RB_E_INVALID);
    assert_non_null(strstr(err.msg, "vertex 8 of 8"));
    struct rb_frame_result res;
    assert_int_equal(rb_reference_render(ref1, 0, &res, &err), RB_E_INVALID);
    rb_reference_destroy(ref1);
    rb_reference_destroy(ref3);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* ---- materials, textures, back faces and skins (DIRECT: no noise) ---------------------------- */

static double srgb(uint8_t c)
{
    double x = c / 255.0;
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* Bilinear with repeat at the texture's own resolution, sRGB decoded per texel first. */
static double tex_srgb(const uint8_t *rgba, int w, int h, double u, double v, int c)
{
    double x = u * w - 0.5, y = v * h - 0.5, fx = floor(x), fy = floor(y), acc = 0.0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            int xi = (((int)fx + i) % w + w) % w, yi = (((int)fy + j) % h + h) % h;
            double wgt = (i ? x - fx : 1 - (x - fx)) * (j ? y - fy : 1 - (y - fy));
            acc += wgt * srgb(rgba[(yi * w + xi) * 4 + c]);
        }
    return acc;
}

/* Six 0.7 m quads in the plane z = 0, seen from +Z, in a 3 x 2 grid (centre cx[i], cy[i]). */
static const float grid_x[6] = {-0.85f, 0.0f, 0.85f, -0.85f, 0.0f, 0.85f};
static const float grid_y[6] = {0.45f, 0.45f, 0.45f, -0.45f, -0.45f, -0.45f};
#define GRID_HALF 0.35f

static void test_materials(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    static const uint8_t base_tex[2 * 2 * 4] = {255, 0, 0,   255, 0,   255, 0,   255,
                                                0,   0, 255, 255, 128, 128, 128, 255};
    static const uint8_t mr_tex[4] = {0, 128, 64, 255};
    static const uint8_t normal_tex[4] = {204, 140, 230, 255};
    static const uint8_t emissive_tex[4] = {64, 128, 255, 255};
    uint32_t t_base = add_texture(s, 2, 2, base_tex), t_mr = add_texture(s, 1, 1, mr_tex);
    uint32_t t_n = add_texture(s, 1, 1, normal_tex), t_e = add_texture(s, 1, 1, emissive_tex);
    struct rb_vec3 u = rb_v3(GRID_HALF, 0, 0), v = rb_v3(0, GRID_HALF, 0);
    /* 0: base colour and metallic-roughness textures */
    struct rb_scene_material m0 = material(1, 1, 1, 1, 1);
    m0.base_color_tex = t_base;
    m0.metallic_roughness_tex = t_mr;
    add_quad(s, rb_v3(grid_x[0], grid_y[0], 0), u, v, add_material(s, m0));
    /* 1: a normal map with normal_scale 0.5 */
    struct rb_scene_material m1 = material(0.5f, 0.5f, 0.5f, 0, 1);
    m1.normal_tex = t_n;
    m1.normal_scale = 0.5f;
    add_quad(s, rb_v3(grid_x[1], grid_y[1], 0), u, v, add_material(s, m1));
    /* 2: emission only (factor x sRGB texture) */
    struct rb_scene_material m2 = material(0, 0, 0, 0, 1);
    m2.specular_factor = 0.0f;
    m2.emissive[0] = m2.emissive[1] = m2.emissive[2] = 2.0f;
    m2.emissive_tex = t_e;
    add_quad(s, rb_v3(grid_x[2], grid_y[2], 0), u, v, add_material(s, m2));
    /* 3: KHR_materials_specular */
    struct rb_scene_material m3 = material(0.5f, 0.5f, 0.5f, 0, 0.4f);
    m3.specular_factor = 0.7f;
    m3.specular_color[0] = 1.5f, m3.specular_color[1] = 0.5f, m3.specular_color[2] = 30.0f;
    add_quad(s, rb_v3(grid_x[3], grid_y[3], 0), u, v, add_material(s, m3));
    /* 4: double-sided, seen from the back (its front faces -Z) */
    struct rb_scene_material m4 = material(0.6f, 0.6f, 0.6f, 0, 1);
    m4.specular_factor = 0.0f;
    m4.double_sided = true;
    add_quad(s, rb_v3(grid_x[4], grid_y[4], 0), v, u, add_material(s, m4));
    /* 5: vertex normals tilted 40 degrees toward +X from the face's +Z */
    struct rb_scene_material m5 = m4;
    m5.double_sided = false;
    uint32_t n5 = add_quad(s, rb_v3(grid_x[5], grid_y[5], 0), u, v, add_material(s, m5));
    const struct rb_scene_primitive *p5 =
        &s->primitives[s->meshes[s->nodes[n5].mesh].first_primitive];
    float tilt = 40.0f * RB_PI / 180.0f;
    for (uint32_t i = 0; i < p5->vertex_count; i++) {
        float *nn = s->vertices[p5->first_vertex + i].normal;
        nn[0] = sinf(tilt), nn[1] = 0.0f, nn[2] = cosf(tilt);
    }
    scene_finish(s);
    /* A point light in front; a directional light from behind the plane at a grazing angle,
     * above quad 5's shading hemisphere but below its face, so it must add nothing. */
    struct rb_vec3 lp = rb_v3(0.3f, 0.2f, 1.5f);
    struct rb_job *job =
        job_new("resolution: [48, 40]\n"
                "frames: {start: 0, end: 0, rate: 24}\n"
                "camera: {fov_y_deg: 50, keys: [{t: 0, position: [0, 0, 3], look_at: [0, 0, 0]}]}\n"
                "lights: [{type: point, position: [0.3, 0.2, 1.5], intensity: 1}, "
                "{type: directional, direction: [-0.9, 0, 0.2], intensity: 5}]\n"
                "integrator: {name: reference, reference: {spp: 1, paths: direct}}\n");
    struct rb_reference *ref = ref_new(job, s, 2);
    struct rb_frame_result r;
    float *px = render(ref, 0, &r);
    uint32_t seen[6] = {0};
    for (uint32_t y = 0; y < r.height_px; y++)
        for (uint32_t x = 0; x < r.width_px; x++) {
            const float *p = px_at(px, &r, x, y);
            struct rb_vec3 o, d;
            pixel_ray(&r, x, y, &o, &d);
            struct rb_vec3 h = rb_v3_add(o, rb_v3_scale(d, -o.z / d.z));
            int q = -1;
            float su = 0, sv = 0;
            for (int i = 0; i < 6; i++) {
                su = (h.x - grid_x[i]) / GRID_HALF, sv = (h.y - grid_y[i]) / GRID_HALF;
                if (fabsf(su) < 0.98f && fabsf(sv) < 0.98f) {
                    q = i;
                    break;
                }
            }
            if (q < 0)
                continue;
            seen[q]++;
            assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
            const float *n = p + RB_OUT_NORMAL, *alb = p + RB_OUT_ALBEDO, *L = p + RB_OUT_BEAUTY;
            struct rb_vec3 vv = rb_v3_normalize(rb_v3_sub(o, h));
            struct rb_vec3 l = rb_v3_sub(lp, h);
            float d2 = rb_v3_dot(l, l);
            l = rb_v3_normalize(l);
            double tu = 0.5 + 0.5 * su, tv = 0.5 - 0.5 * sv; /* add_quad's texture coordinates */
            if (q == 0) {
                double metallic = 64.0 / 255.0;
                for (int c = 0; c < 3; c++) {
                    double want = tex_srgb(base_tex, 2, 2, tu, tv, c) * (1.0 - metallic);
                    if (!(fabs(alb[c] - want) < 2e-5))
                        fail_msg("base colour texture at %g,%g: %g, want %g", tu, tv, alb[c], want);
                }
            } else if (q == 1) {
                double tn[3] = {(204 / 255.0 * 2 - 1) * 0.5, (140 / 255.0 * 2 - 1) * 0.5,
                                230 / 255.0 * 2 - 1};
                double len = sqrt(tn[0] * tn[0] + tn[1] * tn[1] + tn[2] * tn[2]);
                for (int c = 0; c < 3; c++)
                    if (!(fabs(n[c] - tn[c] / len) < 1e-5)) /* tangent +X, bitangent +Y */
                        fail_msg("normal map: %g %g %g", n[0], n[1], n[2]);
            } else if (q == 2) {
                for (int c = 0; c < 3; c++)
                    assert_true(fabs(L[c] - 2.0 * srgb(emissive_tex[c])) < 1e-5);
            } else if (q == 3) {
                float f0[3], f[3], c_diff[3] = {0.5f, 0.5f, 0.5f};
                for (int c = 0; c < 3; c++)
                    f0[c] = fminf(0.04f * m3.specular_color[c], 1.0f) * 0.7f;
                rb_reference_brdf((float[3]){0, 0, 1}, (float[3]){vv.x, vv.y, vv.z},
                                  (float[3]){l.x, l.y, l.z}, c_diff, f0, 0.7f, 0.4f, f);
                for (int c = 0; c < 3; c++) {
                    double want = f[c] * l.z / d2;
                    if (!(fabs(L[c] - want) < 1e-4 * want))
                        fail_msg("specular extension: %g, want %g", L[c], want);
                }
                assert_true(f0[2] > f0[0] && f0[0] > f0[1]); /* the clamp shows */
            } else {
                struct rb_vec3 nn = q == 4 ? rb_v3(0, 0, 1) : rb_v3(sinf(tilt), 0, cosf(tilt));
                double want = 0.6 / PI_D * fmax(rb_v3_dot(nn, l), 0.0) / d2;
                for (int c = 0; c < 3; c++)
                    if (!(fabs(L[c] - want) < 1e-4 * want))
                        fail_msg("quad %d: %g, want %g", q, L[c], want);
                if (!(fabsf(n[0] - nn.x) < 1e-5f && fabsf(n[2] - nn.z) < 1e-5f))
                    fail_msg("quad %d: normal %g %g %g", q, n[0], n[1], n[2]);
            }
        }
    for (int i = 0; i < 6; i++)
        if (seen[i] < 20)
            fail_msg("quad %d covers only %u pixels", i, seen[i]);
    free(px);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* A quad skinned to two joints that carry the same transform (a stretch along X, a turn about
 * +Y, a shift); one pair of vertices has weights (0.5, 0) and the other (0.3, 0.7), so the
 * weight sum's normalization matters. The quad must come out rigidly transformed, and its
 * tilted vertex normals through the inverse transpose; and so must the same quad unskinned
 * under a node with that transform. */
static void test_skin(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    struct rb_scene_material m = material(0.5f, 0.5f, 0.5f, 0, 1);
    uint32_t node =
        add_quad(s, rb_v3(0, 0, 0), rb_v3(0.5f, 0, 0), rb_v3(0, 0.5f, 0), add_material(s, m));
    const struct rb_scene_primitive *pr = &s->primitives[0];
    for (uint32_t i = 0; i < pr->vertex_count; i++) {
        struct rb_scene_vertex *vx = &s->vertices[pr->first_vertex + i];
        bool top = vx->position[1] > 0.0f;
        vx->joints[0] = 0;
        vx->joints[1] = 1;
        vx->weights[0] = top ? 0.3f : 0.5f;
        vx->weights[1] = top ? 0.7f : 0.0f;
        vx->normal[0] = 0.6f, vx->normal[1] = 0.0f, vx->normal[2] = 0.8f;
    }
    float ang = 30.0f * RB_PI / 180.0f;
    struct rb_quat rot = {0, sinf(ang / 2), 0, cosf(ang / 2)};
    struct rb_vec3 shift = rb_v3(0.3f, 0.1f, 0), stretch = rb_v3(1.4f, 1, 1);
    for (int j = 0; j < 2; j++) {
        s->nodes = grow(s->nodes, s->node_count + 1, sizeof(*s->nodes));
        s->nodes[s->node_count++] = (struct rb_scene_node){.parent = NONE,
                                                           .translation = shift,
                                                           .rotation = rot,
                                                           .scale = stretch,
                                                           .mesh = NONE,
                                                           .skin = NONE,
                                                           .camera = NONE,
                                                           .light = NONE,
                                                           .in_scene = true};
    }
    s->skins = calloc(1, sizeof(*s->skins));
    assert_non_null(s->skins);
    s->skin_count = 1;
    s->skins[0].joint_count = 2;
    s->skins[0].joints = malloc(2 * sizeof(uint32_t));
    s->skins[0].inverse_bind = malloc(2 * sizeof(struct rb_mat4));
    assert_non_null(s->skins[0].joints);
    assert_non_null(s->skins[0].inverse_bind);
    s->skins[0].joints[0] = node + 1;
    s->skins[0].joints[1] = node + 2;
    s->skins[0].inverse_bind[0] = s->skins[0].inverse_bind[1] = rb_mat4_identity();
    s->nodes[node].skin = 0;
    scene_finish(s);
    struct rb_job *job =
        job_new("resolution: [32, 32]\n"
                "frames: {start: 0, end: 0, rate: 24}\n"
                "camera: {fov_y_deg: 50, near: 0.1, far: 10, keys: [{t: 0, position: [0, 0, 3], "
                "look_at: [0, 0, 0]}]}\n"
                "lights: [{type: point, position: [0, 0, 3], intensity: 1}]\n"
                "integrator: {name: reference, reference: {spp: 1, paths: direct}}\n");
    struct rb_mat4 T = rb_mat4_trs(shift, rot, stretch), inv = rb_mat4_inverse(&T, NULL);
    /* the skinned quad, then the same quad unskinned under a node with the joints' transform */
    for (int variant = 0; variant < 2; variant++) {
        if (variant == 1) {
            for (uint32_t i = 0; i < pr->vertex_count; i++)
                memset(s->vertices[pr->first_vertex + i].weights, 0, 4 * sizeof(float));
            s->nodes[node].skin = NONE;
            s->nodes[node].translation = shift;
            s->nodes[node].rotation = rot;
            s->nodes[node].scale = stretch;
        }
        struct rb_reference *ref = ref_new(job, s, 1);
        struct rb_frame_result r;
        float *px = render(ref, 0, &r);
        struct rb_vec3 c = rb_mat4_point(&T, rb_v3(0, 0, 0)), nz = rb_mat4_dir(&T, rb_v3(0, 0, 1));
        /* normals: (R S)^-T n = R S^-1 n */
        struct rb_vec3 want_n =
            rb_v3_normalize(rb_quat_rotate(rot, rb_v3(0.6f / stretch.x, 0.0f, 0.8f / stretch.z)));
        uint32_t in = 0, out = 0;
        for (uint32_t y = 0; y < r.height_px; y++)
            for (uint32_t x = 0; x < r.width_px; x++) {
                const float *p = px_at(px, &r, x, y);
                struct rb_vec3 o, d;
                pixel_ray(&r, x, y, &o, &d);
                float t = rb_v3_dot(rb_v3_sub(c, o), nz) / rb_v3_dot(d, nz);
                struct rb_vec3 h = rb_v3_add(o, rb_v3_scale(d, t));
                struct rb_vec3 hl = rb_mat4_point(&inv, h);
                float m2 = fmaxf(fabsf(hl.x), fabsf(hl.y)) / 0.5f;
                if (m2 < 0.97f) {
                    assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
                    float depth = -rb_mat4_point(&r.world_to_camera, h).z;
                    const float *n = p + RB_OUT_NORMAL;
                    if (!(fabsf(p[RB_OUT_DEPTH] - depth) < 1e-4f &&
                          fabsf(n[0] - want_n.x) < 1e-5f && fabsf(n[1] - want_n.y) < 1e-5f &&
                          fabsf(n[2] - want_n.z) < 1e-5f))
                        fail_msg("pixel %u,%u: depth %g (want %g), normal %g %g %g (want %g %g %g)",
                                 x, y, p[RB_OUT_DEPTH], depth, n[0], n[1], n[2], want_n.x, want_n.y,
                                 want_n.z);
                    in++;
                } else if (m2 > 1.03f) {
                    assert_true(p[RB_OUT_BEAUTY + 3] == 0.0f);
                    out++;
                }
            }
        assert_true(in > 100 && out > 100);
        free(px);
        rb_reference_destroy(ref);
    }
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* ---- animation: motion vectors and morph targets -------------------------------------------- */

static void test_motion_and_morph(void **state)
{
    (void)state;
    /* A wall at z = 0 that moves +X at 1 m/s, and a small morphed quad in front of it whose
     * target pushes it 0.5 m toward the camera (weight 1). */
    struct rb_scene *s = scene_new();
    uint32_t mat = add_material(s, material(0.5f, 0.5f, 0.5f, 0, 1));
    uint32_t wall = add_quad(s, rb_v3(0, 0, 0), rb_v3(1.5f, 0, 0), rb_v3(0, 1.5f, 0), mat);
    add_quad(s, rb_v3(0, 0, 0.5f), rb_v3(0.15f, 0, 0), rb_v3(0, 0.15f, 0), mat);
    struct rb_scene_primitive *pr = &s->primitives[1];
    pr->first_morph = 0;
    pr->morph_target_count = 1;
    s->morph_deltas = calloc(4, sizeof(*s->morph_deltas));
    assert_non_null(s->morph_deltas);
    s->morph_delta_count = 4;
    for (int i = 0; i < 4; i++)
        s->morph_deltas[i].position[2] = 0.5f;
    s->meshes[1].default_weights = malloc(sizeof(float));
    assert_non_null(s->meshes[1].default_weights);
    s->meshes[1].default_weights[0] = 1.0f;
    s->meshes[1].weight_count = 1;
    s->animations = calloc(1, sizeof(*s->animations));
    assert_non_null(s->animations);
    struct rb_scene_animation *a = &s->animations[0];
    s->animation_count = 1;
    a->samplers = calloc(1, sizeof(*a->samplers));
    a->channels = calloc(1, sizeof(*a->channels));
    assert_non_null(a->samplers);
    assert_non_null(a->channels);
    a->sampler_count = a->channel_count = 1;
    a->duration_s = 10.0f;
    a->samplers[0].times = malloc(2 * sizeof(float));
    a->samplers[0].values = malloc(6 * sizeof(float));
    assert_non_null(a->samplers[0].times);
    assert_non_null(a->samplers[0].values);
    memcpy(a->samplers[0].times, (float[2]){0, 10}, 2 * sizeof(float));
    memcpy(a->samplers[0].values, (float[6]){0, 0, 0, 10, 0, 0}, 6 * sizeof(float));
    a->samplers[0].key_count = 2;
    a->samplers[0].components = 3;
    a->channels[0] =
        (struct rb_scene_anim_channel){.sampler = 0, .node = wall, .path = RB_ANIM_TRANSLATION};
    scene_finish(s);

    struct rb_job *job =
        job_new("resolution: [32, 32]\n"
                "frames: {start: 0, end: 30, rate: 24}\n"
                "camera: {fov_y_deg: 50, near: 0.1, far: 20, keys: [{t: 0, position: [0, 0, 3], "
                "look_at: [0, 0, 0]}]}\n"
                "lights: [{type: point, position: [0, 0, 3], intensity: 1}]\n"
                "integrator: {name: reference, reference: {spp: 1, paths: direct}}\n");
    struct rb_reference *ref = ref_new(job, s, 1);
    struct rb_frame_result r;
    float *px = render(ref, 12, &r);
    const float dx = 1.0f / 24.0f; /* the wall's move since frame 11 */
    uint32_t moving = 0, morphed = 0;
    for (uint32_t y = 0; y < r.height_px; y++)
        for (uint32_t x = 0; x < r.width_px; x++) {
            const float *p = px_at(px, &r, x, y);
            struct rb_vec3 o, d;
            pixel_ray(&r, x, y, &o, &d);
            /* the morphed quad now sits at z = 1 */
            float tq = (1.0f - o.z) / d.z;
            struct rb_vec3 q = rb_v3_add(o, rb_v3_scale(d, tq));
            if (fmaxf(fabsf(q.x), fabsf(q.y)) < 0.15f - 1e-3f) {
                assert_true(fabsf(p[RB_OUT_DEPTH] - 2.0f) < 1e-4f);
                assert_true(fabsf(p[RB_OUT_MOTION]) < 1e-3f);
                morphed++;
                continue;
            }
            if (fmaxf(fabsf(q.x), fabsf(q.y)) < 0.15f + 1e-3f)
                continue;
            float t = -o.z / d.z;
            struct rb_vec3 h = rb_v3_add(o, rb_v3_scale(d, t));
            float wall_x = 0.5f; /* 12 / 24 s at 1 m/s */
            if (fabsf(h.x - wall_x) > 1.5f - 1e-3f || fabsf(h.y) > 1.5f - 1e-3f ||
                fabsf(h.x - wall_x + dx) > 1.5f - 1e-3f)
                continue;
            assert_true(p[RB_OUT_BEAUTY + 3] == 1.0f);
            assert_true(fabsf(p[RB_OUT_DEPTH] - 3.0f) < 1e-4f);
            /* where this point was a frame ago, through the (static) camera */
            struct rb_vec3 prev = rb_v3(h.x - dx, h.y, h.z);
            struct rb_vec4 c0 = rb_mat4_vec4(&r.world_to_ndc, (struct rb_vec4){h.x, h.y, h.z, 1});
            struct rb_vec4 c1 =
                rb_mat4_vec4(&r.world_to_ndc, (struct rb_vec4){prev.x, prev.y, prev.z, 1});
            float mx = (c1.x / c1.w - c0.x / c0.w) * 0.5f * (float)r.width_px;
            float my = (c1.y / c1.w - c0.y / c0.w) * 0.5f * (float)r.height_px;
            if (!(fabsf(p[RB_OUT_MOTION] - mx) < 2e-3f && fabsf(p[RB_OUT_MOTION + 1] - my) < 2e-3f))
                fail_msg("pixel %u,%u: motion %g,%g, want %g,%g", x, y, p[RB_OUT_MOTION],
                         p[RB_OUT_MOTION + 1], mx, my);
            assert_true(mx < -0.1f);
            moving++;
        }
    if (!(moving > 100 && morphed > 2))
        fail_msg("moving %u morphed %u", moving, morphed);
    free(px);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* ---- the pixel filter ----------------------------------------------------------------------- */

/* A 1.2 x 0.8 m rectangle turned 30 degrees about the view axis before a uniform sky, in the
 * direct path space (no noise on the surface): under center every sample takes the pixel
 * centre's ray; under box each its own point of the pixel, so edge pixels are partly covered.
 * Their alpha is checked against the coverage of a 64 x 64 grid of rays over the pixel. */
static void test_pixel_filter(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    const float ang = 30.0f * RB_PI / 180.0f;
    struct rb_vec3 u = rb_v3(0.6f * cosf(ang), 0.6f * sinf(ang), 0);
    struct rb_vec3 v = rb_v3(-0.4f * sinf(ang), 0.4f * cosf(ang), 0);
    add_quad(s, rb_v3(0, 0, 0), u, v, add_material(s, lambert(0.5f)));
    scene_finish(s);
    const char *fmt = "resolution: [32, 24]\n"
                      "frames: {start: 0, end: 0, rate: 24}\n"
                      "camera: {fov_y_deg: 40, keys: [{t: 0, position: [0.1, 0.2, 3], "
                      "look_at: [0, 0, 0]}]}\n"
                      "lights: [{type: point, position: [0.5, 0.5, 2], intensity: 2}]\n"
                      "environment: {color: [0.2, 0.3, 0.4], intensity: 1}\n"
                      "integrator: {name: reference, reference: {spp: 256, paths: direct%s}}\n";
    struct rb_job *jc = job_new(fmt, ""), *jb = job_new(fmt, ", pixel_filter: box");
    assert_int_equal(jc->integrator.reference.pixel_filter, RB_PIXEL_FILTER_CENTER);
    assert_int_equal(jb->integrator.reference.pixel_filter, RB_PIXEL_FILTER_BOX);
    assert_true(jc->hash != jb->hash);
    struct rb_reference *rc = ref_new(jc, s, 2), *rb1 = ref_new(jb, s, 1);
    struct rb_reference *rb2 = ref_new(jb, s, 2), *rb3 = ref_new(jb, s, 3);
    struct rb_frame_result r;
    float *pc = render(rc, 0, &r), *pb = render(rb1, 0, &r);
    float *pb2 = render(rb2, 0, &r), *pb3 = render(rb3, 0, &r);
    size_t n = (size_t)r.width_px * r.height_px;
    /* deterministic whatever the threads */
    assert_memory_equal(pb, pb2, n * RB_OUT_FLOATS * sizeof(float));
    assert_memory_equal(pb, pb3, n * RB_OUT_FLOATS * sizeof(float));
    float ulen = rb_v3_length(u), vlen = rb_v3_length(v);
    struct rb_vec3 uh = rb_v3_scale(u, 1.0f / ulen), vh = rb_v3_scale(v, 1.0f / vlen);
    uint32_t edge = 0, inside = 0, outside = 0;
    double worst = 0.0;
    for (uint32_t y = 0; y < r.height_px; y++)
        for (uint32_t x = 0; x < r.width_px; x++) {
            const float *c = px_at(pc, &r, x, y), *b = px_at(pb, &r, x, y);
            /* the AOVs are the centre ray's under either filter */
            assert_memory_equal(c + RB_OUT_ALBEDO, b + RB_OUT_ALBEDO,
                                (RB_OUT_MOTION + 2 - RB_OUT_ALBEDO) * sizeof(float));
            assert_true(c[RB_OUT_BEAUTY + 3] == 0.0f || c[RB_OUT_BEAUTY + 3] == 1.0f);
            enum { G = 64 };
            uint32_t hits = 0;
            for (int j = 0; j < G; j++)
                for (int i = 0; i < G; i++) {
                    struct rb_vec3 o, d;
                    image_ray(&r, (float)x + (i + 0.5f) / G, (float)y + (j + 0.5f) / G, &o, &d);
                    struct rb_vec3 h = rb_v3_add(o, rb_v3_scale(d, -o.z / d.z));
                    hits += fabsf(rb_v3_dot(h, uh)) < ulen && fabsf(rb_v3_dot(h, vh)) < vlen;
                }
            double cover = (double)hits / (G * G), alpha = b[RB_OUT_BEAUTY + 3];
            worst = fmax(worst, fabs(alpha - cover));
            if (!(fabs(alpha - cover) <= 0.05))
                fail_msg("pixel %u,%u: alpha %g, covered %g", x, y, alpha, cover);
            if (alpha > 0.0 && alpha < 1.0) {
                edge++;
                continue;
            }
            /* wholly in or out: the same surface or sky as the centre's ray */
            if (alpha == 1.0) {
                assert_true(c[RB_OUT_BEAUTY + 3] == 1.0f);
                for (int k = 0; k < 3; k++)
                    assert_true(fabsf(b[RB_OUT_BEAUTY + k] - c[RB_OUT_BEAUTY + k]) <=
                                0.03f * c[RB_OUT_BEAUTY + k]);
                inside++;
            } else {
                assert_true(c[RB_OUT_BEAUTY + 3] == 0.0f);
                assert_memory_equal(b, c, 10 * sizeof(float)); /* beauty, direct, indirect */
                outside++;
            }
        }
    print_message("# box filter: %u edge pixels, alpha within %.3f of the coverage\n", edge, worst);
    if (!(edge > 40 && inside > 50 && outside > 200))
        fail_msg("edge %u inside %u outside %u", edge, inside, outside);
    free(pb3);
    free(pb2);
    free(pb);
    free(pc);
    rb_reference_destroy(rb3);
    rb_reference_destroy(rb2);
    rb_reference_destroy(rb1);
    rb_reference_destroy(rc);
    rb_job_destroy(jb);
    rb_job_destroy(jc);
    rb_scene_destroy(s);
}

/* ---- determinism, convergence, passes ------------------------------------------------------- */

/* Spheres on a floor before a red wall: a point light, an emissive panel on the wall, a
 * blue-ish sky, a glossy metal sphere; every kind of light and both lobes. */
static struct rb_scene *busy_scene(void)
{
    struct rb_scene *s = scene_new();
    uint32_t white = add_material(s, material(0.7f, 0.7f, 0.7f, 0, 0.8f));
    uint32_t red = add_material(s, material(0.7f, 0.1f, 0.1f, 0, 0.5f));
    uint32_t metal = add_material(s, material(0.9f, 0.8f, 0.5f, 1, 0.3f));
    struct rb_scene_material lamp = material(0, 0, 0, 0, 1);
    lamp.emissive[0] = 4, lamp.emissive[1] = 3.5f, lamp.emissive[2] = 3;
    lamp.double_sided = true;
    add_quad(s, rb_v3(0, 0, 0), rb_v3(2, 0, 0), rb_v3(0, 0, -2), white);
    add_quad(s, rb_v3(0, 1, -1), rb_v3(2, 0, 0), rb_v3(0, 1, 0), red);
    add_quad(s, rb_v3(0.6f, 1.2f, -0.98f), rb_v3(0.3f, 0, 0), rb_v3(0, 0.3f, 0),
             add_material(s, lamp));
    add_sphere(s, rb_v3(-0.2f, 0.4f, 0), 0.4f, 12, 16, metal);
    add_sphere(s, rb_v3(0.5f, 0.25f, 0.4f), 0.25f, 10, 12, white);
    scene_finish(s);
    return s;
}

#define BUSY_JOB_WITH(filter)                                                                      \
    "resolution: [%d, %d]\n"                                                                       \
    "frames: {start: 0, end: 1, rate: 24}\n"                                                       \
    "camera: {fov_y_deg: 50, keys: [{t: 0, position: [0.3, 1.1, 2.6], look_at: [0, 0.4, 0]}]}\n"   \
    "lights: [{type: point, position: [-0.8, 1.5, 0.8], intensity: 1.5}]\n"                        \
    "environment: {color: [0.3, 0.4, 0.6], intensity: 1}\n"                                        \
    "integrator: {name: reference, reference: {spp: %d, max_bounces: 6, rr_depth: 2, "             \
    "pixel_filter: " filter "}}\n"
#define BUSY_JOB BUSY_JOB_WITH("center")
#define BUSY_JOB_BOX BUSY_JOB_WITH("box")

static void test_determinism(void **state)
{
    (void)state;
    struct rb_scene *s = busy_scene();
    struct rb_job *job = job_new(BUSY_JOB, 32, 24, 8);
    struct rb_frame_result r1, r2, r3;
    struct rb_reference *a = ref_new(job, s, 1), *b = ref_new(job, s, 2);
    float *p1 = render(a, 1, &r1), *p2 = render(b, 1, &r2);
    free(render(b, 0, &r3)); /* another frame in between changes nothing */
    free(render(b, 1, &r3));
    struct rb_reference *c = ref_new(job, s, 3);
    float *p3 = render(c, 1, &r3);
    size_t bytes = (size_t)r1.width_px * r1.height_px * RB_OUT_FLOATS * sizeof(float);
    assert_memory_equal(p1, p2, bytes);
    assert_memory_equal(p1, p3, bytes);
    assert_true(r1.ray_count == r2.ray_count && r1.ray_count == r3.ray_count);
    assert_true(r1.ray_count > (uint64_t)r1.width_px * r1.height_px * 8);
    assert_int_equal(r1.spp, 8);
    /* and the frame number changes the noise */
    struct rb_frame_result r0;
    float *p0 = render(a, 0, &r0);
    assert_true(memcmp(p0, p1, bytes) != 0);
    free(p0);
    /* the box filter's samples through the pixel too */
    struct rb_job *jb = job_new(BUSY_JOB_BOX, 32, 24, 8);
    struct rb_reference *d1 = ref_new(jb, s, 1), *d3 = ref_new(jb, s, 3);
    float *b1 = render(d1, 1, &r0), *b3 = render(d3, 1, &r0);
    assert_memory_equal(b1, b3, bytes);
    assert_true(memcmp(b1, p1, bytes) != 0);
    free(b3);
    free(b1);
    rb_reference_destroy(d3);
    rb_reference_destroy(d1);
    rb_job_destroy(jb);
    free(p1);
    free(p2);
    free(p3);
    rb_reference_destroy(c);
    rb_reference_destroy(b);
    rb_reference_destroy(a);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* The indirect light split by the lobe of x1 that reflects it: the parts add up to indirect, and
 * each lobe carries light where its surfaces have it (the metal sphere no diffuse, the
 * dielectrics' 4% Fresnel some specular). */
static void test_indirect_lobes(void **state)
{
    (void)state;
    struct rb_scene *s = busy_scene();
    struct rb_job *job = job_new(BUSY_JOB, 32, 24, 8);
    struct rb_reference *ref = ref_new(job, s, 2);
    struct rb_frame_result r;
    float *px = render(ref, 0, &r);
    size_t n = (size_t)r.width_px * r.height_px, metal = 0, glossy = 0;
    for (size_t i = 0; i < n; i++) {
        const float *p = px + i * RB_OUT_FLOATS;
        for (int c = 0; c < 3; c++) {
            float d = p[RB_OUT_INDIRECT_DIFFUSE + c], sp = p[RB_OUT_INDIRECT_SPECULAR + c];
            float ind = p[RB_OUT_INDIRECT + c];
            if (!(d >= 0.0f && sp >= 0.0f && fabsf(d + sp - ind) <= 1e-5f * ind))
                fail_msg("pixel %zu channel %d: %g + %g, indirect %g", i, c, d, sp, ind);
        }
        bool is_black = p[RB_OUT_BEAUTY + 3] == 1.0f && p[RB_OUT_ALBEDO] == 0.0f &&
                        p[RB_OUT_ALBEDO + 1] == 0.0f && p[RB_OUT_ALBEDO + 2] == 0.0f;
        if (is_black) { /* the metal sphere (and the lamp): no diffuse lobe */
            assert_true(p[RB_OUT_INDIRECT_DIFFUSE + 1] == 0.0f);
            metal += p[RB_OUT_INDIRECT_SPECULAR + 1] > 0.0f;
        } else if (p[RB_OUT_ALBEDO + 1] > 0.0f) {
            glossy +=
                p[RB_OUT_INDIRECT_SPECULAR + 1] > 0.0f && p[RB_OUT_INDIRECT_DIFFUSE + 1] > 0.0f;
        }
    }
    if (!(metal > 10 && glossy > 10))
        fail_msg("%zu metal pixels with specular indirect light, %zu dielectric ones with both",
                 metal, glossy);
    free(px);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

static double rmse(const float *a, const float *b, const struct rb_frame_result *r)
{
    double sum = 0.0;
    size_t n = (size_t)r->width_px * r->height_px;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double d = a[i * RB_OUT_FLOATS + c] - b[i * RB_OUT_FLOATS + c];
            sum += d * d;
        }
    return sqrt(sum / (3.0 * n));
}

/* With independent (hashed) random numbers the reference is plain Monte Carlo, whose error
 * falls as 1/sqrt(spp) on any integrand: this checks that the samples are independent and the
 * estimator's variance finite, on a scene with every kind of light and path. */
static void test_convergence(void **state)
{
    (void)state;
    struct rb_scene *s = busy_scene();
    struct rb_job *j16 = job_new(BUSY_JOB, 24, 24, 16), *j64 = job_new(BUSY_JOB, 24, 24, 64);
    struct rb_job *j1k = job_new(BUSY_JOB, 24, 24, 1024);
    const enum rb_reference_sampler hash = RB_REFERENCE_SAMPLER_HASH;
    struct rb_reference *a = ref_new_sampler(j16, s, 2, hash),
                        *b = ref_new_sampler(j64, s, 2, hash),
                        *c = ref_new_sampler(j1k, s, 2, hash);
    struct rb_frame_result r16, r64, r1k;
    /* The reference is frame 1, whose random numbers are independent of frame 0's, so
     * E[RMSE^2] = s^2 (1/n + 1/1024): the expected ratio is sqrt((1/64 + 1/1024) /
     * (1/16 + 1/1024)) = 0.511. */
    float *p16 = render(a, 0, &r16), *p64 = render(b, 0, &r64), *p1k = render(c, 1, &r1k);
    double e16 = rmse(p16, p1k, &r16), e64 = rmse(p64, p1k, &r64);
    double ratio = e64 / e16;
    print_message("# hashed numbers: RMSE(64) / RMSE(16) = %.4g / %.4g = %.3f\n", e64, e16, ratio);
    if (!(ratio > 0.425 && ratio < 0.575))
        fail_msg("RMSE(64) / RMSE(16) = %g / %g = %g, not 0.5 +- 15%%", e64, e16, ratio);
    assert_true(e16 > 0.0);
    free(p16);
    free(p64);
    free(p1k);
    rb_reference_destroy(c);
    rb_reference_destroy(b);
    rb_reference_destroy(a);
    rb_job_destroy(j1k);
    rb_job_destroy(j64);
    rb_job_destroy(j16);
    rb_scene_destroy(s);
}

/* A floor (albedo 0.8) lit by one emissive triangle 1 m above it, nothing in between: its light
 * is smooth in the emitter point and smooth in the BSDF direction but for the triangle's
 * outline, each a pair of dimensions, and has a closed form. */
static double floor_error(const struct rb_scene *s, const double tri[3][3], uint32_t spp,
                          enum rb_reference_sampler sampler)
{
    struct rb_job *job = job_new(
        "resolution: [32, 24]\n"
        "frames: {start: 0, end: 3, rate: 24}\n"
        "camera: {fov_y_deg: 40, keys: [{t: 0, position: [0, 0.6, 2.2], look_at: [0, 0, 0]}]}\n"
        "integrator: {name: reference, reference: {spp: %u, max_bounces: 0}}\n",
        spp);
    struct rb_reference *ref = ref_new_sampler(job, s, 2, sampler);
    const double up[3] = {0, 1, 0};
    double sum = 0.0;
    uint32_t n = 0;
    for (int f = 0; f < 4; f++) {
        struct rb_frame_result r;
        float *px = render(ref, f, &r);
        for (uint32_t y = 0; y < r.height_px; y++)
            for (uint32_t x = 0; x < r.width_px; x++) {
                struct rb_vec3 o, d;
                pixel_ray(&r, x, y, &o, &d);
                double t = -o.y / d.y, h[3] = {o.x + t * d.x, 0.0, o.z + t * d.z};
                if (!(t > 0.0) || fmax(fabs(h[0]), fabs(h[2])) > 1.5 - 1e-3)
                    continue;
                double want = 0.8 / PI_D * polygon_irradiance(&tri[0][0], 3, h, up, 5.0);
                double e = (px_at(px, &r, x, y)[RB_OUT_BEAUTY] - want) / want;
                sum += e * e;
                n++;
            }
        free(px);
    }
    assert_true(n > 1500);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    return sqrt(sum / n);
}

/* The Sobol sampler against plain Monte Carlo (hashed numbers) on one smooth integrand: relative
 * RMSE against the closed form at 16 and 64 spp. Monte Carlo's falls by 1/sqrt(4) = 0.5. Under
 * an Owen-scrambled (0,2)-sequence the variance of a 2D integrand that is smooth but for jumps
 * along curves is O(n^-1.5) (Owen 1997; smooth everywhere: O(n^-3)), so the ratio is at most
 * 4^-0.75 = 0.35 (0.125 for the smooth part). */
static void test_convergence_sobol(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    add_quad(s, rb_v3(0, 0, 0), rb_v3(1.5f, 0, 0), rb_v3(0, 0, -1.5f),
             add_material(s, lambert(0.8f)));
    const double tri[3][3] = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0, 1, 0.5}};
    struct rb_scene_vertex v[3];
    for (int i = 0; i < 3; i++)
        v[i] = vert((float)tri[i][0], (float)tri[i][1], (float)tri[i][2], 0, -1, 0, 0, 0);
    static const uint32_t idx[3] = {0, 1, 2};
    add_mesh(s, v, 3, idx, 3, add_material(s, lamp(5.0f)), rb_v3(0, 0, 0));
    scene_finish(s);
    const enum rb_reference_sampler sobol = RB_REFERENCE_SAMPLER_SOBOL,
                                    hash = RB_REFERENCE_SAMPLER_HASH;
    double q16 = floor_error(s, tri, 16, sobol), q64 = floor_error(s, tri, 64, sobol);
    double h16 = floor_error(s, tri, 16, hash), h64 = floor_error(s, tri, 64, hash);
    print_message("# relative RMSE at 16, 64 spp: sobol %.3g, %.3g (ratio %.3f); hashed %.3g, "
                  "%.3g (ratio %.3f)\n",
                  q16, q64, q64 / q16, h16, h64, h64 / h16);
    if (!(h64 / h16 > 0.425 && h64 / h16 < 0.575))
        fail_msg("hashed: RMSE(64) / RMSE(16) = %g, not 0.5 +- 15%%", h64 / h16);
    if (!(q64 / q16 < 0.35))
        fail_msg("sobol: RMSE(64) / RMSE(16) = %g, not below 0.35", q64 / q16);
    if (!(q64 < 0.25 * h64 && q16 < h16))
        fail_msg("sobol's RMSE %g, %g not below hashed %g, %g", q16, q64, h16, h64);
    rb_scene_destroy(s);
}

/* The path spaces are subsets with shared random numbers, so several of them must agree bit
 * for bit. DIRECT: emissive triangles light through their fixed point samples, directly only.
 * BDPT counts emitters as it
 * counts punctual lights (at x1, x2 and x3, by light sample and by BSDF sample, MIS'd), and the
 * environment at x1 only: with a dark environment it is FULL with two bounces, and its direct
 * layer is FULL's with no bounces whatever the environment. */
static struct rb_scene *busy_scene_lamp(float emission)
{
    struct rb_scene *s = busy_scene();
    for (uint32_t i = 0; i < s->material_count; i++)
        if (s->materials[i].emissive[0] > 0.0f) {
            for (int c = 0; c < 3; c++)
                s->materials[i].emissive[c] *= emission;
            s->materials[i].base_color[1] = 0.9f; /* mark it in the albedo AOV */
        }
    return s;
}

/* BUSY_JOB's view at 24 x 20, frame 1, lit by lights (a YAML list) and a uniform sky of the
 * given intensity. */
static float *render_space(const struct rb_scene *s, const char *lights, const char *paths, int spp,
                           int bounces, int rr_depth, float env, struct rb_frame_result *r)
{
    struct rb_job *job = job_new(
        "resolution: [24, 20]\n"
        "frames: {start: 0, end: 1, rate: 24}\n"
        "camera: {fov_y_deg: 50, keys: [{t: 0, position: [0.3, 1.1, 2.6], look_at: [0, 0.4, 0]}]}\n"
        "lights: %s\n"
        "default_light: off\n"
        "environment: {color: [0.3, 0.4, 0.6], intensity: %g}\n"
        "integrator: {name: reference, reference: {spp: %d, max_bounces: %d, rr_depth: %d, "
        "paths: %s}}\n",
        lights, env, spp, bounces, rr_depth, paths);
    struct rb_reference *ref = ref_new(job, s, 2);
    float *p = render(ref, 1, r);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    return p;
}

#define BUSY_POINT "[{type: point, position: [-0.8, 1.5, 0.8], intensity: 1.5}]"

static float *render_job(const struct rb_scene *s, const char *paths, int bounces, float env,
                         struct rb_frame_result *r)
{
    return render_space(s, BUSY_POINT, paths, 4, bounces, 1, env, r);
}

static double layer_sum(const float *px, size_t n, int layer)
{
    double sum = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            sum += px[i * RB_OUT_FLOATS + layer + c];
    return sum;
}

static void test_path_spaces(void **state)
{
    (void)state;
    struct rb_scene *lit = busy_scene_lamp(1.0f), *dark = busy_scene_lamp(0.0f);
    struct rb_frame_result r;
    size_t n = 24 * 20;
    /* DIRECT: the lamp lights the scene directly, through its fixed point samples, and adds no
     * indirect light; BDPT: it lights the scene, directly and after bounces. The lamp only adds
     * (its light samples draw numbers no other sample uses), so every layer of every pixel is at
     * least the dark lamp's, in floats too. */
    const char *spaces[2] = {"direct", "bdpt"};
    for (int k = 0; k < 2; k++) {
        float *a = render_job(lit, spaces[k], 5, 1.0f, &r),
              *b = render_job(dark, spaces[k], 5, 1.0f, &r);
        uint32_t lamp = 0, hits = 0, more_direct = 0, more_indirect = 0;
        for (size_t i = 0; i < n; i++) {
            const float *pa = a + i * RB_OUT_FLOATS, *pb = b + i * RB_OUT_FLOATS;
            if (pa[RB_OUT_ALBEDO + 1] > 0.85f) { /* the lamp itself: its emission */
                lamp++;
                assert_true(pa[RB_OUT_DIRECT] > pb[RB_OUT_DIRECT] + 1.0f);
                continue;
            }
            hits += pa[RB_OUT_BEAUTY + 3] > 0.0f;
            if (k == 0 && memcmp(pa + RB_OUT_INDIRECT, pb + RB_OUT_INDIRECT, 3 * sizeof(float)))
                fail_msg("direct: pixel %zu has indirect light from the emissive quad", i);
            for (int c = 0; c < 3; c++)
                if (!(pa[RB_OUT_DIRECT + c] >= pb[RB_OUT_DIRECT + c] &&
                      pa[RB_OUT_INDIRECT + c] >= pb[RB_OUT_INDIRECT + c]))
                    fail_msg("bdpt: pixel %zu is darker with the lamp lit", i);
            more_direct += pa[RB_OUT_DIRECT] > pb[RB_OUT_DIRECT];
            more_indirect += pa[RB_OUT_INDIRECT] > pb[RB_OUT_INDIRECT];
        }
        assert_true(lamp > 0 && hits > n / 2);
        if (k == 0) {
            print_message("# direct: the lamp adds direct light to %u of %u pixels; direct %.4g "
                          "-> %.4g\n",
                          more_direct, hits, layer_sum(b, n, RB_OUT_DIRECT),
                          layer_sum(a, n, RB_OUT_DIRECT));
            if (!(more_direct > hits / 2 && more_indirect == 0))
                fail_msg("direct: the lamp lights %u (direct), %u (indirect) of %u pixels",
                         more_direct, more_indirect, hits);
        }
        if (k == 1) {
            print_message("# bdpt: the lamp adds direct light to %u and indirect to %u of %u "
                          "pixels; indirect %.4g -> %.4g, direct %.4g -> %.4g\n",
                          more_direct, more_indirect, hits, layer_sum(b, n, RB_OUT_INDIRECT),
                          layer_sum(a, n, RB_OUT_INDIRECT), layer_sum(b, n, RB_OUT_DIRECT),
                          layer_sum(a, n, RB_OUT_DIRECT));
            if (!(more_direct > hits / 2 && more_indirect > hits / 4))
                fail_msg("bdpt: the lamp lights %u (direct), %u (indirect) of %u pixels",
                         more_direct, more_indirect, hits);
            assert_true(layer_sum(a, n, RB_OUT_DIRECT) > 1.1 * layer_sum(b, n, RB_OUT_DIRECT));
            assert_true(layer_sum(a, n, RB_OUT_INDIRECT) > 1.1 * layer_sum(b, n, RB_OUT_INDIRECT));
        }
        free(a);
        free(b);
    }
    /* FULL, two bounces, dark environment == BDPT (which caps bounces at two), with the point
     * light and the lamp, or the point light alone, Russian roulette included */
    struct rb_scene *both[2] = {lit, dark};
    for (int k = 0; k < 2; k++) {
        float *full = render_job(both[k], "full", 2, 0.0f, &r),
              *bdpt = render_job(both[k], "bdpt", 5, 0.0f, &r);
        assert_memory_equal(full, bdpt, n * RB_OUT_FLOATS * sizeof(float));
        free(full);
        free(bdpt);
    }
    /* The lamp alone, no roulette: the same, and BDPT's paths end there; FULL finds more light
     * with a third bounce, so the BSDF sample from x3 counts the emitter it hits and goes no
     * further */
    float *full = render_space(lit, "[]", "full", 4, 2, 2, 0.0f, &r),
          *bdpt = render_space(lit, "[]", "bdpt", 4, 5, 2, 0.0f, &r),
          *full3 = render_space(lit, "[]", "full", 4, 3, 3, 0.0f, &r);
    assert_memory_equal(full, bdpt, n * RB_OUT_FLOATS * sizeof(float));
    double ind2 = layer_sum(bdpt, n, RB_OUT_INDIRECT), ind3 = layer_sum(full3, n, RB_OUT_INDIRECT);
    print_message("# lamp alone: indirect %.4g (bdpt), %.4g (full, 3 bounces), direct %.4g\n", ind2,
                  ind3, layer_sum(bdpt, n, RB_OUT_DIRECT));
    assert_true(ind2 > 0.0 && ind3 > ind2 * 1.02);
    free(full3);
    free(full);
    free(bdpt);
    /* and with more bounces FULL finds more light */
    full = render_job(lit, "full", 2, 0.0f, &r);
    float *full5 = render_job(lit, "full", 5, 0.0f, &r);
    assert_true(layer_sum(full5, n, RB_OUT_INDIRECT) > layer_sum(full, n, RB_OUT_INDIRECT) * 1.02);
    free(full5);
    free(full);
    /* BDPT's direct layer == DIRECT (dark sky and lamp), with the same AOVs */
    float *direct = render_job(dark, "direct", 5, 0.0f, &r);
    bdpt = render_job(dark, "bdpt", 5, 0.0f, &r);
    for (size_t i = 0; i < n; i++) {
        const float *pd = direct + i * RB_OUT_FLOATS, *pb = bdpt + i * RB_OUT_FLOATS;
        assert_memory_equal(pd + RB_OUT_DIRECT, pb + RB_OUT_DIRECT, 3 * sizeof(float));
        assert_true(pd[RB_OUT_INDIRECT] == 0.0f && pd[RB_OUT_INDIRECT + 1] == 0.0f);
        assert_memory_equal(pd + RB_OUT_ALBEDO, pb + RB_OUT_ALBEDO,
                            (RB_OUT_MOTION + 2 - RB_OUT_ALBEDO) * sizeof(float));
    }
    free(direct);
    free(bdpt);
    /* and == FULL with no bounces: lamp, point light and sky at x1 */
    bdpt = render_job(lit, "bdpt", 3, 1.0f, &r);
    full = render_job(lit, "full", 0, 1.0f, &r);
    for (size_t i = 0; i < n; i++)
        assert_memory_equal(bdpt + i * RB_OUT_FLOATS + RB_OUT_DIRECT,
                            full + i * RB_OUT_FLOATS + RB_OUT_DIRECT, 3 * sizeof(float));
    free(full);
    free(bdpt);
    rb_scene_destroy(dark);
    rb_scene_destroy(lit);
}

/* Emitters light as punctual lights do in BDPT's path space. A convex emitter of radiance L
 * and surface area A is, seen from outside, a light of intensity L A / 4 on average over
 * directions (Cauchy: a convex body's mean projected area is a quarter of its surface; L pi r^2
 * for a true sphere, whose irradiance outside it is a point's at its centre). So a small
 * emissive sphere and a point light of that intensity at its centre light the busy scene
 * alike, directly and after one and two bounces, up to noise, facets and the sphere's shadow;
 * a path space that gave emitters a bounce more or fewer than punctual lights would not. At
 * 256 samples, since the metal sphere's BSDF samples that hit the small emitter are rare and
 * bright; the facets and the shadow leave about 1.5%. */
static void test_bdpt_emitter_as_point(void **state)
{
    (void)state;
    struct rb_scene *sphere = busy_scene_lamp(0.0f), *point = busy_scene_lamp(0.0f);
    uint32_t mat = add_material(sphere, lamp(1.0f));
    uint32_t node = add_sphere(sphere, rb_v3(-0.8f, 1.5f, 0.8f), 0.05f, 16, 16, mat);
    const struct rb_scene_primitive *prim =
        &sphere->primitives[sphere->meshes[sphere->nodes[node].mesh].first_primitive];
    double area = 0.0;
    for (uint32_t i = 0; i < prim->index_count; i += 3) {
        const uint32_t *t = &sphere->indices[prim->first_index + i];
        const float *p0 = sphere->vertices[prim->first_vertex + t[0]].position;
        const float *p1 = sphere->vertices[prim->first_vertex + t[1]].position;
        const float *p2 = sphere->vertices[prim->first_vertex + t[2]].position;
        struct rb_vec3 e1 = rb_v3(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]);
        struct rb_vec3 e2 = rb_v3(p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]);
        area += 0.5 * rb_v3_length(rb_v3_cross(e1, e2));
    }
    float le = (float)(1.5 / (area / 4.0)); /* BUSY_POINT's intensity, 1.5 */
    for (int c = 0; c < 3; c++)
        sphere->materials[mat].emissive[c] = le;
    struct rb_frame_result r;
    size_t n = 24 * 20;
    float *a = render_space(sphere, "[]", "bdpt", 256, 5, 2, 0.0f, &r),
          *b = render_space(point, BUSY_POINT, "bdpt", 256, 5, 2, 0.0f, &r);
    double sum[2][2] = {{0}};
    uint32_t used = 0;
    for (size_t i = 0; i < n; i++) {
        const float *pa = a + i * RB_OUT_FLOATS, *pb = b + i * RB_OUT_FLOATS;
        if (!(pa[RB_OUT_BEAUTY + 3] > 0.0f) ||
            memcmp(pa + RB_OUT_ALBEDO, pb + RB_OUT_ALBEDO, 3 * sizeof(float)))
            continue; /* the sky, or the sphere where the point light has nothing */
        used++;
        for (int c = 0; c < 3; c++) {
            sum[0][0] += pa[RB_OUT_DIRECT + c];
            sum[0][1] += pa[RB_OUT_INDIRECT + c];
            sum[1][0] += pb[RB_OUT_DIRECT + c];
            sum[1][1] += pb[RB_OUT_INDIRECT + c];
        }
    }
    double rd = sum[0][0] / sum[1][0], ri = sum[0][1] / sum[1][1];
    print_message("# emissive sphere / point light over %u pixels: direct %.4f, indirect %.4f\n",
                  used, rd, ri);
    assert_true(used > n / 2 && sum[1][1] > 0.0);
    if (!(fabs(rd - 1.0) < 0.03 && fabs(ri - 1.0) < 0.04))
        fail_msg("emissive sphere / point light: direct %g, indirect %g, not 1", rd, ri);
    free(b);
    free(a);
    rb_scene_destroy(point);
    rb_scene_destroy(sphere);
}

/* The area-lit Cornell box ($RB_SCENES, skipped without it), lit by its emissive quad alone:
 * DIRECT lights the room directly through the quad's point samples, close to BDPT's direct
 * layer (the quad itself sampled); BDPT lights the room directly and after bounces, as FULL
 * with two bounces does bit for bit, and FULL finds more with more bounces. */
static void test_bdpt_cornell_box(void **state)
{
    (void)state;
    char path[1024];
    if (rb_test_scene(path, sizeof(path), "cornell-box/CornellBox.glb")) {
        print_message("# cornell box: '%s' is absent ($RB_SCENES)\n", path);
        skip(); /* a checkout without the external sample scenes */
    }
    struct rb_scene *s = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_scene_load(path, 0, &s, &err))
        fail_msg("loading '%s' failed: %s", path, err.msg);
    const char *spaces[4] = {"direct", "bdpt", "full", "full"};
    const int bounces[4] = {8, 8, 2, 8};
    float *px[4];
    struct rb_frame_result r;
    for (int k = 0; k < 4; k++) {
        struct rb_job *job = job_new(
            "resolution: [16, 16]\n"
            "frames: {start: 0, end: 0, rate: 24}\n"
            "default_light: off\n"
            "integrator: {name: reference, reference: {spp: 4, max_bounces: %d, rr_depth: 2, "
            "paths: %s}}\n",
            bounces[k], spaces[k]);
        struct rb_reference *ref = ref_new(job, s, 2);
        px[k] = render(ref, 0, &r);
        rb_reference_destroy(ref);
        rb_job_destroy(job);
    }
    size_t n = 16 * 16;
    uint32_t quad = 0, room = 0;
    double sum[3] = {0}, direct = 0.0; /* BDPT's beauty, direct, indirect; DIRECT's direct */
    for (size_t i = 0; i < n; i++) {
        const float *pd = px[0] + i * RB_OUT_FLOATS, *pb = px[1] + i * RB_OUT_FLOATS;
        if (!(pd[RB_OUT_BEAUTY + 3] > 0.0f))
            continue;
        if (pd[RB_OUT_BEAUTY] > 20.0f) { /* the quad's emission (100; the room stays below 2) */
            quad++;
            assert_true(pb[RB_OUT_DIRECT] >= pd[RB_OUT_DIRECT]);
            continue;
        }
        room++;
        assert_true(pd[RB_OUT_INDIRECT] == 0.0f);
        for (int c = 0; c < 3; c++) {
            direct += pd[RB_OUT_DIRECT + c] / 3.0;
            sum[0] += pb[RB_OUT_BEAUTY + c] / 3.0;
            sum[1] += pb[RB_OUT_DIRECT + c] / 3.0;
            sum[2] += pb[RB_OUT_INDIRECT + c] / 3.0;
        }
    }
    print_message("# cornell box, bdpt: %u room pixels, mean beauty %.4g = direct %.4g + indirect "
                  "%.4g; %u quad pixels\n",
                  room, sum[0] / room, sum[1] / room, sum[2] / room, quad);
    print_message("# cornell box, direct: mean direct %.4g over the room (bdpt's %.4g)\n",
                  direct / room, sum[1] / room);
    assert_true(room > n / 2 && quad > 0);
    assert_true(sum[0] / room > 0.05 && sum[2] > 0.1 * sum[1]);
    /* The point samples' estimate of the direct light, within 15% of the sampled quad's. */
    assert_true(fabs(direct - sum[1]) < 0.15 * sum[1]);
    assert_memory_equal(px[1], px[2], n * RB_OUT_FLOATS * sizeof(float));
    assert_true(layer_sum(px[3], n, RB_OUT_INDIRECT) > 1.02 * layer_sum(px[2], n, RB_OUT_INDIRECT));
    for (int k = 0; k < 4; k++)
        free(px[k]);
    rb_scene_destroy(s);
}

struct pass_log {
    uint32_t done[16], total, calls, stop_after;
};

static bool on_pass(void *user, uint32_t spp_done, uint32_t spp_total)
{
    struct pass_log *log = user;
    if (log->calls < 16)
        log->done[log->calls] = spp_done;
    log->calls++;
    log->total = spp_total;
    return log->calls != log->stop_after;
}

static void test_passes(void **state)
{
    (void)state;
    struct rb_scene *s = busy_scene();
    struct rb_job *job = job_new(BUSY_JOB, 8, 8, 40);
    struct pass_log log = {0};
    struct rb_reference *ref = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(
        rb_reference_create(
            &(struct rb_reference_desc){
                .job = job, .scene = s, .thread_count = 2, .on_pass = on_pass, .user = &log},
            &ref, &err),
        RB_OK);
    struct rb_frame_result r;
    float *full = render(ref, 0, &r);
    static const uint32_t want[] = {1, 2, 4, 8, 16, 32, 40};
    assert_int_equal(log.calls, 7);
    assert_int_equal(log.total, 40);
    for (int i = 0; i < 7; i++)
        assert_int_equal(log.done[i], want[i]);
    assert_int_equal(r.spp, 40);
    assert_true(r.pass_count == 1 && r.passes[0].cpu_ms >= 0.0 && r.ray_count > 0);
    /* stopping after the third pass leaves 4 samples: the same as asking for 4 */
    log = (struct pass_log){.stop_after = 3};
    float *stopped = render(ref, 0, &r);
    assert_int_equal(r.spp, 4);
    assert_int_equal(log.calls, 3);
    struct rb_job *j4 = job_new(BUSY_JOB, 8, 8, 4);
    struct rb_reference *ref4 = ref_new(j4, s, 1);
    struct rb_frame_result r4;
    float *four = render(ref4, 0, &r4);
    assert_memory_equal(stopped, four, (size_t)8 * 8 * RB_OUT_FLOATS * sizeof(float));
    assert_true(memcmp(stopped, full, (size_t)8 * 8 * RB_OUT_FLOATS * sizeof(float)) != 0);
    /* likewise under the box filter, whose samples also choose their camera ray: four passes
     * (8 samples) of 40 are 8 samples */
    struct rb_job *jb40 = job_new(BUSY_JOB_BOX, 8, 8, 40), *jb8 = job_new(BUSY_JOB_BOX, 8, 8, 8);
    struct rb_reference *refb = NULL;
    log = (struct pass_log){.stop_after = 4};
    assert_int_equal(
        rb_reference_create(
            &(struct rb_reference_desc){
                .job = jb40, .scene = s, .thread_count = 2, .on_pass = on_pass, .user = &log},
            &refb, &err),
        RB_OK);
    struct rb_reference *refb8 = ref_new(jb8, s, 3);
    float *box_stopped = render(refb, 0, &r);
    assert_int_equal(r.spp, 8);
    float *box8 = render(refb8, 0, &r4);
    assert_memory_equal(box_stopped, box8, (size_t)8 * 8 * RB_OUT_FLOATS * sizeof(float));
    free(box8);
    free(box_stopped);
    rb_reference_destroy(refb8);
    rb_reference_destroy(refb);
    rb_job_destroy(jb8);
    rb_job_destroy(jb40);
    /* a time limit that has run out stops after the first pass */
    struct rb_job_override o = {"integrator.reference.time_limit_s", "1e-9", NULL};
    struct rb_job *jt = NULL;
    char text[1024];
    snprintf(text, sizeof(text), "scene: scenes/features.gltf\noutput: out.####.exr\n" BUSY_JOB, 8,
             8, 40);
    assert_int_equal(rb_job_parse("t.yaml", text, strlen(text), "tests/unit", &o, 1, &jt, &err),
                     RB_OK);
    struct rb_reference *reft = ref_new(jt, s, 2);
    free(render(reft, 0, &r));
    assert_int_equal(r.spp, 1);
    rb_reference_destroy(reft);
    rb_job_destroy(jt);
    free(four);
    free(stopped);
    free(full);
    rb_reference_destroy(ref4);
    rb_job_destroy(j4);
    rb_reference_destroy(ref);
    rb_job_destroy(job);
    rb_scene_destroy(s);
}

/* The variance layer: the same bits whatever the threads; 0 in the direct path space (no
 * random numbers under center) and where the layer is not asked for; finite, >= 0 and mostly
 * > 0 on a lit quad whose pixels are sampled over their area (box); smaller with 256 samples than
 * with 16; and asking for it changes the samples (its two replicates draw other numbers than the
 * one net without it). */
static void test_variance_layer(void **state)
{
    (void)state;
    struct rb_scene *s = scene_new();
    add_quad(s, rb_v3(-1, -1, 0), rb_v3(2, 0, 0), rb_v3(0, 2, 0), add_material(s, lambert(0.5f)));
    scene_finish(s);
    const char *fmt = "resolution: [16, 12]\n"
                      "frames: {start: 0, end: 0, rate: 24}\n"
                      "camera: {fov_y_deg: 60, keys: [{t: 0, position: [0.1, 0.2, 1.5], "
                      "look_at: [0, 0, 0]}]}\n"
                      "lights: [{type: point, position: [0.5, 0.5, 2], intensity: 2}]\n"
                      "environment: {color: [0.2, 0.3, 0.4], intensity: 1}\n"
                      "layers: [%s]\n"
                      "integrator: {name: reference, reference: {spp: %d, paths: %s}}\n";
    /* box: every sample its own point of the pixel, so the light varies over them */
    struct rb_job *jv = job_new(fmt, "variance", 256, "full, pixel_filter: box");
    struct rb_job *jv16 = job_new(fmt, "variance", 16, "full, pixel_filter: box");
    struct rb_job *jd = job_new(fmt, "variance", 16, "direct");
    struct rb_job *jn = job_new(fmt, "depth", 256, "full, pixel_filter: box");
    struct rb_reference *r1 = ref_new(jv, s, 1), *r3 = ref_new(jv, s, 3);
    struct rb_reference *r16 = ref_new(jv16, s, 2), *rd = ref_new(jd, s, 2);
    struct rb_reference *rn = ref_new(jn, s, 2);
    struct rb_frame_result r;
    float *a = render(r1, 0, &r), *b = render(r3, 0, &r), *c = render(r16, 0, &r);
    float *d = render(rd, 0, &r), *plain = render(rn, 0, &r);
    size_t n = (size_t)r.width_px * r.height_px;
    assert_memory_equal(a, b, n * RB_OUT_FLOATS * sizeof(float));
    double sum256 = 0.0, sum16 = 0.0;
    uint32_t positive = 0;
    bool is_same_beauty = true;
    for (size_t i = 0; i < n; i++) {
        float v = a[i * RB_OUT_FLOATS + RB_OUT_VARIANCE];
        assert_true(isfinite(v) && v >= 0.0f);
        positive += v > 0.0f;
        sum256 += v;
        sum16 += c[i * RB_OUT_FLOATS + RB_OUT_VARIANCE];
        assert_true(d[i * RB_OUT_FLOATS + RB_OUT_VARIANCE] == 0.0f);
        assert_true(plain[i * RB_OUT_FLOATS + RB_OUT_VARIANCE] == 0.0f);
        is_same_beauty = is_same_beauty && a[i * RB_OUT_FLOATS] == plain[i * RB_OUT_FLOATS];
    }
    assert_true(positive > n / 4);
    assert_true(sum256 < sum16);
    assert_false(is_same_beauty); /* the replicates draw other numbers */
    free(a);
    free(b);
    free(c);
    free(d);
    free(plain);
    rb_reference_destroy(r1);
    rb_reference_destroy(r3);
    rb_reference_destroy(r16);
    rb_reference_destroy(rd);
    rb_reference_destroy(rn);
    rb_job_destroy(jv);
    rb_job_destroy(jv16);
    rb_job_destroy(jd);
    rb_job_destroy(jn);
    rb_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random),
        cmocka_unit_test(test_brdf_energy),
        cmocka_unit_test(test_brdf_reciprocity),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_ggx_furnace),
        cmocka_unit_test(test_emissive_furnace),
        cmocka_unit_test(test_environment_map),
        cmocka_unit_test(test_direct_point),
        cmocka_unit_test(test_direct_spot_directional),
        cmocka_unit_test(test_area_light_ceiling),
        cmocka_unit_test(test_bake),
        cmocka_unit_test(test_materials),
        cmocka_unit_test(test_skin),
        cmocka_unit_test(test_motion_and_morph),
        cmocka_unit_test(test_pixel_filter),
        cmocka_unit_test(test_variance_layer),
        cmocka_unit_test(test_path_spaces),
        cmocka_unit_test(test_bdpt_emitter_as_point),
        cmocka_unit_test(test_bdpt_cornell_box),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_indirect_lobes),
        cmocka_unit_test(test_convergence),
        cmocka_unit_test(test_convergence_sobol),
        cmocka_unit_test(test_passes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
