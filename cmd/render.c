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

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    /* First ^C: finish the frame in flight. Second: stop now (files are renamed into place,
     * so none is ever torn). */
    if (interrupted)
        signal(SIGINT, SIG_DFL), raise(SIGINT);
    interrupted = 1;
}

struct options {
    const char *job_path;
    struct rb_job_override overrides[MAX_OVERRIDES];
    size_t override_count;
    const char *frames, *size, *output, *out_dir, *integrator, *device;
    const char *spp, *time_limit, *threads;
    bool resume, validate, preview, quiet;
    bool is_lenient; /* --lenient: glTF type errors are warnings */
    int verbose;
    const char *command; /* "render" or "reference" */
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
            "  --frames A-B         render frames A to B (or one frame: A)\n"
            "  --size WxH           override the resolution\n"
            "  --output PATTERN     override the output pattern (#### = frame number)\n"
            "  --out DIR            write into DIR, keeping the pattern's file name\n"
            "  --integrator NAME    direct or reference (bdpt, hybrid: not yet)\n"
            "  --set KEY=VALUE      override any job key by its dotted path (repeatable)\n"
            "  --resume             skip frames whose files are already complete\n"
            "  --preview            also write NAME.####.png through OpenColorIO\n"
            "  --device NAME|INDEX  pick a Vulkan device (default: lavapipe)\n"
            "  --validate           enable the Khronos validation layer; any message fails\n"
            "  --lenient            glTF properties of the wrong type are warnings, not errors\n"
            "  --spp N              reference: samples per pixel\n"
            "  --time-limit S       reference: stop at the pass of samples that crosses S seconds\n"
            "  --threads N          reference: worker threads (default: all cores)\n"
            "  -q, --quiet          no progress output\n"
            "  -v, --verbose        more log output (repeat for debug)\n"
            "  -h, --help           show this help\n"
            "\n"
            "Exit status: 0 ok, 1 rendering failed, 2 bad usage or job, 3 no usable device.\n");
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
        switch (c) {
        case O_FRAMES: o->frames = optarg; break;
        case O_SIZE: o->size = optarg; break;
        case O_OUTPUT: o->output = optarg; break;
        case O_OUT: o->out_dir = optarg; break;
        case O_INTEGRATOR: o->integrator = optarg; break;
        case O_SET: {
            char *eq = strchr(optarg, '=');
            if (!eq || eq == optarg) {
                cmd_error("--set expects KEY=VALUE, got '%s'", optarg);
                return -1;
            }
            if (o->override_count == MAX_OVERRIDES) {
                cmd_error("more than %d --set options", MAX_OVERRIDES);
                return -1;
            }
            *eq = '\0';
            o->overrides[o->override_count++] = (struct rb_job_override){optarg, eq + 1};
            break;
        }
        case O_RESUME: o->resume = true; break;
        case O_PREVIEW: o->preview = true; break;
        case O_DEVICE: o->device = optarg; break;
        case O_VALIDATE: o->validate = true; break;
        case O_SPP: o->spp = optarg; break;
        case O_TIME_LIMIT: o->time_limit = optarg; break;
        case O_THREADS: o->threads = optarg; break;
        case O_LENIENT: o->is_lenient = true; break;
        case 'q': o->quiet = true; break;
        case 'v': o->verbose++; break;
        case 'h': usage(stdout, o->command); return 1;
        default: usage(stderr, o->command); return -1;
        }
    }
    if (optind != argc - 1) {
        cmd_error(optind >= argc ? "%s needs a JOB" : "%s takes one JOB", o->command);
        usage(stderr, o->command);
        return -1;
    }
    o->job_path = argv[optind];
    return 0;
}

/* Applies --size, --frames, --output, --out and --integrator to the parsed job. */
static int apply_cli(const struct options *o, struct rb_job *job)
{
    if (o->size) {
        unsigned w, h;
        char tail;
        if (sscanf(o->size, "%ux%u%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 16384 ||
            h > 16384) {
            cmd_error("--size expects WxH with 1..16384 each, got '%s'", o->size);
            return -1;
        }
        job->width_px = w;
        job->height_px = h;
    }
    if (o->frames) {
        int a, b;
        char tail;
        int n = sscanf(o->frames, "%d-%d%c", &a, &b, &tail);
        if (n == 1)
            b = a;
        if ((n != 1 && n != 2) || b < a) {
            cmd_error("--frames expects A-B with A <= B, or A, got '%s'", o->frames);
            return -1;
        }
        job->frame_start = a;
        job->frame_end = b;
    }
    if (o->output) {
        free(job->output);
        job->output = rb_strdup(o->output);
    }
    if (o->out_dir) {
        const char *slash = strrchr(job->output, '/');
        const char *base = slash ? slash + 1 : job->output;
        size_t n = strlen(o->out_dir) + strlen(base) + 2;
        char *p = malloc(n);
        if (!p)
            return -1;
        snprintf(p, n, "%s/%s", o->out_dir, base);
        free(job->output);
        job->output = p;
    }
    if (o->integrator) {
        enum rb_integrator_kind k = rb_integrator_from_name(o->integrator);
        if (k == RB_INTEGRATOR_DEFAULT) {
            cmd_error("unknown integrator '%s' (direct, bdpt, hybrid, reference)", o->integrator);
            return -1;
        }
        job->integrator.name = k;
    }
    if (strcmp(o->command, "reference") == 0)
        job->integrator.name = RB_INTEGRATOR_REFERENCE;
    if (o->spp) {
        unsigned n;
        char tail;
        if (sscanf(o->spp, "%u%c", &n, &tail) != 1 || n < 1 || n > 1048576) {
            cmd_error("--spp expects 1..1048576, got '%s'", o->spp);
            return -1;
        }
        job->integrator.reference.spp = n;
    }
    if (o->time_limit) {
        double s;
        char tail;
        if (sscanf(o->time_limit, "%lf%c", &s, &tail) != 1 || !(s >= 0.0)) {
            cmd_error("--time-limit expects seconds >= 0, got '%s'", o->time_limit);
            return -1;
        }
        job->integrator.reference.time_limit_s = s;
    }
    if (o->threads) {
        unsigned n;
        char tail;
        if (sscanf(o->threads, "%u%c", &n, &tail) != 1 || n < 1 || n > 1024) {
            cmd_error("--threads expects 1..1024, got '%s'", o->threads);
            return -1;
        }
    }
    if (!job->output) {
        cmd_error("out of memory");
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
        if (done == total)
            fputc('\n', stderr);
    } else if (skipped) {
        fprintf(stderr, "raybundle: frame %d (%d/%d) already complete, skipped\n", frame, done,
                total);
    } else {
        fprintf(stderr, "raybundle: frame %d (%d/%d) %.2f s\n", frame, done, total, sec_per_frame);
    }
}

/* Splits the packed readback into the EXR's layers and writes it with its metadata. */
static enum rb_status write_exr(const char *path, const struct rb_job *job, const struct frame *r,
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
    snprintf(hash, sizeof(hash), "%016llx", (unsigned long long)job->hash);
    struct rb_io_attr attrs[] = {
        {.name = "raybundle:version", .type = RB_IO_ATTR_STRING, .s = RB_VERSION},
        {.name = "raybundle:integrator",
         .type = RB_IO_ATTR_STRING,
         .s = rb_integrator_name(job->integrator.name)},
        {.name = "raybundle:jobHash", .type = RB_IO_ATTR_STRING, .s = hash},
        {.name = "raybundle:frame", .type = RB_IO_ATTR_INT, .i = r->frame},
        {.name = "raybundle:time", .type = RB_IO_ATTR_FLOAT, .f = (float)r->time_s},
        {.name = "worldToCamera", .type = RB_IO_ATTR_M44},
        {.name = "worldToNDC", .type = RB_IO_ATTR_M44},
        {.name = "raybundle:spp", .type = RB_IO_ATTR_INT, .i = (int)r->spp},
    };
    size_t attr_count = sizeof(attrs) / sizeof(attrs[0]) - (r->spp ? 0 : 1);
    /* Our matrices are column-major for column vectors, which is exactly Imath's row-major
     * layout for row vectors: the floats go over unchanged. */
    memcpy(attrs[5].m, r->world_to_camera.m, sizeof(attrs[5].m));
    memcpy(attrs[6].m, r->world_to_ndc.m, sizeof(attrs[6].m));
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
                              .ray_count = r.ray_count};
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
                          .world_to_ndc = r.world_to_ndc};
    for (uint32_t i = 0; i < r.pass_count; i++) {
        rb_strlcpy(out->pass_names[i], r.passes[i].name, sizeof(out->pass_names[i]));
        out->passes[i] = (struct rb_io_pass_time){out->pass_names[i], r.passes[i].gpu_ms, 0};
    }
    return RB_OK;
}

/* Creates the backend the job's integrator needs; GPU errors keep their exit codes. */
static enum rb_status backend_create(struct backend *b, const struct options *o,
                                     const struct rb_job *job, const struct rb_scene *scene,
                                     const float *env, uint32_t env_w, uint32_t env_h,
                                     struct rb_err *err)
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
                                                             .env_height_px = env_h},
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

static int run(struct options *o, int argc, char **argv)
{
    int rc = parse_options(argc, argv, o);
    if (rc)
        return rc > 0 ? RB_EXIT_OK : RB_EXIT_USAGE;
    rb_log_set_level(o->quiet ? RB_LOG_ERROR : (enum rb_log_level)(RB_LOG_WARN + o->verbose));
    if (getenv("RB_VALIDATE") && strcmp(getenv("RB_VALIDATE"), "1") == 0)
        o->validate = true;

    struct rb_err err = RB_ERR_INIT;
    struct rb_job *job = NULL;
    struct rb_scene *scene = NULL;
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
    b.tty = !o->quiet && isatty(STDERR_FILENO);
    if ((st = backend_create(&b, o, job, scene, env, env_w, env_h, &err))) {
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

    int first = job->frame_start, last = resolve_end(job, scene);
    int total = last - first + 1, done = 0;
    signal(SIGINT, on_sigint);
    double started = now_s();
    int rendered = 0;
    for (int f = first; f <= last; f++) {
        if (interrupted) {
            cmd_error("interrupted: frames %d to %d were not rendered", f, last);
            rc = RB_EXIT_FAILED;
            break;
        }
        char path[4096], timing[4096];
        if ((st = rb_io_frame_path(job->output, f, path, sizeof(path), &err)) ||
            (st = rb_io_sidecar_path(path, ".timing.json", timing, sizeof(timing), &err))) {
            cmd_error("%s", err.msg);
            rc = RB_EXIT_USAGE;
            break;
        }
        if (o->resume && rb_io_image_is_complete(path) && access(timing, R_OK) == 0) {
            done++;
            if (!o->quiet)
                progress(b.tty, done, total, f, 0.0, true);
            continue;
        }
        if (o->resume) {
            unsigned stale = rb_io_remove_stale_temps(path);
            if (stale)
                rb_log(RB_LOG_INFO,
                       "frame %d: removed %u temporary file(s) of an interrupted "
                       "run",
                       f, stale);
        }
        double t0 = now_s();
        struct frame r;
        if ((st = backend_render(&b, f, &r, &err)) || (st = rb_io_make_parent_dirs(path, &err)) ||
            (st = write_exr(path, job, &r, scratch, &err)) ||
            (job->color.preview && (st = write_preview(path, job, &r, scratch, &err))) ||
            (st = write_timing(path, job, b.device, b.driver, &r, (now_s() - t0) * 1e3, &err))) {
            cmd_error("frame %d: %s", f, err.msg);
            rc = exit_for(st, true);
            break;
        }
        done++;
        rendered++;
        if (!o->quiet)
            progress(b.tty, done, total, f, (now_s() - started) / rendered, false);
    }
    signal(SIGINT, SIG_DFL);
out:
    free(scratch);
    backend_destroy(&b);
    free(env);
    rb_scene_destroy(scene);
    rb_job_destroy(job);
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
