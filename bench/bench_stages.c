/* Where the time of `ibl prefilter -q IN -o OUT.ktx2 --size N` goes, stage by stage, in one
 * process that makes the same calls as the command (the CLI's allocator, arena.c, included):
 * read and decode (with the sanitize pass), the conversion to the working cube, the fast
 * plan's creation, its pyramid, each level's grids, the output levels, and the KTX2 encode
 * (rgba16f) with the file's write (one stage: the command's output set writes the slices
 * already encoded while the rest is encoded; without OUT, the encode alone). The specular sources the CLI adds for an equirect (a few
 * ms) are left out; the chain is GGX with the linear mapping, as the command's default.
 *
 * Usage: bench_stages [--task-times] [--side-by-side] IN SIZE [THREADS] [OUT.ktx2]
 *        (threads 0: every core)
 *
 * --side-by-side makes the first stages as `ibl prefilter` does for a small input (cli/
 * prefilter.c): the header read (ibl_read_info), then the read with the conversion and the
 * plan (ibl_specular_prepare) as the two tasks of one parallel-for, one stage "read, to cube |
 * plan". With --task-times the loops the two tasks start are timed as any other (each
 * thread's time inside tasks counted once: bench/timed_pool.c).
 *
 * Per stage: wall ms, CPU ms of the process (user + sys, getrusage), each thread's run time
 * (the kernel's per-task schedstat: a thread spinning in the pool's wait counts as running,
 * about 0.1 ms a parallel-for), the page faults taken and the RSS after it. Linux only (the
 * /proc files); elsewhere the thread and RSS columns are blank.
 *
 * --task-times runs the loops through bench/timed_pool.c (a host parallel-for that runs them
 * on a second context's built-in pool, every task timed) and adds a column: the time spent inside
 * the loops' tasks, summed over the threads. The library is told at least two threads, so
 * that one thread runs the loops two would share (the work it splits only for more than one
 * thread, as a ZIP EXR's bands, would otherwise run outside any loop). On one thread the
 * wall time minus it is what runs outside any loop; the task time on two threads against one
 * is what sharing the machine costs the tasks themselves. bench/threads_split.sh reads these
 * over many runs. */
#include "ibl/ibl.h"
#include "bake/specular_internal.h"
#include "../cli/arena.h"
#include "timed_pool.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>
#include <time.h>

enum { MAX_THREADS = 16 };

typedef struct snapshot {
    double wall, user, sys;
    long faults, rss_mb;
    int threads;
    double thread_ms[MAX_THREADS];
} snapshot;

static double seconds(const struct timeval *t) { return (double)t->tv_sec + t->tv_usec * 1e-6; }

/* Each thread's run time so far, in the order /proc lists them (the main thread first). */
static int thread_times(double *ms)
{
    int n = 0;
    DIR *d = opendir("/proc/self/task");
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL && n < MAX_THREADS) {
        if (e->d_name[0] == '.') continue;
        char path[300];
        snprintf(path, sizeof path, "/proc/self/task/%s/schedstat", e->d_name);
        FILE *f = fopen(path, "r");
        unsigned long long ns = 0;
        if (f) {
            if (fscanf(f, "%llu", &ns) != 1) ns = 0;
            fclose(f);
        }
        ms[n++] = (double)ns * 1e-6;
    }
    if (d) closedir(d);
    return n;
}

static void take(snapshot *s)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    s->wall = (double)ts.tv_sec + ts.tv_nsec * 1e-9;
    s->user = seconds(&ru.ru_utime), s->sys = seconds(&ru.ru_stime);
    s->faults = ru.ru_minflt + ru.ru_majflt;
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        fclose(f);
    }
    s->rss_mb = resident * 4096 / 1000000;
    s->threads = thread_times(s->thread_ms);
}

typedef struct timeline {
    snapshot last, start;
    double cpu_total;
    const timed_pool *pool; /* --task-times */
    double last_task_ms;
} timeline;

/* Prints the stage since the last mark and starts the next. */
static void mark(timeline *t, const char *stage)
{
    snapshot now;
    take(&now);
    double cpu = (now.user - t->last.user + now.sys - t->last.sys) * 1e3;
    printf("%-22s %8.1f %8.1f %8.1f %8.1f %7ld %6ld  ", stage, (now.wall - t->last.wall) * 1e3,
           cpu, (now.user - t->last.user) * 1e3, (now.sys - t->last.sys) * 1e3,
           now.faults - t->last.faults, now.rss_mb);
    if (t->pool) {
        double task_ms = timed_pool_task_ms(t->pool);
        printf(" %8.1f  ", task_ms - t->last_task_ms);
        t->last_task_ms = task_ms;
    }
    for (int i = 0; i < now.threads; i++)
        printf(" %7.1f", now.thread_ms[i] - (i < t->last.threads ? t->last.thread_ms[i] : 0.0));
    printf("\n");
    t->last = now;
}

/* The pyramid and every level's grids report progress after each level (plan.c): a mark each. */
typedef struct progress_marks {
    timeline *t;
    int levels, next;
} progress_marks;

static int on_progress(void *user, const char *stage, double fraction)
{
    progress_marks *m = user;
    if (!m->t || strcmp(stage, "prefilter") != 0) return 0;
    int level = (int)(fraction * m->levels + 0.5) - 1;
    if (level < m->next) return 0;
    char name[40];
    snprintf(name, sizeof name, level == 0 ? "pyramid, level 0" : "grids, level %d", level);
    mark(m->t, name);
    m->next = level + 1;
    return 0;
}

static int fail(ibl_context *ctx, const char *what)
{
    fprintf(stderr, "bench_stages: %s: %s\n", what, ibl_context_message(ctx));
    return 1;
}

/* The working cube and its one-shot plan, as ibl_specular_prefilter makes them for the fast
 * method (src/bake/specular.c); prepared is set when they came from ibl_specular_prepare. */
typedef struct working {
    ibl_cubemap work;
    ibl_specular_info info;
    ibl_specular_plan *plan;
    ibl_specular_prepared *prepared;
} working;

/* Reads IN, converts it, reduces it to the plan's edge if larger, then plans: a stage each. */
static int working_in_turn(ibl_context *ctx, timeline *t, const char *in, int size, working *w)
{
    memset(w, 0, sizeof *w);
    ibl_texture tex;
    ibl_read_desc rd = {0};
    if (ibl_read_texture(ctx, in, &rd, &tex, NULL) != IBL_OK) return fail(ctx, in);
    mark(t, "read, decode");
    ibl_image image = {tex.width, tex.height, ibl_texture_level(&tex, 0, 0)};
    ibl_to_cube_desc td = {0};
    ibl_cubemap cube;
    if (ibl_image_to_cubemap(ctx, &image, &td, &cube) != IBL_OK) return fail(ctx, "to cube");
    ibl_texture_free(ctx, &tex);
    mark(t, "to cube");
    ibl_specular_desc d;
    memset(&d, 0, sizeof d);
    d.size = size;
    int edge = 0;
    if (ibl_specular_levels(ctx, &d, cube.size, &w->info) != IBL_OK ||
        ibl_specular_source_size(ctx, &d, cube.size, &edge) != IBL_OK)
        return fail(ctx, "levels");
    d.levels = w->info.levels;
    w->work = cube;
    if (edge != cube.size) {
        if (ibl_cubemap_alloc(ctx, edge, 1, &w->work) != IBL_OK ||
            ibl_cubemap_resample(ctx, &cube, &w->work) != IBL_OK)
            return fail(ctx, "resample");
        ibl_cubemap_free(ctx, &cube);
        mark(t, "resample");
    }
    d.source_size = w->work.size;
    if (ibl__specular_plan_create(ctx, &d, 1, &w->plan) != IBL_OK) return fail(ctx, "plan");
    mark(t, "plan");
    return 0;
}

typedef struct side_by_side {
    ibl_context *ctx;
    const char *in;
    ibl_specular_desc desc;
    int edge;
    ibl_cubemap cube;
    ibl_specular_prepared *prepared;
    ibl_status read_status, prepare_status;
} side_by_side;

static void side_by_side_task(void *arg, int index)
{
    side_by_side *j = arg;
    if (index == 1) {
        j->prepare_status = ibl_specular_prepare(j->ctx, &j->desc, j->edge, &j->prepared);
        return;
    }
    ibl_texture tex;
    ibl_read_desc rd = {0};
    j->read_status = ibl_read_texture(j->ctx, j->in, &rd, &tex, NULL);
    if (j->read_status != IBL_OK) return;
    ibl_image image = {tex.width, tex.height, ibl_texture_level(&tex, 0, 0)};
    ibl_to_cube_desc td = {0};
    j->read_status = ibl_image_to_cubemap(j->ctx, &image, &td, &j->cube);
    ibl_texture_free(j->ctx, &tex);
}

/* The command's way: the cube's edge from the header, then the read with the conversion and
 * the plan side by side; a larger cube is reduced to the plan's edge after, as
 * ibl_specular_prefilter_prepared does. */
static int working_side_by_side(ibl_context *ctx, timeline *t, const char *in, int size, working *w)
{
    memset(w, 0, sizeof *w);
    ibl_file_info head;
    if (ibl_read_info(ctx, in, &head) != IBL_OK) return fail(ctx, in);
    side_by_side j = {ctx, in, {0}, ibl_layout_cube_size(IBL_LAYOUT_AUTO, head.width, head.height),
                      {0}, NULL, IBL_OK, IBL_OK};
    if (j.edge < 1) return fail(ctx, "the cube's edge from the header");
    j.desc.size = size;
    if (ibl_specular_levels(ctx, &j.desc, j.edge, &w->info) != IBL_OK) return fail(ctx, "levels");
    ibl_parallel_for(ctx, 2, side_by_side_task, &j);
    if (j.read_status != IBL_OK) return fail(ctx, in);
    if (j.prepare_status != IBL_OK) return fail(ctx, "prepare");
    w->prepared = j.prepared;
    int edge = 0;
    w->plan = ibl__specular_prepared_plan(j.prepared, &edge);
    if (!w->plan) return fail(ctx, "a prepared chain without a plan");
    mark(t, "read, to cube | plan");
    w->work = j.cube;
    if (edge != j.cube.size) {
        if (ibl_cubemap_alloc(ctx, edge, 1, &w->work) != IBL_OK ||
            ibl_cubemap_resample(ctx, &j.cube, &w->work) != IBL_OK)
            return fail(ctx, "resample");
        ibl_cubemap_free(ctx, &j.cube);
        mark(t, "resample");
    }
    return 0;
}

int main(int argc, char **argv)
{
    int task_times = argc > 1 && strcmp(argv[1], "--task-times") == 0;
    argc -= task_times, argv += task_times;
    int side_by_side = argc > 1 && strcmp(argv[1], "--side-by-side") == 0;
    argc -= side_by_side, argv += side_by_side;
    if (argc < 3) {
        fprintf(stderr, "usage: bench_stages [--task-times] [--side-by-side] IN SIZE [THREADS] [OUT.ktx2]\n");
        return 2;
    }
    const char *in = argv[1], *out = argc > 4 ? argv[4] : NULL;
    int size = atoi(argv[2]), threads = argc > 3 ? atoi(argv[3]) : 0;
    timeline t;
    memset(&t, 0, sizeof t);
    progress_marks marks = {NULL, 0, 0};
    ibl_context_desc cd;
    memset(&cd, 0, sizeof cd);
    cd.threads = threads;
    cd.allocator.alloc = cli_arena_alloc;
    cd.allocator.free = cli_arena_free;
    cd.progress = on_progress;
    cd.progress_user = &marks;
    timed_pool *pool = NULL;
    if (task_times) {
        if (threads <= 0) threads = (int)sysconf(_SC_NPROCESSORS_ONLN);
        pool = timed_pool_create(threads > 0 ? threads : 1);
        if (!pool) return 1;
        cd.parallel_for = timed_pool_parallel_for;
        cd.parallel_host = pool;
        cd.threads = threads > 2 ? threads : 2;
        t.pool = pool;
    }
    ibl_context *ctx = NULL;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    printf("%s -> GGX %d, %d threads\n%-22s %8s %8s %8s %8s %7s %6s %s  %s\n", in, size, threads,
           "stage", "wall ms", "CPU ms", "user", "sys", "faults", "RSS MB",
           pool ? "tasks ms" : "", "run time per thread, ms");
    take(&t.start);
    t.last = t.start;

    working w;
    if ((side_by_side ? working_side_by_side : working_in_turn)(ctx, &t, in, size, &w) != 0) return 1;
    ibl_specular_info info = w.info;
    ibl_cubemap work = w.work;
    ibl_specular_plan *plan = w.plan;
    marks.t = &t, marks.levels = info.levels;
    if (ibl__specular_plan_run_grids(plan, &work) != IBL_OK) return fail(ctx, "grids");
    marks.t = NULL;
    ibl_cubemap chain;
    if (ibl_cubemap_alloc(ctx, size, info.levels, &chain) != IBL_OK ||
        ibl__specular_plan_run_output(plan, &work, &chain) != IBL_OK)
        return fail(ctx, "output");
    if (w.prepared) ibl_specular_prepared_destroy(w.prepared); /* its plan with it */
    else ibl_specular_plan_destroy(plan);
    ibl_cubemap_free(ctx, &work);
    mark(&t, "output levels");

    ibl_texture chain_tex = ibl_texture_from_cubemap(&chain);
    ibl_write_desc wd = {0};
    if (ibl_specular_set_metadata(ctx, &info, &chain_tex) != IBL_OK) return fail(ctx, "metadata");
    if (out) {
        /* as the command writes it: through an output set, whose KTX2 levels are encoded
         * while the slices already encoded are written (src/io/output.c) */
        ibl_output_set *set = NULL;
        ibl_status st = ibl_output_set_create(ctx, &set);
        if (st == IBL_OK) st = ibl_output_set_add_texture(set, out, &chain_tex, &wd);
        if (st == IBL_OK) st = ibl_output_set_commit(set);
        ibl_output_set_destroy(set);
        if (st != IBL_OK) return fail(ctx, out);
        ibl_texture_free(ctx, &chain_tex);
        ibl_cubemap_free(ctx, &chain);
        mark(&t, "encode + write (KTX2)");
    } else {
        void *bytes = NULL;
        size_t bytes_size = 0;
        if (ibl_encode_texture(ctx, IBL_FILE_KTX2, &chain_tex, &wd, &bytes, &bytes_size) != IBL_OK)
            return fail(ctx, "encode");
        ibl_texture_free(ctx, &chain_tex);
        ibl_cubemap_free(ctx, &chain);
        mark(&t, "encode (KTX2)");
        ibl_free(ctx, bytes);
    }
    snapshot end;
    take(&end);
    printf("%-22s %8.1f %8.1f %8.1f %8.1f %7ld %6ld", "total", (end.wall - t.start.wall) * 1e3,
           (end.user - t.start.user + end.sys - t.start.sys) * 1e3, (end.user - t.start.user) * 1e3,
           (end.sys - t.start.sys) * 1e3, end.faults - t.start.faults, end.rss_mb);
    if (pool) printf(" %8.1f", timed_pool_task_ms(pool));
    printf("\n");
    ibl_context_destroy(ctx);
    timed_pool_destroy(pool);
    return 0;
}
