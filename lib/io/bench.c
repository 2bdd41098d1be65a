/* bench.json written: the record raybundle bench leaves beside its runs' sidecars, dumped by
 * Jansson. It lives apart from its reader (timing.c) because it writes through io.c's atomic
 * rename, and timing.c must need nothing but core and Jansson: the fuzz replays link it alone. */
#include "io/io.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>

/* Sets key to v in obj, taking v; false when either allocation failed. */
static bool set(json_t *obj, const char *key, json_t *v)
{
    return v && json_object_set_new(obj, key, v) == 0;
}

enum rb_status rb_io_bench_write(const char *path, const struct rb_io_bench *b, struct rb_err *err)
{
    json_t *root = json_object(), *frames = json_array(), *options = json_array();
    bool ok = root && frames && options;
    for (size_t i = 0; ok && i < b->frame_count; i++)
        ok = json_array_append_new(frames, json_integer(b->frames[i])) == 0;
    for (size_t i = 0; ok && i < b->option_count; i++)
        ok = json_array_append_new(options, json_string(b->options[i])) == 0;
    ok = ok && set(root, "device", json_string(b->device)) &&
         set(root, "driver", json_string(b->driver)) && set(root, "build", json_string(b->build)) &&
         set(root, "job", json_string(b->job)) && set(root, "job_hash", json_string(b->job_hash)) &&
         set(root, "integrator", json_string(b->integrator)) &&
         set(root, "width", json_integer(b->width_px)) &&
         set(root, "height", json_integer(b->height_px)) &&
         set(root, "runs", json_integer(b->run_count)) &&
         set(root, "order", json_string(b->order)) && set(root, "frames", json_incref(frames)) &&
         set(root, "options", json_incref(options));
    char *text = ok ? json_dumps(root, JSON_INDENT(2)) : NULL;
    json_decref(frames);
    json_decref(options);
    json_decref(root);
    if (!text)
        return rb_errf(err, RB_E_NOMEM, "'%s': out of memory (or a string that is not UTF-8)",
                       path);
    size_t len = strlen(text);
    char *data = realloc(text, len + 2);
    if (!data) {
        free(text);
        return rb_errf(err, RB_E_NOMEM, "'%s': out of memory", path);
    }
    data[len] = '\n';
    data[len + 1] = '\0';
    enum rb_status st = rb_io_write_atomic(path, data, len + 1, err);
    free(data);
    return st;
}
