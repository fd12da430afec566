/* Helpers shared by the image I/O tests (test_io.c, test_exr.c): a deterministic random
 * number, the exact half rounding, images, in-memory decoding and a write-read round trip. */
#ifndef IBL_TEST_IO_HELPERS_H
#define IBL_TEST_IO_HELPERS_H

#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One stream per test program (the programs are single-threaded). */
static uint32_t rng_state = 12345;
static inline float frand(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)((rng_state >> 8) / 16777216.0);
}

/* The float nearest to v that a half holds exactly (round to nearest, in double: independent
 * of the library's conversion), for values inside half's normal range. */
static inline float ibl_half_to_float_exact(float v)
{
    if (v == 0.0f) return 0.0f;
    int e;
    frexp((double)v, &e);
    if (e < -13) e = -13; /* half denormals: a fixed step of 2^-24 */
    double step = ldexp(1.0, e - 11);
    double r = nearbyint((double)v / step) * step;
    return (float)(r > 65504.0 ? 65504.0 : r);
}

static inline ibl_image make_image(ibl_context *ctx, int w, int h)
{
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, w, h, &im), IBL_OK);
    return im;
}

static inline uint8_t *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)n + 1);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return b;
}

static inline void spit(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
}

static inline ibl_status decode(ibl_context *ctx, const void *b, size_t n, ibl_texture *t, ibl_file_info *fi)
{
    return ibl_decode_texture(ctx, b, n, "mem.bin", NULL, t, fi);
}

/* Writes an image to path and reads it back. */
static inline ibl_image write_read(ibl_context *ctx, const char *name, const ibl_image *im,
                            const ibl_write_desc *wd, ibl_file_info *fi)
{
    const char *path = test_path(name);
    assert_int_equal(ibl_write_image(ctx, path, im, wd), IBL_OK);
    ibl_image back;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &back, fi), IBL_OK);
    assert_int_equal(back.width, im->width);
    assert_int_equal(back.height, im->height);
    return back;
}

static inline int bits_equal(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

#endif
