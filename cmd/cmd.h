/* The subcommands of the raybundle program, and what they share. */
#ifndef RB_CMD_CMD_H
#define RB_CMD_CMD_H

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
int cmd_help(int argc, char **argv);

/* True while a progress line (ending in '\r' updates, no newline) is open on stderr. */
extern bool cmd_bar_open;
/* Ends an open progress line with a newline, so what is printed next starts a line. */
void cmd_end_bar(void);

/* Prints "raybundle: error: <msg>" to stderr (after ending an open progress line). */
void cmd_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* The last message cmd_error printed (cut to fit), for a farm's failure line. */
extern char cmd_last_error[512];

#endif
