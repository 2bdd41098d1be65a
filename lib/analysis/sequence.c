/* A frame sequence found on disk: the frames STEM.NNNN.exr of a directory, or of a pattern
 * DIR/STEM.####.exr, sorted by number. What raybundle report and flicker read first; needs only
 * core, so the fuzz replays link it alone. */
#include "analysis/analysis.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the sequence ------------------------------------------------------------------------- */

void rb_analysis_sequence_release(struct rb_analysis_sequence *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->frame_count; i++)
        free(s->paths[i]);
    free(s->paths);
    free(s->frames);
    memset(s, 0, sizeof(*s));
}

/* Splits "STEM.DIGITS.exr" into its stem's length and frame; false for any other name. */
static bool frame_name(const char *name, size_t *stem_len, int *frame)
{
    static const char ext[] = ".exr";
    size_t n = strlen(name), e = sizeof(ext) - 1;
    if (n <= e || strcmp(name + n - e, ext) != 0)
        return false;
    size_t end = n - e, start = end;
    while (start > 0 && name[start - 1] >= '0' && name[start - 1] <= '9')
        start--;
    if (start == end || start < 2 || name[start - 1] != '.' || end - start > 9)
        return false;
    *stem_len = start - 1;
    *frame = atoi(name + start);
    return true;
}

static int cmp_frame(const void *pa, const void *pb)
{
    int a = *(const int *)pa, b = *(const int *)pb;
    return (a > b) - (a < b);
}

/* Sorts the frames (and their paths with them) and refuses a frame that is there twice. */
static enum rb_status sort_frames(struct rb_analysis_sequence *s, struct rb_err *err)
{
    /* Frame numbers and indices packed in pairs, so the paths follow their frames. */
    int *pairs = malloc(s->frame_count * 2 * sizeof(*pairs));
    char **paths = malloc(s->frame_count * sizeof(*paths));
    enum rb_status st = RB_OK;
    if (!pairs || !paths) {
        st = rb_errf(err, RB_E_NOMEM, "'%s': out of memory", s->dir);
        goto out;
    }
    for (size_t i = 0; i < s->frame_count; i++) {
        pairs[2 * i] = s->frames[i];
        pairs[2 * i + 1] = (int)i;
    }
    qsort(pairs, s->frame_count, 2 * sizeof(*pairs), cmp_frame);
    for (size_t i = 0; i < s->frame_count; i++) {
        s->frames[i] = pairs[2 * i];
        paths[i] = s->paths[pairs[2 * i + 1]];
    }
    memcpy(s->paths, paths, s->frame_count * sizeof(*paths));
    for (size_t i = 1; i < s->frame_count && st == RB_OK; i++)
        if (s->frames[i] == s->frames[i - 1])
            st = rb_errf(err, RB_E_INVALID, "'%s' and '%s' are both frame %d", s->paths[i - 1],
                         s->paths[i], s->frames[i]);
out:
    free(paths);
    free(pairs);
    return st;
}

/* Adds dir/name as frame to s. */
static enum rb_status add_frame(struct rb_analysis_sequence *s, const char *name, int frame,
                                struct rb_err *err)
{
    int *frames = realloc(s->frames, (s->frame_count + 1) * sizeof(*frames));
    if (frames)
        s->frames = frames;
    char **paths = frames ? realloc(s->paths, (s->frame_count + 1) * sizeof(*paths)) : NULL;
    if (paths)
        s->paths = paths;
    size_t size = strlen(s->dir) + strlen(name) + 2;
    char *path = paths ? malloc(size) : NULL;
    if (!path)
        return rb_errf(err, RB_E_NOMEM, "'%s': out of memory", s->dir);
    snprintf(path, size, "%s/%s", s->dir, name);
    s->frames[s->frame_count] = frame;
    s->paths[s->frame_count++] = path;
    return RB_OK;
}

/* Splits the pattern "DIR/STEM.###.exr" (one run of '#' for the frame number) into out's dir and
 * stem; false, with out untouched, when seq's last component has no '#' (a directory). */
static bool split_pattern(const char *seq, struct rb_analysis_sequence *out, enum rb_status *st,
                          struct rb_err *err)
{
    const char *slash = strrchr(seq, '/'), *name = slash ? slash + 1 : seq;
    char probe[sizeof(out->stem) + 16];
    size_t stem_len, n = strlen(name);
    int frame;
    *st = RB_OK;
    if (!strchr(name, '#'))
        return false;
    /* The name with its '#'s as digits must be a frame's name whose digits were all '#'. */
    bool is_frame = n < sizeof(probe);
    for (size_t i = 0; is_frame && i <= n; i++)
        probe[i] = name[i] == '#' ? '0' : name[i];
    is_frame = is_frame && frame_name(probe, &stem_len, &frame) && stem_len < sizeof(out->stem) &&
               !memchr(name, '#', stem_len) &&
               strspn(name + stem_len + 1, "#") == n - stem_len - 1 - strlen(".exr");
    if (!is_frame) {
        *st = rb_errf(err, RB_E_INVALID,
                      "'%s' is neither a directory nor a pattern DIR/NAME.####.exr", seq);
        return true;
    }
    size_t dir_len = slash ? (size_t)(slash - seq) : 0;
    if (dir_len >= sizeof(out->dir)) {
        *st = rb_errf(err, RB_E_INVALID, "directory '%.40s...' is too long", seq);
        return true;
    }
    if (!slash)
        rb_strlcpy(out->dir, ".", sizeof(out->dir));
    else if (dir_len == 0)
        rb_strlcpy(out->dir, "/", sizeof(out->dir));
    else
        memcpy(out->dir, seq, dir_len);
    memcpy(out->stem, name, stem_len);
    return true;
}

enum rb_status rb_analysis_sequence_scan(const char *seq, struct rb_analysis_sequence *out,
                                         struct rb_err *err)
{
    memset(out, 0, sizeof(*out));
    enum rb_status st = RB_OK;
    bool is_pattern = split_pattern(seq, out, &st, err);
    if (st)
        return st;
    if (!is_pattern && rb_strlcpy(out->dir, seq, sizeof(out->dir)) >= sizeof(out->dir))
        return rb_errf(err, RB_E_INVALID, "directory '%.40s...' is too long", seq);
    size_t len = strlen(out->dir);
    while (len > 1 && out->dir[len - 1] == '/')
        out->dir[--len] = '\0';
    DIR *d = opendir(out->dir);
    if (!d)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", out->dir, strerror(errno));
    char other[256] = "";
    struct dirent *e;
    while (st == RB_OK && (e = readdir(d))) {
        size_t stem_len;
        int frame;
        if (!frame_name(e->d_name, &stem_len, &frame))
            continue;
        if (is_pattern) { /* the pattern's frames alone */
            if (strlen(out->stem) == stem_len && !strncmp(out->stem, e->d_name, stem_len))
                st = add_frame(out, e->d_name, frame, err);
            continue;
        }
        if (stem_len >= sizeof(out->stem)) {
            st = rb_errf(err, RB_E_INVALID, "'%s/%s': the name is too long", out->dir, e->d_name);
            break;
        }
        if (!out->frame_count) {
            memcpy(out->stem, e->d_name, stem_len);
            out->stem[stem_len] = '\0';
        } else if (strlen(out->stem) != stem_len || strncmp(out->stem, e->d_name, stem_len)) {
            /* Reported once the directory is read: the first other stem in sorted order. */
            char stem[256];
            memcpy(stem, e->d_name, stem_len);
            stem[stem_len] = '\0';
            if (!*other || strcmp(stem, other) < 0)
                rb_strlcpy(other, stem, sizeof(other));
            continue;
        }
        st = add_frame(out, e->d_name, frame, err);
    }
    closedir(d);
    if (st)
        return st;
    if (!out->frame_count && is_pattern)
        return rb_errf(err, RB_E_INVALID, "no frames match '%s'", seq);
    if (!out->frame_count)
        return rb_errf(err, RB_E_INVALID, "'%s' holds no frames (files named NAME.####.exr)",
                       out->dir);
    if (*other) {
        bool is_first = strcmp(out->stem, other) < 0;
        return rb_errf(err, RB_E_INVALID,
                       "'%s' holds frames of two sequences, '%s.####.exr' and '%s.####.exr'",
                       out->dir, is_first ? out->stem : other, is_first ? other : out->stem);
    }
    return sort_frames(out, err);
}

long rb_analysis_sequence_find(const struct rb_analysis_sequence *s, int frame)
{
    for (size_t i = 0; i < s->frame_count; i++)
        if (s->frames[i] == frame)
            return (long)i;
    return -1;
}
