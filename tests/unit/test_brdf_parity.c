/* BRDF parity: the shaders' BRDF (shaders/common/brdf.glsl, run on the device through a small
 * compute shader) and the CPU reference's (rb_reference_brdf) agree to 1e-4 relative on a table
 * of normals, view and light directions, roughness from 0.02 to 1, metallic 0 and 1, and
 * colours. Runs on lavapipe with the validation layer on. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "brdf_table.comp.h"
#include "gpu/gpu.h"
#include "reference/reference.h"

#define ENTRIES 4096

struct entry {
    float n[3], v[3], l[3], c_diff[3], f0[3], f90, roughness;
};

/* A fixed xorshift stream: the table is the same on every run. */
static uint32_t rng_state = 0x9e3779b9u;
static float rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (float)(rng_state >> 8) / 16777216.0f;
}

static void random_unit(float out[3])
{
    float z = rnd() * 2.0f - 1.0f, phi = rnd() * 6.28318531f, r = sqrtf(fmaxf(0.0f, 1 - z * z));
    out[0] = r * cosf(phi);
    out[1] = r * sinf(phi);
    out[2] = z;
}

/* A direction within the hemisphere of n (or, for a few entries, below it). */
static void random_dir_around(const float n[3], bool below, float out[3])
{
    random_unit(out);
    float d = out[0] * n[0] + out[1] * n[1] + out[2] * n[2];
    if ((d < 0.0f) != below)
        for (int k = 0; k < 3; k++)
            out[k] = -out[k];
}

static void make_table(struct entry *e)
{
    static const float roughness[] = {0.02f, 0.05f, 0.1f, 0.25f, 0.5f, 0.75f, 1.0f};
    for (int i = 0; i < ENTRIES; i++) {
        random_unit(e[i].n);
        random_dir_around(e[i].n, false, e[i].v);
        random_dir_around(e[i].n, i % 16 == 15, e[i].l); /* some lights below the surface */
        e[i].roughness = i % 3 == 0 ? roughness[(i / 3) % 7] : 0.02f + 0.98f * rnd();
        float base[3] = {rnd(), rnd(), rnd()};
        float metallic = (i / 2) % 2 ? 1.0f : 0.0f;
        float spec = i % 5 == 4 ? rnd() : 1.0f; /* KHR_materials_specular's factor */
        for (int k = 0; k < 3; k++) {
            e[i].c_diff[k] = base[k] * (1.0f - metallic);
            e[i].f0[k] = 0.04f * spec * (1.0f - metallic) + base[k] * metallic;
        }
        e[i].f90 = spec * (1.0f - metallic) + metallic;
    }
}

static void test_brdf_parity(void **state)
{
    (void)state;
    struct entry *table = calloc(ENTRIES, sizeof(*table));
    assert_non_null(table);
    make_table(table);

    struct rb_err err = RB_ERR_INIT;
    struct rb_gpu *gpu = NULL;
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err);
    if (st)
        fail_msg("no device: %s", err.msg);

    struct rb_gpu_buffer in = {0}, out = {0};
    assert_int_equal(
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = ENTRIES * 5 * 16,
                                                        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = "brdf inputs"},
                           &in, &err),
        RB_OK);
    assert_int_equal(
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = ENTRIES * 16,
                                                        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = "brdf outputs"},
                           &out, &err),
        RB_OK);
    float *p = in.mapped;
    for (int i = 0; i < ENTRIES; i++) {
        const struct entry *e = &table[i];
        float rows[20] = {e->n[0], e->n[1],  e->n[2],      e->roughness, e->v[0],
                          e->v[1], e->v[2],  e->f90,       e->l[0],      e->l[1],
                          e->l[2], 0.0f,     e->c_diff[0], e->c_diff[1], e->c_diff[2],
                          0.0f,    e->f0[0], e->f0[1],     e->f0[2],     0.0f};
        memcpy(p + 20 * i, rows, sizeof(rows));
    }

    static const VkDescriptorType types[] = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                             VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
    struct rb_gpu_layout layout = {0};
    VkPipeline pipe = VK_NULL_HANDLE;
    assert_int_equal(rb_gpu_layout_init(gpu, types, 2, sizeof(uint32_t), &layout, &err), RB_OK);
    assert_int_equal(rb_gpu_compute_pipeline(gpu, rb_spv_brdf_table_comp,
                                             sizeof(rb_spv_brdf_table_comp), layout.pipeline_layout,
                                             "brdf_table", &pipe, &err),
                     RB_OK);
    assert_int_equal(rb_gpu_begin(gpu, &err), RB_OK);
    struct rb_gpu_bindings b = {0};
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &in);
    rb_gpu_bind_buffer(&b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &out);
    vkCmdBindPipeline(gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
    rb_gpu_push_bindings(gpu, gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout.pipeline_layout, &b);
    uint32_t count = ENTRIES;
    vkCmdPushConstants(gpu->cmd, layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0, sizeof(count),
                       &count);
    vkCmdDispatch(gpu->cmd, (ENTRIES + 63) / 64, 1, 1);
    rb_gpu_barrier(gpu->cmd);
    st = rb_gpu_submit_wait(gpu, &err);
    if (st)
        fail_msg("%s", err.msg);

    const float *gpu_f = out.mapped;
    int bad = 0, nonzero = 0;
    double worst = 0.0;
    for (int i = 0; i < ENTRIES; i++) {
        const struct entry *e = &table[i];
        float cpu_f[3];
        rb_reference_brdf(e->n, e->v, e->l, e->c_diff, e->f0, e->f90, e->roughness, cpu_f);
        for (int k = 0; k < 3; k++) {
            double a = gpu_f[4 * i + k], c = cpu_f[k];
            double scale = fmax(fabs(a), fabs(c));
            if (scale > 0.0)
                nonzero++;
            /* 1e-4 relative; values below 1e-6 compare absolutely (both are zero there). */
            double rel = fabs(a - c) / fmax(scale, 1e-6);
            if (rel > worst)
                worst = rel;
            if (rel > 1e-4 && bad++ < 8)
                print_message("entry %d channel %d: gpu %.9g cpu %.9g (roughness %g, f90 %g)\n", i,
                              k, a, c, e->roughness, e->f90);
        }
    }
    print_message("BRDF parity: %d entries, worst relative difference %.3g\n", ENTRIES, worst);
    assert_true(nonzero > ENTRIES);
    assert_int_equal(bad, 0);

    vkDestroyPipeline(gpu->device, pipe, NULL);
    rb_gpu_layout_release(gpu, &layout);
    rb_gpu_buffer_release(gpu, &out);
    rb_gpu_buffer_release(gpu, &in);
    rb_gpu_destroy(gpu);
    free(table);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_brdf_parity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
