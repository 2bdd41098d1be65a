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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_is_lavapipe),
        cmocka_unit_test(test_missing_device),
        cmocka_unit_test(test_validation_message_fails),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
