/* rb_log: the library's only way to speak; a replaceable sink (stderr by default). */
#include "core/core.h"

#include <stdarg.h>
#include <stdio.h>

static rb_log_fn sink_fn;
static void *sink_user;
static enum rb_log_level max_level = RB_LOG_WARN;
static unsigned warnings;

void rb_log_set_sink(rb_log_fn fn, void *user)
{
    sink_fn = fn;
    sink_user = user;
}

void rb_log_set_level(enum rb_log_level level)
{
    max_level = level;
}

enum rb_log_level rb_log_get_level(void)
{
    return max_level;
}

unsigned rb_log_warning_count(void)
{
    return warnings;
}

void rb_log(enum rb_log_level level, const char *fmt, ...)
{
    if (level == RB_LOG_WARN)
        warnings++;
    if (level > max_level)
        return;
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    if (sink_fn) {
        sink_fn(level, msg, sink_user);
        return;
    }
    static const char *const names[] = {"error", "warning", "info", "debug"};
    fprintf(stderr, "raybundle: %s: %s\n", names[level], msg);
}
