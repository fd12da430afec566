/* Shared helpers for the cmocka test programs. */
#ifndef IBL_TEST_SUPPORT_H
#define IBL_TEST_SUPPORT_H

#include <setjmp.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "ibl/ibl.h"

/* A context with `threads` threads (0: all cores); fails the test if creation fails. */
ibl_context *test_context(int threads);
/* A fresh empty temporary directory for this test program (removed at exit). */
const char *test_tmpdir(void);
/* test_tmpdir()/name in a static rotating buffer. */
const char *test_path(const char *name);
/* Path of a file in tests/data. */
const char *test_data(const char *name);
/* Runs the ibl CLI with a printf-style argument string through /bin/sh; returns the exit
 * code and, if out is not NULL, stores the combined stdout+stderr (static buffer). */
int test_run_cli(const char **out, const char *fmt, ...);
int test_file_exists(const char *path);
/* Asserts |a - b| <= tol with a readable message. */
#define assert_near(a, b, tol) test_assert_near((double)(a), (double)(b), (double)(tol), #a, __FILE__, __LINE__)
void test_assert_near(double a, double b, double tol, const char *expr, const char *file, int line);
/* FNV-1a 64 of bytes: the tests that pin output bits hash them with it. */
uint64_t test_fnv1a(const void *data, size_t bytes);

/* A growing buffer in memory (free b when done). */
typedef struct test_bytes {
    uint8_t *b;
    size_t n, cap;
} test_bytes;
/* Makes a libpng write struct (png_structp) write into out. */
void test_png_write_to_memory(void *png_write_struct, test_bytes *out);

/* A host's parallel-for (ibl_context_desc.parallel_for with .parallel_host a test_host): each
 * loop runs on the calling thread and threads - 1 threads started for it, which take its
 * indices from one counter; the host remembers the largest loop it was given. */
typedef struct test_host {
    int threads;
    atomic_int largest_loop;
} test_host;
void test_host_parallel_for(void *host, int count, ibl_task_fn task, void *task_arg);

/* Fills a cube with a constant colour. */
void test_fill_cube(ibl_cubemap *cube, float r, float g, float b);
/* Fills level 0 with a smooth colour field of the texel direction (1 + x, 2 + y z, e^(3 z)). */
void test_fill_smooth(ibl_cubemap *cube);
/* The unit direction (double) through the centre of texel (x, y) of a face of edge n. */
void test_texel_dir(int face, int n, int x, int y, double d[3]);
/* Fills level 0 with fn(direction, rgb) at every texel centre, alpha 1. */
void test_fill_cube_fn(ibl_cubemap *cube, void (*fn)(const double *, float *));

#endif
