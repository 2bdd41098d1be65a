/* Fuzz target for the job-file parser: any bytes must give a job or an error, never a crash,
 * a leak or undefined behaviour. Built two ways:
 *   - with clang -fsanitize=fuzzer,address (make fuzz): libFuzzer drives LLVMFuzzerTestOneInput;
 *   - with RB_FUZZ_REPLAY (make check): main() replays the files named on the command line, so
 *     the committed corpus stays a regression test on any compiler. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "job/job.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const struct rb_job_override overrides[] = {{"resolution", "[8, 8]"}};
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

#ifdef RB_FUZZ_REPLAY
/* One TAP line for the whole corpus; each input is named first, so a crash names its input. */
int main(int argc, char **argv)
{
    int failed = 0;
    for (int i = 1; i < argc; i++) {
        char *data = NULL;
        size_t size = 0;
        struct rb_err err = RB_ERR_INIT;
        printf("# %s\n", argv[i]);
        fflush(stdout);
        if (rb_read_file(argv[i], &data, &size, &err)) {
            printf("# %s\n", err.msg);
            failed++;
            continue;
        }
        LLVMFuzzerTestOneInput((const uint8_t *)data, size);
        free(data);
    }
    printf("%s 1 - %d corpus inputs replayed without a crash (%d unreadable)\n1..1\n",
           failed || argc < 2 ? "not ok" : "ok", argc - 1, failed);
    return failed || argc < 2;
}
#endif
