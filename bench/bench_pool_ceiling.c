/* bench_pool_ceiling THREADS [CALLS] [TASKS] [ROUNDS]: the most two threads can gain on this
 * host for a process shaped like `ibl prefilter`. It makes CALLS parallel-fors (default 360,
 * about as many as the 256 chain's command) of TASKS tasks each (default 48) through the
 * library's own pool, every task ROUNDS (default 6000) steps of a dependent floating-point
 * recurrence: no memory traffic, no serial code, the same work at every thread count. Timed
 * by hyperfine at -j 1 and -j 2 (bench/threads.sh), the ratio of the two is the ceiling a
 * whole command of that length meets on this machine: the pool's wake-ups and the host's
 * scheduling of two virtual CPUs, with nothing of ibl's own serial parts in it. */
#include <ibl/ibl.h>

#include <stdio.h>
#include <stdlib.h>

typedef struct spin_job {
    int rounds;
    double *results; /* one per task: what each task computed, so none is optimised away */
} spin_job;

static void spin_task(void *arg, int index)
{
    const spin_job *job = arg;
    double x = 1.0 + index * 1e-3;
    for (int i = 0; i < job->rounds; i++) x = x * 0.9999999 + 1e-7;
    job->results[index] += x;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_pool_ceiling THREADS [CALLS] [TASKS] [ROUNDS]\n");
        return 2;
    }
    int threads = atoi(argv[1]);
    int calls = argc > 2 ? atoi(argv[2]) : 360, tasks = argc > 3 ? atoi(argv[3]) : 48;
    spin_job job = {argc > 4 ? atoi(argv[4]) : 6000, NULL};
    if (threads < 1 || calls < 1 || tasks < 1 || job.rounds < 1) {
        fprintf(stderr, "bench_pool_ceiling: THREADS, CALLS, TASKS and ROUNDS must be positive\n");
        return 2;
    }
    ibl_context_desc cd = {0};
    cd.threads = threads;
    ibl_context *ctx = NULL;
    job.results = calloc((size_t)tasks, sizeof *job.results);
    if (!job.results || ibl_context_create(&cd, &ctx) != IBL_OK) {
        fprintf(stderr, "bench_pool_ceiling: cannot create the context\n");
        return 1;
    }
    for (int c = 0; c < calls; c++) ibl_parallel_for(ctx, tasks, spin_task, &job);
    double sum = 0;
    for (int t = 0; t < tasks; t++) sum += job.results[t];
    ibl_context_destroy(ctx);
    free(job.results);
    return sum > 0 ? 0 : 1; /* the sum is positive: the check keeps the work observable */
}
