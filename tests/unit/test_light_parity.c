/* Light-model parity: the shaders' punctual lights and environment lookup
 * (shaders/common/lights.glsl, run on the device through shaders/light_table.comp) and the CPU
 * reference's (lib/reference/lights.c) agree on a table of lights and shading points, edge cases
 * included, and on a table of directions into a small environment map. The shared functions are
 * called as they are; the few lines around them that pick the light's direction and combine the
 * factors are inline in direct.comp and trace.c, so each side's copy here follows its own file.
 * Straight up and down, GLSL's atan(0, 0) is undefined: there only v and the pole's row are
 * checked. Runs on lavapipe with the validation layer on. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "gpu/gpu.h"
#include "light_table.comp.h"
#include "reference/reference_int.h"
#include "shared.h"

#define LIGHTS 4096
#define DIRS 2048
#define ENV_W 32
#define ENV_H 16
#define ENV_INTENSITY 1.75f

/* Tolerances, stated here and printed as the worst ratio to them (1 == at the limit).
 * - Directions, distances and the map's u: 1e-5 absolute and relative, a few ulps of what
 *   length() and atan() give. The map's v: 1e-4, as lavapipe's acos() is good to about 1.6e-4
 *   radians (v off by 5e-5 at worst here; Vulkan allows 4096 ulps); 1e-4 is 1/600 of a texel.
 * - Falloff (range window x inverse square), spot factor and their product: 1e-4 relative, or
 *   1e-5 absolute on the [0, 1] scale of the window and the cone (times the inverse square for
 *   the falloff and the product). The spot factor t^2, t = (cos - cos_outer) x scale with
 *   scale = 1 / max(1e-3, cos_inner - cos_outer), magnifies a rounding of the cosine by
 *   2 x scale (up to 2000 for a hard edge), so it may also differ by that times TOL_COS: a
 *   cosine's rounding, about twice the worst seen here (1.7e-7, three ulps just below 1).
 * - The environment: 1e-4 relative, or the sampler's sub-texel precision: with bits of
 *   subTexelPrecisionBits (8 on lavapipe), each bilinear weight may be off by 2^-bits, which
 *   moves the result by up to 2^(1-bits) x the largest difference between neighbouring texels;
 *   the map coordinates' tolerances, in texels, move it by up to that difference times them. */
#define TOL_DIR 1e-5
#define TOL_V 1e-4
#define TOL_REL 1e-4
#define TOL_FACTOR 1e-5
#define TOL_COS 4e-7

enum kind {
    POINT_INFINITE,   /* range 0 */
    POINT_INSIDE,     /* dist < range */
    POINT_BEYOND,     /* dist > range: nothing */
    POINT_AT_RANGE,   /* dist == range exactly: the window is 0 */
    POINT_NEAR_RANGE, /* dist just short of the range */
    SPOT_INNER,       /* inside the inner cone: factor 1 */
    SPOT_BETWEEN,     /* between the cones */
    SPOT_OUTSIDE,     /* outside the outer cone: 0 */
    SPOT_EQUAL,       /* inner == outer: a hard edge */
    SPOT_ZERO_INNER,  /* inner 0, the job's default */
    SPOT_ON_AXIS,     /* the point on the axis */
    DIRECTIONAL,
    KIND_COUNT
};

/* A fixed xorshift stream: the tables are the same on every run. */
static uint32_t rng_state = 0x2545f491u;
static float rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (float)(rng_state >> 8) / 16777216.0f;
}

static float rnd_range(float lo, float hi)
{
    return lo + (hi - lo) * rnd();
}

static void random_unit(float out[3])
{
    float z = rnd() * 2.0f - 1.0f, phi = rnd() * 6.28318531f, r = sqrtf(fmaxf(0.0f, 1 - z * z));
    out[0] = r * cosf(phi);
    out[1] = r * sinf(phi);
    out[2] = z;
}

/* A point at distance dist from the light's position, theta_rad away from the axis a (unit). */
static void point_at_angle(const float pos[3], const float a[3], float theta_rad, float dist,
                           float p[3])
{
    float t[3], b[3];
    rb_ref_basis(a, t, b);
    float phi = rnd() * 6.28318531f, s = sinf(theta_rad), c = cosf(theta_rad);
    for (int k = 0; k < 3; k++)
        p[k] = pos[k] + dist * (c * a[k] + s * (cosf(phi) * t[k] + sinf(phi) * b[k]));
}

/* Light i and its shading point: the light as frame.c writes it for direct.comp. */
static void make_light(int i, struct rb_gpu_light *L, float p[4])
{
    enum kind kind = (enum kind)(i % KIND_COUNT);
    float pos[3], axis[3], range = 0.0f, inner = 0.0f, outer = 0.0f;
    float type = kind == DIRECTIONAL ? RB_KIND_DIRECTIONAL
                 : kind < SPOT_INNER ? RB_KIND_POINT
                                     : RB_KIND_SPOT;
    for (int k = 0; k < 3; k++)
        pos[k] = rnd_range(-5.0f, 5.0f);
    random_unit(axis);
    float dist = rnd_range(0.05f, 12.0f);
    if (kind >= SPOT_INNER && kind <= SPOT_ON_AXIS) {
        outer = rnd_range(0.05f, 1.5f);
        inner = kind == SPOT_EQUAL ? outer : kind == SPOT_ZERO_INNER ? 0.0f : outer * rnd();
        range = i % 3 ? dist * rnd_range(1.05f, 4.0f) : 0.0f;
    }
    float theta = 0.0f;
    switch (kind) {
    case POINT_INSIDE: range = dist * rnd_range(1.001f, 3.0f); break;
    case POINT_BEYOND: range = dist * rnd_range(0.2f, 0.999f); break;
    case POINT_NEAR_RANGE: range = dist * 1.001f; break;
    case SPOT_INNER: theta = inner * rnd() * 0.95f; break;
    case SPOT_BETWEEN: theta = inner + (outer - inner) * rnd_range(0.02f, 0.98f); break;
    case SPOT_OUTSIDE: theta = rnd_range(outer * 1.02f, 3.1f); break;
    case SPOT_EQUAL:
    case SPOT_ZERO_INNER: theta = rnd_range(0.0f, 2.0f * outer); break;
    default: break;
    }
    if (kind == POINT_AT_RANGE) {
        /* A (3, 4, 0) offset in eighths from a position on a grid of eighths: every coordinate
         * and the length 5/8 are exact, so dist == range on both sides. */
        static const float off[][3] = {
            {0.375f, 0.5f, 0.0f}, {0.0f, -0.375f, 0.5f}, {-0.5f, 0.0f, -0.375f}};
        const float *o = off[(i / KIND_COUNT) % 3];
        for (int k = 0; k < 3; k++) {
            pos[k] = floorf(pos[k] * 8.0f) / 8.0f;
            p[k] = pos[k] - o[k];
        }
        range = 0.625f;
    } else if (kind == DIRECTIONAL) {
        for (int k = 0; k < 3; k++)
            p[k] = rnd_range(-5.0f, 5.0f);
    } else {
        point_at_angle(pos, axis, theta, dist, p);
    }
    p[3] = 0.0f;
    *L = (struct rb_gpu_light){
        .position = {pos[0], pos[1], pos[2], type},
        .direction = {axis[0], axis[1], axis[2], range},
        .color = {1.0f, 1.0f, 1.0f, -1.0f},
        .cone = {cosf(inner), cosf(outer), 0.0f, 0.0f},
    };
}

/* The same light through the reference: the direction and attenuation as trace.c's
 * next-event estimation computes them. out: l.xyz, attenuation, falloff, spot, dist. */
static void cpu_light(const struct rb_gpu_light *g, const float p[3], float out[7])
{
    const struct rb_ref_light L = {
        .type = (enum rb_light_type)(int)g->position[3],
        .position = {g->position[0], g->position[1], g->position[2]},
        .direction = {g->direction[0], g->direction[1], g->direction[2]},
        .range = g->direction[3],
        .cos_inner = g->cone[0],
        .cos_outer = g->cone[1],
    };
    float l[3], dist = 0.0f, falloff = 1.0f, spot = 1.0f;
    if (L.type == RB_LIGHT_DIRECTIONAL) {
        for (int k = 0; k < 3; k++)
            l[k] = -L.direction[k];
    } else {
        float d[3] = {L.position[0] - p[0], L.position[1] - p[1], L.position[2] - p[2]};
        dist = sqrtf(rb_f3_dot(d, d));
        float inv = 1.0f / rb_ref_maxf(dist, 1e-8f);
        for (int k = 0; k < 3; k++)
            l[k] = d[k] * inv;
        falloff = rb_ref_light_falloff(dist, L.range);
        if (L.type == RB_LIGHT_SPOT) {
            float to_surface[3] = {-l[0], -l[1], -l[2]};
            spot = rb_ref_spot_factor(L.direction, to_surface, L.cos_inner, L.cos_outer);
        }
    }
    float v[7] = {l[0], l[1], l[2], falloff * spot, falloff, spot, dist};
    memcpy(out, v, sizeof(v));
}

/* Directions into the environment: random ones, the poles (v clamps), the seam behind +Z with
 * x = +0 and -0 and just beside it (u wraps), the map's centre (-Z); rotations from -2 pi to
 * 4 pi, 0 included. */
static void make_dir(int i, float d[4])
{
    static const float special[][3] = {
        {0.0f, 1.0f, 0.0f},      {0.0f, -1.0f, 0.0f},    {0.0f, 0.0f, 1.0f},  {-0.0f, 0.0f, 1.0f},
        {1e-4f, 0.3f, 0.95f},    {-1e-4f, 0.3f, 0.95f},  {0.0f, 0.0f, -1.0f}, {1.0f, 0.0f, 0.0f},
        {0.0f, 0.999f, 0.0447f}, {0.02f, -0.9998f, 0.0f}};
    const int n_special = (int)(sizeof(special) / sizeof(special[0]));
    if (i < 2 * n_special) {
        memcpy(d, special[i % n_special], sizeof(special[0]));
        if (i >= n_special) {
            float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int k = 0; k < 3; k++)
                d[k] /= len;
        }
        d[3] = i < n_special ? 0.0f : 1.0f;
        return;
    }
    random_unit(d);
    d[3] = i % 4 == 0 ? 0.0f : rnd_range(-6.28318531f, 12.5663706f);
}

/* The map: random texels in [0, 1), so that a lookup a texel off shows. */
static void make_map(float *rgba)
{
    for (int i = 0; i < ENV_W * ENV_H; i++) {
        for (int k = 0; k < 3; k++)
            rgba[4 * i + k] = rnd();
        rgba[4 * i + 3] = 1.0f;
    }
}

/* The largest difference between neighbouring texels, across the u seam too. */
static double map_max_step(const float *rgba)
{
    double step = 0.0;
    for (int y = 0; y < ENV_H; y++)
        for (int x = 0; x < ENV_W; x++)
            for (int k = 0; k < 3; k++) {
                float t = rgba[4 * (y * ENV_W + x) + k];
                float right = rgba[4 * (y * ENV_W + (x + 1) % ENV_W) + k];
                float down = y + 1 < ENV_H ? rgba[4 * ((y + 1) * ENV_W + x) + k] : t;
                step = fmax(step, fmax(fabs(t - right), fabs(t - down)));
            }
    return step;
}

/* The range of channel k over row y of the map. */
static void row_range(const float *rgba, int y, int k, float *lo, float *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int x = 0; x < ENV_W; x++) {
        *lo = fminf(*lo, rgba[4 * (y * ENV_W + x) + k]);
        *hi = fmaxf(*hi, rgba[4 * (y * ENV_W + x) + k]);
    }
}

static void upload_map(struct rb_gpu *gpu, const float *rgba, struct rb_gpu_image *img)
{
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(
        rb_gpu_image_init(gpu,
                          &(struct rb_gpu_image_desc){.width_px = ENV_W,
                                                      .height_px = ENV_H,
                                                      .format = VK_FORMAT_R32G32B32A32_SFLOAT,
                                                      .usage = VK_IMAGE_USAGE_SAMPLED_BIT |
                                                               VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                      .debug_name = "environment"},
                          img, &err),
        RB_OK);
    struct rb_gpu_buffer staging = {0};
    size_t bytes = (size_t)ENV_W * ENV_H * 16;
    assert_int_equal(
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = bytes,
                                                        .usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = "environment staging"},
                           &staging, &err),
        RB_OK);
    memcpy(staging.mapped, rgba, bytes);
    VkCommandBuffer cmd;
    assert_int_equal(rb_gpu_oneshot_begin(gpu, &cmd, &err), RB_OK);
    rb_gpu_image_barrier(gpu, cmd, img, VK_IMAGE_LAYOUT_UNDEFINED,
                         VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    VkBufferImageCopy copy = {
        .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .imageExtent = {ENV_W, ENV_H, 1},
    };
    vkCmdCopyBufferToImage(cmd, staging.buffer, img->image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                           &copy);
    rb_gpu_image_barrier(gpu, cmd, img, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                         VK_IMAGE_LAYOUT_GENERAL);
    if (rb_gpu_oneshot_end(gpu, cmd, &err))
        fail_msg("%s", err.msg);
    rb_gpu_buffer_release(gpu, &staging);
}

static void storage_buffer(struct rb_gpu *gpu, size_t bytes, const char *name,
                           struct rb_gpu_buffer *out)
{
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = bytes,
                                                        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = name},
                           out, &err),
        RB_OK);
}

/* |a - c| within rel of the larger, or within abs: true when they agree. */
static bool close_to(double a, double c, double rel, double abs_tol)
{
    double diff = fabs(a - c);
    return diff <= rel * fmax(fabs(a), fabs(c)) || diff <= abs_tol;
}

struct tally {
    int bad;
    double worst; /* the largest difference over its tolerance (1 == at the limit) */
};

static void tally(struct tally *t, const char *what, int i, int kind, double a, double c,
                  double rel, double abs_tol)
{
    double diff = fabs(a - c);
    double limit = fmax(rel * fmax(fabs(a), fabs(c)), abs_tol);
    double ratio = limit > 0.0 ? diff / limit : (diff > 0.0 ? INFINITY : 0.0);
    if (ratio > t->worst)
        t->worst = ratio;
    if (!close_to(a, c, rel, abs_tol) && t->bad++ < 12)
        print_message("entry %d (kind %d) %s: gpu %.9g cpu %.9g\n", i, kind, what, a, c);
}

static void test_light_parity(void **state)
{
    (void)state;
    struct rb_gpu_light *lights = calloc(LIGHTS, sizeof(*lights));
    float(*points)[4] = calloc(LIGHTS, sizeof(*points));
    float(*dirs)[4] = calloc(DIRS, sizeof(*dirs));
    float *map = calloc((size_t)ENV_W * ENV_H * 4, sizeof(float));
    assert_true(lights && points && dirs && map);
    for (int i = 0; i < LIGHTS; i++)
        make_light(i, &lights[i], points[i]);
    for (int i = 0; i < DIRS; i++)
        make_dir(i, dirs[i]);
    make_map(map);

    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = NULL;
    if (rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err))
        fail_msg("no device: %s", err.msg);

    struct rb_gpu_buffer in_lights = {0}, in_points = {0}, in_dirs = {0}, out = {0};
    struct rb_gpu_image env = {0};
    storage_buffer(gpu, LIGHTS * sizeof(*lights), "light table lights", &in_lights);
    storage_buffer(gpu, LIGHTS * sizeof(*points), "light table points", &in_points);
    storage_buffer(gpu, DIRS * sizeof(*dirs), "light table directions", &in_dirs);
    storage_buffer(gpu, 2 * (LIGHTS + DIRS) * 16, "light table outputs", &out);
    memcpy(in_lights.mapped, lights, LIGHTS * sizeof(*lights));
    memcpy(in_points.mapped, points, LIGHTS * sizeof(*points));
    memcpy(in_dirs.mapped, dirs, DIRS * sizeof(*dirs));
    upload_map(gpu, map, &env);

    static const VkDescriptorType types[] = {
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
        VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
    struct {
        uint32_t light_count, env_count;
        float env_intensity;
    } push = {LIGHTS, DIRS, ENV_INTENSITY};
    struct rb_gpu_layout layout = {0};
    VkPipeline pipe = VK_NULL_HANDLE;
    assert_int_equal(rb_gpu_layout_init(gpu, types, 5, sizeof(push), &layout, &err), RB_OK);
    assert_int_equal(rb_gpu_compute_pipeline(gpu, rb_spv_light_table_comp,
                                             sizeof(rb_spv_light_table_comp),
                                             layout.pipeline_layout, "light_table", &pipe, &err),
                     RB_OK);
    assert_int_equal(rb_gpu_begin(gpu, &err), RB_OK);
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &in_lights);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &in_points);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &in_dirs);
    /* The direct pass's sampler: u repeats, v clamps, linear. */
    rb_gpu_bind_image(&b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, env.view, gpu->env_sampler,
                      VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &out);
    vkCmdBindPipeline(gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
    rb_gpu_push_bindings(gpu, gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout.pipeline_layout, &b);
    vkCmdPushConstants(gpu->cmd, layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(push),
                       &push);
    vkCmdDispatch(gpu->cmd, (LIGHTS + DIRS + 63) / 64, 1, 1);
    rb_gpu_barrier(gpu->cmd);
    if (rb_gpu_submit_wait(gpu, &err))
        fail_msg("%s", err.msg);

    /* The punctual lights. */
    const float *g = out.mapped;
    struct tally t_dir = {0}, t_dist = {0}, t_falloff = {0}, t_spot = {0}, t_atten = {0};
    int lit[KIND_COUNT] = {0}, dark[KIND_COUNT] = {0}, partial_spot = 0;
    for (int i = 0; i < LIGHTS; i++) {
        int kind = i % KIND_COUNT;
        const struct rb_gpu_light *L = &lights[i];
        float c[7];
        cpu_light(L, points[i], c);
        const float *a = g + 8 * i;
        for (int k = 0; k < 3; k++)
            tally(&t_dir, "l", i, kind, a[k], c[k], 0.0, TOL_DIR);
        tally(&t_dist, "distance", i, kind, a[6], c[6], TOL_DIR, TOL_DIR);
        /* the scales of the absolute tolerances: the inverse square, the cone's magnification */
        bool is_directional = L->position[3] == RB_KIND_DIRECTIONAL;
        double inv_sq = is_directional ? 1.0 : 1.0 / fmax((double)c[6] * c[6], 1e-8);
        double scale =
            L->position[3] == RB_KIND_SPOT ? 1.0 / fmax(1e-3, L->cone[0] - L->cone[1]) : 0.0;
        double spot_tol = TOL_FACTOR + 2.0 * scale * TOL_COS;
        tally(&t_falloff, "falloff", i, kind, a[4], c[4], TOL_REL, TOL_FACTOR * inv_sq);
        tally(&t_spot, "spot factor", i, kind, a[5], c[5], TOL_REL, spot_tol);
        tally(&t_atten, "attenuation", i, kind, a[3], c[3], TOL_REL, spot_tol * inv_sq);
        if (c[3] > 0.0f)
            lit[kind]++;
        else
            dark[kind]++;
        if (c[5] > 0.01f && c[5] < 0.99f)
            partial_spot++;
    }
    print_message("light parity: %d entries; worst difference / tolerance: direction %.3g, "
                  "distance %.3g, falloff %.3g, spot %.3g, attenuation %.3g\n",
                  LIGHTS, t_dir.worst, t_dist.worst, t_falloff.worst, t_spot.worst, t_atten.worst);

    /* The table covers what it claims: each edge case lands where it should on the CPU side. */
    assert_int_equal(dark[POINT_INFINITE] + dark[POINT_INSIDE] + dark[POINT_NEAR_RANGE], 0);
    assert_int_equal(lit[POINT_BEYOND] + lit[POINT_AT_RANGE] + lit[SPOT_OUTSIDE], 0);
    assert_int_equal(dark[SPOT_INNER] + dark[SPOT_ON_AXIS] + dark[DIRECTIONAL], 0);
    assert_true(lit[SPOT_EQUAL] > 0 && dark[SPOT_EQUAL] > 0);
    assert_true(partial_spot > LIGHTS / KIND_COUNT / 2);

    /* The environment: the map coordinates, then the filtered lookup. */
    struct rb_ref_env ref_env = {
        .intensity = ENV_INTENSITY,
        .rgba = map,
        .width_px = ENV_W,
        .height_px = ENV_H,
    };
    double step = map_max_step(map) * ENV_INTENSITY;
    double subtexel_tol = ldexp(2.0 * step, -(int)gpu->props.limits.subTexelPrecisionBits);
    double env_tol = subtexel_tol + step * (TOL_DIR * ENV_W + TOL_V * ENV_H);
    struct tally t_uv = {0}, t_env = {0};
    int poles = 0, pole_bad = 0;
    for (int i = 0; i < DIRS; i++) {
        const float *d = dirs[i];
        const float *a = g + 8 * LIGHTS + 8 * i;
        float c[3], u, v;
        ref_env.rotation_rad = d[3];
        rb_ref_env_eval(&ref_env, d, c);
        rb_ref_equirect_uv(d, d[3], &u, &v);
        tally(&t_uv, "v", i, -1, a[5], v, 0.0, TOL_V);
        if (d[0] == 0.0f && d[2] == 0.0f) {
            /* Straight up or down, u is atan(0, 0): undefined in GLSL, pi in C. Both must still
             * read the pole's row (v clamps there): within its range. */
            poles++;
            for (int k = 0; k < 3; k++) {
                float lo, hi;
                row_range(map, d[1] > 0.0f ? 0 : ENV_H - 1, k, &lo, &hi);
                float x = a[k] / ENV_INTENSITY;
                if (!(x >= lo - 1e-6f && x <= hi + 1e-6f) && pole_bad++ < 4)
                    print_message("direction %d: gpu %.9g outside the pole row's [%g, %g]\n", i, x,
                                  lo, hi);
            }
            continue;
        }
        /* u wraps: 0 and 1 are the same column */
        double du = a[4] - u;
        du -= floor(du + 0.5);
        tally(&t_uv, "u", i, -1, du, 0.0, 0.0, TOL_DIR);
        for (int k = 0; k < 3; k++)
            tally(&t_env, "environment", i, -1, a[k], c[k], TOL_REL, env_tol);
    }
    print_message("environment parity: %d directions (%d poles); worst difference / tolerance: "
                  "uv %.3g, lookup %.3g (of %.3g absolute)\n",
                  DIRS, poles, t_uv.worst, t_env.worst, env_tol);

    assert_int_equal(t_dir.bad, 0);
    assert_int_equal(t_dist.bad, 0);
    assert_int_equal(t_falloff.bad, 0);
    assert_int_equal(t_spot.bad, 0);
    assert_int_equal(t_atten.bad, 0);
    assert_int_equal(t_uv.bad, 0);
    assert_int_equal(t_env.bad, 0);
    assert_int_equal(poles, 4);
    assert_int_equal(pole_bad, 0);

    vkDestroyPipeline(gpu->device, pipe, NULL);
    rb_gpu_layout_release(gpu, &layout);
    rb_gpu_image_release(gpu, &env);
    rb_gpu_buffer_release(gpu, &out);
    rb_gpu_buffer_release(gpu, &in_dirs);
    rb_gpu_buffer_release(gpu, &in_points);
    rb_gpu_buffer_release(gpu, &in_lights);
    rb_gpu_destroy(gpu);
    free(map);
    free(dirs);
    free(points);
    free(lights);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_light_parity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
