/* Which frames a run renders: frame lists as render farms write them (OpenJD and Deadline style,
 * "1-3,5,7-20:2", or "7-20x2" as Deadline writes a step), and the contiguous chunks a farm cuts a
 * run into (--chunk I/N, or a Slurm array task's). A list is a union of stepped ranges, rendered in
 * ascending order with each frame once; nothing here renders or warms up (the frame driver does
 * that for any gap). */
#include "render/render.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum rb_status rb_render_frames_add(struct rb_render_frames *f, int start, int end, int step,
                                    struct rb_err *err)
{
    if (end < start || step < 1)
        return rb_errf(err, RB_E_INVALID, "frames %d to %d by %d: not a range", start, end, step);
    if (f->range_count == f->range_cap) {
        size_t cap = f->range_cap ? 2 * f->range_cap : 8;
        struct rb_render_frame_range *r = realloc(f->ranges, cap * sizeof(*r));
        if (!r)
            return rb_errf(err, RB_E_NOMEM, "out of memory for a frame list");
        f->ranges = r;
        f->range_cap = cap;
    }
    f->ranges[f->range_count++] = (struct rb_render_frame_range){start, end, step};
    return RB_OK;
}

void rb_render_frames_release(struct rb_render_frames *f)
{
    free(f->ranges);
    *f = (struct rb_render_frames)RB_RENDER_FRAMES_INIT;
}

static const char *skip_spaces(const char *p, const char *end)
{
    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    return p;
}

/* A whole number >= 0 that fits an int, at *p (before end); advances *p past it. */
static bool parse_number(const char **p, const char *end, int *out)
{
    const char *s = skip_spaces(*p, end);
    long long v = 0;
    const char *q = s;
    for (; q < end && *q >= '0' && *q <= '9'; q++)
        if ((v = v * 10 + (*q - '0')) > 2147483647LL)
            return false;
    if (q == s)
        return false;
    *out = (int)v;
    *p = skip_spaces(q, end);
    return true;
}

#define NOT_A_FRAME "'%.*s' is not a frame (a whole number, 0 or more), a range A-B, A-B:S or A-BxS"

/* One entry of a list, text[0..len): "A", "A-B", or "A-B:S" and "A-BxS" (Deadline's step). */
static enum rb_status parse_entry(struct rb_render_frames *f, const char *text, size_t len,
                                  struct rb_err *err)
{
    const char *end = text + len, *p = text;
    int a = 0, b = 0, step = 1;
    const char *first = skip_spaces(text, end);
    if (first == end)
        return rb_errf(err, RB_E_INVALID, "an empty entry (two commas, or one at an end)");
    int shown = (int)(end - first);
    while (shown > 0 && (first[shown - 1] == ' ' || first[shown - 1] == '\t'))
        shown--;
    if (!parse_number(&p, end, &a))
        return rb_errf(err, RB_E_INVALID, NOT_A_FRAME, shown, first);
    b = a;
    if (p < end && *p == '-') {
        p++;
        if (!parse_number(&p, end, &b))
            return rb_errf(err, RB_E_INVALID, "'%.*s': the range's end is not a whole number",
                           shown, first);
        if (p < end && (*p == ':' || *p == 'x')) { /* 'x': Deadline's spelling */
            p++;
            if (!parse_number(&p, end, &step))
                return rb_errf(err, RB_E_INVALID, "'%.*s': the step is not a whole number", shown,
                               first);
            if (step < 1)
                return rb_errf(err, RB_E_INVALID, "'%.*s': the step must be 1 or more", shown,
                               first);
        }
        if (b < a)
            return rb_errf(err, RB_E_INVALID, "'%.*s': the range ends before it starts", shown,
                           first);
    } else if (p < end && *p == ':') { /* "5:2"; "0x10" is no frame, not a step */
        return rb_errf(err, RB_E_INVALID, "'%.*s': a step needs a range (A-B:S or A-BxS)", shown,
                       first);
    }
    if (p != end)
        return rb_errf(err, RB_E_INVALID, NOT_A_FRAME, shown, first);
    return rb_render_frames_add(f, a, b, step, err);
}

enum rb_status rb_render_frames_parse(struct rb_render_frames *f, const char *text,
                                      struct rb_err *err)
{
    enum rb_status st = RB_OK;
    const char *p = text;
    for (;;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if ((st = parse_entry(f, p, len, err)))
            break;
        if (!comma)
            break;
        p = comma + 1;
    }
    if (st)
        rb_render_frames_release(f);
    return st;
}

/* The smallest frame of range r that is > after, or INT64_MAX. */
static int64_t range_next(const struct rb_render_frame_range *r, int64_t after)
{
    if (after < r->start)
        return r->start;
    int64_t k = (after - r->start) / r->step + 1, v = r->start + k * r->step;
    return v <= r->end ? v : INT64_MAX;
}

bool rb_render_frames_next(const struct rb_render_frames *f, int64_t after, int *frame)
{
    if (after < (int64_t)f->lo - 1)
        after = (int64_t)f->lo - 1;
    int64_t best = INT64_MAX;
    for (size_t i = 0; i < f->range_count; i++) {
        int64_t v = range_next(&f->ranges[i], after);
        if (v < best)
            best = v;
    }
    if (best > f->hi)
        return false;
    *frame = (int)best;
    return true;
}

bool rb_render_frames_bounds(const struct rb_render_frames *f, int *first, int *last)
{
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (size_t i = 0; i < f->range_count; i++) {
        const struct rb_render_frame_range *r = &f->ranges[i];
        int64_t a = range_next(r, (int64_t)f->lo - 1);
        int64_t top = r->end < f->hi ? r->end : f->hi;
        if (a == INT64_MAX || a > top)
            continue; /* nothing of r in the window */
        int64_t b = r->start + (top - r->start) / r->step * r->step;
        lo = a < lo ? a : lo;
        hi = b > hi ? b : hi;
    }
    if (lo > hi)
        return false;
    *first = (int)lo;
    *last = (int)hi;
    return true;
}

uint64_t rb_render_frames_count(const struct rb_render_frames *f)
{
    uint64_t n = 0;
    int frame;
    for (int64_t at = INT64_MIN; rb_render_frames_next(f, at, &frame); at = frame)
        n++;
    return n;
}

void rb_render_frames_limit(struct rb_render_frames *f, int lo, int hi)
{
    f->lo = lo > f->lo ? lo : f->lo;
    f->hi = hi < f->hi ? hi : f->hi;
}

uint64_t rb_render_frames_chunk(struct rb_render_frames *f, struct rb_render_chunk chunk)
{
    uint64_t n = rb_render_frames_count(f);
    /* n = q N + r: the first r chunks take q + 1 frames, the others q (as numpy's array_split
     * does), so sizes differ by one at most and only trailing chunks can be empty. */
    uint64_t q = n / chunk.count, r = n % chunk.count, i = chunk.index;
    uint64_t from = i * q + (i < r ? i : r), to = from + q + (i < r ? 1 : 0);
    if (from == to) { /* more chunks than frames: this one is empty */
        f->lo = INT_MAX;
        f->hi = INT_MIN;
        return 0;
    }
    int lo = 0, hi = 0, frame = 0;
    uint64_t rank = 0;
    for (int64_t at = INT64_MIN; rank < to && rb_render_frames_next(f, at, &frame); at = frame) {
        if (rank == from)
            lo = frame;
        hi = frame;
        rank++;
    }
    rb_render_frames_limit(f, lo, hi);
    return to - from;
}

/* A whole number >= 0 (below 2^31) in text; false for anything else. */
static bool parse_count(const char *text, uint32_t *out)
{
    const char *p = text;
    int v = 0;
    if (!parse_number(&p, text + strlen(text), &v) || *p)
        return false;
    *out = (uint32_t)v;
    return true;
}

static enum rb_status check_chunk(const struct rb_render_chunk *c, const char *what,
                                  struct rb_err *err)
{
    if (c->count < 1)
        return rb_errf(err, RB_E_INVALID, "%s: the number of chunks must be 1 or more", what);
    if (c->index >= c->count)
        return rb_errf(err, RB_E_INVALID,
                       "%s: there is no chunk %u of %u (chunks are numbered from 0 to %u)", what,
                       c->index, c->count, c->count - 1);
    return RB_OK;
}

enum rb_status rb_render_chunk_parse(const char *text, struct rb_render_chunk *out,
                                     struct rb_err *err)
{
    char what[64];
    snprintf(what, sizeof(what), "'%.40s'", text);
    const char *slash = strchr(text, '/');
    char index[16];
    struct rb_render_chunk c = {0};
    if (!slash || (size_t)(slash - text) >= sizeof(index))
        return rb_errf(err, RB_E_INVALID, "%s is not a chunk: expected I/N (I from 0 to N-1)",
                       what);
    memcpy(index, text, (size_t)(slash - text));
    index[slash - text] = '\0';
    if (!parse_count(index, &c.index) || !parse_count(slash + 1, &c.count))
        return rb_errf(err, RB_E_INVALID, "%s is not a chunk: expected I/N (I from 0 to N-1)",
                       what);
    enum rb_status st = check_chunk(&c, what, err);
    if (st == RB_OK)
        *out = c;
    return st;
}

/* A Slurm variable's value: a whole number, or (when has_default) absent. */
static enum rb_status slurm_value(const char *name, const char *value, bool has_default,
                                  uint32_t *out, struct rb_err *err)
{
    if (!value || !*value) {
        if (has_default)
            return RB_OK;
        return rb_errf(err, RB_E_INVALID,
                       "%s is not set: '--chunk slurm' runs as a task of a Slurm array job "
                       "(sbatch --array=0-N)",
                       name);
    }
    if (!parse_count(value, out))
        return rb_errf(err, RB_E_INVALID, "%s '%.40s' is not a whole number", name, value);
    return RB_OK;
}

enum rb_status rb_render_chunk_slurm(const char *task_id, const char *task_count,
                                     const char *task_min, const char *task_step,
                                     struct rb_render_chunk *out, struct rb_err *err)
{
    uint32_t id = 0, count = 0, min = 0, step = 1;
    enum rb_status st;
    if ((st = slurm_value("SLURM_ARRAY_TASK_ID", task_id, false, &id, err)) ||
        (st = slurm_value("SLURM_ARRAY_TASK_COUNT", task_count, false, &count, err)) ||
        (st = slurm_value("SLURM_ARRAY_TASK_MIN", task_min, true, &min, err)) ||
        (st = slurm_value("SLURM_ARRAY_TASK_STEP", task_step, true, &step, err)))
        return st;
    if (step < 1)
        return rb_errf(err, RB_E_INVALID, "SLURM_ARRAY_TASK_STEP '%s' must be 1 or more",
                       task_step);
    if (count < 1 || id < min || (id - min) % step || (id - min) / step >= count)
        return rb_errf(err, RB_E_INVALID,
                       "SLURM_ARRAY_TASK_ID %u is not one of the %u tasks from %u by %u "
                       "(SLURM_ARRAY_TASK_COUNT, _MIN, _STEP): submit a regular array, such as "
                       "--array=0-%u",
                       id, count, min, step, count ? count - 1 : 0);
    *out = (struct rb_render_chunk){.index = (id - min) / step, .count = count};
    return RB_OK;
}
