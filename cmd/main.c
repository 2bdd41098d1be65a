/* raybundle: the command table, the dispatcher and `raybundle help`. */
#include "cmd.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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
    {"help", cmd_help, "show this list, or 'help job' for every job-file key"},
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

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle <command> [options] [args]\n\ncommands:\n");
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].help);
    fprintf(f, "\n  --version  print the version and exit\n"
               "\n'raybundle <command> --help' describes a command; see raybundle(1) and "
               "raybundle-job(5).\n");
}

int cmd_help(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "job") == 0) {
        rb_job_print_keys(stdout);
        return RB_EXIT_OK;
    }
    if (argc > 1) {
        cmd_error("no help topic '%s' (try 'raybundle help' or 'raybundle help job')", argv[1]);
        return RB_EXIT_USAGE;
    }
    usage(stdout);
    return RB_EXIT_OK;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return RB_EXIT_USAGE;
    }
    if (strcmp(argv[1], "--version") == 0 || strcmp(argv[1], "version") == 0) {
        printf("raybundle %s\n", RB_VERSION);
        return RB_EXIT_OK;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)
        return cmd_help(1, argv);
    for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
        if (strcmp(argv[1], commands[i].name) == 0)
            return commands[i].fn(argc - 1, argv + 1);
    cmd_error("unknown command '%s'", argv[1]);
    usage(stderr);
    return RB_EXIT_USAGE;
}
