/* The corpus replayer every fuzz target links with outside libFuzzer (make check): feeds each
 * file named on the command line, or each file in a directory named there (in name order), to
 * LLVMFuzzerTestOneInput and prints TAP, one line for the whole corpus. A crash or a sanitizer
 * report kills the program, so the runner counts it as a failure. */
#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "core/core.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Replays one file, naming it first so that a crash names its input; 0 when it was read. */
static int replay_file(const char *path)
{
    char *data = NULL;
    size_t size = 0;
    struct rb_err err = RB_ERR_INIT;
    printf("# %s\n", path);
    fflush(stdout);
    if (rb_read_file(path, &data, &size, &err)) {
        printf("# %s\n", err.msg);
        return -1;
    }
    LLVMFuzzerTestOneInput((const uint8_t *)data, size);
    free(data);
    return 0;
}

static int skip_dot(const struct dirent *e)
{
    return e->d_name[0] != '.';
}

int main(int argc, char **argv)
{
    int failed = 0, count = 0;
    for (int i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0 || !S_ISDIR(st.st_mode)) {
            count++;
            failed += replay_file(argv[i]) != 0;
            continue;
        }
        struct dirent **names = NULL;
        int n = scandir(argv[i], &names, skip_dot, alphasort);
        if (n < 0) {
            printf("# cannot list '%s'\n", argv[i]);
            failed++;
            continue;
        }
        for (int k = 0; k < n; k++) {
            char path[4096];
            snprintf(path, sizeof(path), "%s/%s", argv[i], names[k]->d_name);
            count++;
            failed += replay_file(path) != 0;
            free(names[k]);
        }
        free(names);
    }
    printf("%s 1 - %s: %d corpus inputs replayed without a crash (%d unreadable)\n1..1\n",
           failed || count == 0 ? "not ok" : "ok", argv[0], count, failed);
    return failed || count == 0;
}
