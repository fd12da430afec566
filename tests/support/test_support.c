#include "test_support.h"

#include <png.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[256];

static void remove_tmpdir(void)
{
    if (!tmpdir[0]) return;
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
}

ibl_context *test_context(int threads)
{
    ibl_context_desc d = {0};
    d.threads = threads;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    return ctx;
}

const char *test_tmpdir(void)
{
    if (!tmpdir[0]) {
        snprintf(tmpdir, sizeof tmpdir, "/tmp/ibl-test-XXXXXX");
        if (!mkdtemp(tmpdir)) {
            fprintf(stderr, "mkdtemp failed\n");
            abort();
        }
        atexit(remove_tmpdir);
    }
    return tmpdir;
}

const char *test_path(const char *name)
{
    static char buf[8][512];
    static int next;
    char *b = buf[next++ & 7];
    snprintf(b, 512, "%s/%s", test_tmpdir(), name);
    return b;
}

const char *test_data(const char *name)
{
    static char buf[8][512];
    static int next;
    char *b = buf[next++ & 7];
    snprintf(b, 512, "%s/%s", IBL_TEST_DATA, name);
    return b;
}

int test_run_cli(const char **out, const char *fmt, ...)
{
    static char output[65536];
    char args[4096], cmd[4608];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof cmd, "'%s' %s 2>&1", IBL_CLI_PATH, args);
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    size_t n = fread(output, 1, sizeof output - 1, p);
    output[n] = 0;
    int rc = pclose(p);
    if (out) *out = output;
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

int test_file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

void test_assert_near(double a, double b, double tol, const char *expr, const char *file, int line)
{
    double d = a - b;
    if (!(d <= tol && -d <= tol)) {
        fail_msg("%s:%d: %s = %.12g, expected %.12g within %.3g (off by %.3g)", file, line, expr, a,
                 b, tol, d);
    }
}

void test_fill_cube(ibl_cubemap *cube, float r, float g, float b)
{
    size_t n = ibl_cubemap_floats(cube->size, cube->levels) / 4;
    for (size_t i = 0; i < n; i++) {
        cube->data[i * 4 + 0] = r;
        cube->data[i * 4 + 1] = g;
        cube->data[i * 4 + 2] = b;
        cube->data[i * 4 + 3] = 1.0f;
    }
}

void test_texel_dir(int face, int n, int x, int y, double d[3])
{
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++) d[i] /= len;
}

void test_fill_cube_fn(ibl_cubemap *cube, void (*fn)(const double *, float *))
{
    int n = cube->size;
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(cube, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                double d[3];
                test_texel_dir(f, n, x, y, d);
                fn(d, p);
                p[3] = 1.0f;
            }
    }
}

void test_fill_smooth(ibl_cubemap *cube)
{
    int n = cube->size;
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(cube, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                p[0] = 1.0f + d.x;
                p[1] = 2.0f + d.y * d.z;
                p[2] = expf(3.0f * d.z);
                p[3] = 1.0f;
            }
    }
}

uint64_t test_fnv1a(const void *data, size_t bytes)
{
    const unsigned char *p = data;
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < bytes; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static void png_sink_write(png_structp png, png_bytep data, size_t n)
{
    test_bytes *m = png_get_io_ptr(png);
    if (m->n + n > m->cap) {
        m->cap = (m->n + n) * 2;
        m->b = realloc(m->b, m->cap);
        assert_non_null(m->b);
    }
    memcpy(m->b + m->n, data, n);
    m->n += n;
}

static void png_sink_flush(png_structp png)
{
    (void)png;
}

void test_png_write_to_memory(void *png_write_struct, test_bytes *out)
{
    png_set_write_fn((png_structp)png_write_struct, out, png_sink_write, png_sink_flush);
}


typedef struct host_loop {
    atomic_int next;
    int count;
    ibl_task_fn task;
    void *arg;
} host_loop;

static void *host_loop_run(void *p)
{
    host_loop *h = p;
    for (int i; (i = atomic_fetch_add(&h->next, 1)) < h->count;) h->task(h->arg, i);
    return NULL;
}

void test_host_parallel_for(void *host, int count, ibl_task_fn task, void *task_arg)
{
    test_host *t = host;
    /* loops may start inside tasks, on any thread */
    int seen = atomic_load(&t->largest_loop);
    while (count > seen && !atomic_compare_exchange_weak(&t->largest_loop, &seen, count)) {}
    host_loop h = {0, count, task, task_arg};
    enum { MAX_EXTRA = 15 };
    pthread_t extra[MAX_EXTRA];
    int started = 0;
    while (started < t->threads - 1 && started < MAX_EXTRA &&
           pthread_create(&extra[started], NULL, host_loop_run, &h) == 0)
        started++;
    host_loop_run(&h); /* whatever no thread took (all of it if none started) */
    for (int i = 0; i < started; i++) pthread_join(extra[i], NULL);
}
