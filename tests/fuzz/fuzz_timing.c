/* Fuzz target for the JSON readers of lib/io/timing.c: any bytes, read as a timing sidecar and as
 * a bench set's bench.json, must give the record or an error, never a crash, a leak or undefined
 * behaviour. Built as fuzz_job.c is: under libFuzzer by make fuzz, and over the committed corpus
 * (tests/fuzz/corpus/timing) by tests/fuzz/replay.c in make check. */
#include <stddef.h>
#include <stdint.h>

#include "io/io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_io_timing_file t;
    struct rb_io_bench b;
    /* The release runs after a failure too: the readers leave what they built for it. */
    (void)rb_io_timing_parse("fuzz.timing.json", (const char *)data, size, &t, &err);
    rb_io_timing_file_release(&t);
    (void)rb_io_bench_parse("bench.json", (const char *)data, size, &b, &err);
    rb_io_bench_release(&b);
    return 0;
}
