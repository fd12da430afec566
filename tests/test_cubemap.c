/* Cube geometry, exact solid angles, seamless sampling and the mip chain, against analytic
 * values and a brute-force double integral. */
#include "test_support.h"
#include "core/context_internal.h"

#include <math.h>
#include <pthread.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Spherical-quadrilateral areas computed independently (the closed form of Driscoll 2012
 * against numerical integration of the face's area element); tolerance 1e-12 in double. */
static void solid_angle_vectors(void **state)
{
    (void)state;
    assert_near(ibl_cube_texel_solid_angle(1, 0, 0), 2.0943951023931957, 1e-12);
    assert_near(ibl_cube_texel_solid_angle(8, 0, 0), 0.0155686078666, 1e-12);
    assert_near(ibl_cube_texel_solid_angle(8, 4, 4), 0.0588575059471, 1e-12);
    for (int n = 1; n <= 512; n = n < 8 ? n + 1 : n * 2) {
        double sum = 0;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) sum += ibl_cube_texel_solid_angle(n, x, y);
        assert_near(sum, 2.0 * PI / 3.0, 1e-12);
    }
}

/* Independent reference: midpoint-rule integral of the Jacobian 1/(1+u^2+v^2)^(3/2). */
static void solid_angle_brute_force(void **state)
{
    (void)state;
    int n = 5, sub = 400;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            double acc = 0, h = 2.0 / n / sub;
            for (int j = 0; j < sub; j++) {
                for (int i = 0; i < sub; i++) {
                    double u = -1 + 2.0 * x / n + (i + 0.5) * h;
                    double v = -1 + 2.0 * y / n + (j + 0.5) * h;
                    acc += h * h / pow(1 + u * u + v * v, 1.5);
                }
            }
            /* midpoint rule error is O(h^2) ~ 1e-7 relative here */
            assert_near(ibl_cube_texel_solid_angle(n, x, y), acc, 1e-7);
        }
    }
}

static void direction_round_trip(void **state)
{
    (void)state;
    srand(7);
    for (int i = 0; i < 20000; i++) {
        double d[3] = {rand() / (double)RAND_MAX - 0.5, rand() / (double)RAND_MAX - 0.5,
                       rand() / (double)RAND_MAX - 0.5};
        double s, t, back[3];
        int f = ibl_cube_face_st_d(d, &s, &t);
        assert_true(s >= 0 && s <= 1 && t >= 0 && t <= 1);
        ibl_cube_direction_d(f, s, t, back);
        double la = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double lb = sqrt(back[0] * back[0] + back[1] * back[1] + back[2] * back[2]);
        for (int k = 0; k < 3; k++) assert_near(d[k] / la, back[k] / lb, 1e-12);
        ibl_vec3 v = {(float)d[0], (float)d[1], (float)d[2]};
        float sf, tf;
        assert_int_equal(ibl_cube_face_st(v, &sf, &tf), f);
        assert_near(sf, s, 1e-5);
        assert_near(tf, t, 1e-5);
    }
}

/* The OpenGL/Vulkan table, checked at face centres and at s = 1 (sc = +1) and t = 1. */
static void face_orientation(void **state)
{
    (void)state;
    static const float expect[6][3][3] = {
        /* centre, s = 1 edge centre, t = 1 edge centre */
        {{1, 0, 0}, {1, 0, -1}, {1, -1, 0}},
        {{-1, 0, 0}, {-1, 0, 1}, {-1, -1, 0}},
        {{0, 1, 0}, {1, 1, 0}, {0, 1, 1}},
        {{0, -1, 0}, {1, -1, 0}, {0, -1, -1}},
        {{0, 0, 1}, {1, 0, 1}, {0, -1, 1}},
        {{0, 0, -1}, {-1, 0, -1}, {0, -1, -1}},
    };
    for (int f = 0; f < 6; f++) {
        ibl_vec3 c = ibl_cube_direction(f, 0.5f, 0.5f);
        ibl_vec3 s = ibl_cube_direction(f, 1.0f, 0.5f);
        ibl_vec3 t = ibl_cube_direction(f, 0.5f, 1.0f);
        assert_near(c.x, expect[f][0][0], 0); assert_near(c.y, expect[f][0][1], 0); assert_near(c.z, expect[f][0][2], 0);
        assert_near(s.x, expect[f][1][0], 0); assert_near(s.y, expect[f][1][1], 0); assert_near(s.z, expect[f][1][2], 0);
        assert_near(t.x, expect[f][2][0], 0); assert_near(t.y, expect[f][2][1], 0); assert_near(t.z, expect[f][2][2], 0);
    }
}


static void mips_constant_and_energy(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 64, ibl_full_mip_count(64), &cube), IBL_OK);
    assert_int_equal(cube.levels, 7);
    test_fill_cube(&cube, 0.3f, 1.7f, 12345.0f);
    assert_int_equal(ibl_cubemap_build_mips(ctx, &cube), IBL_OK);
    for (int l = 0; l < cube.levels; l++) {
        int n = ibl_level_size(cube.size, l);
        for (int f = 0; f < 6; f++) {
            const float *p = ibl_cubemap_face(&cube, l, f);
            for (int i = 0; i < n * n; i++) {
                assert_true(p[i * 4 + 0] == 0.3f);
                assert_true(p[i * 4 + 1] == 1.7f);
                assert_true(p[i * 4 + 2] == 12345.0f);
            }
        }
    }
    test_fill_smooth(&cube);
    assert_int_equal(ibl_cubemap_build_mips(ctx, &cube), IBL_OK);
    double m0[4];
    ibl_cubemap_mean(&cube, 0, m0);
    for (int l = 1; l < cube.levels; l++) {
        double m[4];
        ibl_cubemap_mean(&cube, l, m);
        /* float storage of each level: a few ulps of relative error */
        for (int c = 0; c < 3; c++) assert_near(m[c] / m0[c], 1.0, 2e-6);
    }
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

/* Bilinear samples vary continuously across every face edge and corner. */
static void seamless_sampling(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &cube), IBL_OK);
    test_fill_smooth(&cube);
    srand(3);
    for (int i = 0; i < 20000; i++) {
        /* a point on an edge or corner, then two sides a hair apart */
        float a = rand() / (float)RAND_MAX * 2 - 1;
        ibl_vec3 edge[3] = {{1, 1, a}, {a, 1, -1}, {1, a, 1}};
        ibl_vec3 corner = {1, -1, 1};
        ibl_vec3 p = i % 4 == 3 ? corner : edge[i % 3];
        float e = 1e-4f;
        ibl_vec3 d1 = {p.x + e * (rand() % 3 - 1), p.y + e * (rand() % 3 - 1), p.z + e * (rand() % 3 - 1)};
        ibl_vec3 d2 = {p.x + e * (rand() % 3 - 1), p.y + e * (rand() % 3 - 1), p.z + e * (rand() % 3 - 1)};
        float c1[4], c2[4];
        ibl_cubemap_sample_bilinear(&cube, 0, d1, c1);
        ibl_cubemap_sample_bilinear(&cube, 0, d2, c2);
        /* values are O(1..20), gradient O(20) per radian: 1e-4 apart gives < 1e-2 */
        for (int c = 0; c < 3; c++) assert_near(c1[c], c2[c], 2e-2);
    }
    /* at a texel centre bilinear returns the texel */
    float out[4];
    ibl_vec3 d = ibl_cube_texel_direction(IBL_FACE_POS_Z, 8, 3, 5);
    ibl_cubemap_sample_bilinear(&cube, 0, d, out);
    assert_near(out[2], ibl_cubemap_face(&cube, 0, IBL_FACE_POS_Z)[(5 * 8 + 3) * 4 + 2], 1e-4);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

static void trilinear_between_levels(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 4, 3, &cube), IBL_OK);
    for (int l = 0; l < 3; l++) {
        int n = ibl_level_size(4, l);
        for (int f = 0; f < 6; f++) {
            float *p = ibl_cubemap_face(&cube, l, f);
            for (int i = 0; i < n * n * 4; i++) p[i] = (float)(l * 10);
        }
    }
    ibl_vec3 d = {0.3f, -0.2f, 0.9f};
    float out[4];
    ibl_cubemap_sample_trilinear(&cube, 0.25f, d, out);
    assert_near(out[0], 2.5, 1e-5);
    ibl_cubemap_sample_trilinear(&cube, 1.5f, d, out);
    assert_near(out[0], 15.0, 1e-5);
    ibl_cubemap_sample_trilinear(&cube, 9.0f, d, out);
    assert_near(out[0], 20.0, 1e-5);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

static void texture_layout_matches_cubemap(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 5, &cube), IBL_OK);
    ibl_texture t = ibl_texture_from_cubemap(&cube);
    for (int l = 0; l < 5; l++)
        for (int f = 0; f < 6; f++) assert_ptr_equal(ibl_texture_level(&t, l, f), ibl_cubemap_face(&cube, l, f));
    assert_int_equal(ibl_texture_floats(IBL_TEXTURE_CUBE, 16, 16, 1, 5), ibl_cubemap_floats(16, 5));
    /* overflow and absurd sizes are refused before allocating */
    assert_int_equal(ibl_texture_floats(IBL_TEXTURE_3D, 1 << 30, 1 << 30, 1 << 30, 1), 0);
    assert_int_equal(ibl_texture_floats(IBL_TEXTURE_CUBE, 8, 16, 1, 1), 0);
    ibl_texture big;
    assert_int_not_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_2D, 1 << 20, 1 << 20, 1, 1, &big), IBL_OK);
    assert_int_equal(ibl_texture_set_metadata(ctx, &t, "a", "1"), IBL_OK);
    assert_int_equal(ibl_texture_set_metadata(ctx, &t, "a", "2"), IBL_OK);
    assert_string_equal(ibl_texture_get_metadata(&t, "a"), "2");
    ibl_texture_free(ctx, &t); /* frees the metadata only */
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

static void sanitize_policy(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    float px[12] = {NAN, 1, 2, 1, -0.5f, 3, 4, 1, INFINITY, 0, 0, 1};
    ibl_pixel_report r;
    assert_int_equal(ibl_sanitize_pixels(ctx, px, 3, 0, 0, &r), IBL_ERR_BAD_PIXELS);
    assert_int_equal(r.nan_count, 1);
    assert_int_equal(r.negative_count, 1);
    assert_int_equal(r.inf_count, 1);
    assert_true(px[0] == 0 && px[4] == 0);
    assert_int_equal(ibl_sanitize_pixels(ctx, px, 3, 1, 0, &r), IBL_OK);
    assert_true(px[8] == 65504.0f);
    ibl_context_destroy(ctx);
}

/* The table of a face's solid angles is the per-texel function, and a face is 4 pi / 6. */
static void solid_angle_table(void **state)
{
    (void)state;
    enum { N = 13 };
    float table[N * N];
    ibl_cube_solid_angle_table(N, table);
    double sum = 0;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            assert_near(table[y * N + x], ibl_cube_texel_solid_angle(N, x, y), 1e-7 * table[y * N + x]);
            sum += table[y * N + x];
        }
    assert_near(sum, 4.0 * PI / 6.0, 1e-6);
}

static void count_hit(void *arg, int index)
{
    __atomic_fetch_add(&((int *)arg)[index], 1, __ATOMIC_RELAXED);
}

static void parallel_for_covers_every_index(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(4);
    static int hits[1000];
    memset(hits, 0, sizeof hits);
    for (int rep = 0; rep < 50; rep++) ibl_parallel_for(ctx, 1000, count_hit, hits);
    for (int i = 0; i < 1000; i++) assert_int_equal(hits[i], 50);
    ibl_context_destroy(ctx);
}

/* ibl__parallel_warm wakes the pool's workers without a job: loops after it still run every
 * index exactly once (a worker that joined the empty job would run the last loop's indices
 * again), on more than one thread (the warm call leaves the pool free), and inside a task it
 * is a no-op (the pool is busy) rather than a deadlock. */
typedef struct warm_job {
    ibl_context *ctx;
    int hits[64];
    pthread_t thread[64];
} warm_job;

static void warm_task(void *arg, int index)
{
    warm_job *j = arg;
    if (index == 0) ibl__parallel_warm(j->ctx); /* nested: must return at once */
    j->thread[index] = pthread_self();
    struct timespec t0, t;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    do clock_gettime(CLOCK_MONOTONIC, &t); /* 0.1 ms of work: the other thread gets a share */
    while ((t.tv_sec - t0.tv_sec) * 1000000000L + (t.tv_nsec - t0.tv_nsec) < 100000L);
    __atomic_fetch_add(&j->hits[index], 1, __ATOMIC_RELAXED);
}

static void parallel_warm_then_loop(void **state)
{
    (void)state;
    ibl__parallel_warm(NULL);
    ibl_context *single = test_context(1);
    ibl__parallel_warm(single);
    ibl_context_destroy(single);
    ibl_context *ctx = test_context(2);
    static warm_job j;
    memset(&j, 0, sizeof j);
    j.ctx = ctx;
    int shared = 0;
    enum { REPS = 20 };
    for (int rep = 0; rep < REPS; rep++) {
        ibl__parallel_warm(ctx);
        if (rep % 2) ibl__parallel_warm(ctx); /* twice in a row: still no job */
        ibl_parallel_for(ctx, 64, warm_task, &j);
        for (int i = 1; i < 64; i++)
            if (!pthread_equal(j.thread[i], j.thread[0])) {
                shared++;
                break;
            }
    }
    for (int i = 0; i < 64; i++) assert_int_equal(j.hits[i], REPS);
    assert_true(shared > 0);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(solid_angle_vectors),
        cmocka_unit_test(solid_angle_brute_force),
        cmocka_unit_test(direction_round_trip),
        cmocka_unit_test(face_orientation),
        cmocka_unit_test(mips_constant_and_energy),
        cmocka_unit_test(seamless_sampling),
        cmocka_unit_test(trilinear_between_levels),
        cmocka_unit_test(texture_layout_matches_cubemap),
        cmocka_unit_test(sanitize_policy),
        cmocka_unit_test(solid_angle_table),
        cmocka_unit_test(parallel_for_covers_every_index),
        cmocka_unit_test(parallel_warm_then_loop),
    };
    return cmocka_run_group_tests_name("cubemap", tests, NULL, NULL);
}
