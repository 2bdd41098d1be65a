/* Fuzz target for the readers of a rendered sequence on disk, as raybundle report, flicker and
 * timing compare meet one: the frame scan of a directory or a pattern, each frame's timing
 * sidecar found beside it, and a bench set (bench.json and its run-NN folders) loaded and
 * compared with itself. Any directory the input describes must give the readers' records or an
 * error, never a crash, a leak or undefined behaviour. Built as fuzz_job.c is: under libFuzzer
 * by make fuzz, and over the committed corpus (tests/fuzz/corpus/sequence) by tests/fuzz/replay.c
 * in make check.
 *
 * The input is a directory: its first part lists file names, one a line (at most two path
 * components of [A-Za-z0-9._-]; a name ending in '/' is a folder; a name with '#' is not made
 * but scanned as a pattern); each following part, after a line "%%", is the content of the next
 * name's file. The files are made in a folder of $TMPDIR that lives as long as the process. */
#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "analysis/analysis.h"
#include "io/io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_NAMES 24
#define MAX_NAME 96

static char root[512];

/* Removes everything under dir (two levels at most, as the names allow). */
static void empty_dir(const char *dir, int depth)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    char path[1024];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
        struct stat sb;
        if (lstat(path, &sb) == 0 && S_ISDIR(sb.st_mode) && depth < 3) {
            empty_dir(path, depth + 1);
            rmdir(path);
        } else {
            unlink(path);
        }
    }
    closedir(d);
}

/* A name the input may make: one or two components of [A-Za-z0-9._#-], none "." or "..". */
static bool is_safe(const char *name)
{
    size_t n = strlen(name), parts = 0;
    if (!n || n > MAX_NAME || name[0] == '/')
        return false;
    if (strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._#-/") != n)
        return false;
    for (const char *p = name; *p;) {
        size_t len = strcspn(p, "/");
        if (len == 0 || (len == 1 && p[0] == '.') || (len == 2 && p[0] == '.' && p[1] == '.'))
            return len == 0 && !p[1] && parts > 0; /* only a final '/' may be empty */
        parts++;
        p += len;
        if (*p == '/')
            p++;
    }
    return parts <= 2;
}

/* Each frame's sidecar, as report reads it: beside the frame, checked against its number. */
static void read_sidecars(const struct rb_analysis_sequence *s)
{
    for (size_t i = 0; i < s->frame_count; i++) {
        char path[2048];
        struct rb_err err = RB_ERR_INIT;
        struct rb_io_timing_file t = {0};
        size_t n = strlen(s->paths[i]);
        if (n < 4 || n + 16 > sizeof(path))
            continue;
        snprintf(path, sizeof(path), "%.*s.timing.json", (int)(n - 4), s->paths[i]);
        if (rb_io_timing_read(path, &t, &err) == RB_OK && t.frame != s->frames[i])
            (void)rb_errf(&err, RB_E_INVALID, "'%s' is the sidecar of frame %d", path, t.frame);
        rb_io_timing_file_release(&t);
        (void)rb_analysis_sequence_find(s, s->frames[i]);
    }
}

static void remove_root(void)
{
    empty_dir(root, 0);
    rmdir(root);
}

static void scan(const char *seq)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_sequence s;
    if (rb_analysis_sequence_scan(seq, &s, &err) == RB_OK)
        read_sidecars(&s);
    rb_analysis_sequence_release(&s);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!root[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(root, sizeof(root), "%s/rb-fuzz-seq.XXXXXX", tmp && *tmp ? tmp : "/tmp");
        if (!mkdtemp(root)) {
            root[0] = '\0';
            return 0;
        }
        atexit(remove_root);
    }
    empty_dir(root, 0);

    /* The parts: names, then contents, split at "\n%%\n". */
    const char *p = (const char *)data, *end = p + size;
    const char *parts[MAX_NAMES + 1];
    size_t lens[MAX_NAMES + 1], part_count = 0;
    while (part_count < MAX_NAMES + 1) {
        const char *cut = NULL;
        for (const char *q = p; q + 4 <= end; q++)
            if (!memcmp(q, "\n%%\n", 4)) {
                cut = q;
                break;
            }
        parts[part_count] = p;
        lens[part_count++] = (size_t)((cut ? cut : end) - p);
        if (!cut)
            break;
        p = cut + 4;
    }

    char names[MAX_NAMES][MAX_NAME + 1];
    size_t name_count = 0;
    for (const char *q = parts[0], *qe = parts[0] + lens[0]; q < qe && name_count < MAX_NAMES;) {
        const char *nl = memchr(q, '\n', (size_t)(qe - q));
        size_t len = (size_t)((nl ? nl : qe) - q);
        if (len <= MAX_NAME) {
            memcpy(names[name_count], q, len);
            names[name_count][len] = '\0';
            if (is_safe(names[name_count]))
                name_count++;
        }
        q += len + 1;
    }

    char path[4096];
    for (size_t i = 0; i < name_count; i++) {
        const char *name = names[i];
        if (strchr(name, '#'))
            continue;
        const char *slash = strchr(name, '/');
        if (slash) { /* the folder first */
            snprintf(path, sizeof(path), "%s/%.*s", root, (int)(slash - name), name);
            (void)mkdir(path, 0777);
            if (!slash[1])
                continue;
        }
        snprintf(path, sizeof(path), "%s/%s", root, name);
        FILE *f = fopen(path, "wb");
        if (!f)
            continue;
        if (i + 1 < part_count)
            fwrite(parts[i + 1], 1, lens[i + 1], f);
        fclose(f);
    }

    scan(root);
    for (size_t i = 0; i < name_count; i++)
        if (strchr(names[i], '#')) {
            snprintf(path, sizeof(path), "%s/%s", root, names[i]);
            scan(path);
        }

    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_timing_set *set = NULL;
    if (rb_analysis_timing_set_load(root, &set, &err) == RB_OK) {
        struct rb_analysis_timing_row *rows = NULL;
        size_t row_count = 0;
        if (rb_analysis_timing_sets_match(set, set, &err) == RB_OK &&
            rb_analysis_timing_compare_sets(
                set, set, &(struct rb_analysis_timing_desc)RB_ANALYSIS_TIMING_DESC_INIT, &rows,
                &row_count, &err) == RB_OK)
            free(rows);
        rb_analysis_timing_set_destroy(set);
    }
    return 0;
}
