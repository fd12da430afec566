/* What it costs to learn a file's size: ibl_read_info (the header alone, from the head of the
 * file) against ibl_read_texture (the whole decode), each file on a one-thread context.
 *   bench_read_info FILE...   (e.g. tests/data/city.exr)
 * Prints, per file and call, the median wall time and the median CPU time (user + sys of the
 * process) of RUNS calls; the file is in the page cache after the first call of each. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "bench_timing.h"
#include "ibl/ibl.h"

enum { RUNS = 21 };

static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* Median wall and CPU milliseconds of RUNS calls (info: ibl_read_info, else ibl_read_texture). */
static int time_calls(ibl_context *ctx, const char *path, int info, double *wall, double *cpu,
                      ibl_file_info *fi)
{
    double w[RUNS], c[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double w0 = bench_now_ms(), c0 = cpu_ms();
        ibl_status s;
        if (info) {
            s = ibl_read_info(ctx, path, fi);
        } else {
            ibl_texture t;
            s = ibl_read_texture(ctx, path, NULL, &t, fi);
            ibl_texture_free(ctx, &t);
        }
        c[r] = cpu_ms() - c0;
        w[r] = bench_now_ms() - w0;
        if (s != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            return 0;
        }
    }
    *wall = bench_median(w, RUNS);
    *cpu = bench_median(c, RUNS);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_read_info FILE...\n");
        return 2;
    }
    ibl_context_desc d = {0};
    d.threads = 1;
    ibl_context *ctx = NULL;
    if (ibl_context_create(&d, &ctx) != IBL_OK) return 1;
    printf("%-28s %-11s %-18s %12s %12s\n", "file", "size", "call", "wall ms", "cpu ms");
    for (int i = 1; i < argc; i++) {
        const char *name = strrchr(argv[i], '/') ? strrchr(argv[i], '/') + 1 : argv[i];
        ibl_file_info fi;
        double wall, cpu;
        for (int info = 1; info >= 0; info--) {
            if (!time_calls(ctx, argv[i], info, &wall, &cpu, &fi)) {
                ibl_context_destroy(ctx);
                return 1;
            }
            char size[32];
            snprintf(size, sizeof size, "%dx%d", fi.width, fi.height);
            printf("%-28s %-11s %-18s %12.4f %12.4f\n", name, size,
                   info ? "ibl_read_info" : "ibl_read_texture", wall, cpu);
        }
    }
    ibl_context_destroy(ctx);
    return 0;
}
