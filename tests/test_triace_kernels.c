/* tri-Ace 2010's box and Gaussian kernels: furnace and energy checks, the box chain's fitted
 * shininess against a brute-force 2D least-squares fit of the real chain's delta response,
 * the Gaussian's spread against the discrete Gaussian of the documented sigma, no filtering
 * across face edges, and bit-identical output at 1, 2 and 8 threads. */
#include "test_support.h"

#include "bake/specular_kernels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;


/* sum of L * solid angle over a level, per channel, in double */
static void level_energy(const ibl_cubemap *c, int level, double out[4])
{
    int n = ibl_level_size(c->size, level);
    memset(out, 0, 4 * sizeof(double));
    for (int f = 0; f < 6; f++) {
        const float *p = ibl_cubemap_face(c, level, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                double w = ibl_cube_texel_solid_angle(n, x, y);
                for (int i = 0; i < 4; i++) out[i] += w * p[i];
            }
    }
}

static void box_constant_and_energy(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap src, dst;
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 5, &dst), IBL_OK);
    test_fill_cube(&src, 0.25f, 3.0f, 1000.0f);
    assert_int_equal(ibl__specular_box(ctx, &src, &dst), IBL_OK);
    for (int l = 0; l < dst.levels; l++) {
        int n = ibl_level_size(16, l);
        for (int f = 0; f < 6; f++) {
            const float *p = ibl_cubemap_face(&dst, l, f);
            /* a constant resampled and area-averaged: exact up to float rounding */
            for (int i = 0; i < n * n; i++) {
                assert_near(p[i * 4 + 0], 0.25, 0.25 * 1e-6);
                assert_near(p[i * 4 + 1], 3.0, 3.0 * 1e-6);
                assert_near(p[i * 4 + 2], 1000.0, 1000.0 * 1e-6);
            }
        }
    }
    test_fill_smooth(&src);
    assert_int_equal(ibl__specular_box(ctx, &src, &dst), IBL_OK);
    double e0[4], es[4];
    level_energy(&dst, 0, e0);
    level_energy(&src, 0, es);
    /* 32 -> 16: each texel the solid-angle-weighted mean of its 2x2 source texels, so the
     * energy is exact up to float storage */
    for (int c = 0; c < 3; c++) assert_near(e0[c] / es[c], 1.0, 2e-6);
    {
        /* 24 -> 16 is no integer ratio: a supersampled resample of a smooth field, 1e-3 */
        ibl_cubemap odd, out;
        assert_int_equal(ibl_cubemap_alloc(ctx, 24, 1, &odd), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, 16, 1, &out), IBL_OK);
        test_fill_smooth(&odd);
        assert_int_equal(ibl__specular_box(ctx, &odd, &out), IBL_OK);
        double eo[4], ei[4];
        level_energy(&out, 0, eo);
        level_energy(&odd, 0, ei);
        for (int c = 0; c < 3; c++) assert_near(eo[c] / ei[c], 1.0, 1e-3);
        ibl_cubemap_free(ctx, &odd);
        ibl_cubemap_free(ctx, &out);
    }
    for (int l = 1; l < dst.levels; l++) {
        double e[4];
        level_energy(&dst, l, e);
        /* the chain is an exact area mean: only float storage per level (a few ulps) */
        for (int c = 0; c < 3; c++) assert_near(e[c] / e0[c], 1.0, 2e-6);
    }
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &dst);
    ibl_context_destroy(ctx);
}

/* Brute-force fit: the real box chain's response to a delta of unit energy in level-0 texel
 * (sx, sy) of +Z, read at level `level` with the library's seamless bilinear sampler, against
 * the normalised Phong lobe centred on each level-0 texel of the level texel holding the
 * delta (the shift average), by 2D least squares over a grid of directions. Golden section
 * in log s. */
static double brute_force_shininess(int size, int level)
{
    ibl_context *ctx = test_context(1);
    int n = ibl_level_size(size, level), sub = size / n;
    int x0 = n / 2, y0 = n / 2;
    ibl_cubemap src, dst;
    assert_int_equal(ibl_cubemap_alloc(ctx, size, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, size, level + 1, &dst), IBL_OK);
    int sx = x0 * sub + sub / 3, sy = y0 * sub + sub / 2;
    ibl_cubemap_face(&src, 0, IBL_FACE_POS_Z)[((size_t)sy * size + sx) * 4] =
        (float)(1.0 / ibl_cube_texel_solid_angle(size, sx, sy));
    assert_int_equal(ibl__specular_box(ctx, &src, &dst), IBL_OK);

    int count0 = sub * sub;
    double (*w0)[3] = malloc(sizeof(double[3]) * count0), *w0_weight = malloc(sizeof(double) * count0), wsum = 0;
    for (int j = 0; j < sub; j++)
        for (int i = 0; i < sub; i++) {
            int k = j * sub + i;
            ibl_vec3 d = ibl_cube_texel_direction(IBL_FACE_POS_Z, size, x0 * sub + i, y0 * sub + j);
            w0[k][0] = d.x, w0[k][1] = d.y, w0[k][2] = d.z;
            w0_weight[k] = ibl_cube_texel_solid_angle(size, x0 * sub + i, y0 * sub + j);
            wsum += w0_weight[k];
        }
    for (int k = 0; k < count0; k++) w0_weight[k] /= wsum;

    /* directions: a window of +Z around the lobe for narrow kernels, every face otherwise */
    int wide = n < 4, faces = wide ? 6 : 1, grid = wide ? 48 : 96;
    double lo = wide ? -1.0 : -0.6, hi = wide ? 1.0 : 0.6, h = (hi - lo) / grid;
    int cells = faces * grid * grid;
    double *area = malloc(sizeof(double) * cells), *resp = malloc(sizeof(double) * cells);
    double *logmu = malloc(sizeof(double) * (size_t)cells * count0);
    assert_non_null(logmu);
    for (int fi = 0; fi < faces; fi++) {
        int face = wide ? fi : IBL_FACE_POS_Z;
        for (int j = 0; j < grid; j++)
            for (int i = 0; i < grid; i++) {
                int c = (fi * grid + j) * grid + i;
                double u = lo + (i + 0.5) * h, v = lo + (j + 0.5) * h, d[3];
                area[c] = ibl_cube_rect_solid_angle(u - h / 2, v - h / 2, u + h / 2, v + h / 2);
                ibl_cube_direction_d(face, (u + 1) / 2, (v + 1) / 2, d);
                double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                ibl_vec3 dir = {(float)d[0], (float)d[1], (float)d[2]};
                float out[4];
                ibl_cubemap_sample_bilinear(&dst, level, dir, out);
                resp[c] = out[0];
                for (int k = 0; k < count0; k++) {
                    double mu = (d[0] * w0[k][0] + d[1] * w0[k][1] + d[2] * w0[k][2]) / l;
                    logmu[(size_t)c * count0 + k] = mu > 0 ? log(mu) : -INFINITY;
                }
            }
    }
    /* E(s) - int R^2 = sum over cells and shifts of (P^2 - 2 R P) dOmega */
#define DISTANCE(s_, out_)                                                                       \
    do {                                                                                          \
        double norm_ = ((s_) + 1.0) / (2.0 * PI), acc_ = 0;                                       \
        for (int c_ = 0; c_ < cells; c_++) {                                                      \
            double inner_ = 0;                                                                    \
            for (int k_ = 0; k_ < count0; k_++) {                                                 \
                double p_ = norm_ * exp((s_) * logmu[(size_t)c_ * count0 + k_]);                  \
                inner_ += w0_weight[k_] * (p_ * p_ - 2.0 * resp[c_] * p_);                        \
            }                                                                                     \
            acc_ += area[c_] * inner_;                                                            \
        }                                                                                         \
        (out_) = acc_;                                                                            \
    } while (0)
    double a = log(0.2 * n * n), b = log(5.0 * n * n), g = 0.5 * (sqrt(5.0) - 1.0);
    double c = b - g * (b - a), d = a + g * (b - a), ec, ed;
    DISTANCE(exp(c), ec);
    DISTANCE(exp(d), ed);
    for (int it = 0; it < 30; it++) {
        if (ec < ed) {
            b = d, d = c, ed = ec;
            c = b - g * (b - a);
            DISTANCE(exp(c), ec);
        } else {
            a = c, c = d, ec = ed;
            d = a + g * (b - a);
            DISTANCE(exp(d), ed);
        }
    }
#undef DISTANCE
    free(w0);
    free(w0_weight);
    free(area);
    free(resp);
    free(logmu);
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &dst);
    ibl_context_destroy(ctx);
    return exp(0.5 * (a + b));
}

static void box_shininess_fit(void **state)
{
    (void)state;
    /* level texels of 8x8 and 4x4 level-0 texels (near the continuum the library assumes),
     * and the 2x2 level whose kernel wraps around the cube */
    int cases[][2] = {{64, 3}, {32, 2}, {16, 3}};
    for (int i = 0; i < 3; i++) {
        double brute = brute_force_shininess(cases[i][0], cases[i][1]);
        double fit = ibl__box_level_shininess(cases[i][0], cases[i][1]);
        print_message("box chain %d level %d: fitted shininess %.2f, brute force %.2f\n", cases[i][0],
                      cases[i][1], fit, brute);
        /* different quadratures and shift samples (4x4 continuum vs the real 8x8 or 4x4
         * texels): a few percent */
        assert_near(fit / brute, 1.0, 0.04);
    }
    /* the fit depends on the level's edge only and grows like n^2 */
    assert_near(ibl__box_level_shininess(256, 2), ibl__box_level_shininess(64, 0), 0);
    for (int n = 16; n <= 256; n *= 2) {
        double r = ibl__box_level_shininess(n, 0) / ibl__box_level_shininess(n / 2, 0);
        assert_near(r, 4.0, 0.05 * 4.0);
    }
    /* the table of power-of-two edges is the fit itself, float for float; other edges fit */
    for (int n = 1; n <= 4096; n *= 2)
        assert_true(ibl__box_level_shininess(n, 0) == ibl__box_fit_shininess(n));
    assert_true(ibl__box_level_shininess(48, 0) == ibl__box_fit_shininess(48));
}

/* The box chain's tri-Ace mapping: level l's material shininess is blinn_factor times the
 * fitted kernel exponent, and lod_offset is the least-squares a of lod = a - 0.5 log2 s over
 * the levels, a = mean(l + 0.5 log2 s_l), which puts every level above 2x2 back within 0.1. */
static void box_lod_offset(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_specular_desc desc = {.filter = IBL_FILTER_BOX, .size = 16, .levels = 5};
    ibl_specular_info info;
    assert_int_equal(ibl_specular_levels(ctx, &desc, 16, &info), IBL_OK);
    assert_int_equal(info.mapping, IBL_MAPPING_TRIACE);
    double sum = 0;
    for (int l = 0; l < 5; l++) {
        double s = 4.2 * ibl__box_level_shininess(16, l);
        assert_near(info.shininess[l], s, 1e-4 * s);
        assert_near(ibl_specular_level_phong_exponent(&info, l), s / 4.2, 1e-4 * s);
        sum += l + 0.5 * log2(s);
    }
    assert_near(info.lod_offset, sum / 5, 1e-5);
    for (int l = 0; l < 3; l++) assert_near(info.lod_offset - 0.5 * log2(info.shininess[l]), l, 0.1);
    ibl_context_destroy(ctx);
}

static void gauss_constant(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap src, dst;
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 6, &dst), IBL_OK);
    test_fill_cube(&src, 0.5f, 7.0f, 250.0f);
    float shininess[6] = {1000, 200, 50, 10, 2, 1};
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, shininess), IBL_OK);
    for (int l = 0; l < dst.levels; l++) {
        int n = ibl_level_size(32, l);
        for (int f = 0; f < 6; f++) {
            const float *p = ibl_cubemap_face(&dst, l, f);
            for (int i = 0; i < n * n; i++) {
                assert_near(p[i * 4 + 0] / 0.5, 1.0, 1e-5);
                assert_near(p[i * 4 + 1] / 7.0, 1.0, 1e-5);
                assert_near(p[i * 4 + 2] / 250.0, 1.0, 1e-5);
            }
        }
    }
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &dst);
    ibl_context_destroy(ctx);
}

/* A delta at a face-centre texel spreads into the discrete Gaussian of the documented sigma:
 * sigma^2 = (n/2)^2 / (s + 3) - 1/12 texels^2, cut at ceil(4 sigma). The reference variance
 * is the discrete kernel's own, computed here. */
static void gauss_delta_spread(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int n = 64;
    float shininess[3] = {250.0f, 80.0f, 1000.0f};
    for (int i = 0; i < 3; i++) {
        double sigma = sqrt((n / 2.0) * (n / 2.0) / (shininess[i] + 3.0) - 1.0 / 12.0);
        assert_near(ibl__gauss_sigma(shininess[i], n), sigma, 1e-12);
        int r = (int)ceil(4 * sigma);
        double w = 0, wk2 = 0;
        for (int k = -r; k <= r; k++) {
            double g = exp(-0.5 * k * k / (sigma * sigma));
            w += g;
            wk2 += g * k * k;
        }
        double expect = wk2 / w;
        ibl_cubemap src, dst;
        assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &src), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &dst), IBL_OK);
        int cx = 32, cy = 31;
        ibl_cubemap_face(&src, 0, IBL_FACE_NEG_Y)[((size_t)cy * n + cx) * 4 + 1] = 1.0f;
        assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, &shininess[i]), IBL_OK);
        const float *p = ibl_cubemap_face(&dst, 0, IBL_FACE_NEG_Y);
        double sum = 0, mx = 0, my = 0, vx = 0, vy = 0, cxy = 0;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double v = p[((size_t)y * n + x) * 4 + 1];
                sum += v, mx += v * x, my += v * y;
            }
        mx /= sum, my /= sum;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double v = p[((size_t)y * n + x) * 4 + 1];
                vx += v * (x - mx) * (x - mx), vy += v * (y - my) * (y - my), cxy += v * (x - mx) * (y - my);
            }
        vx /= sum, vy /= sum, cxy /= sum;
        print_message("gauss s=%g n=%d: sigma %.4f texels, measured sd %.4f / %.4f\n", shininess[i], n,
                      sigma, sqrt(vx), sqrt(vy));
        /* every texel the delta reaches has its whole window inside the face (no cut and
         * renormalised kernel): exact up to float rounding */
        assert_true(cx - 2 * r >= 0 && cx + 2 * r < n && cy - 2 * r >= 0 && cy + 2 * r < n);
        assert_near(sum, 1.0, 1e-5);
        assert_near(mx, cx, 1e-4);
        assert_near(my, cy, 1e-4);
        assert_near(vx / expect, 1.0, 1e-4);
        assert_near(vy / expect, 1.0, 1e-4);
        assert_near(cxy, 0.0, 1e-4);
        ibl_cubemap_free(ctx, &src);
        ibl_cubemap_free(ctx, &dst);
    }
    ibl_context_destroy(ctx);
}

/* The talk's point: nothing crosses a face edge. One lit face; the five others stay exactly
 * 0 at every level, and the lit face's energy stays on it (renormalised kernel). */
static void gauss_stays_in_face(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap src, dst;
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 5, &dst), IBL_OK);
    float *lit = ibl_cubemap_face(&src, 0, IBL_FACE_POS_X);
    for (int i = 0; i < 16 * 16; i++) lit[i * 4] = (float)(1 + i % 7);
    float shininess[5] = {5, 4, 3, 2, 1};
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, shininess), IBL_OK);
    for (int l = 0; l < 5; l++) {
        int n = ibl_level_size(16, l);
        for (int f = 0; f < 6; f++) {
            const float *p = ibl_cubemap_face(&dst, l, f);
            for (int i = 0; i < n * n * 4; i++) {
                if (f != IBL_FACE_POS_X) assert_true(p[i] == 0.0f);
                else if (i % 4 == 0) assert_true(p[i] > 0.0f);
            }
        }
    }
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &dst);
    ibl_context_destroy(ctx);
}

static void gauss_arguments(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap src, dst;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 2, &dst), IBL_OK);
    float bad[2] = {10, -1};
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, bad), IBL_ERR_INVALID_ARGUMENT);
    bad[1] = NAN;
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, bad), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl__specular_box(ctx, NULL, &dst), IBL_ERR_INVALID_ARGUMENT);
    /* infinite shininess: no blur, the box chain */
    float mirror[2] = {INFINITY, INFINITY};
    test_fill_smooth(&src);
    assert_int_equal(ibl__specular_gauss(ctx, &src, &dst, mirror), IBL_OK);
    assert_memory_equal(src.data, dst.data, 6 * 8 * 8 * 4 * sizeof(float));
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &dst);
    ibl_context_destroy(ctx);
}

/* The exact Gaussian chain in double, written apart from specular_gauss.c: each level of the box
 * chain blurred by the 2D Gaussian exp(-(dx^2 + dy^2) / (2 sigma^2)) over the texels within
 * min(ceil(4 sigma), n - 1) on both axes and inside the face, renormalised by the sum of the
 * weights it used. The window is a rectangle, so the 2D sum factorises into a row sum then a
 * column sum; both are done in double. */
static void brute_gauss_level(const float *box, int n, double sigma, double *out)
{
    int r = (int)ceil(4.0 * sigma);
    if (r > n - 1) r = n - 1;
    double *rows = malloc((size_t)n * n * 4 * sizeof(double));
    for (int f = 0; f < 6; f++) {
        const float *in = box + (size_t)f * n * n * 4;
        double *o = out + (size_t)f * n * n * 4;
        for (int pass = 0; pass < 2; pass++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    int i = pass == 0 ? x : y;
                    double acc[4] = {0, 0, 0, 0}, wsum = 0;
                    for (int j = i - r; j <= i + r; j++) {
                        if (j < 0 || j >= n) continue;
                        double w = exp(-0.5 * (j - i) * (j - i) / (sigma * sigma));
                        size_t at = pass == 0 ? ((size_t)y * n + j) * 4 : ((size_t)j * n + x) * 4;
                        for (int c = 0; c < 4; c++) acc[c] += w * (pass == 0 ? in[at + c] : rows[at + c]);
                        wsum += w;
                    }
                    double *d = (pass == 0 ? rows : o) + ((size_t)y * n + x) * 4;
                    for (int c = 0; c < 4; c++) d[c] = acc[c] / wsum;
                }
    }
    free(rows);
}

/* Wide levels are blurred on a grid 2 or 4 times coarser and interpolated back
 * (specular_gauss.c "wide blurs through a Gaussian pyramid"); against the exact chain in double, on a
 * smooth sky with three 2x2 suns of 2000 (one at a face centre, one at a face edge, one at a
 * corner): the worst harm of interpolating a blurred peak. The bound, per level: max error
 * <= 0.15% of the level's largest value and RMS error <= 0.05% of its RMS. The derivation in
 * specular_gauss.c gives <= f_peak / (12 sigma_c^2) = 0.13% at sigma_c = 8 plus < 1e-4 for
 * the kernels' cuts (measured 2026-11-26: 0.026% max, 0.012% RMS at level 0). The output is
 * also the same bits on 1 and 3 threads. */
static void gauss_pyramid_vs_float64(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int n0 = 128, levels = 4;
    float exponent[4] = {0.5f, 0.5f, 2.0f, 1.0f};
    /* levels 0 and 1 take the coarse grid (k = 4 and 2), 2 and 3 the exact blur */
    int expect_k[4] = {4, 2, 1, 1};
    ibl_cubemap src, box, gauss;
    assert_int_equal(ibl_cubemap_alloc(ctx, n0, 1, &src), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, n0, levels, &box), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, n0, levels, &gauss), IBL_OK);
    test_fill_smooth(&src);
    int suns[3][3] = {{IBL_FACE_POS_Z, 63, 63}, {IBL_FACE_POS_X, 0, 70}, {IBL_FACE_NEG_Y, 126, 126}};
    for (int s = 0; s < 3; s++)
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++) {
                float *p = ibl_cubemap_face(&src, 0, suns[s][0]) +
                           ((size_t)(suns[s][2] + dy) * n0 + suns[s][1] + dx) * 4;
                p[0] = p[1] = p[2] = 2000.0f;
            }
    assert_int_equal(ibl__specular_box(ctx, &src, &box), IBL_OK);
    assert_int_equal(ibl__specular_gauss(ctx, &src, &gauss, exponent), IBL_OK);
    for (int l = 0; l < levels; l++) {
        int n = ibl_level_size(n0, l);
        double sigma = ibl__gauss_sigma(exponent[l], n);
        assert_int_equal(ibl__gauss_coarse_factor(sigma, n), expect_k[l]);
        size_t count = 6 * (size_t)n * n * 4;
        double *ref = malloc(count * sizeof(double));
        brute_gauss_level(ibl_cubemap_face(&box, l, 0), n, sigma, ref);
        const float *got = ibl_cubemap_face(&gauss, l, 0);
        double peak = 0, ref2 = 0, err2 = 0, worst = 0;
        for (size_t i = 0; i < count; i++) {
            double e = fabs(got[i] - ref[i]);
            peak = fmax(peak, fabs(ref[i]));
            worst = fmax(worst, e);
            ref2 += ref[i] * ref[i];
            err2 += e * e;
        }
        double rms = sqrt(err2 / ref2);
        print_message("gauss level %d (n %d, sigma %.2f, k %d): max err %.4f%% of peak, rms %.5f%%\n", l, n,
                      sigma, expect_k[l], 100 * worst / peak, 100 * rms);
        assert_true(worst <= 1.5e-3 * peak);
        assert_true(rms <= 5e-4);
        free(ref);
    }
    for (int threads = 1; threads <= 3; threads += 2) {
        ibl_context *other = test_context(threads);
        ibl_cubemap again;
        assert_int_equal(ibl_cubemap_alloc(other, n0, levels, &again), IBL_OK);
        assert_int_equal(ibl__specular_gauss(other, &src, &again, exponent), IBL_OK);
        assert_memory_equal(again.data, gauss.data, ibl_cubemap_floats(n0, levels) * sizeof(float));
        ibl_cubemap_free(other, &again);
        ibl_context_destroy(other);
    }
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &box);
    ibl_cubemap_free(ctx, &gauss);
    ibl_context_destroy(ctx);
}

static void identical_at_any_thread_count(void **state)
{
    (void)state;
    int threads[3] = {1, 2, 8};
    float *ref_box = NULL, *ref_gauss = NULL;
    size_t floats = ibl_cubemap_floats(32, 6);
    float shininess[6] = {900, 250, 60, 15, 4, 1};
    /* 64: the block-mean level 0; 48: the resampled one */
    for (int t = 0; t < 6; t++) {
        ibl_context *ctx = test_context(threads[t % 3]);
        ibl_cubemap src, box, gauss;
        assert_int_equal(ibl_cubemap_alloc(ctx, t < 3 ? 64 : 48, 1, &src), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, 32, 6, &box), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, 32, 6, &gauss), IBL_OK);
        test_fill_smooth(&src);
        assert_int_equal(ibl__specular_box(ctx, &src, &box), IBL_OK);
        assert_int_equal(ibl__specular_gauss(ctx, &src, &gauss, shininess), IBL_OK);
        if (t % 3 == 0) {
            free(ref_box);
            free(ref_gauss);
            ref_box = malloc(floats * sizeof(float));
            ref_gauss = malloc(floats * sizeof(float));
            memcpy(ref_box, box.data, floats * sizeof(float));
            memcpy(ref_gauss, gauss.data, floats * sizeof(float));
        } else {
            assert_memory_equal(ref_box, box.data, floats * sizeof(float));
            assert_memory_equal(ref_gauss, gauss.data, floats * sizeof(float));
        }
        ibl_cubemap_free(ctx, &src);
        ibl_cubemap_free(ctx, &box);
        ibl_cubemap_free(ctx, &gauss);
        ibl_context_destroy(ctx);
    }
    free(ref_box);
    free(ref_gauss);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(box_constant_and_energy),
        cmocka_unit_test(box_shininess_fit),
        cmocka_unit_test(box_lod_offset),
        cmocka_unit_test(gauss_constant),
        cmocka_unit_test(gauss_delta_spread),
        cmocka_unit_test(gauss_stays_in_face),
        cmocka_unit_test(gauss_arguments),
        cmocka_unit_test(gauss_pyramid_vs_float64),
        cmocka_unit_test(identical_at_any_thread_count),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
