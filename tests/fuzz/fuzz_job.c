/* Fuzz target for the job-file parser: any bytes must give a job or an error, never a crash,
 * a leak or undefined behaviour. Built two ways:
 *   - with clang -fsanitize=fuzzer,address (make fuzz): libFuzzer drives LLVMFuzzerTestOneInput;
 *   - with tests/fuzz/replay.c (make check), which replays the committed corpus, so it stays a
 *     regression test on any compiler. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "job/job.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const struct rb_job_override overrides[] = {{"resolution", "[8, 8]", NULL}};
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    rb_log_set_level(RB_LOG_ERROR);
    /* Once plain, once with an override applied on top, as --set does. */
    for (size_t n = 0; n < 2; n++) {
        if (rb_job_parse("fuzz.yaml", (const char *)data, size, "tests/unit/jobs", overrides, n,
                         &job, &err) == RB_OK)
            rb_job_destroy(job);
        job = NULL;
    }
    return 0;
}
