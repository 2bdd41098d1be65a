/* rb_err: one message per failure, with context prepended on the way out; RB_BUG. */
#include "core/core.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum rb_status rb_errf(struct rb_err *err, enum rb_status code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof(err->msg), fmt, ap);
        va_end(ap);
        err->status = code;
    }
    return code;
}

void rb_err_prefix(struct rb_err *err, const char *fmt, ...)
{
    if (!err)
        return;
    char head[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(head, sizeof(head), fmt, ap);
    va_end(ap);
    char tmp[sizeof(head) + sizeof(err->msg) + 2];
    snprintf(tmp, sizeof(tmp), "%s: %s", head, err->msg);
    rb_strlcpy(err->msg, tmp, sizeof(err->msg));
}

const char *rb_status_name(enum rb_status st)
{
    switch (st) {
    case RB_OK: return "ok";
    case RB_E_INVALID: return "invalid input";
    case RB_E_NOMEM: return "out of memory";
    case RB_E_IO: return "i/o error";
    case RB_E_PARSE: return "parse error";
    case RB_E_VULKAN: return "vulkan error";
    case RB_E_NODEVICE: return "no usable device";
    case RB_E_UNSUPPORTED: return "unsupported";
    case RB_E_EXTERNAL: return "library error";
    case RB_E_INTERRUPTED: return "interrupted";
    case RB_E_OVERFLOW: return "buffer overflow";
    }
    return "unknown status";
}

RB_NORETURN void rb_bug(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "raybundle: BUG: %s:%d: ", file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    abort();
}

char *rb_strdup(const char *s)
{
    if (!s)
        return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

size_t rb_strlcpy(char *dst, const char *src, size_t size)
{
    size_t n = strlen(src);
    if (size) {
        size_t c = n < size - 1 ? n : size - 1;
        memcpy(dst, src, c);
        dst[c] = '\0';
    }
    return n;
}

enum rb_status rb_read_file(const char *path, char **out, size_t *out_size, struct rb_err *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
    char *buf = NULL;
    size_t size = 0, cap = 0;
    for (;;) {
        if (size + 4096 + 1 > cap) {
            size_t ncap = cap ? cap * 2 : 65536;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                fclose(f);
                return rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + size, 1, cap - size - 1, f);
        size += got;
        if (got == 0)
            break;
    }
    bool bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return rb_errf(err, RB_E_IO, "cannot read '%s': %s", path, strerror(errno));
    }
    buf[size] = '\0';
    *out = buf;
    if (out_size)
        *out_size = size;
    return RB_OK;
}

uint64_t rb_hash64(const void *data, size_t size, uint64_t seed)
{
    const unsigned char *p = data;
    uint64_t h = seed;
    for (size_t i = 0; i < size; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

double rb_monotonic_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}
