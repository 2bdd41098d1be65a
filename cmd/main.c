/* raybundle: the command table, the dispatcher and `raybundle help`. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "job/job.h"

struct command {
    const char *name;
    int (*fn)(int argc, char **argv);
    const char *help;
};

static const struct command commands[] = {
    {"render", cmd_render, "render a job to per-frame EXR images and timing sidecars"},
    {"reference", cmd_reference, "render a job with the CPU reference path tracer"},
    {"compare", cmd_compare, "compare two images or frame sequences: RMSE, relMSE, PSNR, ..."},
    {"bench", cmd_bench, "render a job N times, keeping every run's timing sidecars"},
    {"timing", cmd_timing, "'timing compare BASE NEW': per-pass regression test of two bench sets"},
    {"flicker", cmd_flicker, "temporal stability of a sequence: warped and excess temporal error"},
    {"report", cmd_report,
     "write an HTML report of a rendered sequence: timing, error, thumbnails"},
    {"info", cmd_info, "list Vulkan devices, drivers and the features raybundle uses"},
    {"help", cmd_help, "show this list, or 'help job [PREFIX]' for the job-file keys"},
};

bool cmd_bar_open;
char cmd_last_error[512];

void cmd_end_bar(void)
{
    if (cmd_bar_open)
        fputc('\n', stderr);
    cmd_bar_open = false;
}

void cmd_error(const char *fmt, ...)
{
    va_list ap;
    cmd_end_bar();
    va_start(ap, fmt);
    vsnprintf(cmd_last_error, sizeof(cmd_last_error), fmt, ap);
    va_end(ap);
    va_start(ap, fmt);
    fputs("raybundle: error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

void cmd_usage_error(const char *command, const char *fmt, ...)
{
    char msg[448];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    cmd_error("%s; see 'raybundle %s%s--help'", msg, command, command[0] ? " " : "");
}

int cmd_terminal_width(int fd)
{
    /* COLUMNS first, as git's term_columns does: the user's word, and a test's. */
    const char *env = getenv("COLUMNS");
    char *end;
    long n = env && *env ? strtol(env, &end, 10) : 0;
    if (n > 0 && n < 10000 && !*end)
        return (int)n;
    struct winsize ws;
    if (isatty(fd) && ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
        return ws.ws_col;
    return 80;
}

void cmd_display_path(const char *path, char *out, size_t size)
{
    /* Lexically: "." parts go, and "dir/.." goes unless dir is itself "..". */
    char buf[4096];
    size_t len = 0, n = strlen(path);
    bool is_abs = path[0] == '/';
    if (n >= sizeof(buf) || n >= size) {
        snprintf(out, size, "%s", path);
        return;
    }
    for (const char *p = path; *p;) {
        while (*p == '/')
            p++;
        size_t part = strcspn(p, "/");
        if (!part)
            break;
        bool is_dot = part == 1 && p[0] == '.';
        bool is_up = part == 2 && p[0] == '.' && p[1] == '.';
        /* the last part kept is "..", which ".." cannot cancel */
        bool last_up = len >= 2 && buf[len - 1] == '.' && buf[len - 2] == '.' &&
                       (len == 2 || buf[len - 3] == '/');
        if (is_dot || (is_up && is_abs && !len)) {
            /* "." is here, and "/.." is "/" */
        } else if (is_up && len && !last_up) {
            while (len && buf[len - 1] != '/')
                len--;
            if (len)
                len--; /* and the slash before the part dropped */
        } else {
            if (len)
                buf[len++] = '/';
            memcpy(buf + len, p, part);
            len += part;
        }
        p += part;
    }
    buf[len] = '\0';
    snprintf(out, size, "%s%s", is_abs ? "/" : "", len || is_abs ? buf : ".");
    /* Only when both name the same file: through a symbolic link, "dir/.." is not ".". */
    struct stat a, b;
    if (stat(path, &a) != 0 || stat(out, &b) != 0 || a.st_dev != b.st_dev || a.st_ino != b.st_ino)
        snprintf(out, size, "%s", path);
}

/* The long option of opts named name[0..len), exactly or as its only abbreviation; NULL when
 * none is, or *ambiguous when several are. */
static const struct option *find_option(const struct option *opts, const char *name, size_t len,
                                        bool *ambiguous)
{
    const struct option *found = NULL;
    size_t matches = 0;
    *ambiguous = false;
    for (const struct option *o = opts; o->name; o++) {
        if (strncmp(o->name, name, len) != 0)
            continue;
        if (strlen(o->name) == len)
            return o;
        found = o;
        matches++;
    }
    *ambiguous = matches > 1;
    return matches == 1 ? found : NULL;
}

/* Reports the option getopt_long refused with '?' (opterr is 0, so it said nothing). */
static void bad_option(int argc, char **argv, const char *shortopts, const struct option *opts,
                       const char *command, cmd_option_note_fn note)
{
    /* An unknown short option: optopt is it, and optind need not have moved past it. */
    if (optopt > 0 && optopt < 256 && !strchr(shortopts, optopt)) {
        cmd_usage_error(command, "unknown option '-%c'", optopt);
        return;
    }
    /* Otherwise getopt_long stepped past the word it refused. */
    const char *arg = optind > 0 && optind <= argc ? argv[optind - 1] : "";
    if (strncmp(arg, "--", 2) != 0) { /* a short option that takes a value, last */
        cmd_usage_error(command, "option '-%c' needs a value", optopt);
        return;
    }
    const char *name = arg + 2;
    size_t len = strcspn(name, "=");
    bool ambiguous;
    const struct option *o = find_option(opts, name, len, &ambiguous);
    if (o && name[len] == '=') {
        cmd_usage_error(command, "option '--%s' takes no value", o->name);
    } else if (o) {
        cmd_usage_error(command, "option '--%s' needs a value", o->name);
    } else if (ambiguous) {
        char list[256] = "";
        for (const struct option *c = opts; c->name; c++)
            if (strncmp(c->name, name, len) == 0)
                snprintf(list + strlen(list), sizeof(list) - strlen(list), "%s'--%s'",
                         list[0] ? ", " : "", c->name);
        cmd_error("option '--%.*s' is ambiguous: it could be %s", (int)len, name, list);
    } else {
        char word[64];
        snprintf(word, sizeof(word), "%.*s", (int)len, name);
        const char *why = note ? note(word) : NULL;
        struct rb_suggest near;
        rb_suggest_init(&near, word);
        for (const struct option *c = opts; c->name; c++)
            rb_suggest_offer(&near, c->name, strlen(c->name));
        if (why)
            cmd_usage_error(command, "%s does not take '--%s': %s", command, word, why);
        else if (near.best[0])
            cmd_error("unknown option '--%s'; did you mean '--%s'?", word, near.best);
        else
            cmd_usage_error(command, "unknown option '--%s'", word);
    }
}

int cmd_getopt_note(int argc, char **argv, const char *shortopts, const struct option *opts,
                    const char *command, cmd_option_note_fn note)
{
    /* A test hook: RB_TEST_LIST_OPTIONS=1 prints the options given to getopt_long, one a line
     * ("-o", "--output"), and stops the command as a usage error does, so that a test can hold
     * each command's --help to its parser (tests/integration/t0012-cli-conventions.sh). */
    const char *list = getenv("RB_TEST_LIST_OPTIONS");
    if (list && strcmp(list, "1") == 0) {
        for (const char *p = shortopts; *p; p++)
            if (*p != ':')
                printf("-%c\n", *p);
        for (const struct option *o = opts; o->name; o++)
            printf("--%s\n", o->name);
        return '?';
    }
    opterr = 0;
    int c = getopt_long(argc, argv, shortopts, opts, NULL);
    if (c == '?' || c == ':')
        bad_option(argc, argv, shortopts, opts, command, note);
    return c == ':' ? '?' : c;
}

int cmd_getopt(int argc, char **argv, const char *shortopts, const struct option *opts,
               const char *command)
{
    return cmd_getopt_note(argc, argv, shortopts, opts, command, NULL);
}

/* "; did you mean 'x'?" for the command nearest to word, or "". */
static void suggest_command(const char *word, char *buf, size_t size)
{
    struct rb_suggest near;
    rb_suggest_init(&near, word);
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        rb_suggest_offer(&near, commands[i].name, strlen(commands[i].name));
    buf[0] = '\0';
    if (near.best[0])
        snprintf(buf, size, "; did you mean '%s'?", near.best);
}

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle <command> [options] [args]\n\ncommands:\n");
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].help);
    fprintf(f, "\n  --version  print the version and exit\n"
               "\n'raybundle <command> --help' describes a command; see raybundle(1) and "
               "raybundle-job(5).\n");
}

/* raybundle help job [PREFIX]: the keys whose path starts with PREFIX. */
static int help_job(const char *prefix)
{
    if (prefix && rb_job_print_keys(stdout, prefix, cmd_terminal_width(STDOUT_FILENO)))
        return RB_EXIT_OK;
    if (!prefix) {
        rb_job_print_keys(stdout, NULL, cmd_terminal_width(STDOUT_FILENO));
        return RB_EXIT_OK;
    }
    /* Nothing matched: the nearest key, or section (the path before a dot), to the prefix. */
    struct rb_suggest near;
    rb_suggest_init(&near, prefix);
    for (size_t i = 0; i < rb_job_key_count(); i++) {
        const char *path = rb_job_key_path(i);
        for (const char *dot = strchr(path, '.'); dot; dot = strchr(dot + 1, '.'))
            rb_suggest_offer(&near, path, (size_t)(dot - path));
        rb_suggest_offer(&near, path, strlen(path));
    }
    if (near.best[0])
        cmd_error("no job key starts with '%s'; did you mean '%s'?", prefix, near.best);
    else
        cmd_error("no job key starts with '%s' ('raybundle help job' lists them all)", prefix);
    return RB_EXIT_USAGE;
}

int cmd_help(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "job") == 0) {
        if (argc > 3) {
            cmd_error("help job takes one key prefix, and '%s' is a second", argv[3]);
            return RB_EXIT_USAGE;
        }
        return help_job(argc > 2 ? argv[2] : NULL);
    }
    if (argc > 1) {
        cmd_error("no help topic '%s' (try 'raybundle help' or 'raybundle help job')", argv[1]);
        return RB_EXIT_USAGE;
    }
    usage(stdout);
    return RB_EXIT_OK;
}

/* What a command printed reaches its reader, or the run fails: a full disk behind standard
 * output is an error (exit 1 where the command had succeeded), as git's and coreutils'
 * close_stdout make it, not a table lost in silence. */
static int finish_stdout(int rc)
{
    errno = 0;
    if (fflush(stdout) == 0 && !ferror(stdout))
        return rc;
    int e = errno;
    if (e == ENOSPC)
        cmd_error("cannot write to standard output: the disk is full (%s)", strerror(e));
    else if (e)
        cmd_error("cannot write to standard output: %s", strerror(e));
    else /* an earlier write failed, and its errno is gone */
        cmd_error("cannot write to standard output: a write failed and output was lost");
    return rc == RB_EXIT_OK ? RB_EXIT_FAILED : rc;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        cmd_usage_error("", "raybundle needs a command, such as 'render'");
        return RB_EXIT_USAGE;
    }
    if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "version") == 0) {
        printf("raybundle %s\n", RB_VERSION);
        return finish_stdout(RB_EXIT_OK);
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)
        return finish_stdout(cmd_help(1, argv));
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        if (strcmp(argv[1], commands[i].name) == 0)
            return finish_stdout(commands[i].fn(argc - 1, argv + 1));
    char hint[96];
    suggest_command(argv[1], hint, sizeof(hint));
    cmd_error("unknown command '%s'%s", argv[1], hint);
    fprintf(stderr, "raybundle: 'raybundle --help' lists the commands\n");
    return RB_EXIT_USAGE;
}
