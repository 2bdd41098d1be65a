/* The frame driver (lib/integrators/driver.c) with integrators of the test's own: the history
 * contract (a chunk equals the same frames of a whole run, warm-up frames included, for history
 * 1 and 3), pass groups (200 recordings of one pass are one timing entry with count 200), the
 * direct integrator's chunk identity, and the barriers derived from the passes' declarations
 * (a declaration left out is a hazard that synchronization validation reports). On lavapipe,
 * validation and synchronization validation on. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "integrators/integrators_int.h"

#define SLOTS_MAX 8

/* A test integrator whose output is the list of frames its slots hold: frame f stamps f into
 * slot f mod n of a tag buffer (also as a warm-up), then copies the tags into the readback. The
 * output of frame f is thus a function of f and its history_frames predecessors, and a missing
 * or wrong warm-up shows as a tag that differs from the whole run's. */
struct tags {
    struct rb_gpu_buffer buffer; /* SLOTS_MAX uint32 */
    uint32_t repeat;             /* extra recordings of the "repeat" pass */
};

static uint32_t tags_history = 3, tags_repeat = 0;

static uint32_t history_tags(const struct rb_job *job)
{
    (void)job;
    return tags_history;
}

static enum rb_status create_tags(struct rb_integrator *it, void **state, struct rb_err *err)
{
    struct tags *t = calloc(1, sizeof(*t));
    if (!t)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    t->repeat = tags_repeat;
    enum rb_status st =
        rb_gpu_buffer_init(it->gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = SLOTS_MAX * 4,
                                                        .usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                                                 VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                        .debug_name = "tags"},
                           &t->buffer, err);
    if (st == RB_OK) {
        VkCommandBuffer cmd;
        if ((st = rb_gpu_oneshot_begin(it->gpu, &cmd, err)) == RB_OK) {
            vkCmdFillBuffer(cmd, t->buffer.buffer, 0, VK_WHOLE_SIZE, 0xffffffffu);
            st = rb_gpu_oneshot_end(it->gpu, cmd, err);
        }
    }
    if (st) {
        rb_gpu_buffer_release(it->gpu, &t->buffer);
        free(t);
        return st;
    }
    *state = t;
    return RB_OK;
}

static void record_tags(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                        const struct rb_frame_ctx *ctx)
{
    struct tags *t = state;
    uint32_t n = it->frame.slot_count;
    uint32_t slot = (uint32_t)(((int64_t)ctx->frame % n + n) % n);
    const struct rb_gpu_access fill[] = {{.buffer = &t->buffer, .use = RB_GPU_TRANSFER_WRITE}};
    const struct rb_gpu_access copy[] = {
        {.buffer = &t->buffer, .use = RB_GPU_TRANSFER_READ},
        {.buffer = &it->frame.readback, .use = RB_GPU_TRANSFER_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "stamp", fill, COUNT(fill));
    vkCmdFillBuffer(cmd, t->buffer.buffer, 4 * slot, 4, (uint32_t)ctx->frame);
    rb_integrator_pass_end(it, cmd);
    for (uint32_t i = 0; i < t->repeat; i++) {
        rb_integrator_pass_begin(it, cmd, "repeat", fill, COUNT(fill));
        vkCmdFillBuffer(cmd, t->buffer.buffer, 4 * (SLOTS_MAX - 1), 4, i);
        rb_integrator_pass_end(it, cmd);
    }
    if (ctx->is_warmup)
        return;
    rb_integrator_pass_begin(it, cmd, "copy", copy, COUNT(copy));
    vkCmdCopyBuffer(cmd, t->buffer.buffer, it->frame.readback.buffer, 1,
                    &(VkBufferCopy){0, 0, 4 * n});
    rb_integrator_pass_end(it, cmd);
}

static void destroy_tags(struct rb_integrator *it, void *state)
{
    struct tags *t = state;
    rb_gpu_buffer_release(it->gpu, &t->buffer);
    free(t);
}

static const struct rb_integrator_ops tags_ops = {
    .name = "tags",
    .history_frames = history_tags,
    .create = create_tags,
    .record = record_tags,
    .destroy = destroy_tags,
};

/* A test integrator whose passes hand a value on through two buffers of its own, each hazard
 * kind once: "fill" writes the frame number into a, "copy" copies a to b (read after write on
 * a), "refill" overwrites a (write after read), "out" copies b to the readback (read after
 * write on b). The readback holds the frame number, not the refilled value, when the barriers
 * order the passes. relay_drop names one declaration to leave out. */
enum relay_drop { DROP_NONE, DROP_COPY_READ_A, DROP_COPY_WRITE_B, DROP_REFILL_A, DROP_OUT_READ_B };
static enum relay_drop relay_drop;

struct relay {
    struct rb_gpu_buffer a, b; /* 16 bytes each */
};

static enum rb_status create_relay(struct rb_integrator *it, void **state, struct rb_err *err)
{
    struct relay *r = calloc(1, sizeof(*r));
    if (!r)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    VkBufferUsageFlags usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    enum rb_status st = rb_gpu_buffer_init(
        it->gpu, &(struct rb_gpu_buffer_desc){.size_bytes = 16, .usage = usage, .debug_name = "a"},
        &r->a, err);
    if (st == RB_OK)
        st = rb_gpu_buffer_init(
            it->gpu,
            &(struct rb_gpu_buffer_desc){.size_bytes = 16, .usage = usage, .debug_name = "b"},
            &r->b, err);
    if (st) {
        rb_gpu_buffer_release(it->gpu, &r->b);
        rb_gpu_buffer_release(it->gpu, &r->a);
        free(r);
        return st;
    }
    *state = r;
    return RB_OK;
}

static void record_relay(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                         const struct rb_frame_ctx *ctx)
{
    struct relay *r = state;
    if (ctx->is_warmup)
        return;
    const struct rb_gpu_access fill[] = {{.buffer = &r->a, .use = RB_GPU_TRANSFER_WRITE}};
    const struct rb_gpu_access copy[] = {
        {.buffer = &r->a, .use = RB_GPU_TRANSFER_READ},
        {.buffer = &r->b, .use = RB_GPU_TRANSFER_WRITE},
    };
    const struct rb_gpu_access out[] = {
        {.buffer = &r->b, .use = RB_GPU_TRANSFER_READ},
        {.buffer = &it->frame.readback, .use = RB_GPU_TRANSFER_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "fill", fill, COUNT(fill));
    vkCmdFillBuffer(cmd, r->a.buffer, 0, VK_WHOLE_SIZE, (uint32_t)ctx->frame);
    rb_integrator_pass_end(it, cmd);
    /* A dropped declaration is left out of the list (the last of copy's, the first of out's). */
    rb_integrator_pass_begin(
        it, cmd, "copy", relay_drop == DROP_COPY_READ_A ? copy + 1 : copy,
        relay_drop == DROP_COPY_READ_A || relay_drop == DROP_COPY_WRITE_B ? 1 : COUNT(copy));
    vkCmdCopyBuffer(cmd, r->a.buffer, r->b.buffer, 1, &(VkBufferCopy){0, 0, 16});
    rb_integrator_pass_end(it, cmd);
    rb_integrator_pass_begin(it, cmd, "refill", fill, relay_drop == DROP_REFILL_A ? 0 : 1);
    vkCmdFillBuffer(cmd, r->a.buffer, 0, VK_WHOLE_SIZE, 0xdeadbeefu);
    rb_integrator_pass_end(it, cmd);
    rb_integrator_pass_begin(it, cmd, "out", relay_drop == DROP_OUT_READ_B ? out + 1 : out,
                             relay_drop == DROP_OUT_READ_B ? 1 : COUNT(out));
    vkCmdCopyBuffer(cmd, r->b.buffer, it->frame.readback.buffer, 1, &(VkBufferCopy){0, 0, 16});
    rb_integrator_pass_end(it, cmd);
}

static void destroy_relay(struct rb_integrator *it, void *state)
{
    struct relay *r = state;
    rb_gpu_buffer_release(it->gpu, &r->b);
    rb_gpu_buffer_release(it->gpu, &r->a);
    free(r);
}

static const struct rb_integrator_ops relay_ops = {
    .name = "relay",
    .history_frames = history_tags,
    .create = create_relay,
    .record = record_relay,
    .destroy = destroy_relay,
};

struct fixture {
    struct rb_gpu *gpu;
    struct rb_job *job;
    struct rb_scene *scene;
};

static int setup(void **state)
{
    static struct fixture f;
    struct rb_err err = RB_ERR_INIT;
    struct rb_job_override o[] = {{"resolution", "[32, 18]", NULL},
                                  {"integrator.direct.shadow_size", "64", NULL}};
    if (rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &f.gpu, &err) ||
        rb_job_load("jobs/demo.yaml", o, 2, &f.job, &err) ||
        rb_scene_load(f.job->scene_path, 0, &f.scene, &err)) {
        fprintf(stderr, "setup: %s\n", err.msg);
        return -1;
    }
    *state = &f;
    return 0;
}

static int teardown(void **state)
{
    struct fixture *f = *state;
    rb_scene_destroy(f->scene);
    rb_job_destroy(f->job);
    rb_gpu_destroy(f->gpu);
    return 0;
}

static struct rb_integrator *make(struct fixture *f, const struct rb_integrator_ops *ops,
                                  uint32_t history)
{
    struct rb_integrator *it = NULL;
    struct rb_err err = RB_ERR_INIT;
    struct rb_integrator_desc d = {
        .job = f->job, .scene = f->scene, .gpu = f->gpu, .history_frames = history};
    if (rb_integrator_create_with(&d, ops, &it, &err))
        fail_msg("create: %s", err.msg);
    return it;
}

/* Renders frames a..b and keeps each frame's first `bytes` of readback, `stride` apart. */
static void render_range(struct rb_integrator *it, int a, int b, size_t bytes, size_t stride,
                         uint8_t *out)
{
    struct rb_err err = RB_ERR_INIT;
    for (int f = a; f <= b; f++) {
        struct rb_frame_result r;
        if (rb_integrator_render(it, f, &r, &err))
            fail_msg("frame %d: %s", f, err.msg);
        memcpy(out + (size_t)(f - a) * stride, r.pixels, bytes);
    }
}

static void test_history_contract(void **state)
{
    struct fixture *f = *state;
    for (uint32_t h = 1; h <= 3; h += 2) {
        tags_history = h;
        tags_repeat = 0;
        uint32_t n = h + 1;
        uint32_t whole[8][SLOTS_MAX], chunk[3][SLOTS_MAX];
        struct rb_integrator *it = make(f, &tags_ops, 0);
        assert_int_equal(rb_integrator_history_frames(it), h);
        assert_int_equal(it->frame.slot_count, n);
        render_range(it, 0, 7, 4 * n, sizeof(whole[0]), (uint8_t *)whole);
        rb_integrator_destroy(it);
        /* The whole run's frame 7 holds frames 7..7-h, one a slot. */
        for (uint32_t s = 0; s < n; s++)
            assert_int_equal(whole[7][s] % n, s);
        for (uint32_t k = 0; k < n; k++) {
            uint32_t want = 7 - k, s = want % n;
            assert_int_equal(whole[7][s], want);
        }
        it = make(f, &tags_ops, 0);
        render_range(it, 5, 7, 4 * n, sizeof(chunk[0]), (uint8_t *)chunk);
        rb_integrator_destroy(it);
        for (int k = 0; k < 3; k++)
            assert_memory_equal(chunk[k], whole[5 + k], 4 * n);
        /* A jump back is a chunk of its own: warm-up again, same bits. */
        it = make(f, &tags_ops, 0);
        render_range(it, 6, 6, 4 * n, sizeof(chunk[0]), (uint8_t *)chunk);
        render_range(it, 5, 5, 4 * n, sizeof(chunk[0]), (uint8_t *)chunk[1]);
        rb_integrator_destroy(it);
        assert_memory_equal(chunk[0], whole[6], 4 * n);
        assert_memory_equal(chunk[1], whole[5], 4 * n);
    }
}

static void test_pass_groups(void **state)
{
    struct fixture *f = *state;
    tags_history = 1;
    tags_repeat = 200;
    struct rb_integrator *it = make(f, &tags_ops, 0);
    struct rb_frame_result r;
    struct rb_err err = RB_ERR_INIT;
    if (rb_integrator_render(it, 0, &r, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(r.pass_count, 3);
    assert_string_equal(r.passes[0].name, "stamp");
    assert_int_equal(r.passes[0].count, 1);
    assert_string_equal(r.passes[1].name, "repeat");
    assert_int_equal(r.passes[1].count, 200);
    assert_true(r.passes[1].gpu_ms >= 0.0);
    assert_string_equal(r.passes[2].name, "copy");
    assert_int_equal(r.passes[2].count, 1);
    assert_int_equal(f->gpu->pass_count, 202); /* more than one query pool's worth */
    rb_integrator_destroy(it);
    tags_repeat = 0;
}

/* The direct integrator keeps the contract with its own history (1) and a longer one (3). */
static void test_direct_chunks(void **state)
{
    struct fixture *f = *state;
    size_t bytes = (size_t)32 * 18 * rb_layer_stride(f->job->layer_mask) * sizeof(float);
    uint8_t *whole = malloc(8 * bytes), *chunk = malloc(3 * bytes);
    assert_non_null(whole);
    assert_non_null(chunk);
    for (uint32_t h = 0; h <= 3; h += 3) {
        struct rb_integrator *it = make(f, &rb_integrator_direct, h);
        assert_int_equal(rb_integrator_history_frames(it), h ? h : 1);
        render_range(it, 0, 7, bytes, bytes, whole);
        rb_integrator_destroy(it);
        it = make(f, &rb_integrator_direct, h);
        render_range(it, 5, 7, bytes, bytes, chunk);
        rb_integrator_destroy(it);
        for (int k = 0; k < 3; k++)
            assert_memory_equal(chunk + k * bytes, whole + (5 + k) * bytes, bytes);
        assert_true(memcmp(whole, whole + 4 * bytes, bytes) != 0); /* the demo moves */
    }
    free(whole);
    free(chunk);
}

static void quiet(enum rb_log_level level, const char *msg, void *user)
{
    (void)level;
    (void)msg;
    (void)user;
}

/* With every declaration the relay's frames are validation-clean and hand the frame number on;
 * each declaration left out is the hazard synchronization validation names, so the driver's
 * barriers come from the declarations and nothing else orders the passes. */
static void test_declared_barriers(void **state)
{
    struct fixture *f = *state;
    static const struct {
        enum relay_drop drop;
        const char *hazard;
    } cases[] = {
        {DROP_COPY_READ_A, "SYNC-HAZARD-READ-AFTER-WRITE"},
        {DROP_COPY_WRITE_B, "SYNC-HAZARD-READ-AFTER-WRITE"},
        {DROP_REFILL_A, "SYNC-HAZARD-WRITE-AFTER-READ"},
        {DROP_OUT_READ_B, "SYNC-HAZARD-READ-AFTER-WRITE"},
    };
    tags_history = 1;
    relay_drop = DROP_NONE;
    struct rb_integrator *it = make(f, &relay_ops, 0);
    struct rb_frame_result r;
    struct rb_err err = RB_ERR_INIT;
    for (int frame = 0; frame < 3; frame++) {
        if (rb_integrator_render(it, frame, &r, &err))
            fail_msg("frame %d: %s", frame, err.msg);
        uint32_t px[4];
        memcpy(px, r.pixels, sizeof(px));
        for (int i = 0; i < 4; i++)
            assert_int_equal(px[i], frame);
    }
    assert_int_equal(r.pass_count, 4);
    rb_integrator_destroy(it);
    for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) {
        relay_drop = cases[c].drop;
        it = make(f, &relay_ops, 0);
        rb_log_set_sink(quiet, NULL);
        enum rb_status st = rb_integrator_render(it, 0, &r, &err);
        rb_log_set_sink(NULL, NULL);
        rb_integrator_destroy(it);
        f->gpu->validation_messages = 0; /* the fixture's device goes on to other tests */
        if (st != RB_E_VULKAN)
            fail_msg("case %zu: rendered (%d) without the declaration", c, (int)st);
        if (!strstr(err.msg, cases[c].hazard))
            fail_msg("case %zu: wanted %s, got: %s", c, cases[c].hazard, err.msg);
    }
    relay_drop = DROP_NONE;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_history_contract),
        cmocka_unit_test(test_pass_groups),
        cmocka_unit_test(test_direct_chunks),
        cmocka_unit_test(test_declared_barriers),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
