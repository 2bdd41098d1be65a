/* raybundle render: parse options, load the job and scene, render each frame, write the EXR,
 * the timing sidecar and (with --preview) a PNG. No rendering logic lives here. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gpu/gpu.h"
#include "integrators/integrators.h"
#include "io/io.h"
#include "job/job.h"
#include "reference/reference.h"
#include "scene/scene.h"
#include "shared.h"

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
    const char *output, *out_dir, *integrator, *device, *threads;
    const char *spp, *time_limit; /* as given, for messages */
    bool resume, validate, preview, quiet;
    bool is_lenient; /* --lenient: glTF type errors are warnings */
    int verbose;
    const char *command; /* "render" or "reference" */
    /* Text behind the options that are sugar for --set (--frames, --size, ...). */
    char frames_start[32], frames_end[32], size_value[48];
    char frames_origin[64], size_origin[64], integrator_origin[64], spp_origin[64],
        time_limit_origin[64];
};

/* One rendered frame, whichever backend made it (the GPU integrators or the CPU reference). */
struct frame {
    int frame;
    double time_s;
    uint32_t width_px, height_px;
    const float *pixels;                              /* RB_OUT_FLOATS per pixel */
    struct rb_io_pass_time passes[RB_GPU_MAX_PASSES]; /* names point into pass_names */
    char pass_names[RB_GPU_MAX_PASSES][32];
    uint32_t pass_count;
    struct rb_mat4 world_to_camera, world_to_ndc;
    uint32_t spp;       /* the reference: samples reached */
    uint64_t ray_count; /* the reference: rays traced */
    uint32_t nonfinite_count;
};

static void usage(FILE *f, const char *command)
{
    if (strcmp(command, "reference") == 0)
        fprintf(f, "usage: raybundle reference JOB [options]\n"
                   "\n"
                   "Renders JOB with the CPU reference path tracer (the ground truth the GPU\n"
                   "integrators are judged against): the same files and layers as render.\n"
                   "\n");
    else
        fprintf(f, "usage: raybundle render JOB [options]\n"
                   "\n"
                   "Renders JOB (a YAML job file, or a .gltf/.glb for a quick look) to per-frame\n"
                   "OpenEXR images with timing sidecars.\n"
                   "\n");
    fprintf(f,
            "  --frames A-B         render frames A to B (or one frame: A); sets frames.*\n"
            "  --size WxH           set the resolution\n"
            "  --output PATTERN     override the output pattern (#### = frame number)\n"
            "  --out DIR            write into DIR, keeping the pattern's file name\n"
            "  --integrator NAME    set integrator.name: direct or reference (render only)\n"
            "  --set KEY=VALUE      override any job key by its dotted path (repeatable)\n"
            "  --resume             skip frames whose files are already complete\n"
            "  --preview            also write NAME.####.png through OpenColorIO\n"
            "  --device NAME|INDEX  pick a Vulkan device (default: lavapipe)\n"
            "  --validate           enable the Khronos validation layer; any message fails\n"
            "  --lenient            glTF properties of the wrong type are warnings, not errors\n"
            "  --spp N              reference: samples per pixel (integrator.reference.spp)\n"
            "  --time-limit S       reference: stop at the pass of samples that crosses S seconds\n"
            "  --threads N          reference: worker threads (default: all cores)\n"
            "  -q, --quiet          no progress output\n"
            "  -v, --verbose        more log output (repeat for debug)\n"
            "  -h, --help           show this help\n"
            "\n"
            "Exit status: 0 ok, 1 rendering failed, 2 bad usage or job, 3 no usable device.\n");
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

/* --frames A-B or A: frames.start and frames.end, checked by the job's key table. A leading
 * '-' belongs to A, so "-3" is a start of -3, which the table refuses. */
static int sugar_frames(struct options *o, const char *arg)
{
    snprintf(o->frames_origin, sizeof(o->frames_origin), "--frames '%s'", arg);
    const char *dash = arg[0] ? strchr(arg + 1, '-') : NULL;
    size_t a = dash ? (size_t)(dash - arg) : strlen(arg);
    const char *end = dash ? dash + 1 : arg;
    if (!arg[0] || a >= sizeof(o->frames_start) || strlen(end) >= sizeof(o->frames_end)) {
        cmd_error("%s: expected A-B or A (frame numbers)", o->frames_origin);
        return -1;
    }
    memcpy(o->frames_start, arg, a);
    o->frames_start[a] = '\0';
    memcpy(o->frames_end, end, strlen(end) + 1);
    if (!o->frames_end[0]) {
        cmd_error("%s: expected A-B or A, and B is missing", o->frames_origin);
        return -1;
    }
    return add_override(o, "frames.start", o->frames_start, o->frames_origin) ||
           add_override(o, "frames.end", o->frames_end, o->frames_origin);
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

static int parse_options(int argc, char **argv, struct options *o)
{
    enum {
        O_FRAMES = 256,
        O_SIZE,
        O_OUTPUT,
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
        O_THREADS
    };
    static const struct option opts[] = {
        {"frames", required_argument, NULL, O_FRAMES},
        {"size", required_argument, NULL, O_SIZE},
        {"output", required_argument, NULL, O_OUTPUT},
        {"out", required_argument, NULL, O_OUT},
        {"integrator", required_argument, NULL, O_INTEGRATOR},
        {"set", required_argument, NULL, O_SET},
        {"resume", no_argument, NULL, O_RESUME},
        {"preview", no_argument, NULL, O_PREVIEW},
        {"device", required_argument, NULL, O_DEVICE},
        {"validate", no_argument, NULL, O_VALIDATE},
        {"spp", required_argument, NULL, O_SPP},
        {"time-limit", required_argument, NULL, O_TIME_LIMIT},
        {"threads", required_argument, NULL, O_THREADS},
        {"lenient", no_argument, NULL, O_LENIENT},
        {"quiet", no_argument, NULL, 'q'},
        {"verbose", no_argument, NULL, 'v'},
        {"help", no_argument, NULL, 'h'},
        {0},
    };
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, "qvh", opts, NULL)) != -1) {
        int bad = 0;
        switch (c) {
        case O_FRAMES: bad = sugar_frames(o, optarg); break;
        case O_SIZE: bad = sugar_size(o, optarg); break;
        case O_OUTPUT: o->output = optarg; break;
        case O_OUT: o->out_dir = optarg; break;
        case O_INTEGRATOR:
            o->integrator = optarg;
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
        case 'q': o->quiet = true; break;
        case 'v': o->verbose++; break;
        case 'h': usage(stdout, o->command); return 1;
        default: usage(stderr, o->command); return -1;
        }
        if (bad)
            return -1;
    }
    if (optind != argc - 1) {
        cmd_error(optind >= argc ? "%s needs a JOB" : "%s takes one JOB", o->command);
        usage(stderr, o->command);
        return -1;
    }
    o->job_path = argv[optind];
    return 0;
}

/* Applies --output and --out (paths as given, relative to the working directory, not to the
 * job file) and refuses the options that the job's integrator would ignore. */
static int apply_cli(const struct options *o, struct rb_job *job)
{
    bool is_reference = strcmp(o->command, "reference") == 0;
    if (is_reference && o->integrator) {
        cmd_error("reference renders with the CPU reference; --integrator is for render");
        return -1;
    }
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
                      opt,
                      rb_integrator_name(job->integrator.name ? job->integrator.name
                                                              : RB_INTEGRATOR_DIRECT));
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

/* The frame range when the job says "to the end of the animation". */
static int resolve_end(const struct rb_job *job, const struct rb_scene *scene)
{
    if (job->frame_end >= 0)
        return job->frame_end;
    uint32_t clips[64], n = 0;
    if (rb_scene_select_clips(scene, job, clips, 64, &n, NULL) || n == 0)
        return job->frame_start;
    double dur = 0.0;
    for (uint32_t i = 0; i < n; i++)
        if (scene->animations[clips[i]].duration_s > dur)
            dur = scene->animations[clips[i]].duration_s;
    double speed = job->animation.speed > 0.0 ? job->animation.speed : 1.0;
    int frames = (int)ceil(dur / speed * job->rate_fps - 1e-6);
    return job->frame_start + (frames > 1 ? frames - 1 : 0);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void progress(bool tty, int done, int total, int frame, double sec_per_frame, bool skipped)
{
    if (tty) {
        int width = 30, fill = total ? done * width / total : width;
        double eta = sec_per_frame * (total - done);
        fprintf(stderr, "\r[%.*s%.*s] %d/%d frames  %.2f s/frame  ETA %.0f s ", fill,
                "##############################", width - fill, "                              ",
                done, total, sec_per_frame, eta);
        cmd_bar_open = true;
        if (done == total)
            cmd_end_bar();
    } else if (skipped) {
        fprintf(stderr, "raybundle: frame %d (%d/%d) already complete, skipped\n", frame, done,
                total);
    } else {
        fprintf(stderr, "raybundle: frame %d (%d/%d) %.2f s\n", frame, done, total, sec_per_frame);
    }
}

/* Splits the packed readback into the EXR's layers and writes it with its metadata. */
static enum rb_status write_exr(const char *path, const struct rb_job *job,
                                const struct rb_scene_setup *setup, const struct frame *r,
                                float *scratch, struct rb_err *err)
{
    size_t n = (size_t)r->width_px * r->height_px;
    static const char *const rgba[] = {"R", "G", "B", "A"};
    static const char *const rgb[] = {"R", "G", "B"};
    static const char *const xyz[] = {"X", "Y", "Z"};
    static const char *const z[] = {"Z"};
    struct {
        const char *name;
        uint32_t offset, count;
        const char *const *channels;
    } layers[] = {
        {NULL, RB_OUT_BEAUTY, 4, rgba},        {"direct", RB_OUT_DIRECT, 3, rgb},
        {"indirect", RB_OUT_INDIRECT, 3, rgb}, {"albedo", RB_OUT_ALBEDO, 3, rgb},
        {"normal", RB_OUT_NORMAL, 3, xyz},     {"depth", RB_OUT_DEPTH, 1, z},
        {"motion", RB_OUT_MOTION, 2, xyz},
    };
    enum { LAYER_COUNT = sizeof(layers) / sizeof(layers[0]) };
    struct rb_io_layer out[LAYER_COUNT];
    float *p = scratch;
    for (int l = 0; l < LAYER_COUNT; l++) {
        for (size_t i = 0; i < n; i++)
            for (uint32_t c = 0; c < layers[l].count; c++)
                p[i * layers[l].count + c] = r->pixels[i * RB_OUT_FLOATS + layers[l].offset + c];
        out[l] = (struct rb_io_layer){.name = layers[l].name,
                                      .channel_count = layers[l].count,
                                      .channel_names = layers[l].channels,
                                      .pixels = p};
        p += n * layers[l].count;
    }
    char hash[17];
    snprintf(hash, sizeof(hash), "%016llx", (unsigned long long)setup->job_hash);
    struct rb_io_attr attrs[] = {
        {.name = "raybundle:version", .type = RB_IO_ATTR_STRING, .s = RB_VERSION},
        {.name = "raybundle:integrator",
         .type = RB_IO_ATTR_STRING,
         .s = rb_integrator_name(job->integrator.name)},
        {.name = "raybundle:jobHash", .type = RB_IO_ATTR_STRING, .s = hash},
        {.name = "raybundle:frame", .type = RB_IO_ATTR_INT, .i = r->frame},
        {.name = "raybundle:time", .type = RB_IO_ATTR_FLOAT, .f = (float)r->time_s},
        {.name = "raybundle:defaultLight",
         .type = RB_IO_ATTR_STRING,
         .s = setup->default_light_note},
        {.name = "worldToCamera", .type = RB_IO_ATTR_M44},
        {.name = "worldToNDC", .type = RB_IO_ATTR_M44},
        {.name = "raybundle:spp", .type = RB_IO_ATTR_INT, .i = (int)r->spp},
    };
    size_t attr_count = sizeof(attrs) / sizeof(attrs[0]) - (r->spp ? 0 : 1);
    /* Our matrices are column-major for column vectors, which is exactly Imath's row-major
     * layout for row vectors: the floats go over unchanged. */
    memcpy(attrs[6].m, r->world_to_camera.m, sizeof(attrs[6].m));
    memcpy(attrs[7].m, r->world_to_ndc.m, sizeof(attrs[7].m));
    return rb_io_exr_write(path, r->width_px, r->height_px, out, LAYER_COUNT, attrs, attr_count,
                           err);
}

static enum rb_status write_preview(const char *exr_path, const struct rb_job *job,
                                    const struct frame *r, float *scratch, struct rb_err *err)
{
    char path[4096];
    enum rb_status st = rb_io_sidecar_path(exr_path, ".png", path, sizeof(path), err);
    if (st)
        return st;
    /* Opaque: the beauty's colour already holds the environment where alpha is 0, and a
     * preview shows what the camera sees. */
    size_t n = (size_t)r->width_px * r->height_px;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            scratch[i * 4 + c] = r->pixels[i * RB_OUT_FLOATS + RB_OUT_BEAUTY + c];
        scratch[i * 4 + 3] = 1.0f;
    }
    struct rb_io_color_desc cd = {job->color.config, job->color.display, job->color.view};
    return rb_io_preview_write(path, r->width_px, r->height_px, scratch, &cd, err);
}

static enum rb_status write_timing(const char *exr_path, const struct rb_job *job,
                                   const char *device, const char *driver, const struct frame *r,
                                   double wall_ms, struct rb_err *err)
{
    char path[4096];
    enum rb_status st = rb_io_sidecar_path(exr_path, ".timing.json", path, sizeof(path), err);
    if (st)
        return st;
    struct rb_io_timing t = {
        .frame = r->frame,
        .time_s = r->time_s,
        .passes = r->passes,
        .pass_count = r->pass_count,
        .wall_ms = wall_ms,
        .device = device,
        .driver = driver,
        .integrator = rb_integrator_name(job->integrator.name),
        .width_px = r->width_px,
        .height_px = r->height_px,
        .spp = r->spp,
        .ray_count = r->ray_count,
        .nonfinite_count = r->nonfinite_count,
    };
    return rb_io_timing_write(path, &t, err);
}

/* The renderer behind a run: the GPU integrator, or the CPU reference. */
struct backend {
    struct rb_gpu *gpu;
    struct rb_integrator *it;
    struct rb_reference *ref;
    char device[256], driver[256];
    bool tty, quiet;
};

static bool on_reference_pass(void *user, uint32_t done, uint32_t total)
{
    const struct backend *b = user;
    if (b->tty && !b->quiet) {
        char line[80];
        snprintf(line, sizeof(line), "  %u/%u samples", done, total);
        fprintf(stderr, "\r%-66s", line); /* pad over the frame bar */
        cmd_bar_open = true;
    }
    return !interrupted;
}

static enum rb_status backend_render(struct backend *b, int f, struct frame *out,
                                     struct rb_err *err)
{
    memset(out, 0, sizeof(*out));
    if (b->ref) {
        struct rb_reference_result r;
        enum rb_status st = rb_reference_render(b->ref, f, &r, err);
        if (st)
            return st;
        *out = (struct frame){.frame = r.frame,
                              .time_s = r.time_s,
                              .width_px = r.width_px,
                              .height_px = r.height_px,
                              .pixels = r.pixels,
                              .pass_count = 1,
                              .world_to_camera = r.world_to_camera,
                              .world_to_ndc = r.world_to_ndc,
                              .spp = r.spp,
                              .ray_count = r.ray_count,
                              .nonfinite_count = r.nonfinite_count};
        out->passes[0] = (struct rb_io_pass_time){"trace", 0.0, r.render_s * 1e3};
        return RB_OK;
    }
    struct rb_frame_result r;
    enum rb_status st = rb_integrator_render(b->it, f, &r, err);
    if (st)
        return st;
    *out = (struct frame){.frame = r.frame,
                          .time_s = r.time_s,
                          .width_px = r.width_px,
                          .height_px = r.height_px,
                          .pixels = r.pixels,
                          .pass_count = r.pass_count,
                          .world_to_camera = r.world_to_camera,
                          .world_to_ndc = r.world_to_ndc,
                          .nonfinite_count = r.nonfinite_count};
    for (uint32_t i = 0; i < r.pass_count; i++) {
        rb_strlcpy(out->pass_names[i], r.passes[i].name, sizeof(out->pass_names[i]));
        out->passes[i] = (struct rb_io_pass_time){out->pass_names[i], r.passes[i].gpu_ms, 0};
    }
    return RB_OK;
}

/* Creates the backend the job's integrator needs; GPU errors keep their exit codes. */
static enum rb_status backend_create(struct backend *b, const struct options *o,
                                     const struct rb_job *job, const struct rb_scene *scene,
                                     const struct rb_scene_setup *setup, const float *env,
                                     uint32_t env_w, uint32_t env_h, struct rb_err *err)
{
    if (job->integrator.name == RB_INTEGRATOR_REFERENCE) {
        unsigned threads = 0;
        if (o->threads)
            sscanf(o->threads, "%u", &threads);
        long cores = sysconf(_SC_NPROCESSORS_ONLN);
        snprintf(b->device, sizeof(b->device), "cpu (%u threads)",
                 threads ? threads : (unsigned)(cores > 0 ? cores : 1));
        snprintf(b->driver, sizeof(b->driver), "raybundle reference %s (Embree 3)", RB_VERSION);
        return rb_reference_create(&(struct rb_reference_desc){.job = job,
                                                               .scene = scene,
                                                               .env_rgba = env,
                                                               .env_width_px = env_w,
                                                               .env_height_px = env_h,
                                                               .setup = setup,
                                                               .thread_count = threads,
                                                               .on_pass = on_reference_pass,
                                                               .user = b},
                                   &b->ref, err);
    }
    enum rb_status st = rb_gpu_create(
        &(struct rb_gpu_desc){.device = o->device, .validate = o->validate}, &b->gpu, err);
    if (st)
        return st;
    rb_strlcpy(b->device, b->gpu->device_name, sizeof(b->device));
    rb_strlcpy(b->driver, b->gpu->driver, sizeof(b->driver));
    return rb_integrator_create(&(struct rb_integrator_desc){.job = job,
                                                             .scene = scene,
                                                             .gpu = b->gpu,
                                                             .env_rgba = env,
                                                             .env_width_px = env_w,
                                                             .env_height_px = env_h,
                                                             .setup = setup},
                                &b->it, err);
}

static void backend_destroy(struct backend *b)
{
    rb_reference_destroy(b->ref);
    rb_integrator_destroy(b->it);
    rb_gpu_destroy(b->gpu);
}

/* Loads the environment map as RGBA floats (RGB gets A = 1; one channel is grey). */
static enum rb_status load_env(const char *path, float **out, uint32_t *w, uint32_t *h,
                               struct rb_err *err)
{
    struct rb_io_image img = {0};
    enum rb_status st = rb_io_image_read(path, &img, err);
    if (st) {
        rb_err_prefix(err, "environment map");
        return st;
    }
    size_t n = (size_t)img.width_px * img.height_px;
    float *px = malloc(n * 4 * sizeof(float));
    if (!px) {
        rb_io_image_release(&img);
        return rb_errf(err, RB_E_NOMEM, "out of memory for environment map '%s'", path);
    }
    for (size_t i = 0; i < n; i++)
        for (uint32_t c = 0; c < 4; c++) {
            const float *s = &img.pixels[i * img.channel_count];
            float v;
            if (c == 3)
                v = img.channel_count >= 4 ? s[3] : 1.0f;
            else
                v = s[c < img.channel_count ? c : 0];
            px[i * 4 + c] = v;
        }
    *out = px;
    *w = img.width_px;
    *h = img.height_px;
    rb_io_image_release(&img);
    return RB_OK;
}

/* Whether --resume may keep the frame at path: complete, with its timing sidecar, and rendered
 * by the same job (the job hash covers the settings that change pixels, the named integrator's
 * settings and sample count, and the contents of the scene and environment map). */
enum resume_verdict { RENDER, KEEP, STALE };

static enum resume_verdict resume_verdict(const char *path, const char *timing, const char *hash)
{
    if (!rb_io_image_is_complete(path) || access(timing, R_OK) != 0)
        return RENDER;
    char recorded[32];
    if (!rb_io_image_attr(path, "raybundle:jobHash", recorded, sizeof(recorded)) ||
        strcmp(recorded, hash) != 0)
        return STALE;
    return KEEP;
}

static uint64_t file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (uint64_t)sb.st_size : 0;
}

/* After the first frame written: refuses to go on when the rest of the range, at the size that
 * frame took, would not fit on the output's file system (with 5% to spare). */
static enum rb_status check_space(const char *path, const char *timing, bool preview, int left,
                                  struct rb_err *err)
{
    uint64_t frame = file_size(path) + file_size(timing);
    if (preview) {
        char png[4096];
        if (rb_io_sidecar_path(path, ".png", png, sizeof(png), NULL) == RB_OK)
            frame += file_size(png);
    }
    uint64_t need = frame * (uint64_t)left, have = rb_io_free_bytes(path);
    if (have == UINT64_MAX || need + need / 20 <= have)
        return RB_OK;
    return rb_errf(err, RB_E_IO,
                   "the %d frames left need about %.1f GB at %.0f KB a frame, and the output's "
                   "file system has %.1f GB free",
                   left, need / 1e9, frame / 1e3, have / 1e9);
}

/* The directory part of a pattern, for the closing line. */
static void output_dir(const char *pattern, char *dir, size_t size)
{
    const char *slash = strrchr(pattern, '/');
    if (slash)
        snprintf(dir, size, "%.*s/", (int)(slash - pattern), pattern);
    else
        rb_strlcpy(dir, "./", size);
}

static int run(struct options *o, int argc, char **argv)
{
    int rc = parse_options(argc, argv, o);
    if (rc)
        return rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;
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
    struct backend b = {.quiet = o->quiet};
    float *env = NULL, *scratch = NULL;
    uint32_t env_w = 0, env_h = 0;
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
    if ((st = rb_scene_load(job->scene_path, o->is_lenient ? RB_SCENE_LOAD_LENIENT : 0, &scene,
                            &err))) {
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    if (job->environment.map && (st = load_env(job->environment.map, &env, &env_w, &env_h, &err))) {
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    if ((st = rb_scene_setup_init(job, scene, env, env_w, env_h, &setup, &err))) {
        cmd_error("%s", err.msg);
        rc = exit_for(st, false);
        goto out;
    }
    int first = job->frame_start, last = resolve_end(job, scene);
    if ((st = rb_job_check_output(job->output, first, last, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE;
        goto out;
    }
    b.tty = !o->quiet && isatty(STDERR_FILENO);
    if ((st = backend_create(&b, o, job, scene, &setup, env, env_w, env_h, &err))) {
        cmd_error("%s", err.msg);
        rc = st == RB_E_UNSUPPORTED || st == RB_E_INVALID ? RB_EXIT_USAGE : exit_for(st, true);
        goto out;
    }
    scratch = malloc((size_t)job->width_px * job->height_px * RB_OUT_FLOATS * sizeof(float));
    if (!scratch) {
        cmd_error("out of memory");
        rc = RB_EXIT_FAILED;
        goto out;
    }
    char path[4096], timing[4096], hash[17];
    snprintf(hash, sizeof(hash), "%016llx", (unsigned long long)setup.job_hash);
    if ((st = rb_io_frame_path(job->output, first, path, sizeof(path), &err)) ||
        (st = rb_io_check_writable(path, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_USAGE; /* a bad output location, found before any rendering */
        goto out;
    }

    int total = last - first + 1, done = 0, rendered = 0, skipped = 0, stale = 0;
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    double started = now_s();
    for (int f = first; f <= last; f++) {
        if (interrupted) {
            cmd_error("interrupted: frames %d to %d were not rendered", f, last);
            rc = RB_EXIT_FAILED;
            break;
        }
        if ((st = rb_io_frame_path(job->output, f, path, sizeof(path), &err)) ||
            (st = rb_io_sidecar_path(path, ".timing.json", timing, sizeof(timing), &err))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_USAGE;
            break;
        }
        if (o->resume) {
            enum resume_verdict v = resume_verdict(path, timing, hash);
            if (v == KEEP) {
                done++;
                skipped++;
                if (!o->quiet)
                    progress(b.tty, done, total, f, 0.0, true);
                continue;
            }
            if (v == STALE) {
                stale++;
                if (!o->quiet && !b.tty)
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
        double t0 = now_s();
        struct frame r;
        if ((st = backend_render(&b, f, &r, &err))) {
            cmd_error("frame %d: %s", f, err.msg);
            rc = exit_for(st, true);
            break;
        }
        if (b.ref && interrupted && r.spp < job->integrator.reference.spp) {
            /* Stopped by the signal, not by the job's time limit: a partial frame is never
             * written under the frame's name, so --resume renders it again. */
            cmd_error("interrupted: frame %d stopped at %u of %u samples and was not written; "
                      "frames %d to %d were not rendered",
                      f, r.spp, job->integrator.reference.spp, f, last);
            rc = RB_EXIT_FAILED;
            break;
        }
        if ((st = write_exr(path, job, &setup, &r, scratch, &err)) ||
            (job->color.preview && (st = write_preview(path, job, &r, scratch, &err))) ||
            (st = write_timing(path, job, b.device, b.driver, &r, (now_s() - t0) * 1e3, &err))) {
            cmd_error("frame %d: %s", f, err.msg);
            rc = exit_for(st, true);
            break;
        }
        if (f == abort_after)
            kill(getpid(), SIGKILL);
        done++;
        rendered++;
        if (!o->quiet)
            progress(b.tty, done, total, f, (now_s() - started) / rendered, false);
        if (rendered == 1 && f < last &&
            (st = check_space(path, timing, job->color.preview, last - f, &err))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_FAILED;
            break;
        }
    }
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (rc == RB_EXIT_OK) {
        char dir[4096];
        output_dir(job->output, dir, sizeof(dir));
        printf("%d frame%s (%d-%d) in %s: %d rendered", total, total == 1 ? "" : "s", first, last,
               dir, rendered);
        if (o->resume)
            printf(", %d kept, %d rendered again (another job)", skipped, stale);
        printf(", %.1f s\n", now_s() - started);
    }
out:
    cmd_end_bar();
    free(scratch);
    backend_destroy(&b);
    free(env);
    rb_scene_destroy(scene);
    rb_job_destroy(job);
    rb_log_set_sink(NULL, NULL);
    return rc;
}

int cmd_render(int argc, char **argv)
{
    struct options o = {.command = "render"};
    return run(&o, argc, argv);
}

int cmd_reference(int argc, char **argv)
{
    struct options o = {.command = "reference"};
    return run(&o, argc, argv);
}
