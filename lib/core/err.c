/* rb_err: one message per failure, with context prepended on the way out; RB_BUG. */
#include "core/core.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

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

/* For messages: what a file that is not a regular file is instead. */
static const char *file_kind(mode_t mode)
{
    if (S_ISDIR(mode))
        return "a directory";
    if (S_ISFIFO(mode))
        return "a FIFO";
    if (S_ISCHR(mode))
        return "a character device";
    if (S_ISBLK(mode))
        return "a block device";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a regular file";
}

enum rb_status rb_file_check_regular(const char *path, struct rb_err *err)
{
    struct stat sb;
    if (stat(path, &sb) != 0)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
    if (!S_ISREG(sb.st_mode))
        return rb_errf(err, RB_E_IO, "cannot read '%s': it is %s, not a regular file", path,
                       file_kind(sb.st_mode));
    return RB_OK;
}

enum rb_status rb_file_open_regular(const char *path, uint64_t max_bytes, int *fd,
                                    uint64_t *size_bytes, struct rb_err *err)
{
    /* stat first: opening some devices has effects of its own. */
    enum rb_status st = rb_file_check_regular(path, err);
    if (st)
        return st;
    int f = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (f < 0)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
    struct stat sb;
    if (fstat(f, &sb) != 0) {
        st = rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
    } else if (!S_ISREG(sb.st_mode)) {
        st = rb_errf(err, RB_E_IO, "cannot read '%s': it is %s, not a regular file", path,
                     file_kind(sb.st_mode));
    } else if ((uint64_t)sb.st_size > max_bytes) {
        st = rb_errf(err, RB_E_IO,
                     "cannot read '%s': %llu bytes, more than the %llu a file may have", path,
                     (unsigned long long)sb.st_size, (unsigned long long)max_bytes);
    }
    if (st) {
        close(f);
        return st;
    }
    *fd = f;
    *size_bytes = (uint64_t)sb.st_size;
    return RB_OK;
}

enum rb_status rb_read_file(const char *path, char **out, size_t *out_size, struct rb_err *err)
{
    int fd = -1;
    uint64_t size = 0;
    enum rb_status st = rb_file_open_regular(path, RB_FILE_MAX_BYTES, &fd, &size, err);
    if (st)
        return st;
    char *buf = malloc((size_t)size + 1);
    if (!buf) {
        close(fd);
        return rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
    }
    /* Up to the size fstat gave: a file that grows meanwhile is read as it was. */
    size_t got = 0;
    while (got < size) {
        ssize_t n = read(fd, buf + got, (size_t)size - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int saved = errno;
            free(buf);
            close(fd);
            return rb_errf(err, RB_E_IO, "cannot read '%s': %s", path, strerror(saved));
        }
        if (n == 0)
            break; /* shrank meanwhile */
        got += (size_t)n;
    }
    close(fd);
    buf[got] = '\0';
    *out = buf;
    if (out_size)
        *out_size = got;
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
