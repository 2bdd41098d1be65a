/* The subcommands of the raybundle program, and what they share. */
#ifndef RB_CMD_CMD_H
#define RB_CMD_CMD_H

#include <getopt.h>

#include "core/core.h"

enum rb_exit {
    RB_EXIT_OK = 0,
    RB_EXIT_FAILED = 1, /* rendering failed */
    RB_EXIT_USAGE = 2,  /* bad usage or bad job */
    RB_EXIT_NODEVICE = 3,
};

int cmd_render(int argc, char **argv);
int cmd_reference(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_timing(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_flicker(int argc, char **argv);
int cmd_help(int argc, char **argv);

/* raybundle bench's runs, rendered by cmd/render.c for cmd/bench.c. */
struct cmd_bench_run {
    const char *out_dir;  /* --out: the set's directory */
    const char *job_path; /* JOB as given */
    const char *runs;     /* --runs as given, or NULL */
    bool is_quiet;        /* -q: no progress lines */
    uint32_t run_count;   /* set by the first on_run call */
    uint32_t run;         /* 0 before the first run, then the run just rendered (1-based) */
    /* what run rendered (the same for every run of a job) */
    char device[256], driver[256], job_hash[17];
    const char *integrator;
    uint32_t width_px, height_px;
    int first, last; /* the frame range */
    double wall_s;   /* the run, from its first frame to its files written */
};
typedef int (*cmd_bench_fn)(struct cmd_bench_run *run, void *user);
/* Parses bench's command line (render's options, --runs N, and --out DIR for the set), calls
 * on_run with run 0 (which checks --runs and the directory and sets run_count), then renders
 * the job run_count times into out_dir/run-01, ... (timing sidecars alone), calling on_run after
 * each. Returns the exit status: the first nonzero of on_run's and the renders'. */
int cmd_render_bench(int argc, char **argv, cmd_bench_fn on_run, void *user);

/* True while a progress line (ending in '\r' updates, no newline) is open on stderr. */
extern bool cmd_bar_open;
/* Ends an open progress line with a newline, so what is printed next starts a line. */
void cmd_end_bar(void);

/* The width to fit lines to on fd: $COLUMNS when set to a number, else the terminal's (fd being
 * one), else 80. */
int cmd_terminal_width(int fd);

/* path as shown to a person: without "." parts and "dir/.." pairs ("jobs/../out/x" is
 * "out/x"), when that names the same file; else path as it is (a missing file, a symbolic link
 * on the way). */
void cmd_display_path(const char *path, char *out, size_t size);

/* Prints "raybundle: error: <msg>" to stderr (after ending an open progress line). */
void cmd_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* The last message cmd_error printed (cut to fit), for a farm's failure line. */
extern char cmd_last_error[512];

/* A usage error of command ("render", "timing compare"; "" for raybundle itself), in one line
 * that says where the usage is: "raybundle: error: <msg>; see 'raybundle render --help'". */
void cmd_usage_error(const char *command, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* getopt_long for command, with raybundle's messages instead of getopt's: an unknown option
 * (with the nearest known one: "did you mean '--preview'?"), an ambiguous abbreviation (with
 * what it could be), a value missing, or given to an option that takes none. Returns what
 * getopt_long returns, and '?' after reporting one of these (exit RB_EXIT_USAGE). Set optind = 1
 * before the first call. */
int cmd_getopt(int argc, char **argv, const char *shortopts, const struct option *opts,
               const char *command);
/* Why command does not take the long option name that another command sharing its parser takes,
 * or NULL when it is no such option. */
typedef const char *(*cmd_option_note_fn)(const char *name);
/* cmd_getopt, saying note's reason when an unknown option is one that note knows. */
int cmd_getopt_note(int argc, char **argv, const char *shortopts, const struct option *opts,
                    const char *command, cmd_option_note_fn note);

#endif
