/* A run of a job: the renderer (the GPU frame driver or the CPU reference) behind one result
 * type, the --resume decision, and the frame's files. Layers go into the EXR in the order of
 * enum rb_layer (core.h); the metadata holds nothing that depends on the time of the
 * render, so equal pixels give equal bytes.
 * Writing is off the critical path: a rendered frame is copied into one of QUEUE_DEPTH pending
 * entries and written (layer split, EXR compression, hit ratios, preview, sidecar, atomic
 * renames) by one writer thread, in frame order, while the next frame renders. A write error is
 * reported by the next call that hands over a frame or flushes. */
#include "render/render.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gpu/gpu.h"
#include "integrators/integrators.h"
#include "io/io.h"
#include "reference/reference.h"
#include "shared.h"

#define QUEUE_DEPTH 2 /* frames rendered but not yet written, at most */

struct rb_render {
    const struct rb_job *job;
    const struct rb_scene_setup *setup;
    struct rb_gpu *gpu;
    struct rb_integrator *it;
    struct rb_reference *ref;
    bool (*on_pass)(void *user, uint32_t spp_done, uint32_t spp_total);
    void (*on_written)(void *user, int frame, const char *path, double wall_ms);
    void *user;
    bool was_stopped;    /* on_pass said stop during this frame */
    bool strict;         /* desc->strict */
    bool is_timing_only; /* the sidecar alone: no EXR, no preview (bench) */
    char hash[17];       /* the setup's job hash, as the EXR records it */
    char device[256], driver[256];
    float *scratch; /* the writer's copies of layers for the EXR and the preview */

    /* the writer thread and the frames it has yet to write */
    pthread_t writer;
    bool has_writer, is_stopping;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    struct pending {
        bool is_full;
        char path[4096];
        struct rb_frame_result f; /* pixels, hits, passes: the entry's own copies */
        float *pixels;
        float *hits; /* width x height floats, from the first frame that has hit ratios */
        struct rb_pass_time *passes;
        uint32_t pass_cap;
        struct rb_ray_counts ray_counts;
        double wall_ms;
    } queue[QUEUE_DEPTH];
    uint32_t head, count;    /* the oldest pending entry, and how many are full */
    enum rb_status write_st; /* the writer's first failure, RB_OK until then */
    struct rb_err write_err; /* its message */
    int write_frame;         /* the frame it failed on */
};

static void *writer_main(void *arg);

static bool on_reference_pass(void *user, uint32_t done, uint32_t total)
{
    struct rb_render *r = user;
    if (r->on_pass && !r->on_pass(r->user, done, total)) {
        r->was_stopped = true;
        return false;
    }
    return true;
}

/* A frame's floats a pixel: the GPU reads back the job's layers, the reference makes all. */
static uint32_t frame_stride(const struct rb_job *job)
{
    return rb_layer_stride(job->integrator.name == RB_INTEGRATOR_REFERENCE ? RB_LAYERS_ALL
                                                                           : job->layer_mask);
}

enum rb_status rb_render_create(const struct rb_render_desc *desc, struct rb_render **out,
                                struct rb_err *err)
{
    const struct rb_job *job = desc->job;
    struct rb_render *r = calloc(1, sizeof(*r));
    if (!r)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    r->job = job;
    r->setup = desc->setup;
    r->on_pass = desc->on_pass;
    r->on_written = desc->on_written;
    r->strict = desc->strict;
    r->user = desc->user;
    r->is_timing_only = desc->is_timing_only;
    snprintf(r->hash, sizeof(r->hash), "%016llx", (unsigned long long)desc->setup->job_hash);
    enum rb_status st = RB_OK;
    size_t frame_floats = (size_t)job->width_px * job->height_px * frame_stride(job);
    r->scratch = malloc(frame_floats * sizeof(float));
    if (!r->scratch) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for a %ux%u frame", job->width_px,
                     job->height_px);
        goto fail;
    }
    if (job->integrator.name == RB_INTEGRATOR_REFERENCE) {
        long cores = sysconf(_SC_NPROCESSORS_ONLN);
        snprintf(r->device, sizeof(r->device), "cpu (%u threads)",
                 desc->thread_count ? desc->thread_count : (unsigned)(cores > 0 ? cores : 1));
        snprintf(r->driver, sizeof(r->driver), "raybundle reference %s (Embree 3)", RB_VERSION);
        st = rb_reference_create(&(struct rb_reference_desc){.job = job,
                                                             .scene = desc->scene,
                                                             .env_rgba = desc->env_rgba,
                                                             .env_width_px = desc->env_width_px,
                                                             .env_height_px = desc->env_height_px,
                                                             .setup = desc->setup,
                                                             .thread_count = desc->thread_count,
                                                             .on_pass = on_reference_pass,
                                                             .user = r},
                                 &r->ref, err);
    } else {
        st =
            rb_gpu_create(&(struct rb_gpu_desc){.device = desc->device, .validate = desc->validate},
                          &r->gpu, err);
        if (st == RB_OK) {
            rb_strlcpy(r->device, r->gpu->device_name, sizeof(r->device));
            rb_strlcpy(r->driver, r->gpu->driver, sizeof(r->driver));
            st = rb_integrator_create(
                &(struct rb_integrator_desc){.job = job,
                                             .scene = desc->scene,
                                             .gpu = r->gpu,
                                             .env_rgba = desc->env_rgba,
                                             .env_width_px = desc->env_width_px,
                                             .env_height_px = desc->env_height_px,
                                             .setup = desc->setup},
                &r->it, err);
        }
    }
    if (st)
        goto fail;
    for (int q = 0; q < QUEUE_DEPTH; q++)
        if (!(r->queue[q].pixels = malloc(frame_floats * sizeof(float)))) {
            st = rb_errf(err, RB_E_NOMEM, "out of memory for the frames waiting to be written");
            goto fail;
        }
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->changed, NULL);
    if (pthread_create(&r->writer, NULL, writer_main, r) != 0) {
        pthread_cond_destroy(&r->changed);
        pthread_mutex_destroy(&r->lock);
        st = rb_errf(err, RB_E_NOMEM, "cannot start the writer thread");
        goto fail;
    }
    r->has_writer = true;
    *out = r;
    return RB_OK;
fail:
    rb_render_destroy(r);
    return st;
}

void rb_render_destroy(struct rb_render *r)
{
    if (!r)
        return;
    if (r->has_writer) {
        pthread_mutex_lock(&r->lock);
        r->is_stopping = true; /* the writer finishes what is queued, then ends */
        pthread_cond_broadcast(&r->changed);
        pthread_mutex_unlock(&r->lock);
        pthread_join(r->writer, NULL);
        pthread_cond_destroy(&r->changed);
        pthread_mutex_destroy(&r->lock);
    }
    for (int q = 0; q < QUEUE_DEPTH; q++) {
        free(r->queue[q].pixels);
        free(r->queue[q].hits);
        free(r->queue[q].passes);
    }
    rb_reference_destroy(r->ref);
    rb_integrator_destroy(r->it);
    rb_gpu_destroy(r->gpu);
    free(r->scratch);
    free(r);
}

const char *rb_render_device(const struct rb_render *r)
{
    return r->device;
}

const char *rb_render_driver(const struct rb_render *r)
{
    return r->driver;
}

int rb_render_last_frame(const struct rb_job *job, const struct rb_scene *scene)
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

uint32_t rb_render_warmup_frames(const struct rb_render *r, int f)
{
    return r->it ? rb_integrator_warmup_frames(r->it, f) : 0;
}

/* ---- resume --------------------------------------------------------------------------------- */

enum rb_render_verdict rb_render_resume_verdict(const struct rb_render *r, const char *path)
{
    char timing[4096], hits[4096], recorded[32];
    /* bdpt's frames have their hit ratios beside them, written before the timing sidecar. */
    bool has_hits = rb_integrator_resolve(r->job->integrator.name) == RB_INTEGRATOR_BDPT;
    if (rb_io_sidecar_path(path, ".timing.json", timing, sizeof(timing), NULL) != RB_OK ||
        rb_io_sidecar_path(path, ".hits.exr", hits, sizeof(hits), NULL) != RB_OK ||
        !rb_io_image_is_complete(path) || access(timing, R_OK) != 0 ||
        (has_hits && !rb_io_image_is_complete(hits)))
        return RB_RENDER_NEW;
    /* The sidecar is written last, so it is what says the frame is done: one that does not
     * parse as a sidecar (a torn or overwritten file) would break report and timing compare
     * later, so the frame is rendered again. */
    struct rb_io_timing_file side = {0};
    bool side_ok = rb_io_timing_read(timing, &side, NULL) == RB_OK;
    bool side_matches = side_ok && (!side.job_hash[0] || !strcmp(side.job_hash, r->hash)) &&
                        side.has_hits == has_hits;
    rb_io_timing_file_release(&side);
    if (!side_ok)
        return RB_RENDER_NEW;
    if (!rb_io_image_attr(path, "raybundle:jobHash", recorded, sizeof(recorded)) ||
        strcmp(recorded, r->hash) != 0 || !side_matches)
        return RB_RENDER_STALE;
    return RB_RENDER_KEEP;
}

/* ---- writing -------------------------------------------------------------------------------- */

/* The metadata every image of a frame carries (the frame's EXR and its hit ratios): what made
 * it, for which job, which frame. Returns the count (at most FRAME_ATTRS). The device is the
 * timing sidecar's, not the EXR's: the same pixels from another driver are the same bytes. */
#define FRAME_ATTRS 5
static size_t frame_attrs(const struct rb_render *r, const struct rb_frame_result *f,
                          struct rb_io_attr *out)
{
    out[0] = (struct rb_io_attr){
        .name = "raybundle:version", .type = RB_IO_ATTR_STRING, .s = RB_VERSION};
    out[1] = (struct rb_io_attr){.name = "raybundle:integrator",
                                 .type = RB_IO_ATTR_STRING,
                                 .s = rb_integrator_name(r->job->integrator.name)};
    out[2] =
        (struct rb_io_attr){.name = "raybundle:jobHash", .type = RB_IO_ATTR_STRING, .s = r->hash};
    out[3] = (struct rb_io_attr){.name = "raybundle:frame", .type = RB_IO_ATTR_INT, .i = f->frame};
    out[4] = (struct rb_io_attr){
        .name = "raybundle:time", .type = RB_IO_ATTR_FLOAT, .f = (float)f->time_s};
    return FRAME_ATTRS;
}

/* Splits the packed pixels into the EXR's layers (the beauty and the job's layers, in
 * RB_LAYER order) and writes it with its metadata. */
static enum rb_status write_exr(const struct rb_render *r, const char *path,
                                const struct rb_frame_result *f, struct rb_err *err)
{
    size_t n = (size_t)f->width_px * f->height_px;
    static const char *const rgba[] = {"R", "G", "B", "A"};
    const char *channels[RB_LAYER_COUNT][4];
    struct rb_io_layer out[1 + RB_LAYER_COUNT];
    uint32_t offset[1 + RB_LAYER_COUNT], layer_count = 0;
    out[layer_count] = (struct rb_io_layer){.channel_count = 4, .channel_names = rgba};
    offset[layer_count++] = 0;
    for (uint32_t l = 0; l < RB_LAYER_COUNT; l++) {
        if (!(r->job->layer_mask & (1u << l)))
            continue;
        if (!(f->layer_mask & (1u << l)))
            return rb_errf(err, RB_E_INVALID, "'%s': the renderer made no '%s' layer", path,
                           rb_layer_name((enum rb_layer)l));
        for (uint32_t c = 0; c < rb_layer_width((enum rb_layer)l); c++)
            channels[l][c] = rb_layer_channel((enum rb_layer)l, c);
        out[layer_count] = (struct rb_io_layer){.name = rb_layer_name((enum rb_layer)l),
                                                .channel_count = rb_layer_width((enum rb_layer)l),
                                                .channel_names = channels[l]};
        offset[layer_count++] = rb_layer_offset(f->layer_mask, (enum rb_layer)l);
    }
    float *p = r->scratch;
    for (uint32_t l = 0; l < layer_count; l++) {
        uint32_t count = out[l].channel_count;
        for (size_t i = 0; i < n; i++)
            for (uint32_t c = 0; c < count; c++)
                p[i * count + c] = f->pixels[i * f->floats_per_pixel + offset[l] + c];
        out[l].pixels = p;
        p += n * count;
    }
    struct rb_io_attr attrs[FRAME_ATTRS + 4];
    size_t attr_count = frame_attrs(r, f, attrs);
    attrs[attr_count++] = (struct rb_io_attr){.name = "raybundle:defaultLight",
                                              .type = RB_IO_ATTR_STRING,
                                              .s = r->setup->default_light_note};
    /* Our matrices are column-major for column vectors, which is exactly Imath's row-major
     * layout for row vectors: the floats go over unchanged. */
    attrs[attr_count] = (struct rb_io_attr){.name = "worldToCamera", .type = RB_IO_ATTR_M44};
    memcpy(attrs[attr_count++].m, f->world_to_camera.m, sizeof(attrs[0].m));
    attrs[attr_count] = (struct rb_io_attr){.name = "worldToNDC", .type = RB_IO_ATTR_M44};
    memcpy(attrs[attr_count++].m, f->world_to_ndc.m, sizeof(attrs[0].m));
    if (f->spp)
        attrs[attr_count++] =
            (struct rb_io_attr){.name = "raybundle:spp", .type = RB_IO_ATTR_INT, .i = (int)f->spp};
    return rb_io_exr_write(path, f->width_px, f->height_px, out, layer_count, attrs, attr_count,
                           err);
}

/* The hit ratios beside the frame (NAME.####.hits.exr): one float channel, Y, 1 where every
 * temporal cache hit and 0 where none did, with the frame's metadata. */
static enum rb_status write_hits(const struct rb_render *r, const char *exr_path,
                                 const struct rb_frame_result *f, struct rb_err *err)
{
    char path[4096];
    enum rb_status st = rb_io_sidecar_path(exr_path, ".hits.exr", path, sizeof(path), err);
    if (st)
        return st;
    static const char *const y[] = {"Y"};
    const struct rb_io_layer layer = {.channel_count = 1, .channel_names = y, .pixels = f->hits};
    struct rb_io_attr attrs[FRAME_ATTRS + 1];
    size_t attr_count = frame_attrs(r, f, attrs);
    attrs[attr_count++] = (struct rb_io_attr){
        .name = "ImageDescription",
        .type = RB_IO_ATTR_STRING,
        .s = "hit ratio: the temporal caches' sum of h / l (1: every cache hit, 0: none)"};
    return rb_io_exr_write(path, f->width_px, f->height_px, &layer, 1, attrs, attr_count, err);
}

static enum rb_status write_preview(const struct rb_render *r, const char *exr_path,
                                    const struct rb_frame_result *f, struct rb_err *err)
{
    char path[4096];
    enum rb_status st = rb_io_sidecar_path(exr_path, ".png", path, sizeof(path), err);
    if (st)
        return st;
    /* Opaque: the beauty's colour already holds the environment where alpha is 0, and a
     * preview shows what the camera sees. */
    size_t n = (size_t)f->width_px * f->height_px;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            r->scratch[i * 4 + c] = f->pixels[i * f->floats_per_pixel + c]; /* the beauty */
        r->scratch[i * 4 + 3] = 1.0f;
    }
    const struct rb_job *job = r->job;
    struct rb_io_color_desc cd = {job->color.config, job->color.display, job->color.view};
    return rb_io_preview_write(path, f->width_px, f->height_px, r->scratch, &cd, err);
}

enum rb_status rb_render_preview_from_exr(const struct rb_render *r, const char *path, bool *wrote,
                                          struct rb_err *err)
{
    char png[4096];
    struct rb_io_image img = {0};
    float *rgba = NULL;
    *wrote = false;
    enum rb_status st = rb_io_sidecar_path(path, ".png", png, sizeof(png), err);
    if (st || access(png, F_OK) == 0)
        return st;
    if ((st = rb_io_image_read(path, &img, err)))
        return st;
    int ch[3] = {rb_io_image_channel(&img, "R"), rb_io_image_channel(&img, "G"),
                 rb_io_image_channel(&img, "B")};
    size_t n = (size_t)img.width_px * img.height_px;
    if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0) {
        st = rb_errf(err, RB_E_INVALID, "'%s' has no R, G and B to make its preview from", path);
        goto out;
    }
    if (!(rgba = malloc(n * 4 * sizeof(float)))) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory for the preview of '%s'", path);
        goto out;
    }
    /* Opaque, as write_preview makes it. */
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            rgba[i * 4 + c] = img.pixels[i * img.channel_count + (size_t)ch[c]];
        rgba[i * 4 + 3] = 1.0f;
    }
    const struct rb_job *job = r->job;
    struct rb_io_color_desc cd = {job->color.config, job->color.display, job->color.view};
    if ((st = rb_io_preview_write(png, img.width_px, img.height_px, rgba, &cd, err)) == RB_OK)
        *wrote = true;
out:
    free(rgba);
    rb_io_image_release(&img);
    return st;
}

static enum rb_status write_timing(const struct rb_render *r, const char *exr_path,
                                   const struct rb_frame_result *f, double wall_ms,
                                   struct rb_err *err)
{
    char path[4096];
    struct rb_io_hits hits;
    enum rb_status st = rb_io_sidecar_path(exr_path, ".timing.json", path, sizeof(path), err);
    if (st || (f->hits && (st = rb_io_hits_summarize(f->hits, (size_t)f->width_px * f->height_px,
                                                     &hits, err))))
        return st;
    struct rb_io_timing t = {
        .frame = f->frame,
        .time_s = f->time_s,
        .passes = f->passes,
        .pass_count = f->pass_count,
        .wall_ms = wall_ms,
        .device = r->device,
        .driver = r->driver,
        .job_hash = r->hash,
        .integrator = rb_integrator_name(r->job->integrator.name),
        .width_px = f->width_px,
        .height_px = f->height_px,
        .spp = f->spp,
        .ray_count = f->ray_count,
        .nonfinite_count = f->nonfinite_count,
        .bundle_nodes_max = f->bundle_nodes_max,
        .bundle_nodes_capacity = f->bundle_nodes_capacity,
        .bundle_nodes_dropped = f->bundle_nodes_dropped,
        .hits = f->hits ? &hits : NULL,
        .ray_counts = f->ray_counts,
    };
    return rb_io_timing_write(path, &t, err);
}

/* ---- the writer ------------------------------------------------------------------------------ */

/* Removes path if it exists; its absence is fine. */
static enum rb_status remove_side(const char *path, struct rb_err *err)
{
    if (unlink(path) != 0 && errno != ENOENT)
        return rb_errf(err, RB_E_IO, "cannot remove the old '%s': %s", path, strerror(errno));
    return RB_OK;
}

/* A frame's files are all of one render. Before its EXR is written: the old sidecar goes (it
 * is written last, and says the frame is complete: a render stopped before it leaves none, and
 * --resume renders the frame again), and so do the hit ratios and the preview this render does
 * not write (a direct render over a bdpt frame, a render without --preview over one with). */
static enum rb_status remove_stale_sides(const struct rb_render *r, const struct pending *e,
                                         struct rb_err *err)
{
    char path[4096];
    enum rb_status st;
    if ((st = rb_io_sidecar_path(e->path, ".timing.json", path, sizeof(path), err)) ||
        (st = remove_side(path, err)))
        return st;
    if (!e->f.hits && ((st = rb_io_sidecar_path(e->path, ".hits.exr", path, sizeof(path), err)) ||
                       (st = remove_side(path, err))))
        return st;
    if (!r->job->color.preview &&
        ((st = rb_io_sidecar_path(e->path, ".png", path, sizeof(path), err)) ||
         (st = remove_side(path, err))))
        return st;
    return RB_OK;
}

static void *writer_main(void *arg)
{
    struct rb_render *r = arg;
    pthread_mutex_lock(&r->lock);
    for (;;) {
        while (!r->count && !r->is_stopping)
            pthread_cond_wait(&r->changed, &r->lock);
        if (!r->count)
            break; /* stopping, and nothing left to write */
        struct pending *e = &r->queue[r->head];
        pthread_mutex_unlock(&r->lock);
        /* The entry is the writer's until it is emptied; the scratch is the writer's alone. */
        struct rb_err err = RB_ERR_INIT;
        enum rb_status st = RB_OK;
        if (r->write_st == RB_OK) /* after a failure, nothing more is written */
            (void)((st = rb_io_make_parent_dirs(e->path, &err)) ||
                   (!r->is_timing_only && (st = remove_stale_sides(r, e, &err))) ||
                   (!r->is_timing_only && (st = write_exr(r, e->path, &e->f, &err))) ||
                   (!r->is_timing_only && e->f.hits &&
                    (st = write_hits(r, e->path, &e->f, &err))) ||
                   (!r->is_timing_only && r->job->color.preview &&
                    (st = write_preview(r, e->path, &e->f, &err))) ||
                   (st = write_timing(r, e->path, &e->f, e->wall_ms, &err)));
        if (r->write_st == RB_OK && st == RB_OK && r->on_written)
            r->on_written(r->user, e->f.frame, e->path, e->wall_ms);
        pthread_mutex_lock(&r->lock);
        if (st && r->write_st == RB_OK) {
            r->write_st = st;
            r->write_err = err;
            r->write_frame = e->f.frame;
        }
        e->is_full = false;
        r->head = (r->head + 1) % QUEUE_DEPTH;
        r->count--;
        pthread_cond_broadcast(&r->changed);
    }
    pthread_mutex_unlock(&r->lock);
    return NULL;
}

/* The writer's failure, as the caller's: "frame N: <message>". Call with the lock held. */
static enum rb_status write_failure(struct rb_render *r, struct rb_err *err)
{
    return rb_errf(err, r->write_st, "frame %d: %s", r->write_frame, r->write_err.msg);
}

enum rb_status rb_render_flush(struct rb_render *r, struct rb_err *err)
{
    if (!r || !r->has_writer)
        return RB_OK;
    pthread_mutex_lock(&r->lock);
    while (r->count)
        pthread_cond_wait(&r->changed, &r->lock);
    enum rb_status st = r->write_st ? write_failure(r, err) : RB_OK;
    pthread_mutex_unlock(&r->lock);
    return st;
}

/* Copies the frame into a free entry (waiting for the writer when both are full). */
static enum rb_status hand_over(struct rb_render *r, const char *path,
                                const struct rb_frame_result *f, double wall_ms, struct rb_err *err)
{
    pthread_mutex_lock(&r->lock);
    while (r->count == QUEUE_DEPTH && !r->write_st)
        pthread_cond_wait(&r->changed, &r->lock);
    enum rb_status st = RB_OK;
    if (r->write_st) {
        st = write_failure(r, err);
        goto out;
    }
    struct pending *e = &r->queue[(r->head + r->count) % QUEUE_DEPTH];
    if (f->pass_count > e->pass_cap) {
        struct rb_pass_time *p = realloc(e->passes, f->pass_count * sizeof(*p));
        if (!p) {
            st = rb_errf(err, RB_E_NOMEM, "frame %d: out of memory for its pass timings", f->frame);
            goto out;
        }
        e->passes = p;
        e->pass_cap = f->pass_count;
    }
    size_t n = (size_t)f->width_px * f->height_px;
    if (f->hits && !e->hits && !(e->hits = malloc(n * sizeof(*e->hits)))) {
        st = rb_errf(err, RB_E_NOMEM, "frame %d: out of memory for its hit ratios", f->frame);
        goto out;
    }
    if (rb_strlcpy(e->path, path, sizeof(e->path)) >= sizeof(e->path)) {
        st = rb_errf(err, RB_E_INVALID, "frame %d: path too long: '%s'", f->frame, path);
        goto out;
    }
    /* Only the layers the job writes are in a GPU frame's readback (floats_per_pixel). */
    memcpy(e->pixels, f->pixels, n * f->floats_per_pixel * sizeof(float));
    if (f->hits) /* the integrator's buffer is reused by the next frame */
        memcpy(e->hits, f->hits, n * sizeof(*e->hits));
    if (f->pass_count)
        memcpy(e->passes, f->passes, f->pass_count * sizeof(*e->passes));
    e->f = *f;
    e->f.pixels = e->pixels;
    e->f.hits = f->hits ? e->hits : NULL;
    e->f.passes = e->passes;
    if (f->ray_counts) {
        e->ray_counts = *f->ray_counts;
        e->f.ray_counts = &e->ray_counts;
    }
    e->wall_ms = wall_ms;
    e->is_full = true;
    r->count++;
    pthread_cond_broadcast(&r->changed);
out:
    pthread_mutex_unlock(&r->lock);
    return st;
}

enum rb_status rb_render_frame(struct rb_render *r, int frame, const char *path,
                               struct rb_render_frame_info *info, struct rb_err *err)
{
    double t0 = rb_monotonic_s();
    struct rb_frame_result f;
    r->was_stopped = false;
    enum rb_status st = r->ref ? rb_reference_render(r->ref, frame, &f, err)
                               : rb_integrator_render(r->it, frame, &f, err);
    if (st) {
        rb_err_prefix(err, "frame %d", frame);
        return st;
    }
    *info = (struct rb_render_frame_info){.is_partial = r->was_stopped &&
                                                        f.spp < r->job->integrator.reference.spp,
                                          .spp = f.spp,
                                          .nonfinite_count = f.nonfinite_count};
    if (info->is_partial)
        return RB_OK; /* never under the frame's name: --resume renders it again */
    if (r->strict && f.nonfinite_count)
        return rb_errf(err, RB_E_INVALID,
                       "frame %d: %u non-finite values (NaN or Inf) in the output, and --strict "
                       "makes that an error",
                       frame, f.nonfinite_count);
    if (r->strict && f.bundle_nodes_dropped)
        return rb_errf(err, RB_E_NOMEM,
                       "frame %d: the ray-bundle node buffer overflowed (%u fragments dropped; a "
                       "bundle needed %u nodes, the buffer holds %u), and --strict makes that "
                       "an error: raise integrator.bdpt.node_buffer_kib",
                       frame, f.bundle_nodes_dropped, f.bundle_nodes_max, f.bundle_nodes_capacity);
    info->wall_ms = (rb_monotonic_s() - t0) * 1e3;
    return hand_over(r, path, &f, info->wall_ms, err);
}

enum rb_status rb_render_write(struct rb_render *r, const char *path,
                               const struct rb_frame_result *f, double wall_ms, struct rb_err *err)
{
    const struct rb_job *job = r->job;
    if (!f->pixels || f->width_px != job->width_px || f->height_px != job->height_px ||
        f->floats_per_pixel > frame_stride(job))
        return rb_errf(err, RB_E_INVALID,
                       "frame %d: a %ux%u frame of %u floats a pixel does not fit the job's %ux%u "
                       "of at most %u",
                       f->frame, f->width_px, f->height_px, f->floats_per_pixel, job->width_px,
                       job->height_px, frame_stride(job));
    return hand_over(r, path, f, wall_ms, err);
}

/* ---- space, environment -----------------------------------------------------------------------
 */

static uint64_t file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (uint64_t)sb.st_size : 0;
}

/* bytes in the unit that gives it one to three digits before the point: 512 bytes, 48 KB,
 * 3.2 MB, 1.5 GB, 2.1 TB (powers of 1000, as file systems report free space). */
static const char *human_bytes(uint64_t bytes, char *buf, size_t size)
{
    static const char *const units[] = {"KB", "MB", "GB", "TB", "PB"};
    if (bytes < 1000) {
        snprintf(buf, size, "%llu bytes", (unsigned long long)bytes);
        return buf;
    }
    double v = (double)bytes / 1e3;
    size_t u = 0;
    for (; v >= 1000.0 && u + 1 < sizeof(units) / sizeof(units[0]); u++)
        v /= 1000.0;
    snprintf(buf, size, u == 0 ? "%.0f %s" : "%.1f %s", v, units[u]);
    return buf;
}

enum rb_status rb_render_check_space(const char *path, bool has_preview, int frames_left,
                                     struct rb_err *err)
{
    char side[4096];
    uint64_t frame = file_size(path);
    if (rb_io_sidecar_path(path, ".timing.json", side, sizeof(side), NULL) == RB_OK)
        frame += file_size(side);
    if (has_preview && rb_io_sidecar_path(path, ".png", side, sizeof(side), NULL) == RB_OK)
        frame += file_size(side);
    if (rb_io_sidecar_path(path, ".hits.exr", side, sizeof(side), NULL) == RB_OK)
        frame += file_size(side); /* 0 when the integrator writes none */
    uint64_t need = frame * (uint64_t)frames_left, have = rb_io_free_bytes(path);
    if (have == UINT64_MAX || need + need / 20 <= have)
        return RB_OK;
    char a[32], b[32], c[32];
    return rb_errf(err, RB_E_IO,
                   "the %d frames left need about %s at %s a frame, and the output's file system "
                   "has %s free",
                   frames_left, human_bytes(need, a, sizeof(a)), human_bytes(frame, b, sizeof(b)),
                   human_bytes(have, c, sizeof(c)));
}

enum rb_status rb_render_load_env(const char *path, double intensity, float **out,
                                  uint32_t *width_px, uint32_t *height_px, struct rb_err *err)
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
            px[i * 4 + c] =
                c == 3 ? (img.channel_count >= 4 ? s[3] : 1.0f) : s[c < img.channel_count ? c : 0];
        }
    /* Radiance, the colours times environment.intensity: finite, >= 0 and within the bound. */
    for (size_t i = 0; i < n * 4; i++) {
        double v = px[i] * intensity;
        if (i % 4 == 3 || (v >= 0 && v <= RB_MAX_RADIANCE))
            continue;
        size_t x = i / 4 % img.width_px, y = i / 4 / img.width_px;
        if (!(px[i] >= 0) || !isfinite(px[i]))
            st = rb_errf(err, RB_E_INVALID,
                         "environment map '%s': pixel (%zu, %zu) channel %zu is %g, not a finite "
                         "number >= 0",
                         path, x, y, i % 4, px[i]);
        else
            st = rb_errf(err, RB_E_INVALID,
                         "environment map '%s': pixel (%zu, %zu) channel %zu is %g, which times "
                         "'environment.intensity' (%g) is more than %g",
                         path, x, y, i % 4, px[i], intensity, RB_MAX_RADIANCE);
        free(px);
        rb_io_image_release(&img);
        return st;
    }
    *out = px;
    *width_px = img.width_px;
    *height_px = img.height_px;
    rb_io_image_release(&img);
    return RB_OK;
}
