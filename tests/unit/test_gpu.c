/* The GPU context: lavapipe is found and chosen by default, a device that does not exist is
 * RB_E_NODEVICE, and a validation-layer message makes rb_gpu_check_validation (and with it every
 * submit) fail -- the plumbing that lets the test suite treat validation errors as failures.
 * Descriptor layouts past the old 16 bindings work, and layouts past the device's limits fail at
 * create time with the limit's name. The barrier builder, given two passes' declarations,
 * emits the barrier each hazard needs and none between reads. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "gpu/gpu.h"

#include "bindings_shared.h"
#include "many_bindings.comp.h"

static char first_error[1024];

static void capture(enum rb_log_level level, const char *msg, void *user)
{
    (void)user;
    if (level == RB_LOG_ERROR && !first_error[0])
        rb_strlcpy(first_error, msg, sizeof(first_error));
}

static void test_default_is_lavapipe(void **state)
{
    (void)state;
    struct rb_gpu *gpu = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err);
    if (st)
        fail_msg("%s", err.msg);
    assert_true(gpu->is_lavapipe);
    assert_non_null(strstr(gpu->device_name, "llvmpipe"));
    assert_true(gpu->driver[0] != '\0');
    assert_int_equal(rb_gpu_check_validation(gpu, &err), RB_OK);
    /* An empty frame submits cleanly and times nothing. */
    assert_int_equal(rb_gpu_begin(gpu, &err), RB_OK);
    rb_gpu_pass_begin(gpu, gpu->cmd, "empty");
    rb_gpu_pass_end(gpu, gpu->cmd);
    assert_int_equal(rb_gpu_submit_wait(gpu, &err), RB_OK);
    assert_int_equal(rb_gpu_pass_times(gpu, &err), RB_OK);
    assert_int_equal(gpu->pass_count, 1);
    assert_string_equal(gpu->passes[0].name, "empty");
    assert_true(gpu->passes[0].gpu_ms >= 0.0 && gpu->passes[0].gpu_ms < 1000.0);
    rb_gpu_destroy(gpu);
}

static void test_missing_device(void **state)
{
    (void)state;
    struct rb_gpu *gpu = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_gpu_create(&(struct rb_gpu_desc){.device = "no-such-gpu"}, &gpu, &err),
                     RB_E_NODEVICE);
    assert_null(gpu);
    assert_non_null(strstr(err.msg, "no-such-gpu"));
    assert_int_equal(rb_gpu_create(&(struct rb_gpu_desc){.device = "99"}, &gpu, &err),
                     RB_E_NODEVICE);
    assert_non_null(strstr(err.msg, "out of range"));
}

static void test_validation_message_fails(void **state)
{
    (void)state;
    struct rb_gpu *gpu = NULL;
    struct rb_err err = RB_ERR_INIT;
    first_error[0] = '\0';
    rb_log_set_sink(capture, NULL);
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err);
    if (st)
        fail_msg("%s", err.msg);
    /* A buffer of size 0 is invalid usage (VUID-VkBufferCreateInfo-size-00912). */
    VkBufferCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
        .size = 0,
        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
    };
    VkBuffer buf = VK_NULL_HANDLE;
    if (vkCreateBuffer(gpu->device, &ci, NULL, &buf) == VK_SUCCESS && buf)
        vkDestroyBuffer(gpu->device, buf, NULL);
    rb_log_set_sink(NULL, NULL);
    assert_true(gpu->validation_messages >= 1);
    assert_int_equal(rb_gpu_check_validation(gpu, &err), RB_E_VULKAN);
    assert_non_null(strstr(err.msg, "validation message"));
    assert_non_null(strstr(first_error, "VUID-VkBufferCreateInfo-size"));
    rb_gpu_destroy(gpu);
}

/* 19 storage buffers in and one out: each input holds a value of its own, and the shader copies
 * input i to out[i], so a binding that reached the wrong buffer (or none) shows. The bindings are
 * set in reverse order: they land by number, not by call order. */
static void test_many_bindings(void **state)
{
    (void)state;
    enum { IN_COUNT = RB_BIND_MANY_BINDINGS_COUNT - 1 };
    _Static_assert(RB_BIND_MANY_BINDINGS_COUNT > 16, "more than the old fixed 16");
    struct rb_gpu *gpu = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err);
    if (st)
        fail_msg("%s", err.msg);
    struct rb_gpu_buffer in[IN_COUNT] = {{0}}, out = {0};
    for (int i = 0; i < IN_COUNT; i++) {
        assert_int_equal(rb_gpu_buffer_init(gpu,
                                            &(struct rb_gpu_buffer_desc){
                                                .size_bytes = sizeof(uint32_t),
                                                .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                .is_host_visible = true,
                                                .debug_name = "many_bindings.in"},
                                            &in[i], &err),
                         RB_OK);
        *(uint32_t *)in[i].mapped = 0x5eed0000u + 97u * (uint32_t)i;
    }
    assert_int_equal(
        rb_gpu_buffer_init(gpu,
                           &(struct rb_gpu_buffer_desc){.size_bytes = IN_COUNT * sizeof(uint32_t),
                                                        .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        .is_host_visible = true,
                                                        .debug_name = "many_bindings.out"},
                           &out, &err),
        RB_OK);
    memset(out.mapped, 0, IN_COUNT * sizeof(uint32_t));

    VkDescriptorType types[RB_BIND_MANY_BINDINGS_COUNT];
    for (int i = 0; i < RB_BIND_MANY_BINDINGS_COUNT; i++)
        types[i] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    struct rb_gpu_layout layout = {0};
    VkPipeline pipe = VK_NULL_HANDLE;
    st = rb_gpu_layout_init(gpu, types, RB_BIND_MANY_BINDINGS_COUNT, 0, &layout, &err);
    if (st)
        fail_msg("%s", err.msg);
    assert_int_equal(layout.binding_count, RB_BIND_MANY_BINDINGS_COUNT);
    assert_int_equal(rb_gpu_compute_pipeline(gpu, rb_spv_many_bindings_comp,
                                             sizeof(rb_spv_many_bindings_comp),
                                             layout.pipeline_layout, "many_bindings", &pipe, &err),
                     RB_OK);
    assert_int_equal(rb_gpu_begin(gpu, &err), RB_OK);
    struct rb_gpu_bindings b = {0};
    rb_gpu_bindings_set_buffer(&b, RB_BIND_MANY_BINDINGS_OUT, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                               &out);
    for (int i = IN_COUNT - 1; i >= 0; i--)
        rb_gpu_bindings_set_buffer(&b, RB_BIND_MANY_BINDINGS_IN + (uint32_t)i,
                                   VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &in[i]);
    assert_int_equal(b.count, RB_BIND_MANY_BINDINGS_COUNT);
    vkCmdBindPipeline(gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
    rb_gpu_push_bindings(gpu, gpu->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout.pipeline_layout, &b);
    vkCmdDispatch(gpu->cmd, 1, 1, 1);
    rb_gpu_memory_barrier(gpu->cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
    st = rb_gpu_submit_wait(gpu, &err); /* fails on any validation message */
    if (st)
        fail_msg("%s", err.msg);
    const uint32_t *o = out.mapped;
    for (int i = 0; i < IN_COUNT; i++)
        assert_int_equal(o[i], 0x5eed0000u + 97u * (uint32_t)i);
    assert_int_equal(gpu->validation_messages, 0);

    vkDestroyPipeline(gpu->device, pipe, NULL);
    rb_gpu_layout_release(gpu, &layout);
    rb_gpu_buffer_release(gpu, &out);
    for (int i = 0; i < IN_COUNT; i++)
        rb_gpu_buffer_release(gpu, &in[i]);
    rb_gpu_destroy(gpu);
}

/* A layout past a limit is refused before Vulkan sees it, naming the limit and both numbers:
 * on the device (33 bindings against lavapipe's 32 push descriptors) and against made-up limits
 * for each per-stage count. */
static void test_layout_limits(void **state)
{
    (void)state;
    struct rb_gpu *gpu = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){.validate = true}, &gpu, &err);
    if (st)
        fail_msg("%s", err.msg);
    VkDescriptorType types[RB_GPU_MAX_BINDINGS + 1];
    for (int i = 0; i < RB_GPU_MAX_BINDINGS + 1; i++)
        types[i] = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    struct rb_gpu_layout layout = {0};
    assert_int_equal(rb_gpu_layout_init(gpu, types, RB_GPU_MAX_BINDINGS + 1, 0, &layout, &err),
                     RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "33 bindings, more than maxPushDescriptors (32)"));
    assert_null(layout.set_layout);
    /* The most the device and the binding list allow is fine. */
    st = rb_gpu_layout_init(gpu, types, RB_GPU_MAX_BINDINGS, 0, &layout, &err);
    if (st)
        fail_msg("%s", err.msg);
    rb_gpu_layout_release(gpu, &layout);
    assert_int_equal(rb_gpu_check_validation(gpu, &err), RB_OK);

    VkPhysicalDeviceLimits lim = gpu->props.limits;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, types, 20, &err), RB_OK);
    assert_int_equal(rb_gpu_layout_check(&lim, 16, types, 20, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "20 bindings, more than maxPushDescriptors (16)"));
    lim.maxPerStageDescriptorStorageBuffers = 16;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, types, 20, &err), RB_E_UNSUPPORTED);
    assert_non_null(
        strstr(err.msg, "20 storage buffers, more than maxPerStageDescriptorStorageBuffers (16)"));
    lim = gpu->props.limits;
    lim.maxPerStageResources = 19;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, types, 20, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "20 resources, more than maxPerStageResources (19)"));

    const VkDescriptorType mixed[] = {
        VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,         VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
        VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,          VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
        VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_SAMPLER,
    };
    lim = gpu->props.limits;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_OK);
    lim.maxPerStageDescriptorUniformBuffers = 1;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "2 uniform buffers"));
    lim = gpu->props.limits;
    lim.maxPerStageDescriptorStorageImages = 1;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "2 storage images"));
    lim = gpu->props.limits;
    lim.maxPerStageDescriptorSamplers = 1; /* the combined image sampler counts as one */
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "2 samplers"));
    lim = gpu->props.limits;
    lim.maxPerStageResources = 5; /* the sampler alone is not a resource */
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_OK);
    lim.maxPerStageResources = 4;
    assert_int_equal(rb_gpu_layout_check(&lim, 32, mixed, 6, &err), RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "5 resources, more than maxPerStageResources (4)"));
    rb_gpu_destroy(gpu);
}

/* The limit checks name the pass, the resource, the size and the limit; the readback's bands fit
 * the storage range and start aligned. Made-up limits keep the messages exact on any device; the
 * device's own limits are read at create (the spec's minimum maxPushDescriptors is 32). */
static void test_limits(void **state)
{
    (void)state;
    struct rb_gpu fake = {
        .max_push_descriptors = 32, .max_buffer_bytes = 5000, .max_allocation_bytes = 4000};
    fake.props.limits.maxStorageBufferRange = 1000;
    fake.props.limits.minStorageBufferOffsetAlignment = 64;
    fake.props.limits.maxComputeWorkGroupCount[0] = 65535;
    fake.props.limits.maxComputeWorkGroupCount[1] = 100;
    fake.props.limits.maxComputeWorkGroupCount[2] = 1;
    struct rb_err err = RB_ERR_INIT;

    assert_int_equal(rb_gpu_check_storage_range(&fake, "output", "readback", 1000, &err), RB_OK);
    assert_int_equal(rb_gpu_check_storage_range(&fake, "output", "readback", 1001, &err),
                     RB_E_UNSUPPORTED);
    assert_string_equal(err.msg, "pass 'output': storage buffer 'readback' binds 1001 bytes, more "
                                 "than the device's maxStorageBufferRange (1000 bytes)");
    assert_int_equal(rb_gpu_check_buffer_size(&fake, "output", "readback", 4000, &err), RB_OK);
    assert_int_equal(rb_gpu_check_buffer_size(&fake, "output", "readback", 4001, &err),
                     RB_E_UNSUPPORTED);
    assert_string_equal(err.msg, "pass 'output': buffer 'readback' needs 4001 bytes, more than "
                                 "the device's maxMemoryAllocationSize (4000 bytes)");
    assert_int_equal(rb_gpu_check_buffer_size(&fake, "output", "readback", 5001, &err),
                     RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "maxBufferSize (5000 bytes)"));
    assert_int_equal(rb_gpu_check_dispatch(&fake, "direct", 65535, 100, 1, &err), RB_OK);
    assert_int_equal(rb_gpu_check_dispatch(&fake, "direct", 1, 101, 1, &err), RB_E_UNSUPPORTED);
    assert_string_equal(err.msg, "pass 'direct': dispatch of 1 x 101 x 1 workgroups: 101 in y, "
                                 "more than the device's maxComputeWorkGroupCount[1] (100)");
    assert_int_equal(rb_gpu_check_push_descriptors(&fake, NULL, 32, &err), RB_OK);
    assert_int_equal(rb_gpu_check_push_descriptors(&fake, NULL, 33, &err), RB_E_UNSUPPORTED);
    assert_string_equal(err.msg, "push-descriptor set of 33 bindings, more than the device's "
                                 "maxPushDescriptors (32)");

    /* Bands: as many rows as fit, a multiple of the alignment in bytes, and one more aligned step
     * of rows would not fit. */
    const VkDeviceSize row_sizes[] = {40, 48, 100, 125, 999};
    for (size_t i = 0; i < sizeof(row_sizes) / sizeof(row_sizes[0]); i++) {
        VkDeviceSize row = row_sizes[i];
        uint32_t rows = rb_gpu_storage_band_rows(&fake, row, 1000);
        assert_int_equal(rb_gpu_check_storage_bands(&fake, "output", "readback", row, 1000, &err),
                         rows ? RB_OK : RB_E_UNSUPPORTED);
        VkDeviceSize step = 1;
        while (step * row % 64)
            step++;
        if (rows == 0) {
            assert_true(step * row > 1000);
            continue;
        }
        assert_true(rows * row <= 1000);
        assert_int_equal(rows * row % 64, 0);
        assert_true((rows + step) * row > 1000);
    }
    /* 125-byte rows need 64 of them to start aligned: 8000 bytes. */
    assert_int_equal(rb_gpu_check_storage_bands(&fake, "output", "readback", 125, 1000, &err),
                     RB_E_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "pass 'output': storage buffer 'readback' binds at least 8000 "
                                    "bytes (64 rows of 125 bytes"));
    assert_non_null(strstr(err.msg, "maxStorageBufferRange (1000 bytes)"));
    /* Everything in one binding when it fits, whatever the alignment. */
    assert_int_equal(rb_gpu_storage_band_rows(&fake, 125, 8), 8);

    struct rb_gpu *gpu = NULL;
    enum rb_status st = rb_gpu_create(&(struct rb_gpu_desc){0}, &gpu, &err);
    if (st)
        fail_msg("%s", err.msg);
    assert_true(gpu->max_push_descriptors >= 32);
    assert_true(gpu->max_allocation_bytes > 0 && gpu->max_buffer_bytes > 0);
    /* A 3840x2160 readback: several aligned bands within the device's range. */
    VkDeviceSize row = 3840 * 20 * sizeof(float);
    uint32_t rows = rb_gpu_storage_band_rows(gpu, row, 2160);
    assert_true(rows > 0);
    assert_true(rows * row <= gpu->props.limits.maxStorageBufferRange);
    assert_int_equal(rows * row % gpu->props.limits.minStorageBufferOffsetAlignment, 0);
    rb_gpu_destroy(gpu);
}

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* Fake handles: rb_gpu_barriers_derive reads nothing but the declarations. */
#define FAKE_BUFFER(n)                                                                             \
    {                                                                                              \
        .buffer = (VkBuffer)(uintptr_t)(n)                                                         \
    }
#define FAKE_IMAGE(n, aspect_bits)                                                                 \
    {                                                                                              \
        .image = (VkImage)(uintptr_t)(n), .aspect = (aspect_bits)                                  \
    }

static const VkDependencyInfo *derive(struct rb_gpu_barriers *b, const struct rb_gpu_access *uses,
                                      uint32_t count)
{
    static VkDependencyInfo dep;
    struct rb_err err = RB_ERR_INIT;
    if (rb_gpu_barriers_derive(b, uses, count, &dep, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(dep.memoryBarrierCount, 0); /* per resource, never global */
    return &dep;
}

static void expect_image(const VkDependencyInfo *dep, const struct rb_gpu_image *img,
                         VkPipelineStageFlags2 src, VkAccessFlags2 src_access,
                         VkPipelineStageFlags2 dst, VkAccessFlags2 dst_access, VkImageLayout from,
                         VkImageLayout to)
{
    assert_int_equal(dep->bufferMemoryBarrierCount, 0);
    assert_int_equal(dep->imageMemoryBarrierCount, 1);
    const VkImageMemoryBarrier2 *m = &dep->pImageMemoryBarriers[0];
    assert_int_equal(m->sType, VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2);
    assert_true(m->image == img->image);
    assert_int_equal(m->srcStageMask, src);
    assert_int_equal(m->srcAccessMask, src_access);
    assert_int_equal(m->dstStageMask, dst);
    assert_int_equal(m->dstAccessMask, dst_access);
    assert_int_equal(m->oldLayout, from);
    assert_int_equal(m->newLayout, to);
    assert_int_equal(m->subresourceRange.aspectMask, img->aspect);
    assert_int_equal(m->subresourceRange.levelCount, VK_REMAINING_MIP_LEVELS);
    assert_int_equal(m->subresourceRange.layerCount, VK_REMAINING_ARRAY_LAYERS);
    assert_int_equal(m->srcQueueFamilyIndex, VK_QUEUE_FAMILY_IGNORED);
}

static void expect_buffer(const VkDependencyInfo *dep, const struct rb_gpu_buffer *buf,
                          VkPipelineStageFlags2 src, VkAccessFlags2 src_access,
                          VkPipelineStageFlags2 dst, VkAccessFlags2 dst_access)
{
    assert_int_equal(dep->imageMemoryBarrierCount, 0);
    assert_int_equal(dep->bufferMemoryBarrierCount, 1);
    const VkBufferMemoryBarrier2 *m = &dep->pBufferMemoryBarriers[0];
    assert_int_equal(m->sType, VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2);
    assert_true(m->buffer == buf->buffer);
    assert_int_equal(m->srcStageMask, src);
    assert_int_equal(m->srcAccessMask, src_access);
    assert_int_equal(m->dstStageMask, dst);
    assert_int_equal(m->dstAccessMask, dst_access);
    assert_int_equal(m->offset, 0);
    assert_int_equal(m->size, VK_WHOLE_SIZE);
}

static void expect_none(const VkDependencyInfo *dep)
{
    assert_int_equal(dep->bufferMemoryBarrierCount, 0);
    assert_int_equal(dep->imageMemoryBarrierCount, 0);
}

#define STAGE(x) VK_PIPELINE_STAGE_2_##x##_BIT
#define ACCESS(x) VK_ACCESS_2_##x##_BIT

/* The direct integrator's shape: an attachment written by a raster pass and read by two compute
 * passes, a uniform buffer every pass reads, a buffer written and read back by the host. The
 * attachment cases are checked only here: the validation layer of Debian 12 (1.3.239) does not
 * see the accesses of dynamic rendering, so its synchronization checks miss those hazards. */
static void test_barrier_builder(void **state)
{
    (void)state;
    struct rb_gpu_barriers b = RB_GPU_BARRIERS_INIT;
    struct rb_gpu_image gb = FAKE_IMAGE(0x100, VK_IMAGE_ASPECT_COLOR_BIT);
    struct rb_gpu_image depth = FAKE_IMAGE(0x200, VK_IMAGE_ASPECT_DEPTH_BIT);
    struct rb_gpu_image out = FAKE_IMAGE(0x300, VK_IMAGE_ASPECT_COLOR_BIT);
    struct rb_gpu_buffer globals = FAKE_BUFFER(0x100), readback = FAKE_BUFFER(0x400);
    const struct rb_gpu_access raster[] = {
        {.buffer = &globals, .use = RB_GPU_GRAPHICS_UNIFORM},
        {.image = &gb, .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    const struct rb_gpu_access shade[] = {
        {.buffer = &globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = &gb, .use = RB_GPU_COMPUTE_READ},
        {.image = &out, .use = RB_GPU_COMPUTE_WRITE},
    };
    const struct rb_gpu_access pack[] = {
        {.buffer = &globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = &gb, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &readback, .use = RB_GPU_COMPUTE_WRITE},
    };
    const struct rb_gpu_access host[] = {{.buffer = &readback, .use = RB_GPU_HOST_READ}};

    /* First uses of resources in GENERAL with nothing before them: no barrier. */
    expect_none(derive(&b, raster, COUNT(raster)));
    /* Read after write: the attachment's write made visible to the compute read. globals has
     * gb's handle value, but is a buffer: it is not confused with the image, and two reads of it
     * need nothing. */
    expect_image(derive(&b, shade, COUNT(shade)), &gb, STAGE(COLOR_ATTACHMENT_OUTPUT),
                 ACCESS(COLOR_ATTACHMENT_WRITE), STAGE(COMPUTE_SHADER), ACCESS(SHADER_STORAGE_READ),
                 VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
    /* A second read in a stage and access the write is visible to already: nothing. */
    expect_none(derive(&b, pack, COUNT(pack)));
    /* The host's read waits for the compute write. */
    expect_buffer(derive(&b, host, 1), &readback, STAGE(COMPUTE_SHADER),
                  ACCESS(SHADER_STORAGE_WRITE), STAGE(HOST), ACCESS(HOST_READ));

    /* The next frame: write after read on the attachment (the two compute reads finish first),
     * write after write on the depth attachment; the readback, read by the host after the last
     * fence, needs nothing. */
    const VkDependencyInfo *dep = derive(&b, raster, COUNT(raster));
    assert_int_equal(dep->bufferMemoryBarrierCount, 0);
    assert_int_equal(dep->imageMemoryBarrierCount, 2);
    const VkImageMemoryBarrier2 *m = dep->pImageMemoryBarriers;
    assert_true(m[0].image == gb.image && m[1].image == depth.image); /* declaration order */
    assert_int_equal(m[0].srcStageMask, STAGE(COLOR_ATTACHMENT_OUTPUT) | STAGE(COMPUTE_SHADER));
    assert_int_equal(m[0].srcAccessMask, ACCESS(COLOR_ATTACHMENT_WRITE));
    assert_int_equal(m[0].dstStageMask, STAGE(COLOR_ATTACHMENT_OUTPUT));
    assert_int_equal(m[0].dstAccessMask, ACCESS(COLOR_ATTACHMENT_WRITE));
    VkPipelineStageFlags2 tests = STAGE(EARLY_FRAGMENT_TESTS) | STAGE(LATE_FRAGMENT_TESTS);
    VkAccessFlags2 ds =
        ACCESS(DEPTH_STENCIL_ATTACHMENT_READ) | ACCESS(DEPTH_STENCIL_ATTACHMENT_WRITE);
    assert_int_equal(m[1].srcStageMask, tests);
    assert_int_equal(m[1].srcAccessMask, ACCESS(DEPTH_STENCIL_ATTACHMENT_WRITE));
    assert_int_equal(m[1].dstStageMask, tests);
    assert_int_equal(m[1].dstAccessMask, ds);
    assert_int_equal(m[1].subresourceRange.aspectMask, VK_IMAGE_ASPECT_DEPTH_BIT);
    /* Read after write on the attachment again, write after write on the compute output; the
     * readback, read by the host after the last fence, is written with no barrier. */
    dep = derive(&b, shade, COUNT(shade));
    assert_int_equal(dep->bufferMemoryBarrierCount, 0);
    assert_int_equal(dep->imageMemoryBarrierCount, 2);
    m = dep->pImageMemoryBarriers;
    assert_true(m[0].image == gb.image && m[1].image == out.image);
    assert_int_equal(m[0].srcStageMask, STAGE(COLOR_ATTACHMENT_OUTPUT));
    assert_int_equal(m[0].dstAccessMask, ACCESS(SHADER_STORAGE_READ));
    assert_int_equal(m[1].srcStageMask, STAGE(COMPUTE_SHADER));
    assert_int_equal(m[1].srcAccessMask, ACCESS(SHADER_STORAGE_WRITE));
    assert_int_equal(m[1].dstStageMask, STAGE(COMPUTE_SHADER));
    assert_int_equal(m[1].dstAccessMask, ACCESS(SHADER_STORAGE_WRITE));
    expect_none(derive(&b, pack, COUNT(pack)));
    expect_buffer(derive(&b, host, 1), &readback, STAGE(COMPUTE_SHADER),
                  ACCESS(SHADER_STORAGE_WRITE), STAGE(HOST), ACCESS(HOST_READ));
    rb_gpu_barriers_release(&b);
}

/* Uses joined within a pass, write after write of a transfer, an undeclared resource left
 * alone, and layout changes. */
static void test_barrier_builder_cases(void **state)
{
    (void)state;
    struct rb_gpu_barriers b = RB_GPU_BARRIERS_INIT;
    struct rb_gpu_buffer a = FAKE_BUFFER(0x10), c = FAKE_BUFFER(0x20);
    struct rb_gpu_image tex = FAKE_IMAGE(0x30, VK_IMAGE_ASPECT_COLOR_BIT);

    /* A fill, then a shader that reads and adds to the same buffer (two uses, one barrier). */
    expect_none(derive(&b, &(struct rb_gpu_access){.buffer = &a, .use = RB_GPU_TRANSFER_WRITE}, 1));
    const struct rb_gpu_access rw[] = {
        {.buffer = &a, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &a, .use = RB_GPU_COMPUTE_WRITE},
    };
    expect_buffer(derive(&b, rw, COUNT(rw)), &a, STAGE(ALL_TRANSFER), ACCESS(TRANSFER_WRITE),
                  STAGE(COMPUTE_SHADER),
                  ACCESS(SHADER_STORAGE_READ) | ACCESS(SHADER_STORAGE_WRITE));
    /* A pass that declares only c: a's pending write gets no barrier (undeclared is unsynced). */
    expect_none(derive(&b, &(struct rb_gpu_access){.buffer = &c, .use = RB_GPU_COMPUTE_READ}, 1));
    /* Two passes reading c, a buffer nobody wrote: never a barrier. */
    expect_none(derive(&b, &(struct rb_gpu_access){.buffer = &c, .use = RB_GPU_VERTEX_READ}, 1));

    /* A compute write, then a sampled read in another layout: the transition waits for the
     * write and makes it visible; a second read the same way needs nothing; a read in another
     * stage waits for the first reader's stage (the transition is a write) with no access. */
    expect_none(derive(&b, &(struct rb_gpu_access){.image = &tex, .use = RB_GPU_COMPUTE_WRITE}, 1));
    const struct rb_gpu_access sampled = {.image = &tex,
                                          .use = RB_GPU_FRAGMENT_SAMPLED,
                                          .layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    expect_image(derive(&b, &sampled, 1), &tex, STAGE(COMPUTE_SHADER), ACCESS(SHADER_STORAGE_WRITE),
                 STAGE(FRAGMENT_SHADER), ACCESS(SHADER_SAMPLED_READ), VK_IMAGE_LAYOUT_GENERAL,
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    expect_none(derive(&b, &sampled, 1));
    const struct rb_gpu_access compute_sampled = {.image = &tex,
                                                  .use = RB_GPU_COMPUTE_SAMPLED,
                                                  .layout =
                                                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    expect_image(derive(&b, &compute_sampled, 1), &tex, STAGE(FRAGMENT_SHADER), 0,
                 STAGE(COMPUTE_SHADER), ACCESS(SHADER_SAMPLED_READ),
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    /* Back to GENERAL (layout 0) for a write: waits for both readers. */
    expect_image(derive(&b, &(struct rb_gpu_access){.image = &tex, .use = RB_GPU_COMPUTE_WRITE}, 1),
                 &tex, STAGE(FRAGMENT_SHADER) | STAGE(COMPUTE_SHADER), 0, STAGE(COMPUTE_SHADER),
                 ACCESS(SHADER_STORAGE_WRITE), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                 VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_barriers_release(&b);
    assert_null(b.tracked);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_is_lavapipe),
        cmocka_unit_test(test_missing_device),
        cmocka_unit_test(test_validation_message_fails),
        cmocka_unit_test(test_many_bindings),
        cmocka_unit_test(test_layout_limits),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_barrier_builder),
        cmocka_unit_test(test_barrier_builder_cases),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
