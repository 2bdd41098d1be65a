/* raybundle bench: renders a job N times, run by run (cmd/render.c renders each run, timing
 * sidecars alone), and records the set in DIR/bench.json: device, driver, build, job hash,
 * runs, frames and options, what raybundle timing compare checks before it compares two sets. */
#include "cmd.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/io.h"

#define MAX_RUNS 99    /* run-01 .. run-99 */
#define DEFAULT_RUNS 9 /* the fewest runs timing compare does not warn about */

struct bench {
    char **options; /* the command line after 'bench', copied before parsing changes it */
    size_t option_count;
    struct cmd_bench_run first; /* what run 1 rendered */
    double wall_s;              /* every run's, summed */
};

/* True when dir is missing or empty (a set goes into a directory of its own). */
static bool is_empty_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return errno == ENOENT;
    struct dirent *e;
    bool is_empty = true;
    while (is_empty && (e = readdir(d)))
        is_empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
    closedir(d);
    return is_empty;
}

static int start(struct cmd_bench_run *run)
{
    run->run_count = DEFAULT_RUNS;
    if (run->runs) {
        unsigned n;
        char tail;
        if (sscanf(run->runs, "%u%c", &n, &tail) != 1 || n < 1 || n > MAX_RUNS) {
            cmd_error("--runs expects 1..%d, got '%s'", MAX_RUNS, run->runs);
            return RB_EXIT_USAGE;
        }
        run->run_count = n;
    }
    if (!is_empty_dir(run->out_dir)) {
        cmd_error("--out '%s' is not an empty directory: a bench set needs one of its own",
                  run->out_dir);
        return RB_EXIT_USAGE;
    }
    return RB_EXIT_OK;
}

/* Writes DIR/bench.json once every run is rendered. */
static int finish(const struct bench *b, const struct cmd_bench_run *run)
{
    const struct cmd_bench_run *f = &b->first;
    size_t frame_count = (size_t)(f->last - f->first + 1);
    int *frames = malloc(frame_count * sizeof(*frames));
    if (!frames) {
        cmd_error("out of memory");
        return RB_EXIT_FAILED;
    }
    for (size_t i = 0; i < frame_count; i++)
        frames[i] = f->first + (int)i;
    struct rb_io_bench rec = {.width_px = f->width_px,
                              .height_px = f->height_px,
                              .run_count = run->run_count,
                              .order = "run-by-run",
                              .frames = frames,
                              .frame_count = frame_count,
                              .options = b->options,
                              .option_count = b->option_count};
    rb_strlcpy(rec.device, f->device, sizeof(rec.device));
    rb_strlcpy(rec.driver, f->driver, sizeof(rec.driver));
    rb_strlcpy(rec.build, "raybundle " RB_VERSION, sizeof(rec.build));
    rb_strlcpy(rec.job, f->job_path, sizeof(rec.job));
    rb_strlcpy(rec.job_hash, f->job_hash, sizeof(rec.job_hash));
    rb_strlcpy(rec.integrator, f->integrator, sizeof(rec.integrator));
    char path[4096];
    struct rb_err err = RB_ERR_INIT;
    snprintf(path, sizeof(path), "%s/bench.json", run->out_dir);
    enum rb_status st = rb_io_make_parent_dirs(path, &err);
    if (!st)
        st = rb_io_bench_write(path, &rec, &err);
    free(frames);
    if (st) {
        cmd_error("%s", err.msg);
        return RB_EXIT_FAILED;
    }
    printf("%u runs of %zu frame%s (%d-%d) on %s in %s/: %.1f s\n", run->run_count, frame_count,
           frame_count == 1 ? "" : "s", f->first, f->last, f->device, run->out_dir, b->wall_s);
    return RB_EXIT_OK;
}

static int on_run(struct cmd_bench_run *run, void *user)
{
    struct bench *b = user;
    if (run->run == 0)
        return start(run);
    if (run->run == 1)
        b->first = *run;
    else if (strcmp(run->job_hash, b->first.job_hash) || strcmp(run->device, b->first.device)) {
        /* each run loads the job and scene again: one of them changed under the bench */
        cmd_error("run %u rendered job %s on '%s', and run 1 job %s on '%s': was the job or "
                  "scene changed during the bench?",
                  run->run, run->job_hash, run->device, b->first.job_hash, b->first.device);
        return RB_EXIT_FAILED;
    }
    b->wall_s += run->wall_s;
    if (!run->is_quiet)
        fprintf(stderr, "raybundle: run %u/%u: %d frames in %.2f s\n", run->run, run->run_count,
                run->last - run->first + 1, run->wall_s);
    return run->run == run->run_count ? finish(b, run) : RB_EXIT_OK;
}

int cmd_bench(int argc, char **argv)
{
    struct bench b = {.option_count = argc > 1 ? (size_t)argc - 1 : 0};
    int rc = RB_EXIT_OK;
    if (b.option_count && !(b.options = calloc(b.option_count, sizeof(*b.options))))
        rc = RB_EXIT_FAILED;
    for (size_t i = 0; rc == RB_EXIT_OK && i < b.option_count; i++)
        if (!(b.options[i] = rb_strdup(argv[i + 1])))
            rc = RB_EXIT_FAILED;
    if (rc)
        cmd_error("out of memory");
    else
        rc = cmd_render_bench(argc, argv, on_run, &b);
    for (size_t i = 0; b.options && i < b.option_count; i++)
        free(b.options[i]);
    free(b.options);
    return rc;
}
