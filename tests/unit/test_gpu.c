/* The GPU context: lavapipe is found and chosen by default, a device that does not exist is
 * RB_E_NODEVICE, and a validation-layer message makes rb_gpu_check_validation (and with it every
 * submit) fail -- the plumbing that lets the test suite treat validation errors as failures. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "gpu/gpu.h"

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
    double ms = -1.0;
    assert_int_equal(rb_gpu_pass_times(gpu, &ms, &err), RB_OK);
    assert_true(ms >= 0.0 && ms < 1000.0);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_is_lavapipe),
        cmocka_unit_test(test_missing_device),
        cmocka_unit_test(test_validation_message_fails),
        cmocka_unit_test(test_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
