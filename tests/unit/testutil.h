/* Helpers the unit tests share: a private temporary directory and its removal. Header-only
 * (static inline), so each test program stays one file plus the library. */
#ifndef RB_TESTS_TESTUTIL_H
#define RB_TESTS_TESTUTIL_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Removes path and, for a directory, everything under it (no symlinks are followed). */
static inline void rb_test_rm_rf(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return;
    if (!S_ISDIR(st.st_mode)) {
        unlink(path);
        return;
    }
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char sub[4096];
            int n = snprintf(sub, sizeof(sub), "%s/%s", path, e->d_name);
            if (n > 0 && (size_t)n < sizeof(sub))
                rb_test_rm_rf(sub);
        }
        closedir(d);
    }
    rmdir(path);
}

/* Creates "$TMPDIR/rb_test_<tag>.XXXXXX" (or under /tmp) into buf; 0 on success. */
static inline int rb_test_mkdtemp(char *buf, size_t size, const char *tag)
{
    const char *base = getenv("TMPDIR");
    snprintf(buf, size, "%s/rb_test_%s.XXXXXX", base && *base ? base : "/tmp", tag);
    return mkdtemp(buf) ? 0 : -1;
}

/* Writes the path of an external sample scene ($RB_SCENES, default ../shared/scenes) into buf
 * and returns 0 when the file exists, -1 when it does not: a test that needs it then calls
 * cmocka's skip(), so a fresh clone without the scenes still passes. */
static inline int rb_test_scene(char *buf, size_t size, const char *rel)
{
    const char *dir = getenv("RB_SCENES");
    snprintf(buf, size, "%s/%s", dir && *dir ? dir : "../shared/scenes", rel);
    return access(buf, R_OK) == 0 ? 0 : -1;
}

#ifdef fail_msg /* after <cmocka.h> */
#include <math.h>

/* cmocka 1.1's assert_float_equal works in float; this checks doubles within tol. */
#define assert_double_equal(a, b, tol) rb_test_near((a), (b), (tol), #a, __FILE__, __LINE__)

static inline void rb_test_near(double a, double b, double tol, const char *expr, const char *file,
                                int line)
{
    if (!(fabs(a - b) <= tol))
        fail_msg("%s:%d: %s is %.17g, want %.17g (within %g)", file, line, expr, a, b, tol);
}
#endif

#endif
