/* Shared pieces of the ibl command-line tool: argument parsing, messages, exit codes,
 * the context every command runs in, and the progress display. */
#ifndef IBL_CLI_H
#define IBL_CLI_H

#include "ibl/ibl.h"

enum { CLI_EXIT_OK = 0, CLI_EXIT_BAD_INPUT = 1, CLI_EXIT_USAGE = 2 };

/* Options every command accepts, parsed by cli_common_option. */
typedef struct cli_common {
    int quiet;            /* -q: only errors                          */
    int threads;          /* --threads N (0: all cores)                */
    int clamp;            /* --clamp: clamp infinite pixels            */
    double max_memory_mib; /* --max-memory MiB (0: library default)   */
} cli_common;

typedef struct cli_args {
    int argc;
    char **argv;
    int index;
    const char *command; /* for messages: "convert" */
    const char *usage;   /* the command's --help text */
    cli_common common;
    const char *positional[8];
    int positional_count;
} cli_args;

/* Returns the next option or positional argument, or NULL at the end. Handles --help by
 * printing usage and exiting 0 (the CLI may exit; the library never does). */
const char *cli_next(cli_args *a);
/* For the option just returned: is it `name` (or `alias`)? For valued options, reads the value
 * ("--size 16" or "--size=16"); a missing value is a usage error. */
int cli_is(cli_args *a, const char *arg, const char *name, const char *alias);
const char *cli_value(cli_args *a, const char *arg);
/* cli_is for an option without a value ("--flag=x" is a usage error). */
int cli_flag(cli_args *a, const char *arg, const char *name, const char *alias);
int cli_int(cli_args *a, const char *arg, int min, int max);
double cli_double(cli_args *a, const char *arg, double min, double max);
/* The value of an SH window option: none, auto or a Hanning width. */
void cli_sh_window_value(cli_args *a, const char *arg, ibl_sh_window *window, double *width);
/* Handles the common options; returns 1 if arg was one of them. */
int cli_common_option(cli_args *a, const char *arg);
/* Stores a positional argument or fails with a usage error for an unknown option. */
void cli_positional_or_unknown(cli_args *a, const char *arg);

/* Prints "ibl CMD: message" to stderr and exits with CLI_EXIT_USAGE. */
void cli_usage_error(const cli_args *a, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3), noreturn))
#endif
    ;
/* The one-line error of a failed library call: the context's message, or PATH and the status
 * name when the library left none. */
void cli_report_failure(ibl_context *ctx, const char *path, ibl_status status);

/* Prints "ibl: message" to stderr (one line). */
void cli_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Prints to stderr unless quiet. */
void cli_info(const cli_common *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Maps a library status to the exit code (bad input: 1, usage: 2). */
int cli_exit_code(ibl_status status);
/* Creates the context for a command (threads, memory limit, progress on a terminal). */
ibl_context *cli_context(const cli_common *c);
/* Prints warnings about sanitised pixels of a file that was read. */
void cli_report_pixels(const cli_common *c, const char *path, const ibl_pixel_report *r);
/* Warns about texels a writer stored at the format's largest value. */
void cli_warn_clamped(const cli_common *c, const char *path, const ibl_write_report *r,
                      ibl_format format);
/* Non-zero if the path's container stores 8-bit display values (PNG, JPEG). */
int cli_is_display_format(const char *path);
/* Seconds since an arbitrary start (monotonic). */
double cli_seconds(void);
/* Installs SIGINT/SIGTERM handlers so that Ctrl-C cancels through the progress callback. */
void cli_install_signal_handlers(void);

/* Every subcommand: int cli_cmd_NAME(int argc, char **argv); */
#define IBL_COMMAND(name, summary) int cli_cmd_##name(int argc, char **argv);
#include "commands.def"
#undef IBL_COMMAND

#endif
