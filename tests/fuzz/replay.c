/* The corpus replayer every fuzz target links with outside libFuzzer (make check): feeds each
 * file named on the command line to LLVMFuzzerTestOneInput and prints TAP, one line for the
 * whole corpus. A crash kills the program, so the runner counts it as a failure. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/core.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

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
