/* Timing files read back, and bench.json: the sidecars rb_io_timing_write writes and the record
 * raybundle bench leaves beside its runs (written by io.c and bench.c), parsed with Jansson.
 * Only the fields raybundle timing compare and report need are read, and the hit-ratio summary
 * where there is one; a missing or mistyped one is an error that names its JSON path, a file that
 * does not parse one that names its line and column. Needs only core and Jansson, so the fuzz
 * replays link it alone. */
#include "io/io.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- reading ------------------------------------------------------------------------------ */

/* The object in path's file, or in text (size bytes) when text is given (path then names it). */
static enum rb_status load(const char *path, const char *text, size_t size, json_t **out,
                           struct rb_err *err)
{
    json_error_t je;
    json_t *root;
    if (text) {
        root = json_loadb(text, size, JSON_REJECT_DUPLICATES, &je);
    } else {
        FILE *f = fopen(path, "rb");
        if (!f)
            return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
        root = json_loadf(f, JSON_REJECT_DUPLICATES, &je);
        fclose(f);
    }
    if (!root)
        return rb_errf(err, RB_E_PARSE, "%s:%d:%d: %s", path, je.line, je.column, je.text);
    if (!json_is_object(root)) {
        json_decref(root);
        return rb_errf(err, RB_E_PARSE, "%s: expected a JSON object", path);
    }
    *out = root;
    return RB_OK;
}

/* A field of obj; what names obj's place in the file ("" at the top, "passes[2]"). */
static json_t *field(json_t *obj, const char *what, const char *key, const char *path,
                     struct rb_err *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        rb_errf(err, RB_E_PARSE, "%s: no '%s%s%s'", path, what, *what ? "." : "", key);
    return v;
}

static enum rb_status get_string(json_t *obj, const char *what, const char *key, char *out,
                                 size_t size, const char *path, struct rb_err *err)
{
    json_t *v = field(obj, what, key, path, err);
    if (!v)
        return RB_E_PARSE;
    if (!json_is_string(v))
        return rb_errf(err, RB_E_PARSE, "%s: '%s%s%s' is not a string", path, what,
                       *what ? "." : "", key);
    if (rb_strlcpy(out, json_string_value(v), size) >= size)
        return rb_errf(err, RB_E_PARSE, "%s: '%s%s%s' is longer than %zu bytes", path, what,
                       *what ? "." : "", key, size - 1);
    return RB_OK;
}

/* A finite number (JSON's null, which the writer gives NaN, is refused). */
static enum rb_status get_number(json_t *obj, const char *what, const char *key, double *out,
                                 const char *path, struct rb_err *err)
{
    json_t *v = field(obj, what, key, path, err);
    if (!v)
        return RB_E_PARSE;
    if (!json_is_number(v) || !isfinite(json_number_value(v)))
        return rb_errf(err, RB_E_PARSE, "%s: '%s%s%s' is not a finite number", path, what,
                       *what ? "." : "", key);
    *out = json_number_value(v);
    return RB_OK;
}

/* An integer in [min, max]. */
static enum rb_status get_int(json_t *obj, const char *what, const char *key, long long min,
                              long long max, long long *out, const char *path, struct rb_err *err)
{
    json_t *v = field(obj, what, key, path, err);
    if (!v)
        return RB_E_PARSE;
    if (!json_is_integer(v) || json_integer_value(v) < min || json_integer_value(v) > max)
        return rb_errf(err, RB_E_PARSE, "%s: '%s%s%s' is not an integer in %lld..%lld", path, what,
                       *what ? "." : "", key, min, max);
    *out = json_integer_value(v);
    return RB_OK;
}

static json_t *get_array(json_t *obj, const char *key, const char *path, struct rb_err *err)
{
    json_t *v = field(obj, "", key, path, err);
    if (v && !json_is_array(v)) {
        rb_errf(err, RB_E_PARSE, "%s: '%s' is not an array", path, key);
        return NULL;
    }
    return v;
}

/* ---- timing sidecar ----------------------------------------------------------------------- */

static enum rb_status read_pass(json_t *p, size_t i, struct rb_pass_time *out, const char *path,
                                struct rb_err *err)
{
    char what[32];
    snprintf(what, sizeof(what), "passes[%zu]", i);
    if (!json_is_object(p))
        return rb_errf(err, RB_E_PARSE, "%s: '%s' is not an object", path, what);
    long long count = 1;
    enum rb_status st;
    if ((st = get_string(p, what, "name", out->name, sizeof(out->name), path, err)) ||
        (st = get_number(p, what, "gpu_ms", &out->gpu_ms, path, err)) ||
        (json_object_get(p, "count") &&
         (st = get_int(p, what, "count", 1, UINT32_MAX, &count, path, err))) ||
        (json_object_get(p, "cpu_ms") &&
         (st = get_number(p, what, "cpu_ms", &out->cpu_ms, path, err))))
        return st;
    out->count = (uint32_t)count;
    return RB_OK;
}

/* The "hits" object, where there is one: four numbers, null (no finite hit ratio) read as NaN. */
static enum rb_status read_hits(json_t *root, struct rb_io_timing_file *out, const char *path,
                                struct rb_err *err)
{
    json_t *h = json_object_get(root, "hits");
    if (!h)
        return RB_OK;
    if (!json_is_object(h))
        return rb_errf(err, RB_E_PARSE, "%s: 'hits' is not an object", path);
    const char *const key[] = {"mean", "p5", "p50", "p95"};
    double *const v[] = {&out->hits.mean, &out->hits.p5, &out->hits.p50, &out->hits.p95};
    for (int i = 0; i < 4; i++) {
        enum rb_status st;
        if (json_is_null(json_object_get(h, key[i])))
            *v[i] = NAN;
        else if ((st = get_number(h, "hits", key[i], v[i], path, err)))
            return st;
    }
    out->has_hits = true;
    return RB_OK;
}

static enum rb_status timing_load(const char *path, const char *text, size_t size,
                                  struct rb_io_timing_file *out, struct rb_err *err)
{
    memset(out, 0, sizeof(*out));
    json_t *root = NULL;
    enum rb_status st = load(path, text, size, &root, err);
    if (st)
        return st;
    long long frame = 0;
    json_t *passes = NULL;
    if ((st = get_int(root, "", "frame", INT32_MIN, INT32_MAX, &frame, path, err)) ||
        (st = get_number(root, "", "wall_ms", &out->wall_ms, path, err)) ||
        (st = get_string(root, "", "device", out->device, sizeof(out->device), path, err)) ||
        (st = get_string(root, "", "driver", out->driver, sizeof(out->driver), path, err)) ||
        (json_object_get(root, "job_hash") &&
         (st =
              get_string(root, "", "job_hash", out->job_hash, sizeof(out->job_hash), path, err))) ||
        (st = read_hits(root, out, path, err)))
        goto out;
    out->frame = (int)frame;
    if (!(passes = get_array(root, "passes", path, err))) {
        st = RB_E_PARSE;
        goto out;
    }
    size_t n = json_array_size(passes);
    if (n && !(out->passes = calloc(n, sizeof(*out->passes)))) {
        st = rb_errf(err, RB_E_NOMEM, "%s: out of memory for %zu passes", path, n);
        goto out;
    }
    for (size_t i = 0; i < n; i++, out->pass_count++)
        if ((st = read_pass(json_array_get(passes, i), i, &out->passes[i], path, err)))
            goto out;
out:
    json_decref(root);
    return st;
}

enum rb_status rb_io_timing_read(const char *path, struct rb_io_timing_file *out,
                                 struct rb_err *err)
{
    return timing_load(path, NULL, 0, out, err);
}

enum rb_status rb_io_timing_parse(const char *name, const char *text, size_t size,
                                  struct rb_io_timing_file *out, struct rb_err *err)
{
    return timing_load(name, text ? text : "", size, out, err);
}

void rb_io_timing_file_release(struct rb_io_timing_file *t)
{
    if (!t)
        return;
    free(t->passes);
    memset(t, 0, sizeof(*t));
}

/* ---- bench.json --------------------------------------------------------------------------- */

static enum rb_status bench_load(const char *path, const char *text, size_t size,
                                 struct rb_io_bench *out, struct rb_err *err)
{
    memset(out, 0, sizeof(*out));
    json_t *root = NULL, *frames = NULL, *options = NULL;
    enum rb_status st = load(path, text, size, &root, err);
    if (st)
        return st;
    long long w = 0, h = 0, runs = 0;
    if ((st = get_string(root, "", "device", out->device, sizeof(out->device), path, err)) ||
        (st = get_string(root, "", "driver", out->driver, sizeof(out->driver), path, err)) ||
        (st = get_string(root, "", "build", out->build, sizeof(out->build), path, err)) ||
        (st = get_string(root, "", "job", out->job, sizeof(out->job), path, err)) ||
        (st = get_string(root, "", "job_hash", out->job_hash, sizeof(out->job_hash), path, err)) ||
        (st = get_string(root, "", "integrator", out->integrator, sizeof(out->integrator), path,
                         err)) ||
        (st = get_string(root, "", "order", out->order, sizeof(out->order), path, err)) ||
        (st = get_int(root, "", "width", 0, UINT32_MAX, &w, path, err)) ||
        (st = get_int(root, "", "height", 0, UINT32_MAX, &h, path, err)) ||
        (st = get_int(root, "", "runs", 1, UINT32_MAX, &runs, path, err)))
        goto out;
    out->width_px = (uint32_t)w;
    out->height_px = (uint32_t)h;
    out->run_count = (uint32_t)runs;
    if (!(frames = get_array(root, "frames", path, err)) ||
        !(options = get_array(root, "options", path, err))) {
        st = RB_E_PARSE;
        goto out;
    }
    size_t nf = json_array_size(frames), no = json_array_size(options);
    if ((nf && !(out->frames = calloc(nf, sizeof(*out->frames)))) ||
        (no && !(out->options = calloc(no, sizeof(*out->options))))) {
        st = rb_errf(err, RB_E_NOMEM, "%s: out of memory", path);
        goto out;
    }
    for (size_t i = 0; i < nf; i++, out->frame_count++) {
        json_t *v = json_array_get(frames, i);
        if (!json_is_integer(v) || json_integer_value(v) < INT32_MIN ||
            json_integer_value(v) > INT32_MAX) {
            st = rb_errf(err, RB_E_PARSE, "%s: 'frames[%zu]' is not a frame number", path, i);
            goto out;
        }
        out->frames[i] = (int)json_integer_value(v);
    }
    for (size_t i = 0; i < no; i++, out->option_count++) {
        json_t *v = json_array_get(options, i);
        if (!json_is_string(v)) {
            st = rb_errf(err, RB_E_PARSE, "%s: 'options[%zu]' is not a string", path, i);
            goto out;
        }
        if (!(out->options[i] = rb_strdup(json_string_value(v)))) {
            st = rb_errf(err, RB_E_NOMEM, "%s: out of memory", path);
            goto out;
        }
    }
out:
    json_decref(root);
    return st;
}

enum rb_status rb_io_bench_read(const char *path, struct rb_io_bench *out, struct rb_err *err)
{
    return bench_load(path, NULL, 0, out, err);
}

enum rb_status rb_io_bench_parse(const char *name, const char *text, size_t size,
                                 struct rb_io_bench *out, struct rb_err *err)
{
    return bench_load(name, text ? text : "", size, out, err);
}

void rb_io_bench_release(struct rb_io_bench *b)
{
    if (!b)
        return;
    for (size_t i = 0; i < b->option_count; i++)
        free(b->options[i]);
    free(b->options);
    free(b->frames);
    memset(b, 0, sizeof(*b));
}
