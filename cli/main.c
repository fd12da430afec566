/* ibl - the command-line front end. Every command is a thin client of the public API. */
#include "cli.h"

#include <stdio.h>
#include <string.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

typedef struct command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv);
} command;

static const command commands[] = {
#define IBL_COMMAND(n, s) {#n, s, cli_cmd_##n},
#include "commands.def"
#undef IBL_COMMAND
};

static void print_help(FILE *out)
{
    fprintf(out,
            "ibl %s - physically based image-based lighting\n\n"
            "usage: ibl COMMAND [options]   (ibl COMMAND --help for details)\n\ncommands:\n",
            IBL_VERSION_STRING);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-12s %s\n", commands[i].name, commands[i].summary);
    fprintf(out,
            "\noptions every command takes:\n"
            "  -q, --quiet        print only errors\n"
            "  -j, --threads N    worker threads (default: every core); output is identical for any N\n"
            "  --clamp            accept infinite pixels and clamp them (refused otherwise)\n"
            "  --max-memory MiB   the most memory the library may hold at once, all buffers\n"
            "                     together (default: half of the physical memory, or of the\n"
            "                     ulimit or container limit when lower; here %.0f MiB)\n"
            "\nexit status: 0 success, 1 bad input, 2 bad usage\n",
            (double)ibl_default_max_bytes() / 1048576.0);
}

int cli_cmd_version(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    printf("ibl %s\n", IBL_VERSION_STRING);
    return CLI_EXIT_OK;
}

int main(int argc, char **argv)
{
#ifdef __GLIBC__
    /* A command allocates a few large buffers, frees some and allocates others: keep freed
     * memory in the heap for reuse instead of returning it to the kernel (every fresh page
     * costs a fault; docs/PERFORMANCE.md "Specular prefilter"). */
    mallopt(M_MMAP_THRESHOLD, 512 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    mallopt(M_TOP_PAD, 64 << 20);
#endif
    if (argc < 2) {
        print_help(stderr);
        return CLI_EXIT_USAGE;
    }
    const char *name = argv[1];
    if (strcmp(name, "--help") == 0 || strcmp(name, "-h") == 0 || strcmp(name, "help") == 0) {
        print_help(stdout);
        return CLI_EXIT_OK;
    }
    if (strcmp(name, "--version") == 0) return cli_cmd_version(0, NULL);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++) {
        if (strcmp(name, commands[i].name) == 0) {
            cli_install_signal_handlers();
            int rc = commands[i].run(argc - 2, argv + 2);
            /* what went to standard output must have arrived (a full disk, a closed pipe) */
            if (fflush(stdout) != 0 || ferror(stdout)) {
                cli_error("cannot write to standard output");
                if (rc == CLI_EXIT_OK) rc = CLI_EXIT_BAD_INPUT;
            }
            return rc;
        }
    }
    fprintf(stderr, "ibl: unknown command '%s' (see 'ibl --help')\n", name);
    return CLI_EXIT_USAGE;
}
