/* Files in and out, the C side: frame paths, sidecar names, atomic writes, the EXR channel and
 * metadata policy, the preview's quantization, and the timing sidecar's JSON. The libraries
 * themselves sit behind exr_shim.cpp (OpenEXR), png_codec.c (libpng), ocio_shim.cpp and
 * oiio_shim.cpp, which decide nothing.
 *
 * What raybundle writes, and the EXRs and PNGs it reads back, go through OpenEXR and libpng
 * alone, so every build writes the same bytes. OpenImageIO serves what only it does: reading
 * other formats (a reference image from elsewhere) and resizing report thumbnails. A build
 * without it (RB_WITH_OIIO=0, the portable one: Debian's OpenImageIO pulls in hundreds of
 * megabytes of plugins) says so when asked for those. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "io/io.h"

#include "io/exr_shim.h"
#include "io/ocio_shim.h"
#include "io/png_codec.h"

#ifndef RB_WITH_OIIO
#define RB_WITH_OIIO 1
#endif
#if RB_WITH_OIIO
#include "io/oiio_shim.h"
#endif

#include <errno.h>
#include <glob.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

/* The last place to look for data: the default prefix's. The binary looks beside itself first
 * (../share/raybundle), so an install under any prefix finds its own. */
#define RB_DATADIR "/usr/local/share/raybundle"

/* Rec.709 / sRGB primaries and D65 white, as OpenEXR's chromaticities: red, green, blue, white
 * (x, y). */
static const float rec709_chromaticities[8] = {0.64f, 0.33f, 0.30f,   0.60f,
                                               0.15f, 0.06f, 0.3127f, 0.3290f};

/* ---- paths ------------------------------------------------------------------------------ */

/* The start of the file name in path (after the last '/'). */
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* The final extension's dot in path's file name, or the terminating NUL when there is none.
 * A leading dot (".hidden") is part of the name, not an extension. */
static const char *extension(const char *path)
{
    const char *base = base_name(path);
    const char *dot = strrchr(base, '.');
    return dot && dot != base ? dot : path + strlen(path);
}

enum rb_status rb_io_frame_path(const char *pattern, int frame, char *out, size_t size,
                                struct rb_err *err)
{
    if (!pattern || !*pattern)
        return rb_errf(err, RB_E_INVALID, "frame path: empty pattern");
    if (!out || !size)
        return rb_errf(err, RB_E_INVALID, "frame path for '%s': no output buffer", pattern);

    int n;
    const char *last = strrchr(pattern, '#');
    if (last) {
        const char *first = last;
        while (first > pattern && first[-1] == '#')
            first--;
        int width = (int)(last - first + 1);
        /* %0*d pads after the sign: frame -12 in "####" gives "-012". */
        n = snprintf(out, size, "%.*s%0*d%s", (int)(first - pattern), pattern, width, frame,
                     last + 1);
    } else {
        const char *ext = extension(pattern);
        n = snprintf(out, size, "%.*s.%04d%s", (int)(ext - pattern), pattern, frame, ext);
    }
    if (n < 0 || (size_t)n >= size) {
        out[0] = '\0';
        return rb_errf(err, RB_E_OVERFLOW, "frame path for '%s' is longer than %zu bytes", pattern,
                       size - 1);
    }
    return RB_OK;
}

enum rb_status rb_io_sidecar_path(const char *exr_path, const char *suffix, char *out, size_t size,
                                  struct rb_err *err)
{
    if (!exr_path || !*exr_path)
        return rb_errf(err, RB_E_INVALID, "sidecar path: empty image path");
    if (!out || !size)
        return rb_errf(err, RB_E_INVALID, "sidecar path for '%s': no output buffer", exr_path);
    const char *ext = extension(exr_path);
    int n = snprintf(out, size, "%.*s%s", (int)(ext - exr_path), exr_path, suffix ? suffix : "");
    if (n < 0 || (size_t)n >= size) {
        out[0] = '\0';
        return rb_errf(err, RB_E_OVERFLOW, "sidecar path for '%s' is longer than %zu bytes",
                       exr_path, size - 1);
    }
    return RB_OK;
}

/* mkdir that accepts an existing directory (and only a directory). */
static enum rb_status make_dir(const char *dir, struct rb_err *err)
{
    if (mkdir(dir, 0777) == 0)
        return RB_OK;
    int e = errno;
    struct stat st;
    if (e == EEXIST && stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode))
            return RB_OK;
        return rb_errf(err, RB_E_IO, "cannot create directory '%s': %s", dir, strerror(ENOTDIR));
    }
    return rb_errf(err, RB_E_IO, "cannot create directory '%s': %s", dir, strerror(e));
}

enum rb_status rb_io_make_parent_dirs(const char *path, struct rb_err *err)
{
    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "make directories: empty path");
    const char *slash = strrchr(path, '/');
    if (!slash || slash == path)
        return RB_OK; /* "file" or "/file": the parent is "." or "/" */

    enum rb_status st = RB_OK;
    char *dir = rb_strdup(path);
    if (!dir)
        return rb_errf(err, RB_E_NOMEM, "make directories for '%s': out of memory", path);
    dir[slash - path] = '\0';
    /* Each prefix ending before a '/', then the whole directory. */
    for (char *p = dir + 1; *p; p++) {
        if (*p != '/' || p[-1] == '/')
            continue;
        *p = '\0';
        st = make_dir(dir, err);
        *p = '/';
        if (st)
            goto out;
    }
    st = make_dir(dir, err);
out:
    free(dir);
    return st;
}

/* The directory part of path into dir ("." when it has none). */
static void dirname_of(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        rb_strlcpy(dir, ".", size);
    else if (slash == path)
        rb_strlcpy(dir, "/", size);
    else
        snprintf(dir, size, "%.*s", (int)(slash - path), path);
}

enum rb_status rb_io_check_writable(const char *path, struct rb_err *err)
{
    enum rb_status st = rb_io_make_parent_dirs(path, err);
    if (st)
        return st;
    char dir[PATH_MAX], probe[PATH_MAX + 64];
    dirname_of(path, dir, sizeof(dir));
    snprintf(probe, sizeof(probe), "%s/.raybundle-probe.tmp.%ld", dir, (long)getpid());
    int fd = open(probe, O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd < 0)
        return rb_errf(err, RB_E_IO, "cannot write to directory '%s': %s", dir, strerror(errno));
    close(fd);
    unlink(probe);
    return RB_OK;
}

uint64_t rb_io_free_bytes(const char *path)
{
    char dir[PATH_MAX];
    dirname_of(path, dir, sizeof(dir));
    struct statvfs vfs;
    if (statvfs(dir, &vfs) != 0)
        return UINT64_MAX;
    return (uint64_t)vfs.f_bavail * vfs.f_frsize;
}

unsigned rb_io_remove_stale_temps(const char *path)
{
    /* "<stem>.*.tmp.*" covers the frame and its sidecars: a/f.0003.exr.tmp.N.exr,
     * a/f.0003.timing.json.tmp.N, a/f.0003.png.tmp.N.png. */
    size_t n = strlen(path);
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    int stem = (int)(dot && (!slash || dot > slash) ? (size_t)(dot - path) : n);
    char *pattern = malloc(n + 16);
    if (!pattern)
        return 0;
    snprintf(pattern, n + 16, "%.*s.*.tmp.*", stem, path);
    unsigned removed = 0;
    glob_t g;
    if (glob(pattern, GLOB_NOSORT, NULL, &g) == 0) {
        for (size_t i = 0; i < g.gl_pathc; i++)
            if (unlink(g.gl_pathv[i]) == 0)
                removed++;
        globfree(&g);
    }
    free(pattern);
    return removed;
}

struct rb_io_output_lock {
    char *pattern, *dir, *path;
    int fd;
    dev_t dir_dev;
    ino_t dir_ino;
};

enum rb_status rb_io_output_lock_create(const char *pattern, struct rb_io_output_lock **out,
                                        struct rb_err *err)
{
    enum rb_status st = RB_OK;
    struct rb_io_output_lock *lock = calloc(1, sizeof(*lock));
    size_t n = strlen(pattern);
    if (!lock || !(lock->pattern = rb_strdup(pattern)) || !(lock->dir = malloc(n + 2)) ||
        !(lock->path = malloc(n + 16))) {
        st = rb_errf(err, RB_E_NOMEM, "output lock for '%s': out of memory", pattern);
        goto fail;
    }
    lock->fd = -1;
    /* The directory: the pattern's, cut before a component that holds the frame number. */
    const char *hash = strchr(pattern, '#');
    const char *slash = strrchr(pattern, '/');
    const char *name = slash ? slash + 1 : pattern;
    if (hash && slash && hash < slash) {
        const char *s = pattern + (hash - pattern);
        while (s > pattern && *s != '/')
            s--;
        slash = *s == '/' ? s : NULL;
    }
    if (!slash)
        rb_strlcpy(lock->dir, ".", n + 2);
    else if (slash == pattern)
        rb_strlcpy(lock->dir, "/", n + 2);
    else
        snprintf(lock->dir, n + 2, "%.*s", (int)(slash - pattern), pattern);
    snprintf(lock->path, n + 16, "%s/.%s.lock", lock->dir, name);
    if ((st = rb_io_make_parent_dirs(lock->path, err)))
        goto fail;
    lock->fd = open(lock->path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    struct stat sb;
    if (lock->fd < 0 || stat(lock->dir, &sb) != 0) {
        st = rb_errf(err, RB_E_IO, "cannot open lock file '%s': %s", lock->path, strerror(errno));
        goto fail;
    }
    lock->dir_dev = sb.st_dev;
    lock->dir_ino = sb.st_ino;
    *out = lock;
    return RB_OK;
fail:
    rb_io_output_lock_destroy(lock);
    return st;
}

void rb_io_output_lock_destroy(struct rb_io_output_lock *lock)
{
    if (!lock)
        return;
    if (lock->fd >= 0)
        close(lock->fd); /* drops every claim */
    free(lock->pattern);
    free(lock->dir);
    free(lock->path);
    free(lock);
}

enum rb_status rb_io_output_lock_claim(struct rb_io_output_lock *lock, int frame,
                                       struct rb_err *err)
{
    /* Record locks (fcntl), not flock: a byte per frame lets chunks of one output share the
     * file. They belong to the process, which opens this file only here: closing another
     * descriptor of it would drop them. */
    struct flock fl = {.l_type = F_WRLCK,
                       .l_whence = SEEK_SET,
                       .l_start = (off_t)frame + ((off_t)1 << 31),
                       .l_len = 1};
    if (fcntl(lock->fd, F_SETLK, &fl) == 0)
        return RB_OK;
    int e = errno;
    if (e != EACCES && e != EAGAIN)
        return rb_errf(err, RB_E_IO, "cannot lock frame %d in '%s': %s", frame, lock->path,
                       strerror(e));
    struct flock who = fl;
    long pid = fcntl(lock->fd, F_GETLK, &who) == 0 && who.l_type != F_UNLCK ? (long)who.l_pid : 0;
    char by[48] = "";
    if (pid > 0)
        snprintf(by, sizeof(by), " (pid %ld)", pid);
    return rb_errf(err, RB_E_INVALID,
                   "frame %d of '%s' is being rendered by another raybundle%s; render other "
                   "frames (--frames, --chunk) or another output (--out)",
                   frame, lock->pattern, by);
}

enum rb_status rb_io_output_lock_check(const struct rb_io_output_lock *lock, struct rb_err *err)
{
    struct stat sb, fsb;
    if (stat(lock->dir, &sb) != 0 || sb.st_dev != lock->dir_dev || sb.st_ino != lock->dir_ino ||
        (fstat(lock->fd, &fsb) == 0 && fsb.st_nlink == 0))
        return rb_errf(err, RB_E_IO,
                       "output directory '%s' was removed during the run: the frames written to "
                       "it are lost",
                       lock->dir);
    return RB_OK;
}

/* "cannot write 'path': why" for the errno e; a full disk or quota said in words, with the
 * folder whose disk it is. */
static enum rb_status write_error(const char *path, int e, struct rb_err *err)
{
    char dir[PATH_MAX];
    dirname_of(path, dir, sizeof(dir));
    if (e == ENOSPC)
        return rb_errf(err, RB_E_IO,
                       "cannot write '%s': the disk is full (no space left on the device that "
                       "holds '%s')",
                       path, dir);
    if (e == EDQUOT)
        return rb_errf(err, RB_E_IO,
                       "cannot write '%s': the disk quota is used up (on the device that holds "
                       "'%s')",
                       path, dir);
    return rb_errf(err, RB_E_IO, "cannot write '%s': %s", path, strerror(e));
}

/* "<path>.tmp.<pid><ext>": beside path, so the final rename stays on one file system. */
static char *temp_path(const char *path, const char *ext)
{
    size_t n = strlen(path) + strlen(ext) + 32;
    char *tmp = malloc(n);
    if (tmp)
        snprintf(tmp, n, "%s.tmp.%ld%s", path, (long)getpid(), ext);
    return tmp;
}

/* fsync a file that someone else (OpenImageIO) wrote and closed. */
static int fsync_path(const char *path)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    int r = fsync(fd);
    int e = errno;
    close(fd);
    errno = e;
    return r;
}

enum rb_status rb_io_write_atomic(const char *path, const void *data, size_t size,
                                  struct rb_err *err)
{
    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "write: empty path");
    if (!data && size)
        return rb_errf(err, RB_E_INVALID, "cannot write '%s': no data", path);

    enum rb_status st = RB_OK;
    int fd = -1, e = 0;
    char *tmp = temp_path(path, "");
    if (!tmp)
        return rb_errf(err, RB_E_NOMEM, "cannot write '%s': out of memory", path);

    fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) {
        e = errno;
        goto fail;
    }
    const char *p = data;
    for (size_t left = size; left;) {
        ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0) {
            e = errno;
            goto fail;
        }
        p += w;
        left -= (size_t)w;
    }
    if (fsync(fd) != 0) {
        e = errno;
        goto fail;
    }
    int r = close(fd);
    fd = -1;
    if (r != 0 || rename(tmp, path) != 0) {
        e = errno;
        goto fail;
    }
    goto out;
fail:
    if (fd >= 0)
        close(fd);
    unlink(tmp);
    st = write_error(path, e, err);
out:
    free(tmp);
    return st;
}

/* Writes an EXR through the shim to a temporary name, fsyncs it, and renames it over path. */
static enum rb_status write_exr_atomic(const char *path, struct rb_exr_write_desc *desc,
                                       struct rb_err *err)
{
    enum rb_status st = RB_OK;
    char msg[400];
    char *tmp = temp_path(path, ".exr");
    if (!tmp)
        return rb_errf(err, RB_E_NOMEM, "cannot write '%s': out of memory", path);
    desc->path = tmp;
    int r = rb_exr_write(desc, msg, sizeof(msg));
    if (r != RB_EXR_OK) {
        unlink(tmp);
        /* OpenEXR's text names the temporary file: a full disk is said of the frame's. */
        if (r == RB_EXR_NOSPACE || r == RB_EXR_NOQUOTA)
            st = write_error(path, r == RB_EXR_NOSPACE ? ENOSPC : EDQUOT, err);
        else
            st = rb_errf(err, RB_E_EXTERNAL, "cannot write '%s': %s", path, msg);
        goto out;
    }
    if (fsync_path(tmp) != 0 || rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        st = write_error(path, e, err);
        goto out;
    }
out:
    free(tmp);
    return st;
}

/* ---- EXR -------------------------------------------------------------------------------- */

static bool is_beauty(const struct rb_io_layer *l)
{
    return !l->name || !*l->name;
}

/* Checks count*a*b fits in size_t and returns it, or 0 on overflow. */
static size_t mul3(size_t count, size_t a, size_t b)
{
    if (a && count > SIZE_MAX / a)
        return 0;
    if (b && count * a > SIZE_MAX / b)
        return 0;
    return count * a * b;
}

enum rb_status rb_io_exr_write(const char *path, uint32_t width_px, uint32_t height_px,
                               const struct rb_io_layer *layers, size_t layer_count,
                               const struct rb_io_attr *attrs, size_t attr_count,
                               struct rb_err *err)
{
    static const char *const rgba_names[4] = {"R", "G", "B", "A"};
    enum rb_status st = RB_OK;
    char **names = NULL;
    bool *is_half = NULL;
    float *pixels = NULL;
    struct rb_exr_attr *oattrs = NULL;
    size_t *order = NULL;
    uint32_t total = 0;

    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "exr: empty path");
    if (!width_px || !height_px)
        return rb_errf(err, RB_E_INVALID, "exr '%s': empty image (%ux%u)", path, width_px,
                       height_px);
    if (!layers || !layer_count)
        return rb_errf(err, RB_E_INVALID, "exr '%s': no layers", path);
    for (size_t i = 0; i < layer_count; i++) {
        const struct rb_io_layer *l = &layers[i];
        const char *ln = is_beauty(l) ? "beauty" : l->name;
        if (l->channel_count < 1 || l->channel_count > 4)
            return rb_errf(err, RB_E_INVALID, "exr '%s': layer '%s' has %u channels (1..4)", path,
                           ln, l->channel_count);
        if (!l->pixels)
            return rb_errf(err, RB_E_INVALID, "exr '%s': layer '%s' has no pixels", path, ln);
        if (!l->channel_names && !is_beauty(l))
            return rb_errf(err, RB_E_INVALID, "exr '%s': layer '%s' has no channel names", path,
                           ln);
        for (uint32_t c = 0; l->channel_names && c < l->channel_count; c++)
            if (!l->channel_names[c] || !*l->channel_names[c])
                return rb_errf(err, RB_E_INVALID, "exr '%s': layer '%s' channel %u has no name",
                               path, ln, c);
        total += l->channel_count;
    }
    size_t pixel_count = (size_t)width_px * height_px;
    size_t pixel_bytes = mul3(pixel_count, total, sizeof(float));
    if (!pixel_bytes)
        return rb_errf(err, RB_E_INVALID, "exr '%s': image too large", path);

    names = calloc(total, sizeof(*names));
    is_half = calloc(total, sizeof(*is_half));
    pixels = malloc(pixel_bytes);
    order = calloc(layer_count, sizeof(*order));
    oattrs = calloc(attr_count + 2, sizeof(*oattrs));
    if (!names || !is_half || !pixels || !order || !oattrs) {
        st = rb_errf(err, RB_E_NOMEM, "exr '%s': out of memory", path);
        goto out;
    }

    /* File order: the beauty's channels first, then the layers in the caller's order. */
    size_t n_order = 0;
    for (size_t i = 0; i < layer_count; i++)
        if (is_beauty(&layers[i]))
            order[n_order++] = i;
    for (size_t i = 0; i < layer_count; i++)
        if (!is_beauty(&layers[i]))
            order[n_order++] = i;

    uint32_t ch = 0;
    for (size_t k = 0; k < layer_count; k++) {
        const struct rb_io_layer *l = &layers[order[k]];
        for (uint32_t c = 0; c < l->channel_count; c++, ch++) {
            const char *cn = l->channel_names ? l->channel_names[c] : rgba_names[c];
            size_t n = strlen(cn) + (is_beauty(l) ? 0 : strlen(l->name) + 1) + 1;
            names[ch] = malloc(n);
            if (!names[ch]) {
                st = rb_errf(err, RB_E_NOMEM, "exr '%s': out of memory", path);
                goto out;
            }
            if (is_beauty(l))
                snprintf(names[ch], n, "%s", cn);
            else
                snprintf(names[ch], n, "%s.%s", l->name, cn);
            for (uint32_t j = 0; j < ch; j++)
                if (!strcmp(names[j], names[ch])) {
                    st = rb_errf(err, RB_E_INVALID, "exr '%s': channel '%s' appears twice", path,
                                 names[ch]);
                    goto out;
                }
            is_half[ch] = l->is_half;
            const float *src = l->pixels;
            for (size_t p = 0; p < pixel_count; p++)
                pixels[p * total + ch] = src[p * l->channel_count + c];
        }
    }

    /* Our metadata, unless the caller gives an attribute of the same name. Nothing here
     * depends on the time or the host, so equal pixels give equal bytes (test_io checks the
     * header has no capDate). */
    size_t na = 0;
    const struct rb_exr_attr ours[2] = {
        {.name = "chromaticities", .type = RB_EXR_ATTR_CHROMATICITIES, .fv = rec709_chromaticities},
        {.name = "software", .type = RB_EXR_ATTR_STRING, .s = "raybundle " RB_VERSION},
    };
    for (size_t k = 0; k < 2; k++) {
        bool given = false;
        for (size_t i = 0; i < attr_count; i++)
            given |= attrs[i].name && !strcmp(attrs[i].name, ours[k].name);
        if (!given)
            oattrs[na++] = ours[k];
    }
    for (size_t i = 0; i < attr_count; i++) {
        const struct rb_io_attr *a = &attrs[i];
        if (!a->name || !*a->name) {
            st = rb_errf(err, RB_E_INVALID, "exr '%s': attribute %zu has no name", path, i);
            goto out;
        }
        struct rb_exr_attr *o = &oattrs[na++];
        o->name = a->name;
        switch (a->type) {
        case RB_IO_ATTR_STRING:
            if (!a->s) {
                st = rb_errf(err, RB_E_INVALID, "exr '%s': attribute '%s' has no string", path,
                             a->name);
                goto out;
            }
            o->type = RB_EXR_ATTR_STRING;
            o->s = a->s;
            break;
        case RB_IO_ATTR_INT:
            o->type = RB_EXR_ATTR_INT;
            o->i = a->i;
            break;
        case RB_IO_ATTR_FLOAT:
            o->type = RB_EXR_ATTR_FLOAT;
            o->f = a->f;
            break;
        case RB_IO_ATTR_M44:
            o->type = RB_EXR_ATTR_M44;
            o->fv = a->m;
            break;
        default:
            st = rb_errf(err, RB_E_INVALID, "exr '%s': attribute '%s' has unknown type %d", path,
                         a->name, (int)a->type);
            goto out;
        }
    }

    struct rb_exr_write_desc desc = {
        .width_px = width_px,
        .height_px = height_px,
        .channel_count = total,
        .channel_names = (const char *const *)names,
        .channel_is_half = is_half,
        .pixels = pixels,
        .attrs = oattrs,
        .attr_count = na,
    };
    st = write_exr_atomic(path, &desc, err);
out:
    for (uint32_t i = 0; names && i < total; i++)
        free(names[i]);
    free(names);
    free(is_half);
    free(pixels);
    free(order);
    free(oattrs);
    return st;
}

/* ---- reading ---------------------------------------------------------------------------- */

/* Allocates img's pixels and channel names for width x height x channels; false when too large
 * or out of memory (err says which, naming path). */
static enum rb_status image_alloc(const char *path, struct rb_io_image *img, uint32_t width_px,
                                  uint32_t height_px, uint32_t channel_count, struct rb_err *err)
{
    size_t bytes = mul3((size_t)width_px * height_px, channel_count, sizeof(float));
    if (!bytes)
        return rb_errf(err, RB_E_INVALID, "cannot read '%s': image too large", path);
    img->width_px = width_px;
    img->height_px = height_px;
    img->channel_count = channel_count;
    img->pixels = malloc(bytes);
    img->channel_names = calloc(channel_count, sizeof(*img->channel_names));
    if (!img->pixels || !img->channel_names)
        return rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
    return RB_OK;
}

static enum rb_status name_channel(const char *path, struct rb_io_image *img, uint32_t c,
                                   const char *name, struct rb_err *err)
{
    if (!(img->channel_names[c] = rb_strdup(name)))
        return rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
    return RB_OK;
}

static enum rb_status read_exr(const char *path, struct rb_io_image *img, struct rb_err *err)
{
    struct rb_exr_input *in = NULL;
    uint32_t w, h, n;
    char msg[400];
    if (rb_exr_open(path, &in, &w, &h, &n, msg, sizeof(msg)) != RB_EXR_OK)
        return rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    enum rb_status st = image_alloc(path, img, w, h, n, err);
    for (uint32_t c = 0; !st && c < n; c++)
        st = name_channel(path, img, c, rb_exr_channel_name(in, c), err);
    if (!st && rb_exr_read(in, img->pixels, msg, sizeof(msg)) != RB_EXR_OK)
        st = rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    rb_exr_close(in);
    return st;
}

static enum rb_status read_png(const char *path, struct rb_io_image *img, struct rb_err *err)
{
    uint32_t w, h, n;
    float *pixels = NULL;
    char msg[400];
    if (!rb_png_decode(path, &w, &h, &n, &pixels, msg, sizeof(msg)))
        return rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    img->width_px = w;
    img->height_px = h;
    img->channel_count = n;
    img->pixels = pixels;
    if (!(img->channel_names = calloc(n, sizeof(*img->channel_names))))
        return rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
    enum rb_status st = RB_OK;
    for (uint32_t c = 0; !st && c < n; c++)
        st = name_channel(path, img, c, rb_png_channel_name(n, c), err);
    return st;
}

#if RB_WITH_OIIO
static enum rb_status read_oiio(const char *path, struct rb_io_image *img, struct rb_err *err)
{
    struct rb_oiio_input *in = NULL;
    struct rb_oiio_info info = {0};
    char msg[400];
    if (rb_oiio_input_open(path, &in, &info, msg, sizeof(msg)) != RB_OIIO_OK)
        return rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    enum rb_status st =
        image_alloc(path, img, info.width_px, info.height_px, info.channel_count, err);
    for (uint32_t c = 0; !st && c < info.channel_count; c++)
        st = name_channel(path, img, c, rb_oiio_input_channel_name(in, c), err);
    if (!st && rb_oiio_input_read(in, img->pixels, msg, sizeof(msg)) != RB_OIIO_OK)
        st = rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    rb_oiio_input_close(in);
    return st;
}
#endif

enum rb_status rb_io_image_read(const char *path, struct rb_io_image *out, struct rb_err *err)
{
    struct rb_io_image img = {0};

    if (!path || !*path || !out)
        return rb_errf(err, RB_E_INVALID, "read image: no path");
    /* Before any format probe: a FIFO would block it, and a device has no end to read to. */
    enum rb_status st = rb_file_check_regular(path, err);
    if (st)
        return st;
    if (rb_exr_is_exr(path))
        st = read_exr(path, &img, err);
    else if (rb_png_is_png(path))
        st = read_png(path, &img, err);
    else
#if RB_WITH_OIIO
        st = read_oiio(path, &img, err);
#else
        st = rb_errf(err, RB_E_UNSUPPORTED,
                     "cannot read '%s': it is neither OpenEXR nor PNG, and this build of "
                     "raybundle reads other formats only through OpenImageIO, which it was "
                     "built without",
                     path);
#endif
    if (!st) {
        *out = img;
        img = (struct rb_io_image){0};
    }
    rb_io_image_release(&img);
    return st;
}

void rb_io_image_release(struct rb_io_image *img)
{
    if (!img)
        return;
    for (uint32_t c = 0; img->channel_names && c < img->channel_count; c++)
        free(img->channel_names[c]);
    free(img->channel_names);
    free(img->pixels);
    *img = (struct rb_io_image){0};
}

int rb_io_image_channel(const struct rb_io_image *img, const char *name)
{
    if (!img || !name)
        return -1;
    for (uint32_t c = 0; c < img->channel_count; c++)
        if (img->channel_names[c] && !strcmp(img->channel_names[c], name))
            return (int)c;
    return -1;
}

bool rb_io_image_attr(const char *path, const char *name, char *out, size_t size)
{
    char msg[400];
    uint32_t w, h, n;
    if (!path || !name)
        return false;
    if (rb_exr_is_exr(path)) {
        struct rb_exr_input *in = NULL;
        if (rb_exr_open(path, &in, &w, &h, &n, msg, sizeof(msg)) != RB_EXR_OK)
            return false;
        bool found = rb_exr_attr_text(in, name, out, size);
        rb_exr_close(in);
        return found;
    }
#if RB_WITH_OIIO
    struct rb_oiio_input *in = NULL;
    struct rb_oiio_info info;
    if (rb_oiio_input_open(path, &in, &info, msg, sizeof(msg)) != RB_OIIO_OK)
        return false;
    bool found = rb_oiio_input_attr(in, name, out, size);
    rb_oiio_input_close(in);
    return found;
#else
    return false;
#endif
}

enum rb_status rb_io_image_attrs_read(const char *path, struct rb_io_image_attrs *out,
                                      struct rb_err *err)
{
    struct rb_exr_input *in = NULL;
    uint32_t w, h, n;
    char msg[400];
    enum rb_status st = RB_OK;

    if (!out)
        return rb_errf(err, RB_E_INVALID, "read attributes: no output");
    *out = (struct rb_io_image_attrs){0};
    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "read attributes: no path");
    if ((st = rb_file_check_regular(path, err)))
        return st;
    if (!rb_exr_is_exr(path))
        return RB_OK;
    if (rb_exr_open(path, &in, &w, &h, &n, msg, sizeof(msg)) != RB_EXR_OK)
        return rb_errf(err, RB_E_EXTERNAL, "cannot read '%s': %s", path, msg);
    size_t count = rb_exr_attr_count(in);
    out->names = calloc(count ? count : 1, sizeof(*out->names));
    out->values = calloc(count ? count : 1, sizeof(*out->values));
    if (!out->names || !out->values) {
        st = rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
        goto out;
    }
    for (size_t i = 0; i < count; i++) {
        const char *name = rb_exr_attr_name(in, i);
        char text[4096];
        if (!rb_exr_attr_text(in, name, text, sizeof(text)))
            snprintf(text, sizeof(text), "(%s)", rb_exr_attr_type(in, i));
        out->names[i] = rb_strdup(name);
        out->values[i] = rb_strdup(text);
        out->count = i + 1;
        if (!out->names[i] || !out->values[i]) {
            st = rb_errf(err, RB_E_NOMEM, "cannot read '%s': out of memory", path);
            goto out;
        }
    }
out:
    rb_exr_close(in);
    return st;
}

void rb_io_image_attrs_release(struct rb_io_image_attrs *a)
{
    if (!a)
        return;
    for (size_t i = 0; i < a->count; i++) {
        free(a->names[i]);
        free(a->values[i]);
    }
    free(a->names);
    free(a->values);
    *a = (struct rb_io_image_attrs){0};
}

const char *rb_io_channel_base(const char *name)
{
    const char *dot = name ? strrchr(name, '.') : NULL;
    return dot ? dot + 1 : name;
}

/* The length of the layer part of a channel name: 0 for the beauty's. */
static size_t layer_part(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? (size_t)(dot - name) : 0;
}

/* Where a layer goes in the listing: the beauty (len 0), then raybundle's layers in the order of
 * enum rb_layer, then every other. */
static uint32_t layer_rank(const char *name, size_t len)
{
    if (!len)
        return 0;
    for (uint32_t l = 0; l < RB_LAYER_COUNT; l++) {
        const char *known = rb_layer_name((enum rb_layer)l);
        if (strlen(known) == len && !strncmp(known, name, len))
            return 1 + l;
    }
    return 1 + RB_LAYER_COUNT;
}

enum rb_status rb_io_image_layers_init(struct rb_io_image_layers *out,
                                       const struct rb_io_image *img, struct rb_err *err)
{
    if (!out)
        return rb_errf(err, RB_E_INVALID, "image layers: no output");
    *out = (struct rb_io_image_layers){0};
    if (!img)
        return rb_errf(err, RB_E_INVALID, "image layers: no image");
    uint32_t n = img->channel_count;
    uint32_t *rank = calloc(n ? n : 1, sizeof(*rank));
    out->layers = calloc(n ? n : 1, sizeof(*out->layers));
    if (!rank || !out->layers) {
        free(rank);
        return rb_errf(err, RB_E_NOMEM, "image layers: out of memory");
    }
    for (uint32_t c = 0; c < n; c++) {
        const char *name = img->channel_names[c];
        size_t len = layer_part(name);
        size_t k = 0;
        /* The layer whose first channel has the same layer part. */
        while (k < out->count) {
            const char *first = img->channel_names[out->layers[k].channels[0]];
            if (layer_part(first) == len && !strncmp(first, name, len))
                break;
            k++;
        }
        struct rb_io_image_layer *l = &out->layers[k];
        if (k == out->count) {
            if (!(l->channels = calloc(n, sizeof(*l->channels))) ||
                !(l->name = malloc(len ? len + 1 : sizeof("beauty")))) {
                free(l->channels);
                *l = (struct rb_io_image_layer){0};
                free(rank);
                return rb_errf(err, RB_E_NOMEM, "image layers: out of memory");
            }
            if (len) {
                memcpy(l->name, name, len);
                l->name[len] = '\0';
            } else {
                memcpy(l->name, "beauty", sizeof("beauty"));
            }
            rank[k] = layer_rank(name, len);
            out->count++;
        }
        l->channels[l->channel_count++] = c;
    }
    /* A stable insertion sort by rank: layers of one rank keep the order of the channels. */
    for (size_t i = 1; i < out->count; i++) {
        struct rb_io_image_layer l = out->layers[i];
        uint32_t r = rank[i];
        size_t j = i;
        for (; j > 0 && rank[j - 1] > r; j--) {
            out->layers[j] = out->layers[j - 1];
            rank[j] = rank[j - 1];
        }
        out->layers[j] = l;
        rank[j] = r;
    }
    free(rank);
    return RB_OK;
}

void rb_io_image_layers_release(struct rb_io_image_layers *l)
{
    if (!l)
        return;
    for (size_t i = 0; i < l->count; i++) {
        free(l->layers[i].name);
        free(l->layers[i].channels);
    }
    free(l->layers);
    *l = (struct rb_io_image_layers){0};
}

bool rb_io_image_is_complete(const char *path)
{
    struct rb_io_image img = {0};
    struct stat sb;
    if (!path || stat(path, &sb) != 0 || !S_ISREG(sb.st_mode))
        return false;
    bool ok = rb_io_image_read(path, &img, NULL) == RB_OK;
    rb_io_image_release(&img);
    return ok;
}

/* ---- color ------------------------------------------------------------------------------ */

static bool file_exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

const char *rb_io_library_versions(void)
{
    static char buf[160];
#if RB_WITH_OIIO
    snprintf(buf, sizeof(buf), "OpenImageIO %s, OpenEXR %s, libpng %s, OpenColorIO %s",
             rb_oiio_version(), rb_exr_version(), rb_png_version(), rb_ocio_version());
#else
    snprintf(buf, sizeof(buf),
             "OpenImageIO (not in this build), OpenEXR %s, libpng %s, "
             "OpenColorIO %s",
             rb_exr_version(), rb_png_version(), rb_ocio_version());
#endif
    return buf;
}

const char *rb_io_default_ocio_config(void)
{
    /* Not thread-safe: one static buffer, rebuilt on each call. */
    static char found[PATH_MAX + 64];
    const char *datadir = getenv("RB_DATADIR");
    if (datadir && *datadir) {
        snprintf(found, sizeof(found), "%s/ocio/config.ocio", datadir);
        if (file_exists(found))
            return found;
    }

    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n > 0) {
        exe[n] = '\0';
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = '\0';
            /* Installed: <prefix>/bin/raybundle. Source tree: <repo>/build/raybundle. */
            static const char *const rel[] = {"../share/raybundle/ocio/config.ocio",
                                              "../share/ocio/config.ocio"};
            for (size_t i = 0; i < sizeof(rel) / sizeof(rel[0]); i++) {
                char path[PATH_MAX + 64];
                snprintf(path, sizeof(path), "%s/%s", exe, rel[i]);
                if (file_exists(path) && realpath(path, found))
                    return found;
            }
        }
    }
    snprintf(found, sizeof(found), "%s/ocio/config.ocio", RB_DATADIR);
    return found;
}

static uint8_t quantize(float v)
{
    if (!(v > 0.0f)) /* also NaN */
        return 0;
    if (v >= 1.0f)
        return 255;
    return (uint8_t)(v * 255.0f + 0.5f);
}

/* The display bytes of scene-linear RGBA (count pixels, premultiplied): unpremultiplied, through
 * desc's view transform (or none for data), quantized to 8 bits. what names the image in
 * messages. *out (count*4 bytes, freed with free()) only on success. */
static enum rb_status display_bytes(const char *what, uint32_t width_px, uint32_t height_px,
                                    const float *rgba, const struct rb_io_color_desc *desc,
                                    bool is_data, uint8_t **out, struct rb_err *err)
{
    enum rb_status st = RB_OK;
    float *work = NULL;
    uint8_t *bytes = NULL;
    char msg[480];

    if (!width_px || !height_px || !rgba)
        return rb_errf(err, RB_E_INVALID, "%s: empty image", what);
    const char *config = desc && desc->config && *desc->config ? desc->config : NULL;
    if (!config && !is_data) {
        const char *env = getenv("OCIO");
        config = env && *env ? env : rb_io_default_ocio_config();
    }
    struct stat sb;
    if (config && stat(config, &sb) != 0)
        return rb_errf(err, RB_E_IO, "ocio: cannot read config '%s': %s", config, strerror(errno));
    if (config && !S_ISREG(sb.st_mode))
        return rb_errf(err, RB_E_IO, "ocio: cannot read config '%s': not a regular file", config);

    size_t count = (size_t)width_px * height_px;
    size_t fbytes = mul3(count, 4, sizeof(float));
    if (!fbytes)
        return rb_errf(err, RB_E_INVALID, "%s: image too large", what);
    work = malloc(fbytes);
    bytes = malloc(count * 4);
    if (!work || !bytes) {
        st = rb_errf(err, RB_E_NOMEM, "%s: out of memory", what);
        goto out;
    }
    /* The render is premultiplied; PNG stores unassociated alpha, and the view transform is
     * meant for color, not color times coverage. */
    memcpy(work, rgba, fbytes);
    for (size_t p = 0; p < count; p++) {
        float a = work[p * 4 + 3];
        if (a > 0.0f && a < 1.0f)
            for (int c = 0; c < 3; c++)
                work[p * 4 + c] /= a;
    }

    int r = is_data ? RB_OCIO_OK
                    : rb_ocio_display_view_apply(config, desc ? desc->display : NULL,
                                                 desc ? desc->view : NULL, work, width_px,
                                                 height_px, NULL, NULL, 0, msg, sizeof(msg));
    if (r != RB_OCIO_OK) {
        st = rb_errf(err, r == RB_OCIO_NO_NAME ? RB_E_INVALID : RB_E_EXTERNAL, "%s", msg);
        goto out;
    }
    for (size_t i = 0; i < count * 4; i++)
        bytes[i] = quantize(work[i]);
    *out = bytes;
    bytes = NULL;
out:
    free(work);
    free(bytes);
    return st;
}

/* The display and view's transform built and applied to one pixel, as every preview will be:
 * what loads only then (a LUT file the config names, a transform OpenColorIO cannot build)
 * fails here, before any frame, rather than after the first frame was written. */
static enum rb_status color_probe(const char *config, const struct rb_io_color_desc *desc,
                                  struct rb_err *err)
{
    float rgba[4] = {0.18f, 0.18f, 0.18f, 1.0f};
    char msg[480];
    int r =
        rb_ocio_display_view_apply(config, desc ? desc->display : NULL, desc ? desc->view : NULL,
                                   rgba, 1, 1, NULL, NULL, 0, msg, sizeof(msg));
    if (r != RB_OCIO_OK)
        return rb_errf(err, r == RB_OCIO_NO_NAME ? RB_E_INVALID : RB_E_EXTERNAL, "%s", msg);
    return RB_OK;
}

enum rb_status rb_io_color_check(const struct rb_io_color_desc *desc, struct rb_err *err)
{
    const char *config = desc && desc->config && *desc->config ? desc->config : NULL;
    if (!config) {
        const char *env = getenv("OCIO");
        config = env && *env ? env : rb_io_default_ocio_config();
    }
    struct stat sb;
    if (stat(config, &sb) != 0)
        return rb_errf(err, RB_E_IO, "ocio: cannot read config '%s': %s", config, strerror(errno));
    char display[256] = "", names[2048] = "", msg[480];
    int r = rb_ocio_view_names(config, desc ? desc->display : NULL, display, names, sizeof(names),
                               msg, sizeof(msg));
    if (r != RB_OCIO_OK)
        return rb_errf(err, r == RB_OCIO_NO_NAME ? RB_E_INVALID : RB_E_EXTERNAL, "%s", msg);
    const char *view = desc ? desc->view : NULL;
    if (!view || !*view)
        return color_probe(config, desc, err); /* the display's default, which the config has */
    char list[1024] = "";
    struct rb_suggest near;
    rb_suggest_init(&near, view);
    for (char *p = names, *nl; (nl = strchr(p, '\n')); p = nl + 1) {
        size_t len = (size_t)(nl - p);
        if (len == strlen(view) && strncmp(p, view, len) == 0)
            return color_probe(config, desc, err);
        rb_suggest_offer(&near, p, len);
        size_t used = strlen(list);
        snprintf(list + used, sizeof(list) - used, "%s'%.*s'", used ? ", " : "", (int)len, p);
    }
    if (near.best[0])
        return rb_errf(err, RB_E_INVALID,
                       "ocio: view '%s' not found for display '%s' in config '%s'; did you mean "
                       "'%s'? (it has %s)",
                       view, display, config, near.best, list);
    return rb_errf(err, RB_E_INVALID,
                   "ocio: view '%s' not found for display '%s' in config '%s' (it has %s)", view,
                   display, config, list);
}

enum rb_status rb_io_preview_write(const char *path, uint32_t width_px, uint32_t height_px,
                                   const float *rgba, const struct rb_io_color_desc *desc,
                                   struct rb_err *err)
{
    uint8_t *bytes = NULL;
    char what[600];
    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "preview: empty path");
    snprintf(what, sizeof(what), "preview '%s'", path);
    enum rb_status st = display_bytes(what, width_px, height_px, rgba, desc, false, &bytes, err);
    if (st)
        return st;
    st = rb_io_png_write(path, width_px, height_px, bytes, err);
    free(bytes);
    return st;
}

enum rb_status rb_io_png_write(const char *path, uint32_t width_px, uint32_t height_px,
                               const uint8_t *rgba, struct rb_err *err)
{
    if (!path || !*path)
        return rb_errf(err, RB_E_INVALID, "PNG: empty path");
    if (!width_px || !height_px || !rgba)
        return rb_errf(err, RB_E_INVALID, "cannot write '%s': empty image", path);
    void *png = NULL;
    size_t png_size = 0;
    char msg[300];
    enum rb_status st;
    if (!rb_png_encode(rgba, width_px, height_px, "raybundle " RB_VERSION, &png, &png_size, msg,
                       sizeof(msg)))
        st = rb_errf(err, RB_E_EXTERNAL, "cannot write '%s': %s", path, msg);
    else
        st = rb_io_write_atomic(path, png, png_size, err);
    free(png);
    return st;
}

enum rb_status rb_io_thumbnail_data_uri(uint32_t width_px, uint32_t height_px, const float *rgba,
                                        const struct rb_io_thumbnail_desc *desc, char **out,
                                        struct rb_err *err)
{
#if RB_WITH_OIIO
    static const char prefix[] = "data:image/png;base64,";
    struct rb_io_thumbnail_desc d = desc ? *desc : (struct rb_io_thumbnail_desc){0};
    uint32_t w = d.width_px ? d.width_px : width_px, h = d.height_px ? d.height_px : height_px;
    float *small = NULL;
    uint8_t *bytes = NULL;
    void *png = NULL;
    size_t png_size = 0;
    char *uri = NULL, msg[400];
    enum rb_status st = RB_OK;

    if (!width_px || !height_px || !rgba)
        return rb_errf(err, RB_E_INVALID, "thumbnail: empty image");
    if (w > width_px || h > height_px)
        return rb_errf(err, RB_E_INVALID, "thumbnail: %ux%u is larger than the %ux%u image", w, h,
                       width_px, height_px);
    if (w != width_px || h != height_px) {
        if (!(small = malloc((size_t)w * h * 4 * sizeof(float)))) {
            st = rb_errf(err, RB_E_NOMEM, "thumbnail: out of memory");
            goto out;
        }
        if (rb_oiio_resize(rgba, width_px, height_px, 4, small, w, h, msg, sizeof(msg))) {
            st = rb_errf(err, RB_E_EXTERNAL, "thumbnail: cannot resize: %s", msg);
            goto out;
        }
    }
    if ((st = display_bytes("thumbnail", w, h, small ? small : rgba, d.color, d.is_data, &bytes,
                            err)))
        goto out;
    if (!rb_png_encode(bytes, w, h, "raybundle " RB_VERSION, &png, &png_size, msg, sizeof(msg))) {
        st = rb_errf(err, RB_E_EXTERNAL, "thumbnail: cannot encode a PNG: %s", msg);
        goto out;
    }
    size_t len = 4 * ((png_size + 2) / 3) + 1;
    if (!(uri = malloc(sizeof(prefix) - 1 + len))) {
        st = rb_errf(err, RB_E_NOMEM, "thumbnail: out of memory");
        goto out;
    }
    memcpy(uri, prefix, sizeof(prefix) - 1);
    if (rb_oiio_base64_encode(png, png_size, uri + sizeof(prefix) - 1, len, msg, sizeof(msg))) {
        st = rb_errf(err, RB_E_EXTERNAL, "thumbnail: %s", msg);
        goto out;
    }
    *out = uri;
    uri = NULL;
out:
    free(uri);
    free(png);
    free(bytes);
    free(small);
    return st;
#else
    (void)width_px;
    (void)height_px;
    (void)rgba;
    (void)desc;
    (void)out;
    return rb_errf(err, RB_E_UNSUPPORTED,
                   "thumbnail: this build of raybundle has no OpenImageIO, which resizes and "
                   "encodes thumbnails");
#endif
}

/* ---- timing sidecar ------------------------------------------------------------------- */

/* A growing text buffer; a failed allocation sets is_oom and drops further text. */
struct text {
    char *s;
    size_t len, cap;
    bool is_oom;
};

static void text_add(struct text *t, const char *s, size_t n)
{
    if (t->is_oom)
        return;
    if (t->len + n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 1024;
        while (cap < t->len + n + 1)
            cap *= 2;
        char *p = realloc(t->s, cap);
        if (!p) {
            t->is_oom = true;
            return;
        }
        t->s = p;
        t->cap = cap;
    }
    memcpy(t->s + t->len, s, n);
    t->len += n;
    t->s[t->len] = '\0';
}

static void text_puts(struct text *t, const char *s)
{
    text_add(t, s, strlen(s));
}

__attribute__((format(printf, 2, 3))) static void text_printf(struct text *t, const char *fmt, ...)
{
    char buf[128];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof(buf)) {
        t->is_oom = true; /* not reached: only numbers go through here */
        return;
    }
    text_add(t, buf, (size_t)n);
}

/* A JSON number: the shortest of %.15g / %.17g that reads back exactly; null for NaN and
 * infinities, which JSON cannot spell. */
static void json_number(struct text *t, double v)
{
    if (!isfinite(v)) {
        text_puts(t, "null");
        return;
    }
    char buf[64];
    snprintf(buf, sizeof(buf), "%.15g", v);
    if (strtod(buf, NULL) != v)
        snprintf(buf, sizeof(buf), "%.17g", v);
    text_puts(t, buf);
}

static void json_string(struct text *t, const char *s)
{
    if (!s) {
        text_puts(t, "null");
        return;
    }
    text_puts(t, "\"");
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        switch (*p) {
        case '"': text_puts(t, "\\\""); break;
        case '\\': text_puts(t, "\\\\"); break;
        case '\b': text_puts(t, "\\b"); break;
        case '\f': text_puts(t, "\\f"); break;
        case '\n': text_puts(t, "\\n"); break;
        case '\r': text_puts(t, "\\r"); break;
        case '\t': text_puts(t, "\\t"); break;
        default:
            if (*p < 0x20)
                text_printf(t, "\\u%04x", *p);
            else
                text_add(t, (const char *)p, 1);
        }
    }
    text_puts(t, "\"");
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The nearest-rank percentile p (1..100) of n >= 1 sorted values: the k-th smallest,
 * k = ceil(p * n / 100), in integers so no rounding moves a rank. */
static double nearest_rank(const float *sorted, size_t n, unsigned p)
{
    return sorted[(p * n + 99) / 100 - 1];
}

enum rb_status rb_io_hits_summarize(const float *values, size_t count, struct rb_io_hits *out,
                                    struct rb_err *err)
{
    float *sorted = malloc((count ? count : 1) * sizeof(*sorted));
    if (!sorted)
        return rb_errf(err, RB_E_NOMEM, "out of memory for the hit ratios' percentiles");
    double sum = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < count; i++)
        if (isfinite(values[i])) {
            sum += values[i];
            sorted[n++] = values[i];
        }
    if (n == 0) {
        *out = (struct rb_io_hits){NAN, NAN, NAN, NAN};
    } else {
        qsort(sorted, n, sizeof(*sorted), cmp_float);
        *out = (struct rb_io_hits){.mean = sum / (double)n,
                                   .p5 = nearest_rank(sorted, n, 5),
                                   .p50 = nearest_rank(sorted, n, 50),
                                   .p95 = nearest_rank(sorted, n, 95)};
    }
    free(sorted);
    return RB_OK;
}

enum rb_status rb_io_timing_write(const char *path, const struct rb_io_timing *tm,
                                  struct rb_err *err)
{
    if (!path || !*path || !tm)
        return rb_errf(err, RB_E_INVALID, "timing: no path or no timing");
    if (tm->pass_count && !tm->passes)
        return rb_errf(err, RB_E_INVALID, "timing '%s': %zu passes but no pass array", path,
                       tm->pass_count);

    struct text t = {0};
    double gpu_total_ms = 0.0;
    text_printf(&t, "{\n  \"frame\": %d,\n  \"time_s\": ", tm->frame);
    json_number(&t, tm->time_s);
    text_puts(&t, ",\n  \"passes\": [");
    for (size_t i = 0; i < tm->pass_count; i++) {
        text_puts(&t, i ? ",\n    {\"name\": " : "\n    {\"name\": ");
        json_string(&t, tm->passes[i].name);
        text_puts(&t, ", \"gpu_ms\": ");
        json_number(&t, tm->passes[i].gpu_ms);
        text_printf(&t, ", \"count\": %u", tm->passes[i].count);
        if (tm->passes[i].cpu_ms > 0.0) {
            text_puts(&t, ", \"cpu_ms\": ");
            json_number(&t, tm->passes[i].cpu_ms);
        }
        text_puts(&t, "}");
        gpu_total_ms += tm->passes[i].gpu_ms;
    }
    text_puts(&t, tm->pass_count ? "\n  ],\n  \"wall_ms\": " : "],\n  \"wall_ms\": ");
    json_number(&t, tm->wall_ms);
    text_puts(&t, ",\n  \"gpu_total_ms\": ");
    json_number(&t, gpu_total_ms);
    text_puts(&t, ",\n  \"device\": ");
    json_string(&t, tm->device);
    text_puts(&t, ",\n  \"driver\": ");
    json_string(&t, tm->driver);
    if (tm->job_hash) {
        text_puts(&t, ",\n  \"job_hash\": ");
        json_string(&t, tm->job_hash);
    }
    text_puts(&t, ",\n  \"integrator\": ");
    json_string(&t, tm->integrator);
    text_printf(&t, ",\n  \"width\": %u,\n  \"height\": %u", tm->width_px, tm->height_px);
    text_printf(&t, ",\n  \"nonfinite\": %u", tm->nonfinite_count);
    if (tm->bundle_nodes_capacity)
        text_printf(&t,
                    ",\n  \"bundle_nodes\": {\"max\": %u, \"capacity\": %u, \"dropped\": %u, "
                    "\"overflow\": %s}",
                    tm->bundle_nodes_max, tm->bundle_nodes_capacity, tm->bundle_nodes_dropped,
                    tm->bundle_nodes_dropped ? "true" : "false");
    if (tm->spp)
        text_printf(&t, ",\n  \"spp\": %u", tm->spp);
    if (tm->ray_count)
        text_printf(&t, ",\n  \"rays\": %llu", (unsigned long long)tm->ray_count);
    if (tm->ray_counts) {
        const struct rb_ray_counts *c = tm->ray_counts;
        /* a field at a time: text_printf holds one short line */
        const uint64_t v[] = {c->requested, c->screen_hits, c->queued,
                              c->bvh_hits,  c->misses,      c->dropped};
        const char *const key[] = {"requested", "screen_hits", "queued",
                                   "bvh_hits",  "misses",      "dropped"};
        text_puts(&t, ",\n  \"ray_counts\": {");
        for (size_t i = 0; i < sizeof(v) / sizeof(v[0]); i++)
            text_printf(&t, "%s\"%s\": %llu", i ? ", " : "", key[i], (unsigned long long)v[i]);
        text_puts(&t, "}");
        if (c->has_check)
            text_printf(&t, ",\n  \"screen_check\": {\"checked\": %llu, \"agreed\": %llu}",
                        (unsigned long long)c->screen_checked,
                        (unsigned long long)c->screen_agreed);
    }
    if (tm->hits) {
        const double v[] = {tm->hits->mean, tm->hits->p5, tm->hits->p50, tm->hits->p95};
        const char *const key[] = {"{\"mean\": ", ", \"p5\": ", ", \"p50\": ", ", \"p95\": "};
        text_puts(&t, ",\n  \"hits\": ");
        for (int i = 0; i < 4; i++) {
            text_puts(&t, key[i]);
            json_number(&t, v[i]);
        }
        text_puts(&t, "}");
    }
    text_puts(&t, "\n}\n");

    enum rb_status st;
    if (t.is_oom)
        st = rb_errf(err, RB_E_NOMEM, "timing '%s': out of memory", path);
    else
        st = rb_io_write_atomic(path, t.s, t.len, err);
    free(t.s);
    return st;
}
