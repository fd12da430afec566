#include "cli.h"
#include "arena.h"

#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t interrupted;

/* The first Ctrl-C asks the library to stop at its next progress check (at the latest before
 * an output is renamed into place, so nothing partial is left); a second one exits at once. */
static void on_signal(int sig)
{
    if (interrupted) _exit(128 + sig);
    interrupted = 1;
}

void cli_install_signal_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

double cli_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Prints text on one line: control characters (a newline in a file name) are shown as \xNN,
 * so that every message stays one line a script can read. */
static void put_one_line(const char *text)
{
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p < 0x20 || *p == 0x7f) fprintf(stderr, "\\x%02x", *p);
        else fputc(*p, stderr);
    }
}

static void put_message(const char *prefix, const char *fmt, va_list ap, const char *suffix)
{
    char buf[8192];
    vsnprintf(buf, sizeof buf, fmt, ap);
    fputs(prefix, stderr);
    put_one_line(buf);
    fputs(suffix, stderr);
    fputc('\n', stderr);
}

void cli_usage_error(const cli_args *a, const char *fmt, ...)
{
    char prefix[64], suffix[96];
    const char *cmd = a && a->command ? a->command : "";
    snprintf(prefix, sizeof prefix, "ibl %s: ", cmd);
    snprintf(suffix, sizeof suffix, " (see 'ibl %s --help')", cmd);
    va_list ap;
    va_start(ap, fmt);
    put_message(prefix, fmt, ap, suffix);
    va_end(ap);
    exit(CLI_EXIT_USAGE);
}

void cli_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    put_message("ibl: ", fmt, ap, "");
    va_end(ap);
}

void cli_report_failure(ibl_context *ctx, const char *path, ibl_status status)
{
    const char *msg = ibl_context_message(ctx);
    size_t n = path ? strlen(path) : 0;
    if (!msg || !*msg) cli_error("%s: %s", path, ibl_status_name(status));
    else if (path && (strncmp(msg, path, n) != 0 || msg[n] != ':')) cli_error("%s: %s", path, msg);
    else cli_error("%s", msg);
}

void cli_info(const cli_common *c, const char *fmt, ...)
{
    if (c && c->quiet) return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
}

const char *cli_next(cli_args *a)
{
    if (a->index >= a->argc) return NULL;
    const char *arg = a->argv[a->index++];
    if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
        fputs(a->usage, stdout);
        exit(CLI_EXIT_OK);
    }
    return arg;
}

static const char *pending_value;

int cli_is(cli_args *a, const char *arg, const char *name, const char *alias)
{
    (void)a;
    pending_value = NULL;
    size_t n = strlen(name);
    if (strcmp(arg, name) == 0 || (alias && strcmp(arg, alias) == 0)) return 1;
    if (strncmp(arg, name, n) == 0 && arg[n] == '=') {
        pending_value = arg + n + 1;
        return 1;
    }
    /* a one-letter alias takes its value attached, as getopt does: -j2, -oOUT */
    if (alias && alias[0] == '-' && alias[1] && !alias[2] && strncmp(arg, alias, 2) == 0 && arg[2]) {
        pending_value = arg + 2;
        return 1;
    }
    return 0;
}

int cli_flag(cli_args *a, const char *arg, const char *name, const char *alias)
{
    if (!cli_is(a, arg, name, alias)) return 0;
    if (pending_value) cli_usage_error(a, "%s takes no value", name);
    return 1;
}

const char *cli_value(cli_args *a, const char *arg)
{
    if (pending_value) {
        const char *v = pending_value;
        pending_value = NULL;
        return v;
    }
    if (a->index >= a->argc) cli_usage_error(a, "%s needs a value", arg);
    return a->argv[a->index++];
}

int cli_int(cli_args *a, const char *arg, int min, int max)
{
    const char *v = cli_value(a, arg);
    char *end = NULL;
    long x = strtol(v, &end, 10);
    if (!*v || *end || x < min || x > max)
        cli_usage_error(a, "%s wants a whole number from %d to %d, not '%s'", arg, min, max, v);
    return (int)x;
}

double cli_double(cli_args *a, const char *arg, double min, double max)
{
    const char *v = cli_value(a, arg);
    char *end = NULL;
    double x = strtod(v, &end);
    if (!*v || *end || !(x >= min && x <= max))
        cli_usage_error(a, "%s wants a number from %g to %g, not '%s'", arg, min, max, v);
    return x;
}

void cli_sh_window_value(cli_args *a, const char *arg, ibl_sh_window *window, double *width)
{
    const char *v = cli_value(a, arg);
    if (strcmp(v, "none") == 0) {
        *window = IBL_SH_WINDOW_NONE;
    } else if (strcmp(v, "auto") == 0) {
        *window = IBL_SH_WINDOW_AUTO;
    } else {
        char *end = NULL;
        *width = strtod(v, &end);
        if (!*v || *end || !(*width > 0 && *width < 1e6))
            cli_usage_error(a, "%s wants none, auto or a positive width, not '%s'", arg, v);
        *window = IBL_SH_WINDOW_HANNING;
    }
}

int cli_common_option(cli_args *a, const char *arg)
{
    if (cli_flag(a, arg, "--quiet", "-q")) {
        a->common.quiet = 1;
        return 1;
    }
    if (cli_is(a, arg, "--threads", "-j")) {
        a->common.threads = cli_int(a, arg, 0, 256);
        return 1;
    }
    if (cli_flag(a, arg, "--clamp", NULL)) {
        a->common.clamp = 1;
        return 1;
    }
    if (cli_is(a, arg, "--max-memory", NULL)) {
        a->common.max_memory_mib = cli_double(a, arg, 1, 1e9);
        return 1;
    }
    return 0;
}

void cli_positional_or_unknown(cli_args *a, const char *arg)
{
    if (arg[0] == '-' && arg[1] != 0) cli_usage_error(a, "unknown option '%s'", arg);
    if (a->positional_count >= 8) cli_usage_error(a, "too many arguments");
    a->positional[a->positional_count++] = arg;
}

int cli_exit_code(ibl_status status)
{
    if (status == IBL_OK) return CLI_EXIT_OK;
    if (status == IBL_ERR_CANCELLED) return 130;
    if (status == IBL_ERR_INVALID_ARGUMENT) return CLI_EXIT_USAGE;
    return CLI_EXIT_BAD_INPUT;
}

typedef struct progress_state {
    int tty;
    double last_print;
    char stage[64];
} progress_state;

static progress_state progress;

static int on_progress(void *user, const char *stage, double fraction)
{
    (void)user;
    if (interrupted) {
        if (progress.tty) fputs("\r\033[K", stderr);
        return 1;
    }
    if (!progress.tty) return 0;
    double now = cli_seconds();
    int new_stage = stage && strncmp(progress.stage, stage, sizeof progress.stage - 1) != 0;
    if (!new_stage && now - progress.last_print < 0.1 && fraction < 1.0) return 0;
    progress.last_print = now;
    if (stage) snprintf(progress.stage, sizeof progress.stage, "%s", stage);
    int width = 30, filled = (int)(fraction * width + 0.5);
    fprintf(stderr, "\r\033[K%-20s [", progress.stage);
    for (int i = 0; i < width; i++) fputc(i < filled ? '#' : ' ', stderr);
    fprintf(stderr, "] %3d%%", (int)(fraction * 100 + 0.5));
    if (fraction >= 1.0) fputs("\r\033[K", stderr);
    fflush(stderr);
    return 0;
}


ibl_context *cli_context(const cli_common *c)
{
    ibl_context_desc d;
    memset(&d, 0, sizeof d);
    d.threads = c->threads;
    if (c->max_memory_mib > 0) d.max_bytes = (uint64_t)(c->max_memory_mib * 1048576.0);
    progress.tty = !c->quiet && isatty(STDERR_FILENO);
    d.progress = on_progress;
    d.allocator.alloc = cli_arena_alloc;
    d.allocator.free = cli_arena_free;
    ibl_context *ctx = NULL;
    if (ibl_context_create(&d, &ctx) != IBL_OK) {
        cli_error("cannot create the library context (out of memory?)");
        exit(CLI_EXIT_BAD_INPUT);
    }
    return ctx;
}

void cli_report_pixels(const cli_common *c, const char *path, const ibl_pixel_report *r)
{
    if (!r) return;
    if (r->nan_count)
        cli_info(c, "ibl: warning: %s: %llu texels had NaN values, set to 0\n", path,
                 (unsigned long long)r->nan_count);
    if (r->negative_count)
        cli_info(c, "ibl: warning: %s: %llu texels had negative values, set to 0\n", path,
                 (unsigned long long)r->negative_count);
    if (r->inf_count)
        cli_info(c, "ibl: warning: %s: %llu texels were infinite, clamped\n", path,
                 (unsigned long long)r->inf_count);
}

void cli_warn_clamped(const cli_common *c, const char *path, const ibl_write_report *r,
                      ibl_format format)
{
    if (!r || !r->clamped_texels) return;
    cli_info(c, "ibl: warning: %s: %llu texels above %g were stored as %g (the largest %s value)\n",
             path, (unsigned long long)r->clamped_texels, (double)ibl_format_max_value(format),
             (double)ibl_format_max_value(format),
             ibl_format_name(format ? format : IBL_FORMAT_RGBA16F));
}


int cli_is_display_format(const char *path)
{
    ibl_file_type t = ibl_file_type_from_path(path);
    return t == IBL_FILE_PNG || t == IBL_FILE_JPEG;
}
