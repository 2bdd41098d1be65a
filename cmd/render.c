/* raybundle render and reference: parse options, load the job and scene, and run the frame
 * range through lib/render (which renders and writes each frame), with progress, signals and
 * exit codes. No rendering logic lives here. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "io/io.h"
#include "job/job.h"
#include "render/render.h"
#include "scene/scene.h"

#define MAX_OVERRIDES 64

static volatile sig_atomic_t interrupted; /* the signal that asked us to stop, or 0 */

static void on_signal(int sig)
{
    /* First SIGINT or SIGTERM: a GPU frame in flight is finished and written; a reference
     * frame stops sampling and is not written. Second: stop now (files are renamed into place,
     * so none is ever torn). */
    if (interrupted)
        signal(sig, SIG_DFL), raise(sig);
    interrupted = sig;
}

/* Log lines and errors end an open progress bar's line first. */
static void log_sink(enum rb_log_level level, const char *msg, void *user)
{
    (void)user;
    static const char *const names[] = {"error", "warning", "info", "debug"};
    cmd_end_bar();
    fprintf(stderr, "raybundle: %s: %s\n", names[level], msg);
}

struct options {
    const char *job_path;
    struct rb_job_override overrides[MAX_OVERRIDES];
    size_t override_count;
    const char *output, *out_dir, *device, *threads;
    const char *spp, *time_limit; /* as given, for messages */
    bool resume, validate, preview, quiet;
    bool is_lenient; /* --lenient: glTF type errors and forbidden values are warnings */
    bool is_strict;  /* --strict: a full ray-bundle node buffer fails the frame */
    bool is_openjd;  /* --progress=openjd: OpenJD progress messages on stdout */
    int verbose;
    struct rb_render_frames frames; /* --frames' list; no ranges: the job's range */
    struct rb_render_chunk chunk;   /* --chunk; count 0: all the frames */
    const char *command;            /* "render", "reference" or "bench" */
    const char *runs;               /* bench: --runs as given */
    bool is_timing_only;            /* bench: timing sidecars alone, no images */
    /* Text behind the options that are sugar for --set (--frames, --size, ...). */
    char frames_start[32], frames_end[32], size_value[48];
    char frames_origin[64], size_origin[64], integrator_origin[64], spp_origin[64],
        time_limit_origin[64], view_origin[64];
};

/* The commands of this file, as bits of a set. */
enum { FOR_RENDER = 1 << 0, FOR_REFERENCE = 1 << 1, FOR_BENCH = 1 << 2, FOR_ALL = 7 };

enum {
    O_FRAMES = 256,
    O_SIZE,
    O_OUT,
    O_INTEGRATOR,
    O_SET,
    O_RESUME,
    O_PREVIEW,
    O_DEVICE,
    O_VALIDATE,
    O_LENIENT,
    O_SPP,
    O_TIME_LIMIT,
    O_THREADS,
    O_STRICT,
    O_RUNS,
    O_CHUNK,
    O_PROGRESS,
    O_VIEW
};

/* One option of render, reference and bench. The one table that getopt, each command's --help
 * and the note on another command's option read, so that help and parser cannot disagree. */
struct flag {
    const char *name; /* the long name; a letter val is its short name too */
    int has_arg;
    int val;
    unsigned commands;  /* FOR_*: the commands that take it */
    const char *arg;    /* the value in --help, or NULL */
    const char *help;   /* --help's text; '\n' continues it on an indented line */
    const char *absent; /* why the other commands do not take it, or NULL (all do) */
};

static const struct flag flags[] = {
    {"frames", required_argument, O_FRAMES, FOR_ALL, "LIST",
     "render frames A-B, or a list such as 1-3,5,7-20:2\n"
     "(A-B:S or A-BxS steps by S); sets frames.* to its first\n"
     "and last frame",
     NULL},
    {"chunk", required_argument, O_CHUNK, FOR_ALL, "I/N",
     "render the I-th (from 0) of N even, contiguous chunks of\n"
     "the frames; 'slurm': SLURM_ARRAY_TASK_ID's of _COUNT",
     NULL},
    {"size", required_argument, O_SIZE, FOR_ALL, "WxH", "set the resolution", NULL},
    {"output", required_argument, 'o', FOR_ALL, "PATTERN",
     "override the output pattern (#### = frame number)", NULL},
    {"out", required_argument, O_OUT, FOR_RENDER | FOR_REFERENCE, "DIR",
     "write into DIR, keeping the pattern's file name", NULL},
    {"out", required_argument, O_OUT, FOR_BENCH, "DIR",
     "the set's directory (required): each run's timing sidecars\n"
     "go into DIR/run-01, ..., keeping the pattern's file name",
     NULL},
    {"runs", required_argument, O_RUNS, FOR_BENCH, "N",
     "render the job N times, 1 to 99 (default 9)", "only bench renders a job several times"},
    {"integrator", required_argument, O_INTEGRATOR, FOR_RENDER | FOR_BENCH, "NAME",
     "set integrator.name: direct, bdpt, hybrid or reference\n(in any case)",
     "it always renders with the CPU reference path tracer"},
    {"set", required_argument, O_SET, FOR_ALL, "KEY=VALUE",
     "override any job key by its dotted path (repeatable)", NULL},
    {"resume", no_argument, O_RESUME, FOR_RENDER | FOR_REFERENCE, NULL,
     "skip frames whose files are already complete",
     "it renders every frame afresh and writes no images"},
    {"progress", required_argument, O_PROGRESS, FOR_ALL, "MODE",
     "auto (a bar on a terminal, lines otherwise) or openjd\n"
     "(openjd_progress and openjd_status lines on stdout)",
     NULL},
    {"preview", no_argument, O_PREVIEW, FOR_RENDER | FOR_REFERENCE, NULL,
     "also write NAME.####.png through OpenColorIO",
     "it renders every frame afresh and writes no images"},
    {"view", required_argument, O_VIEW, FOR_RENDER | FOR_REFERENCE, "NAME",
     "the OpenColorIO view of --preview's PNGs (color.view);\n"
     "default: the display's first ('ACES 1.0 - SDR Video')",
     "it renders every frame afresh and writes no images"},
    {"device", required_argument, O_DEVICE, FOR_RENDER | FOR_BENCH, "NAME|INDEX",
     "pick a Vulkan device (default: lavapipe)", "it renders on the CPU, with no Vulkan device"},
    {"validate", no_argument, O_VALIDATE, FOR_RENDER | FOR_BENCH, NULL,
     "enable the Khronos validation layer; any message fails",
     "it renders on the CPU, with no Vulkan device"},
    {"lenient", no_argument, O_LENIENT, FOR_ALL, NULL,
     "glTF properties of the wrong type, and values glTF 2.0\n"
     "forbids, are warnings, not errors",
     NULL},
    {"strict", no_argument, O_STRICT, FOR_RENDER | FOR_BENCH, NULL,
     "a frame with NaN or Inf values, or (bdpt) a full ray-bundle\n"
     "node buffer, fails (exit 1)",
     "it renders on the CPU, with no ray-bundle node buffer"},
    {"spp", required_argument, O_SPP, FOR_ALL, "N",
     "reference: samples per pixel (integrator.reference.spp)", NULL},
    {"time-limit", required_argument, O_TIME_LIMIT, FOR_ALL, "S",
     "reference: stop at the pass of samples that crosses S seconds", NULL},
    {"threads", required_argument, O_THREADS, FOR_ALL, "N",
     "reference: worker threads (default: all cores)", NULL},
    {"quiet", no_argument, 'q', FOR_ALL, NULL, "no progress output", NULL},
    {"verbose", no_argument, 'v', FOR_ALL, NULL, "more log output (repeat for debug)", NULL},
    {"help", no_argument, 'h', FOR_ALL, NULL, "show this help", NULL},
};
#define FLAG_COUNT (sizeof(flags) / sizeof(flags[0]))

static unsigned command_bit(const char *command)
{
    return strcmp(command, "reference") == 0 ? FOR_REFERENCE
           : strcmp(command, "bench") == 0   ? FOR_BENCH
                                             : FOR_RENDER;
}

/* For cmd_getopt_note: why an option of this file's other commands is not the one's parsed. */
static const char *flag_absent(const char *name)
{
    for (size_t i = 0; i < FLAG_COUNT; i++)
        if (strcmp(flags[i].name, name) == 0 && flags[i].absent)
            return flags[i].absent;
    return NULL;
}

static void usage(FILE *f, const char *command)
{
    unsigned bit = command_bit(command);
    if (bit == FOR_REFERENCE)
        fprintf(f, "usage: raybundle reference JOB [options]\n"
                   "\n"
                   "Renders JOB with the CPU reference path tracer (the ground truth the GPU\n"
                   "integrators are judged against): the same files and layers as render.\n"
                   "\n");
    else if (bit == FOR_BENCH)
        fprintf(f, "usage: raybundle bench JOB --out DIR [--runs N] [options]\n"
                   "\n"
                   "Renders JOB N times (default 9), run by run, keeping each run's timing\n"
                   "sidecars in DIR/run-01, DIR/run-02, ... and what was measured in\n"
                   "DIR/bench.json, for 'raybundle timing compare'. No images are written.\n"
                   "\n");
    else
        fprintf(f, "usage: raybundle render JOB [options]\n"
                   "\n"
                   "Renders JOB (a YAML job file, or a .gltf/.glb for a quick look) to per-frame\n"
                   "OpenEXR images with timing sidecars.\n"
                   "\n");
    for (size_t i = 0; i < FLAG_COUNT; i++) {
        const struct flag *g = &flags[i];
        if (!(g->commands & bit))
            continue;
        char left[64], short_name[8] = "";
        if (g->val < 256)
            snprintf(short_name, sizeof(short_name), "-%c, ", g->val);
        snprintf(left, sizeof(left), "  %s--%s%s%s", short_name, g->name, g->arg ? " " : "",
                 g->arg ? g->arg : "");
        fprintf(f, "%-22s ", left);
        for (const char *p = g->help; *p; p++) {
            fputc(*p, f);
            if (*p == '\n')
                fprintf(f, "%23s", "");
        }
        fputc('\n', f);
    }
    fprintf(f,
            "\nExit status: 0 ok, 1 rendering failed, 2 bad usage or job, 3 no usable device.\n");
}

static int add_override(struct options *o, const char *key, const char *value, const char *origin)
{
    if (o->override_count == MAX_OVERRIDES) {
        cmd_error("more than %d --set options and the options that set job keys", MAX_OVERRIDES);
        return -1;
    }
    o->overrides[o->override_count++] = (struct rb_job_override){key, value, origin};
    return 0;
}

/* --frames LIST (A, A-B, A-B:S, comma-separated, as farms write them): its first and last frame
 * set frames.start and frames.end, checked by the job's key table; the list picks frames
 * between them. A later --frames replaces an earlier one. */
static int sugar_frames(struct options *o, const char *arg)
{
    snprintf(o->frames_origin, sizeof(o->frames_origin), "--frames '%.48s%s'", arg,
             strlen(arg) > 48 ? "..." : "");
    struct rb_err err = RB_ERR_INIT;
    int first = 0, last = 0;
    rb_render_frames_release(&o->frames);
    if (rb_render_frames_parse(&o->frames, arg, &err) ||
        !rb_render_frames_bounds(&o->frames, &first, &last)) {
        cmd_error("%s: %s", o->frames_origin, err.msg);
        return -1;
    }
    snprintf(o->frames_start, sizeof(o->frames_start), "%d", first);
    snprintf(o->frames_end, sizeof(o->frames_end), "%d", last);
    return add_override(o, "frames.start", o->frames_start, o->frames_origin) ||
           add_override(o, "frames.end", o->frames_end, o->frames_origin);
}

/* --chunk I/N, or --chunk slurm: the chunk of this Slurm array task. */
static int parse_chunk(struct options *o, const char *arg)
{
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st =
        strcmp(arg, "slurm") == 0
            ? rb_render_chunk_slurm(getenv("SLURM_ARRAY_TASK_ID"), getenv("SLURM_ARRAY_TASK_COUNT"),
                                    getenv("SLURM_ARRAY_TASK_MIN"), getenv("SLURM_ARRAY_TASK_STEP"),
                                    &o->chunk, &err)
            : rb_render_chunk_parse(arg, &o->chunk, &err);
    if (st) {
        cmd_error("--chunk %s: %s", strcmp(arg, "slurm") == 0 ? "slurm" : "I/N", err.msg);
        return -1;
    }
    return 0;
}

/* --size WxH: resolution [W, H], checked by the key table. */
static int sugar_size(struct options *o, const char *arg)
{
    snprintf(o->size_origin, sizeof(o->size_origin), "--size '%s'", arg);
    const char *x = strchr(arg, 'x');
    if (!x || x == arg || !x[1] || strlen(arg) > 32) {
        cmd_error("%s: expected WxH, e.g. 640x360", o->size_origin);
        return -1;
    }
    snprintf(o->size_value, sizeof(o->size_value), "[%.*s, %s]", (int)(x - arg), arg, x + 1);
    return add_override(o, "resolution", o->size_value, o->size_origin);
}

/* --progress auto|openjd, in any case. */
static int parse_progress(struct options *o, const char *arg)
{
    static const char *const modes[] = {"auto", "openjd"};
    struct rb_suggest near;
    rb_suggest_init(&near, arg);
    for (size_t i = 0; i < sizeof(modes) / sizeof(modes[0]); i++) {
        if (strcasecmp(arg, modes[i]) == 0) {
            o->is_openjd = i == 1;
            return 0;
        }
        rb_suggest_offer(&near, modes[i], strlen(modes[i]));
    }
    cmd_error("--progress expects auto or openjd, got '%s'%s%s%s", arg,
              near.best[0] ? "; did you mean '" : "", near.best, near.best[0] ? "'?" : "");
    return -1;
}

static int parse_options(int argc, char **argv, struct options *o)
{
    /* getopt's table and short options: the rows of this command */
    unsigned bit = command_bit(o->command);
    struct option opts[FLAG_COUNT + 1];
    char shortopts[2 * FLAG_COUNT + 1];
    size_t n = 0, ns = 0;
    for (size_t i = 0; i < FLAG_COUNT; i++) {
        if (!(flags[i].commands & bit))
            continue;
        opts[n++] = (struct option){flags[i].name, flags[i].has_arg, NULL, flags[i].val};
        if (flags[i].val < 256) {
            shortopts[ns++] = (char)flags[i].val;
            if (flags[i].has_arg == required_argument)
                shortopts[ns++] = ':';
        }
    }
    opts[n] = (struct option){0};
    shortopts[ns] = '\0';
    int c;
    optind = 1;
    while ((c = cmd_getopt_note(argc, argv, shortopts, opts, o->command, flag_absent)) != -1) {
        int bad = 0;
        switch (c) {
        case O_FRAMES: bad = sugar_frames(o, optarg); break;
        case O_SIZE: bad = sugar_size(o, optarg); break;
        case 'o': o->output = optarg; break;
        case O_OUT: o->out_dir = optarg; break;
        case O_INTEGRATOR:
            snprintf(o->integrator_origin, sizeof(o->integrator_origin), "--integrator '%s'",
                     optarg);
            bad = add_override(o, "integrator.name", optarg, o->integrator_origin);
            break;
        case O_SET: {
            char *eq = strchr(optarg, '=');
            if (!eq || eq == optarg) {
                cmd_error("--set expects KEY=VALUE, got '%s'", optarg);
                return -1;
            }
            *eq = '\0';
            bad = add_override(o, optarg, eq + 1, NULL);
            break;
        }
        case O_RESUME: o->resume = true; break;
        case O_PREVIEW: o->preview = true; break;
        case O_VIEW:
            snprintf(o->view_origin, sizeof(o->view_origin), "--view '%.48s'", optarg);
            bad = add_override(o, "color.view", optarg, o->view_origin);
            break;
        case O_DEVICE: o->device = optarg; break;
        case O_VALIDATE: o->validate = true; break;
        case O_SPP:
            o->spp = optarg;
            snprintf(o->spp_origin, sizeof(o->spp_origin), "--spp '%s'", optarg);
            bad = add_override(o, "integrator.reference.spp", optarg, o->spp_origin);
            break;
        case O_TIME_LIMIT:
            o->time_limit = optarg;
            snprintf(o->time_limit_origin, sizeof(o->time_limit_origin), "--time-limit '%s'",
                     optarg);
            bad =
                add_override(o, "integrator.reference.time_limit_s", optarg, o->time_limit_origin);
            break;
        case O_THREADS: o->threads = optarg; break;
        case O_LENIENT: o->is_lenient = true; break;
        case O_STRICT: o->is_strict = true; break;
        case O_RUNS: o->runs = optarg; break;
        case O_CHUNK: bad = parse_chunk(o, optarg); break;
        case O_PROGRESS: bad = parse_progress(o, optarg); break;
        case 'q': o->quiet = true; break;
        case 'v': o->verbose++; break;
        case 'h': usage(stdout, o->command); return 1;
        default: return -1; /* reported */
        }
        if (bad)
            return -1;
    }
    if (optind >= argc) {
        cmd_usage_error(o->command, "%s needs a job file", o->command);
        return -1;
    }
    if (optind < argc - 1) {
        cmd_usage_error(o->command, "%s takes one job file, and '%s' is a second", o->command,
                        argv[optind + 1]);
        return -1;
    }
    o->job_path = argv[optind];
    /* The job's checks that depend on its integrator (the layers it can write) see the one that
     * renders: the reference, whatever the job names. */
    if (strcmp(o->command, "reference") == 0 &&
        add_override(o, "integrator.name", "reference", "raybundle reference"))
        return -1;
    return 0;
}

/* Applies --output and --out (paths as given, relative to the working directory, not to the
 * job file) and refuses the options that the job's integrator would ignore. */
static int apply_cli(const struct options *o, struct rb_job *job)
{
    bool is_reference = strcmp(o->command, "reference") == 0; /* which takes no --integrator */
    if (is_reference)
        job->integrator.name = RB_INTEGRATOR_REFERENCE;
    if (job->integrator.name != RB_INTEGRATOR_REFERENCE) {
        const char *opt = o->spp          ? "--spp"
                          : o->time_limit ? "--time-limit"
                          : o->threads    ? "--threads"
                                          : NULL;
        if (opt) {
            cmd_error("%s applies to the reference integrator only, and this job renders with "
                      "'%s' (use 'raybundle reference')",
                      opt, rb_integrator_name(job->integrator.name));
            return -1;
        }
    }
    if (o->threads) {
        unsigned n;
        char tail;
        if (sscanf(o->threads, "%u%c", &n, &tail) != 1 || n < 1 || n > 1024) {
            cmd_error("--threads expects 1..1024, got '%s'", o->threads);
            return -1;
        }
    }
    if (o->output) {
        free(job->output);
        job->output = rb_strdup(o->output);
    }
    if (o->out_dir && job->output) {
        const char *slash = strrchr(job->output, '/');
        const char *base = slash ? slash + 1 : job->output;
        size_t n = strlen(o->out_dir) + strlen(base) + 2;
        char *p = malloc(n);
        if (p)
            snprintf(p, n, "%s/%s", o->out_dir, base);
        free(job->output);
        job->output = p;
    }
    if (!job->output) {
        cmd_error("out of memory");
        return -1;
    }
    struct rb_err err = RB_ERR_INIT;
    if ((o->output || o->out_dir) &&
        rb_job_check_output(job->output, job->frame_start, job->frame_end, &err)) {
        cmd_error("%s: %s", o->output ? "--output" : "--out", err.msg);
        return -1;
    }
    rb_job_rehash(job);
    return 0;
}

static int exit_for(enum rb_status st, bool rendering)
{
    if (st == RB_E_NODEVICE)
        return RB_EXIT_NODEVICE;
    if (rendering)
        return RB_EXIT_FAILED;
    return st == RB_E_VULKAN || st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
}

/* What progress reports need to know, also inside a reference frame. */
struct progress_state {
    bool is_tty, is_openjd, is_quiet;
    bool is_saved; /* a "Saved: PATH" line on stdout for each frame written */
    int done, total;
    int percent; /* the last openjd_progress printed */
    int width;   /* the terminal's columns, for the bar */
};

/* One of OpenJD's stdout messages ("openjd_progress: 40"), flushed, so a farm's agent reading a
 * pipe sees it when it happens. */
static void openjd(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void openjd(const char *fmt, ...)
{
    va_list ap;
    flockfile(stdout); /* one line, whole, beside the writer thread's "Saved:" lines */
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    fflush(stdout);
    funlockfile(stdout);
}

/* openjd_progress for frames done out of total, plus fraction of the next: whole percent, printed
 * when it changes; 100 only once every frame is done. */
static void openjd_percent(struct progress_state *p, double fraction)
{
    int percent = (int)(((double)p->done + fraction) * 100.0 / p->total);
    if (p->done < p->total && percent > 99)
        percent = 99;
    if (percent != p->percent)
        openjd("openjd_progress: %d", percent);
    p->percent = percent;
}

/* A line on the terminal's bar: text, cut to fit the width and padded over what was there. */
static void bar_line(const struct progress_state *p, const char *text)
{
    int room = p->width > 1 ? p->width - 1 : 0; /* the last column would wrap on some terminals */
    fprintf(stderr, "\r%-*.*s", room, room, text);
    cmd_bar_open = true;
}

/* frame f's progress: ms is its sidecar's wall_ms, sec_per_frame the run's mean so far. */
static void progress(struct progress_state *p, int frame, double ms, double sec_per_frame,
                     bool skipped)
{
    bool tty = p->is_tty;
    int done = p->done, total = p->total;
    if (p->is_openjd) {
        openjd("openjd_status: frame %d %s (%d/%d)", frame,
               skipped ? "already complete, kept" : "rendered", done, total);
        openjd_percent(p, 0.0);
        return;
    }
    if (p->is_quiet)
        return;
    if (tty) {
        char tail[128], line[512];
        snprintf(tail, sizeof(tail), " %d/%d frames  %.2f s/frame  ETA %.0f s", done, total,
                 sec_per_frame, sec_per_frame * (total - done));
        /* The bar takes what the numbers leave of the width, up to 30; none below 10. */
        int bar = p->width - 1 - (int)strlen(tail) - 2;
        bar = bar > 30 ? 30 : bar;
        if (bar < 10) {
            bar_line(p, tail + 1);
        } else {
            int fill = total ? done * bar / total : bar;
            snprintf(line, sizeof(line), "[%.*s%.*s]%s", fill, "##############################",
                     bar - fill, "                              ", tail);
            bar_line(p, line);
        }
        if (done == total)
            cmd_end_bar();
    } else if (skipped) {
        fprintf(stderr, "raybundle: frame %d (%d/%d) already complete, skipped\n", frame, done,
                total);
    } else {
        fprintf(stderr, "raybundle: frame %d (%d/%d) %.1f ms\n", frame, done, total, ms);
    }
}

/* Frames first to last, as a range ("4" or "4 to 7", which reads for negative frames too). */
static void span_text(int first, int last, char *buf, size_t size)
{
    if (first == last)
        snprintf(buf, size, "frame %d", first);
    else
        snprintf(buf, size, "frames %d to %d", first, last);
}

/* Before frame f: the warm-up frames the integrator renders first, which are slow and write
 * nothing, so a silent gap would look like a hang or lost frames. */
static void warmup(struct progress_state *p, int frame, uint32_t count)
{
    if (!count || p->is_quiet)
        return;
    char span[64], line[160];
    span_text(frame - (int)count, frame - 1, span, sizeof(span));
    if (p->is_openjd) {
        openjd("openjd_status: warming up on %s for frame %d", span, frame);
    } else if (p->is_tty) {
        snprintf(line, sizeof(line), "warming up on %s for frame %d (not written)", span, frame);
        bar_line(p, line);
    } else {
        fprintf(stderr, "raybundle: warming up on %s for frame %d (not written)\n", span, frame);
    }
}

/* For the writer: "Saved: PATH (MS ms)", MS the sidecar's wall_ms to 0.1 ms, for a farm's log. */
static void on_written(void *user, int frame, const char *path, double wall_ms)
{
    (void)frame;
    const struct progress_state *p = user;
    if (!p->is_saved)
        return;
    char shown[4096];
    cmd_display_path(path, shown, sizeof(shown));
    flockfile(stdout);
    printf("Saved: %s (%.1f ms)\n", shown,
           wall_ms); /* the sidecar's wall_ms, as the bar shows it */
    fflush(stdout);
    funlockfile(stdout);
}

/* The frames of f as a farm writes a list: runs of one step as "A-B" or "A-B:S", other frames
 * alone ("1-3,5-11:2"); cut with "..." when it does not fit size. */
static void frames_text(const struct rb_render_frames *f, char *buf, size_t size)
{
    int run[3] = {0, 0, 0}, n = 0, frame = 0; /* the run's first, step, last; n its frames */
    size_t len = 0;
    bool more = rb_render_frames_next(f, INT64_MIN, &frame);
    buf[0] = '\0';
    while (n || more) {
        bool extends = more && (n == 1 || (n > 1 && frame - run[2] == run[1]));
        if (more && (n == 0 || extends)) {
            if (n == 0)
                run[0] = frame;
            else if (n == 1)
                run[1] = frame - run[0];
            run[2] = frame;
            n++;
            more = rb_render_frames_next(f, frame, &frame);
            continue;
        }
        /* Close the run. Two frames a step apart but for 1 are two entries, and the second
         * may start the next run. */
        char item[48];
        bool has_again = false;
        if (n == 1)
            snprintf(item, sizeof(item), "%d", run[0]);
        else if (run[1] == 1)
            snprintf(item, sizeof(item), "%d-%d", run[0], run[2]);
        else if (n == 2)
            snprintf(item, sizeof(item), "%d", run[0]), has_again = true;
        else
            snprintf(item, sizeof(item), "%d-%d:%d", run[0], run[2], run[1]);
        if (len + strlen(item) + 5 >= size) {
            snprintf(buf + len, size - len, "%s...", len ? "," : "");
            return;
        }
        len += (size_t)snprintf(buf + len, size - len, "%s%s", len ? "," : "", item);
        n = 0;
        if (has_again) {
            run[0] = run[2];
            n = 1;
        }
    }
}

/* The directory part of a pattern, for the closing line, as cmd_display_path shows it. */
static void output_dir(const char *pattern, char *dir, size_t size)
{
    char raw[4096];
    const char *slash = strrchr(pattern, '/');
    if (slash)
        snprintf(raw, sizeof(raw), "%.*s", (int)(slash - pattern), pattern);
    else
        rb_strlcpy(raw, ".", sizeof(raw));
    cmd_display_path(raw, dir, size);
    size_t n = strlen(dir);
    if (n + 1 < size && (n == 0 || dir[n - 1] != '/'))
        dir[n] = '/', dir[n + 1] = '\0';
}

/* Progress of a reference frame on a terminal or to a farm; stops sampling once a signal came. */
static bool on_reference_pass(void *user, uint32_t done, uint32_t total)
{
    struct progress_state *p = user;
    if (p->is_openjd && total)
        openjd_percent(p, (double)done / total);
    else if (p->is_tty) {
        char line[80];
        snprintf(line, sizeof(line), "  %u/%u samples", done, total);
        bar_line(p, line); /* over the frame bar */
    }
    return !interrupted;
}

/* A failed write into a folder removed during the run is reported as the removal, its cause. */
static enum rb_status removed_first(const struct rb_io_output_lock *lock, enum rb_status st,
                                    struct rb_err *err)
{
    struct rb_err gone = RB_ERR_INIT;
    if (lock && rb_io_output_lock_check(lock, &gone)) {
        *err = gone;
        return RB_E_IO;
    }
    return st;
}

/* Renders the job once as o says; bench, when not NULL, gets what was rendered and the
 * closing line is left to the caller. */
static int render_job(struct options *o, struct cmd_bench_run *bench)
{
    int rc;
    rb_log_set_level(o->quiet ? RB_LOG_ERROR : (enum rb_log_level)(RB_LOG_WARN + o->verbose));
    rb_log_set_sink(log_sink, NULL);
    if (getenv("RB_VALIDATE") && strcmp(getenv("RB_VALIDATE"), "1") == 0)
        o->validate = true;
    /* A test hook: kill the process (SIGKILL, like a farm's scheduler) right after frame N's
     * files are written, for deterministic resume tests. */
    const char *abort_env = getenv("RB_TEST_ABORT_AFTER_FRAME");
    int abort_after = abort_env && *abort_env ? atoi(abort_env) : INT32_MIN;

    struct rb_err err = RB_ERR_INIT;
    struct rb_job *job = NULL;
    struct rb_scene *scene = NULL;
    struct rb_scene_setup setup;
    struct rb_render *r = NULL;
    struct rb_io_output_lock *lock = NULL;
    float *env = NULL;
    uint32_t env_w = 0, env_h = 0;
    struct progress_state prog = {.is_tty = !o->quiet && !o->is_openjd && isatty(STDERR_FILENO),
                                  .is_openjd = o->is_openjd,
                                  .is_quiet = o->quiet,
                                  .is_saved =
                                      !o->quiet && !o->is_timing_only && !isatty(STDOUT_FILENO),
                                  .percent = -1,
                                  .width = cmd_terminal_width(STDERR_FILENO)};
    bool tty = prog.is_tty;
    enum rb_status st;
    rc = RB_EXIT_OK;

    if ((st = rb_job_load(o->job_path, o->overrides, o->override_count, &job, &err))) {
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    if (apply_cli(o, job)) {
        rc = RB_EXIT_USAGE;
        goto out;
    }
    if (o->preview)
        job->color.preview = true;
    /* A view or display the config lacks, or a transform that does not build, fails now, not
     * at the first frame's preview after a frame's work; a config the job names is said at
     * its key. */
    if (job->color.preview && !o->is_timing_only &&
        (st = rb_io_color_check(
             &(struct rb_io_color_desc){job->color.config, job->color.display, job->color.view},
             &err))) {
        if (st != RB_E_INVALID && job->at.color_config)
            rb_err_prefix(&err, "%s", job->at.color_config);
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    st = rb_scene_load(job->scene_path, o->is_lenient ? RB_SCENE_LOAD_LENIENT : 0, &scene, &err);
    if (!st && job->environment.map &&
        (st = rb_render_load_env(job->environment.map, job->environment.intensity, &env, &env_w,
                                 &env_h, &err)) &&
        job->at.environment_map)
        rb_err_prefix(&err, "%s", job->at.environment_map); /* the job's line that names it */
    if (st || (st = rb_scene_setup_init(job, scene, env, env_w, env_h, &setup, &err))) {
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    /* The frames: --frames' list or the job's range, within the job's range, then the chunk.
     * The output pattern was checked against the range by the job parser and apply_cli. */
    int first = job->frame_start, last = rb_render_last_frame(job, scene);
    char chunk_note[48] = "";
    if (o->chunk.count)
        snprintf(chunk_note, sizeof(chunk_note), ", chunk %u/%u", o->chunk.index, o->chunk.count);
    if (!o->frames.range_count && (st = rb_render_frames_add(&o->frames, first, last, 1, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_FAILED;
        goto out;
    }
    rb_render_frames_limit(&o->frames, first, last);
    if (o->chunk.count)
        rb_render_frames_chunk(&o->frames, o->chunk);
    if (!rb_render_frames_bounds(&o->frames, &first, &last)) {
        if (!o->chunk.count) { /* a --set of frames.* after --frames left none of its frames */
            cmd_error("%s: none of its frames is in the job's range, %d to %d", o->frames_origin,
                      first, last);
            rc = RB_EXIT_USAGE;
            goto out;
        }
        if (o->is_openjd)
            openjd("openjd_status: chunk %u/%u has no frames", o->chunk.index, o->chunk.count);
        printf("0 frames (chunk %u/%u of %d-%d): nothing to render\n", o->chunk.index,
               o->chunk.count, first, last);
        goto out;
    }
    prog.total = (int)rb_render_frames_count(&o->frames);
    unsigned threads = 0;
    if (o->threads)
        sscanf(o->threads, "%u", &threads);
    if ((st = rb_render_create(&(struct rb_render_desc){.job = job,
                                                        .scene = scene,
                                                        .setup = &setup,
                                                        .env_rgba = env,
                                                        .env_width_px = env_w,
                                                        .env_height_px = env_h,
                                                        .device = o->device,
                                                        .validate = o->validate,
                                                        .strict = o->is_strict,
                                                        .thread_count = threads,
                                                        .is_timing_only = o->is_timing_only,
                                                        .on_pass = on_reference_pass,
                                                        .on_written = on_written,
                                                        .user = &prog},
                               &r, &err))) {
        cmd_error("%s", err.msg);
        /* A job the renderer cannot take is a bad job (2); a scene or frame past a limit of the
         * device or the integrator (RB_E_UNSUPPORTED: lights, buffer ranges) is one the device
         * cannot render (1), which another device or integrator may. */
        rc = st == RB_E_INVALID ? RB_EXIT_USAGE : exit_for(st, true);
        goto out;
    }
    char path[4096];
    if ((st = rb_io_frame_path(job->output, first, path, sizeof(path), &err)) ||
        (st = rb_io_check_writable(path, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE; /* a bad output location, found before any rendering */
        goto out;
    }
    /* Every frame of the run is claimed before the first is rendered, so a second render of
     * any of them stops at once (exit 2, as a bad output location), while a farm's chunks,
     * each with frames of its own, share the folder. */
    st = rb_io_output_lock_create(job->output, &lock, &err);
    for (int f = first, more = 1; !st && more; more = rb_render_frames_next(&o->frames, f, &f))
        st = rb_io_output_lock_claim(lock, f, &err);
    if (st) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE;
        goto out;
    }

    int total = prog.total, rendered = 0, skipped = 0, stale = 0;
    char list[160];
    frames_text(&o->frames, list, sizeof(list));
    if (o->is_openjd) {
        openjd("openjd_status: rendering %d frame%s (%s%s)", total, total == 1 ? "" : "s", list,
               chunk_note);
        openjd_percent(&prog, 0.0);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    double started = rb_monotonic_s();
    /* In ascending order; the frame driver warms up before a frame that follows a gap. */
    for (int f = first, more = 1; more; more = rb_render_frames_next(&o->frames, f, &f)) {
        if (interrupted) {
            cmd_error("interrupted: frames %d to %d were not rendered", f, last);
            rc = RB_EXIT_FAILED;
            break;
        }
        /* The writer would create a removed folder again: stop instead of counting frames
         * written into a folder that was deleted. */
        if ((st = rb_io_output_lock_check(lock, &err))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_FAILED;
            break;
        }
        if ((st = rb_io_frame_path(job->output, f, path, sizeof(path), &err))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_USAGE;
            break;
        }
        if (o->resume) {
            enum rb_render_verdict v = rb_render_resume_verdict(r, path);
            bool wrote = false;
            if (v == RB_RENDER_KEEP && job->color.preview &&
                (st = rb_render_preview_from_exr(r, path, &wrote, &err))) {
                cmd_error("%s", err.msg);
                rc = exit_for(st, true);
                break;
            }
            if (wrote && !o->quiet && !tty && !o->is_openjd)
                fprintf(stderr, "raybundle: frame %d: wrote its missing preview\n", f);
            if (v == RB_RENDER_KEEP) {
                prog.done++;
                skipped++;
                progress(&prog, f, 0.0, 0.0, true);
                continue;
            }
            if (v == RB_RENDER_STALE) {
                stale++;
                if (!o->quiet && !tty)
                    fprintf(stderr,
                            "raybundle: frame %d was rendered by another job or setting: "
                            "rendering it again\n",
                            f);
            }
            unsigned temps = rb_io_remove_stale_temps(path);
            if (temps)
                rb_log(RB_LOG_INFO, "frame %d: removed %u temporary file(s) of an interrupted run",
                       f, temps);
        }
        struct rb_render_frame_info info;
        warmup(&prog, f, rb_render_warmup_frames(r, f));
        if ((st = rb_render_frame(r, f, path, &info, &err))) {
            st = removed_first(lock, st, &err);
            cmd_error("%s", err.msg); /* it names the frame */
            rc = exit_for(st, true);
            break;
        }
        if (info.is_partial) {
            cmd_error("interrupted: frame %d stopped at %u of %u samples and was not written; "
                      "frames %d to %d were not rendered",
                      f, info.spp, job->integrator.reference.spp, f, last);
            rc = RB_EXIT_FAILED;
            break;
        }
        if (f == abort_after && rb_render_flush(r, &err) == RB_OK)
            kill(getpid(), SIGKILL);
        prog.done++;
        rendered++;
        progress(&prog, f, info.wall_ms, (rb_monotonic_s() - started) / rendered, false);
        if (rendered == 1 && f < last &&
            ((st = rb_render_flush(r, &err)) ||
             (st = rb_render_check_space(path, job->color.preview, total - prog.done, &err)))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_FAILED;
            break;
        }
    }
    /* The frames still with the writer (the one in flight when a signal came, too). */
    if ((st = rb_render_flush(r, &err)) ||
        (rc == RB_EXIT_OK && (st = rb_io_output_lock_check(lock, &err)))) {
        st = removed_first(lock, st, &err);
        /* A write failure the loop stopped on is the writer's still: said once. */
        if (rc == RB_EXIT_OK || strcmp(err.msg, cmd_last_error) != 0)
            cmd_error("%s", err.msg);
        if (rc == RB_EXIT_OK)
            rc = exit_for(st, true);
    }
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (rc == RB_EXIT_OK && bench) {
        rb_strlcpy(bench->device, rb_render_device(r), sizeof(bench->device));
        rb_strlcpy(bench->driver, rb_render_driver(r), sizeof(bench->driver));
        snprintf(bench->job_hash, sizeof(bench->job_hash), "%016llx",
                 (unsigned long long)setup.job_hash);
        bench->integrator = rb_integrator_name(job->integrator.name);
        bench->width_px = job->width_px;
        bench->height_px = job->height_px;
        bench->first = first;
        bench->last = last;
        bench->wall_s = rb_monotonic_s() - started;
    } else if (rc == RB_EXIT_OK) {
        char dir[4096];
        output_dir(job->output, dir, sizeof(dir));
        printf("%d frame%s (%s%s) in %s: %d rendered", total, total == 1 ? "" : "s", list,
               chunk_note, dir, rendered);
        if (o->resume)
            printf(", %d kept, %d rendered again (another job)", skipped, stale);
        printf(", %.1f s\n", rb_monotonic_s() - started);
    }
out:
    cmd_end_bar();
    if (rc != RB_EXIT_OK && o->is_openjd)
        openjd("openjd_fail: %s", cmd_last_error);
    rb_render_destroy(r);
    rb_io_output_lock_destroy(lock);
    free(env);
    rb_scene_destroy(scene);
    rb_job_destroy(job);
    rb_log_set_sink(NULL, NULL);
    return rc;
}

static int run(struct options *o, int argc, char **argv)
{
    int rc = parse_options(argc, argv, o);
    if (rc) {
        if (rc < 0 && o->is_openjd)
            openjd("openjd_fail: %s", cmd_last_error);
        rc = rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;
    } else {
        rc = render_job(o, NULL);
    }
    rb_render_frames_release(&o->frames);
    return rc;
}

/* cmd_render_bench's runs, with o's frames released by the caller. */
static int bench_runs(struct options *o, int argc, char **argv, cmd_bench_fn on_run, void *user)
{
    int rc = parse_options(argc, argv, o);
    if (rc)
        return rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;
    if (!o->out_dir) { /* its parser takes no --resume or --preview */
        cmd_usage_error("bench", "bench needs --out DIR, the directory of the set");
        return RB_EXIT_USAGE;
    }
    struct cmd_bench_run b = {
        .out_dir = o->out_dir, .job_path = o->job_path, .runs = o->runs, .is_quiet = o->quiet};
    char dir[4096];
    if ((rc = on_run(&b, user)))
        return rc;
    for (b.run = 1; b.run <= b.run_count; b.run++) {
        if ((size_t)snprintf(dir, sizeof(dir), "%s/run-%02u", b.out_dir, b.run) >= sizeof(dir)) {
            cmd_error("--out '%s': the path is too long", b.out_dir);
            return RB_EXIT_USAGE;
        }
        o->out_dir = dir;
        if ((rc = render_job(o, &b)) || (rc = on_run(&b, user)))
            return rc;
    }
    return RB_EXIT_OK;
}

int cmd_render_bench(int argc, char **argv, cmd_bench_fn on_run, void *user)
{
    struct options o = {
        .command = "bench", .is_timing_only = true, .frames = RB_RENDER_FRAMES_INIT};
    int rc = bench_runs(&o, argc, argv, on_run, user);
    rb_render_frames_release(&o.frames);
    return rc;
}

int cmd_render(int argc, char **argv)
{
    struct options o = {.command = "render", .frames = RB_RENDER_FRAMES_INIT};
    return run(&o, argc, argv);
}

int cmd_reference(int argc, char **argv)
{
    struct options o = {.command = "reference", .frames = RB_RENDER_FRAMES_INIT};
    return run(&o, argc, argv);
}
