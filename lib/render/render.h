/* A run of a job, as `raybundle render` and `raybundle reference` make it: the renderer behind it
 * (the GPU frame driver or the CPU reference, one result type for both), the decision --resume
 * makes for a frame, and the writing of a frame's files (the EXR with its layers and metadata,
 * the hit ratios, the timing sidecar, the preview), each to a temporary name and renamed. The
 * command parses options, reports progress and chooses exit codes; this module does the work. */
#ifndef RB_RENDER_RENDER_H
#define RB_RENDER_RENDER_H

#include <limits.h>

#include "core/core.h"
#include "job/job.h"
#include "scene/scene.h"

struct rb_render;

struct rb_render_desc {
    const struct rb_job *job;           /* borrowed; must outlive the run */
    const struct rb_scene *scene;       /* borrowed */
    const struct rb_scene_setup *setup; /* borrowed */
    const float *env_rgba;              /* borrowed; rb_render_load_env's, or NULL */
    uint32_t env_width_px, env_height_px;
    const char *device;    /* GPU: a device name substring or index; NULL: lavapipe */
    bool validate;         /* GPU: the Khronos validation layer; any message fails */
    bool strict;           /* a frame with non-finite output values, or (bdpt) a full
                            * ray-bundle node buffer, fails (nothing of it is written) instead
                            * of a warning and a count or flag in the sidecar */
    uint32_t thread_count; /* reference: worker threads; 0: every core */
    bool is_timing_only;   /* write the timing sidecar alone (raybundle bench): no EXR, PNG */
    /* reference: called after each pass of samples; returning false stops the frame, which is
     * then partial and not written. May be NULL. */
    bool (*on_pass)(void *user, uint32_t spp_done, uint32_t spp_total);
    /* Called on the writer thread once every file of a frame is written and renamed into place
     * (path: its EXR; wall_ms: its sidecar's), in frame order. May be NULL. */
    void (*on_written)(void *user, int frame, const char *path, double wall_ms);
    void *user;
};

/* Creates the renderer the job's integrator names. RB_E_NODEVICE without a usable device,
 * RB_E_UNSUPPORTED for an integrator that does not exist yet, RB_E_INVALID for a job the
 * renderer cannot take; *out only on success. */
enum rb_status rb_render_create(const struct rb_render_desc *desc, struct rb_render **out,
                                struct rb_err *err);
/* Writes what is still queued (failures are lost: flush first to see them), then frees. */
void rb_render_destroy(struct rb_render *r);

/* The device and driver the frames are rendered with, for the sidecar and messages. */
const char *rb_render_device(const struct rb_render *r);
const char *rb_render_driver(const struct rb_render *r);

/* The last frame of the job's range: frames.end, or the end of the selected animation. */
int rb_render_last_frame(const struct rb_job *job, const struct rb_scene *scene);

/* How many warm-up frames rendering frame f renders first (frames f - n to f - 1: they fill
 * what the frames after them read, and are not written); 0 when f follows the last frame
 * rendered, and always for the reference. */
uint32_t rb_render_warmup_frames(const struct rb_render *r, int f);

/* What --resume does with frame f. */
enum rb_render_verdict {
    RB_RENDER_NEW = 0, /* no complete frame there: render it */
    RB_RENDER_KEEP,    /* complete, with its sidecar, rendered by this very job: keep it */
    RB_RENDER_STALE,   /* complete, but another job's (setting, scene contents, environment) */
};
/* Decides for the frame at path (the EXR; its timing sidecar beside it, and for bdpt its hit
 * ratios: a frame without a complete NAME.####.hits.exr is rendered again). */
enum rb_render_verdict rb_render_resume_verdict(const struct rb_render *r, const char *path);

/* --resume --preview for a kept frame (RB_RENDER_KEEP): when the preview beside the EXR at path
 * is missing, writes it from the EXR's beauty, the same bits a render writes (the beauty is
 * stored as float), and sets *wrote. Fails naming the file. */
enum rb_status rb_render_preview_from_exr(const struct rb_render *r, const char *path, bool *wrote,
                                          struct rb_err *err);

/* What rendering a frame did. */
struct rb_render_frame_info {
    bool is_partial; /* the reference was stopped (on_pass returned false): nothing written */
    uint32_t spp;    /* the reference's samples reached; 0 for the GPU */
    uint32_t nonfinite_count;
    double wall_ms; /* rendering it and handing it to the writer (the sidecar's wall_ms) */
};

/* Renders frame f and hands it to the writer thread, which writes path (EXR), its hit ratios
 * (NAME.####.hits.exr) when the renderer made them, its timing sidecar and, when the job asks
 * for previews, its PNG, in frame order, while the caller renders
 * the next frame (at most two frames wait). A partial frame is not written. Fails with the
 * renderer's status, or with an earlier frame's write failure ("frame N: ..."); a file is
 * either complete or absent. */
enum rb_status rb_render_frame(struct rb_render *r, int frame, const char *path,
                               struct rb_render_frame_info *info, struct rb_err *err);

/* Hands a frame result made elsewhere to the writer thread, as rb_render_frame hands over the
 * frames it renders: its files at path (the EXR, the hit ratios when f->hits is set, the preview
 * and the timing sidecar), f and what it points at copied. f must be the job's size, with at
 * most the floats a pixel of the renderer's frames (RB_E_INVALID otherwise); fails as
 * rb_render_frame does on an earlier write failure. */
enum rb_status rb_render_write(struct rb_render *r, const char *path,
                               const struct rb_frame_result *f, double wall_ms, struct rb_err *err);

/* Waits until every frame handed over is written; the first write failure, if any. Callers
 * flush before they rely on the files (a space check, the closing line); destroy flushes too. */
enum rb_status rb_render_flush(struct rb_render *r, struct rb_err *err);

/* After the first frame written at path: RB_E_IO when frames_left more frames of that size
 * (EXR, sidecar, preview, hit ratios) would not fit on the output's file system, with 5% to
 * spare. */
enum rb_status rb_render_check_space(const char *path, bool has_preview, int frames_left,
                                     struct rb_err *err);

/* ---- which frames: lists and chunks (frames.c) ------------------------------------------- */

/* Frames start, start + step, ... up to end (inclusive). */
struct rb_render_frame_range {
    int start, end, step; /* end >= start, step >= 1 */
};

/* A set of frames: the union of ranges, seen through the window lo..hi. Iterated in ascending
 * order, each frame once, whatever the ranges' order and overlaps. Caller storage:
 * RB_RENDER_FRAMES_INIT (empty, no window), rb_render_frames_release. */
struct rb_render_frames {
    struct rb_render_frame_range *ranges;
    size_t range_count, range_cap;
    int lo, hi; /* only frames in lo..hi belong to the set */
};
#define RB_RENDER_FRAMES_INIT                                                                      \
    {                                                                                              \
        .lo = INT_MIN, .hi = INT_MAX                                                               \
    }

/* Adds a range; RB_E_INVALID when end < start or step < 1. */
enum rb_status rb_render_frames_add(struct rb_render_frames *f, int start, int end, int step,
                                    struct rb_err *err);
/* Adds the ranges of a frame list as render farms write one (OpenJD, Deadline): entries
 * separated by commas, each a frame "A", a range "A-B" (inclusive) or a stepped range "A-B:S"
 * ("A-BxS" as Deadline writes it); whole numbers >= 0, spaces around them allowed. RB_E_INVALID
 * naming the bad entry; on failure f is released (empty). */
enum rb_status rb_render_frames_parse(struct rb_render_frames *f, const char *text,
                                      struct rb_err *err);
void rb_render_frames_release(struct rb_render_frames *f);

/* The smallest frame of the set greater than after (INT64_MIN: the first); false when none. */
bool rb_render_frames_next(const struct rb_render_frames *f, int64_t after, int *frame);
/* The first and last frame of the set; false when it is empty. */
bool rb_render_frames_bounds(const struct rb_render_frames *f, int *first, int *last);
/* How many frames the set holds (it counts them one by one). */
uint64_t rb_render_frames_count(const struct rb_render_frames *f);
/* Narrows the window to lo..hi (within the current one). */
void rb_render_frames_limit(struct rb_render_frames *f, int lo, int hi);

/* One of count contiguous chunks of a run's frames, numbered from 0. */
struct rb_render_chunk {
    uint32_t index, count; /* index < count */
};
/* Narrows f to the chunk: its n frames in ascending order are cut into count contiguous runs,
 * the first n % count of n / count + 1 frames, the others of n / count, so the union of the
 * chunks is f. Returns the chunk's frame count (0 for the last chunks when there are more
 * chunks than frames). */
uint64_t rb_render_frames_chunk(struct rb_render_frames *f, struct rb_render_chunk chunk);
/* Parses "I/N" (0 <= I < N); RB_E_INVALID naming the text. */
enum rb_status rb_render_chunk_parse(const char *text, struct rb_render_chunk *out,
                                     struct rb_err *err);
/* The chunk of a Slurm array task, from the values of SLURM_ARRAY_TASK_ID and
 * SLURM_ARRAY_TASK_COUNT (required) and SLURM_ARRAY_TASK_MIN and SLURM_ARRAY_TASK_STEP (NULL:
 * 0 and 1): index (ID - MIN) / STEP of COUNT. RB_E_INVALID naming the variable when one is unset,
 * malformed, or the task is not on that grid. */
enum rb_status rb_render_chunk_slurm(const char *task_id, const char *task_count,
                                     const char *task_min, const char *task_step,
                                     struct rb_render_chunk *out, struct rb_err *err);

/* Loads an environment map as RGBA floats (RGB gets A = 1; one channel is grey), freed with
 * free(). Fails with the image reader's status, the path named, or with RB_E_INVALID naming the
 * first pixel whose colour is not finite, is negative, or times intensity (the job's
 * environment.intensity) is more than RB_MAX_RADIANCE. */
enum rb_status rb_render_load_env(const char *path, double intensity, float **out,
                                  uint32_t *width_px, uint32_t *height_px, struct rb_err *err);

#endif
