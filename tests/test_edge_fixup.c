/* Edge fixups (overlap, overlap2, bent, warp) against independent geometry: seam partners
 * are found by brute force (nearest texel on another face, or the mirror image across the
 * plane bisecting two faces), never with the library's own neighbour code, and the bent
 * kernel's effect is measured with a slow float64 Phong convolution written here. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

typedef struct tref {
    int face, x, y;
} tref;

static void dir_of(ibl_vec3 v, double d[3])
{
    double l = sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
    d[0] = v.x / l, d[1] = v.y / l, d[2] = v.z / l;
}

static double angle_d(const double a[3], const double b[3])
{
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    return atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

static double angle_v(ibl_vec3 a, ibl_vec3 b)
{
    double da[3], db[3];
    dir_of(a, da);
    dir_of(b, db);
    return angle_d(da, db);
}

static void centre(int face, int n, int x, int y, double d[3])
{
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++) d[i] /= l;
}

/* The `count` texels nearest to (face, x, y) on other faces, one per face, nearest first. */
static int nearest_on_other_faces(int face, int n, int x, int y, tref *out, int count)
{
    double c[3];
    centre(face, n, x, y, c);
    double best_a[6];
    tref best[6];
    for (int g = 0; g < 6; g++) {
        best_a[g] = 1e9;
        if (g == face) continue;
        for (int yy = 0; yy < n; yy++)
            for (int xx = 0; xx < n; xx++) {
                double d[3];
                centre(g, n, xx, yy, d);
                double a = angle_d(c, d);
                if (a < best_a[g]) best_a[g] = a, best[g] = (tref){g, xx, yy};
            }
    }
    for (int k = 0; k < count; k++) {
        int arg = -1;
        for (int g = 0; g < 6; g++)
            if (best_a[g] < 1e8 && (arg < 0 || best_a[g] < best_a[arg])) arg = g;
        out[k] = best[arg];
        best_a[arg] = 1e9;
    }
    return count;
}

static float *texel(ibl_cubemap *c, int level, tref r)
{
    int n = ibl_level_size(c->size, level);
    return ibl_cubemap_face(c, level, r.face) + ((size_t)r.y * n + r.x) * 4;
}

static void fill_random(ibl_cubemap *c, unsigned seed)
{
    srand(seed);
    size_t count = ibl_cubemap_floats(c->size, c->levels);
    for (size_t i = 0; i < count; i++) c->data[i] = (float)(rand() % 1000) / 37.0f;
}

static int is_edge(int n, int x, int y) { return x == 0 || y == 0 || x == n - 1 || y == n - 1; }
static int is_corner(int n, int x, int y) { return (x == 0 || x == n - 1) && (y == 0 || y == n - 1); }

static void names(void **state)
{
    (void)state;
    const char *all[] = {"none", "overlap", "overlap2", "bent", "warp"};
    for (int i = 0; i < 5; i++) {
        ibl_edge_fixup f = IBL_EDGE_FIXUP_NONE;
        assert_int_equal(ibl_edge_fixup_from_name(all[i], &f), 1);
        assert_int_equal((int)f, i);
        assert_string_equal(ibl_edge_fixup_name(f), all[i]);
    }
    ibl_edge_fixup f = IBL_EDGE_FIXUP_WARP;
    assert_int_equal(ibl_edge_fixup_from_name("Overlap2", &f), 1);
    assert_int_equal(f, IBL_EDGE_FIXUP_OVERLAP2);
    f = IBL_EDGE_FIXUP_WARP;
    assert_int_equal(ibl_edge_fixup_from_name("overlap3", &f), 0);
    assert_int_equal(ibl_edge_fixup_from_name("", &f), 0);
    assert_int_equal(ibl_edge_fixup_from_name(NULL, &f), 0);
    assert_int_equal(f, IBL_EDGE_FIXUP_WARP); /* unchanged */
}

/* Overlap: across all 12 seams the partner texels are equal (bit for bit) and equal to the
 * mean of the two originals; the three texels at each of the 8 corners equal the mean of
 * their originals; every other texel is untouched. Partners by brute-force nearest texel. */
static void overlap_seams_and_corners(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int sizes[] = {8, 5, 3, 2};
    for (int si = 0; si < 4; si++) {
        int n = sizes[si];
        ibl_cubemap cube, orig;
        assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &cube), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &orig), IBL_OK);
        fill_random(&cube, 11u + (unsigned)n);
        memcpy(orig.data, cube.data, ibl_cubemap_floats(n, 1) * sizeof(float));
        assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP, &cube, 0), IBL_OK);
        int pairs = 0, corners = 0;
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    tref t = {f, x, y}, p[2];
                    float *now = texel(&cube, 0, t), *was = texel(&orig, 0, t);
                    if (!is_edge(n, x, y)) {
                        for (int c = 0; c < 4; c++) assert_true(now[c] == was[c]);
                        continue;
                    }
                    int corner = is_corner(n, x, y);
                    nearest_on_other_faces(f, n, x, y, p, corner ? 2 : 1);
                    for (int c = 0; c < 4; c++) {
                        double expect = was[c];
                        for (int k = 0; k < (corner ? 2 : 1); k++) expect += texel(&orig, 0, p[k])[c];
                        expect /= corner ? 3.0 : 2.0;
                        /* float storage of a mean of values < 30: a few ulps */
                        assert_near(now[c], expect, 1e-5);
                        for (int k = 0; k < (corner ? 2 : 1); k++) assert_true(texel(&cube, 0, p[k])[c] == now[c]);
                    }
                    corner ? corners++ : pairs++;
                }
        /* 12 seams of n - 2 pairs (each pair seen from both sides), 8 corners of 3 texels */
        assert_int_equal(pairs, 2 * 12 * (n - 2));
        assert_int_equal(corners, 3 * 8);
        ibl_cubemap_free(ctx, &cube);
        ibl_cubemap_free(ctx, &orig);
    }
    ibl_context_destroy(ctx);
}

/* A 1x1 level becomes the mean of all six faces for overlap, overlap2, bent and warp; none
 * leaves it alone. Levels other than the one named are untouched. */
static void one_by_one_level(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_edge_fixup all[] = {IBL_EDGE_FIXUP_NONE, IBL_EDGE_FIXUP_OVERLAP, IBL_EDGE_FIXUP_OVERLAP2,
                            IBL_EDGE_FIXUP_BENT, IBL_EDGE_FIXUP_WARP};
    for (int i = 0; i < 5; i++) {
        ibl_cubemap cube;
        assert_int_equal(ibl_cubemap_alloc(ctx, 4, 3, &cube), IBL_OK);
        fill_random(&cube, 5);
        float before[6][4], level1[6 * 4 * 4];
        for (int f = 0; f < 6; f++) memcpy(before[f], ibl_cubemap_face(&cube, 2, f), sizeof before[f]);
        memcpy(level1, ibl_cubemap_face(&cube, 1, 0), sizeof level1);
        assert_int_equal(ibl_edge_fixup_apply(ctx, all[i], &cube, 2), IBL_OK);
        for (int c = 0; c < 4; c++) {
            double mean = 0;
            for (int f = 0; f < 6; f++) mean += before[f][c] / 6.0;
            for (int f = 0; f < 6; f++) {
                float v = ibl_cubemap_face(&cube, 2, f)[c];
                if (all[i] == IBL_EDGE_FIXUP_NONE) assert_true(v == before[f][c]);
                else assert_near(v, mean, 1e-5);
            }
        }
        assert_memory_equal(level1, ibl_cubemap_face(&cube, 1, 0), sizeof level1);
        ibl_cubemap_free(ctx, &cube);
    }
    ibl_context_destroy(ctx);
}

/* Overlap2, hand-computed: every face constant (+X 1, -X 2, +Y 3, -Y 4, +Z 5, -Z 6), n = 6.
 * On +Z (OpenGL table: s = 1 is +x, so x = n-1 borders +X; t = 0 is +y, so y = 0 borders
 * +Y; t = 1 borders -Y; x = 0 borders -X):
 *   edge texel next to +X            (5 + 1) / 2            = 3
 *   one texel in from the +X edge    3/4 * 5 + 1/4 * 1       = 4
 *   one in from +X and from +Y       1/2 * 5 + 1/4 (1 + 3)   = 3.5
 *   corner +Z/+X/+Y                  (5 + 1 + 3) / 3         = 3
 *   edge texel next to +Y            (5 + 3) / 2            = 4
 *   one in from -X and from -Y       1/2 * 5 + 1/4 (2 + 4)   = 4
 *   interior                         5 */
static void overlap2_hand_case(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int n = 6;
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &cube), IBL_OK);
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(&cube, 0, f);
        for (int i = 0; i < n * n * 4; i++) p[i] = (float)(f + 1);
    }
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP2, &cube, 0), IBL_OK);
    const float *z = ibl_cubemap_face(&cube, 0, IBL_FACE_POS_Z);
#define AT(x, y) z[((y) * n + (x)) * 4]
    assert_near(AT(n - 1, 2), 3.0, 1e-6);
    assert_near(AT(n - 2, 2), 4.0, 1e-6);
    assert_near(AT(n - 2, 3), 4.0, 1e-6);
    assert_near(AT(n - 2, 1), 3.5, 1e-6);
    assert_near(AT(n - 1, 0), 3.0, 1e-6);
    assert_near(AT(n - 2, 0), 4.0, 1e-6);
    assert_near(AT(2, 0), 4.0, 1e-6);
    assert_near(AT(1, n - 2), 4.0, 1e-6);
    assert_near(AT(2, 2), 5.0, 0);
    assert_near(AT(3, 3), 5.0, 0);
#undef AT
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

/* The mirror image of texel (face, x, y) across the plane bisecting its face and the
 * neighbour in axis direction `axis` (0: x, 1: y, 2: z) with sign `sign`: the neighbour's
 * texel at the same depth. Reflection d - 2 (d.k) k, k = (m - a) / |m - a|. */
static tref mirror_partner(int face, int n, int x, int y, const double a[3])
{
    double d[3], m[3], k[3];
    centre(face, n, x, y, d);
    ibl_cube_direction_d(face, 0.5, 0.5, m);
    double kl = 0;
    for (int i = 0; i < 3; i++) k[i] = m[i] - a[i], kl += k[i] * k[i];
    kl = sqrt(kl);
    double dk = 0;
    for (int i = 0; i < 3; i++) k[i] /= kl, dk += d[i] * k[i];
    for (int i = 0; i < 3; i++) d[i] -= 2 * dk * k[i];
    double s, t;
    int g = ibl_cube_face_st_d(d, &s, &t);
    tref r = {g, (int)floor(s * n), (int)floor(t * n)};
    return r;
}

/* Overlap2 on random data, n = 8: each texel is checked against the rule written out here
 * with partners from mirror images (independent of the library's unfolding). */
static void overlap2_random(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int n = 8;
    ibl_cubemap cube, orig;
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &cube), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &orig), IBL_OK);
    fill_random(&cube, 77);
    memcpy(orig.data, cube.data, ibl_cubemap_floats(n, 1) * sizeof(float));
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP2, &cube, 0), IBL_OK);
    for (int f = 0; f < 6; f++) {
        double m[3], s_axis[3], t_axis[3], sx[3], ty[3];
        ibl_cube_direction_d(f, 0.5, 0.5, m);
        ibl_cube_direction_d(f, 1.0, 0.5, sx);
        ibl_cube_direction_d(f, 0.5, 1.0, ty);
        for (int i = 0; i < 3; i++) s_axis[i] = sx[i] - m[i], t_axis[i] = ty[i] - m[i];
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                int depth[4] = {x, n - 1 - x, y, n - 1 - y};
                double axes[4][3];
                for (int i = 0; i < 3; i++) {
                    axes[0][i] = -s_axis[i], axes[1][i] = s_axis[i];
                    axes[2][i] = -t_axis[i], axes[3][i] = t_axis[i];
                }
                int zeros = 0, ones = 0, near_edges[4];
                for (int e = 0; e < 4; e++) {
                    if (depth[e] == 0) zeros++;
                    if (depth[e] == 1) near_edges[ones++] = e;
                }
                tref t = {f, x, y};
                float *now = texel(&cube, 0, t), *was = texel(&orig, 0, t);
                for (int c = 0; c < 4; c++) {
                    double expect = was[c];
                    if (zeros > 0) {
                        tref p[2];
                        nearest_on_other_faces(f, n, x, y, p, zeros);
                        expect = was[c];
                        for (int k = 0; k < zeros; k++) expect += texel(&orig, 0, p[k])[c];
                        expect /= zeros + 1;
                    } else if (ones > 0) {
                        expect = (1.0 - 0.25 * ones) * was[c];
                        for (int k = 0; k < ones; k++)
                            expect += 0.25 * texel(&orig, 0, mirror_partner(f, n, x, y, axes[near_edges[k]]))[c];
                    }
                    assert_near(now[c], expect, 1e-5);
                }
            }
    }
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &orig);
    ibl_context_destroy(ctx);
}

/* Bent: unchanged at the face centre; at an edge texel the angle perpendicular to the edge
 * grows by fraction * (the angle between the two edge texels' normals seen perpendicular to
 * the edge), the partner found by brute force; the fraction follows the documented ramp. */
static void bent_angles(void **state)
{
    (void)state;
    int sizes[] = {5, 7, 8, 16};
    ibl_bent_desc custom = {0.3f, 0.9f, 0.2f};
    struct {
        const ibl_bent_desc *desc;
        float radius;
        double fraction;
    } cases[] = {{NULL, 0.0f, 0.5}, {NULL, 0.25f, 0.75}, {NULL, 2.0f, 1.0},
                 {&custom, 0.1f, 0.6}, {&custom, 0.5f, 0.9}};
    for (int si = 0; si < 4; si++) {
        int n = sizes[si];
        for (int ci = 0; ci < 5; ci++) {
            double fraction = cases[ci].fraction;
            for (int f = 0; f < 6; f++) {
                if (n % 2) {
                    ibl_vec3 c = ibl_cube_texel_direction(f, n, n / 2, n / 2);
                    ibl_vec3 b = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_BENT, cases[ci].desc, f, n,
                                                                n / 2, n / 2, cases[ci].radius);
                    assert_true(angle_v(b, c) < 1e-6);
                }
                /* every texel on the x = n-1 edge: the plane perpendicular to that edge is
                 * spanned by the face normal m and the edge's outward axis a */
                double m[3], sx[3], a[3];
                ibl_cube_direction_d(f, 0.5, 0.5, m);
                ibl_cube_direction_d(f, 1.0, 0.5, sx);
                for (int i = 0; i < 3; i++) a[i] = sx[i] - m[i];
                for (int y = 1; y < n - 1; y++) {
                    tref p;
                    nearest_on_other_faces(f, n, n - 1, y, &p, 1);
                    double dn[3], dp[3], db[3];
                    centre(f, n, n - 1, y, dn);
                    centre(p.face, n, p.x, p.y, dp);
                    dir_of(ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_BENT, cases[ci].desc, f, n, n - 1, y,
                                                          cases[ci].radius),
                           db);
#define PERP(d) atan2((d)[0] * a[0] + (d)[1] * a[1] + (d)[2] * a[2], (d)[0] * m[0] + (d)[1] * m[1] + (d)[2] * m[2])
                    double target = PERP(dp) - PERP(dn);
                    /* float directions: ~1e-7 rad */
                    assert_near(PERP(db) - PERP(dn), fraction * target, 2e-6);
                    if (y == n / 2 && n % 2) {
                        /* mid-edge: the full 3D angle, both to the normal and to the partner */
                        double full = angle_d(dn, dp);
                        assert_near(angle_d(db, dn), fraction * full, 2e-6);
                        assert_near(angle_d(db, dp), (1.0 - fraction) * full, 2e-6);
                    }
#undef PERP
                }
            }
        }
    }
}

/* At the default small-radius fraction (1/2) every edge texel meets its partner across the
 * seam, and the three corner texels meet at the cube corner. */
static void bent_partners_meet(void **state)
{
    (void)state;
    for (int n = 2; n <= 16; n *= 2) {
        double worst = 0;
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    if (!is_edge(n, x, y)) continue;
                    tref p[2];
                    int k = nearest_on_other_faces(f, n, x, y, p, is_corner(n, x, y) ? 2 : 1);
                    ibl_vec3 b = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_BENT, NULL, f, n, x, y, 0.0f);
                    for (int i = 0; i < k; i++) {
                        ibl_vec3 q = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_BENT, NULL, p[i].face, n, p[i].x,
                                                                    p[i].y, 0.0f);
                        double a = angle_v(b, q);
                        if (a > worst) worst = a;
                    }
                }
        assert_true(worst < 2e-6); /* float directions */
    }
}

/* ---- the bent kernel against plain filtering, with a brute-force Phong convolution ---- */

static double env(const double d[3])
{
    /* smooth but strongly varying: a gradient, a broad lobe and a tighter one */
    double a = 0.6 * d[0] - 0.3 * d[1] + 0.74 * d[2];
    double b = -0.5 * d[0] + 0.8 * d[1] + 0.33 * d[2];
    return 1.0 + 0.8 * d[1] + 3.0 * exp(4.0 * (a - 1.0)) + 6.0 * exp(20.0 * (b - 1.0));
}

/* Filters a level of edge n around each texel's kernel direction from a source of edge m:
 * P = sum L w max(c.l, 0)^s / sum w max(c.l, 0)^s over every source texel, in double. */
static void phong_level(int m, const double *src, int n, double s, ibl_edge_fixup fixup,
                        const ibl_bent_desc *desc, double *out)
{
    double half = acos(pow(0.5, 1.0 / s)); /* where the lobe falls to half */
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double c[3];
                dir_of(ibl_edge_fixup_texel_direction(fixup, desc, f, n, x, y, (float)half), c);
                double num = 0, den = 0;
                for (int g = 0; g < 6; g++)
                    for (int yy = 0; yy < m; yy++)
                        for (int xx = 0; xx < m; xx++) {
                            double l[3];
                            centre(g, m, xx, yy, l);
                            double mu = c[0] * l[0] + c[1] * l[1] + c[2] * l[2];
                            if (mu <= 0) continue;
                            double w = ibl_cube_texel_solid_angle(m, xx, yy) * pow(mu, s);
                            num += w * src[((size_t)g * m + yy) * m + xx];
                            den += w;
                        }
                out[((size_t)f * n + y) * n + x] = num / den;
            }
}

/* Mean |L(A) - L(B)| over the seam pairs (non-corner edge texels and their partners). */
static double seam_jump(int n, const double *level)
{
    double sum = 0;
    int count = 0;
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                if (!is_edge(n, x, y) || is_corner(n, x, y)) continue;
                tref p;
                nearest_on_other_faces(f, n, x, y, &p, 1);
                sum += fabs(level[((size_t)f * n + y) * n + x] - level[((size_t)p.face * n + p.y) * n + p.x]);
                count++;
            }
    return sum / count;
}

static void bent_reduces_seam_jump(void **state)
{
    (void)state;
    int m = 16, n = 8;
    double *src = malloc(sizeof(double) * 6 * m * m), *out = malloc(sizeof(double) * 6 * n * n);
    assert_non_null(src);
    assert_non_null(out);
    for (int g = 0; g < 6; g++)
        for (int y = 0; y < m; y++)
            for (int x = 0; x < m; x++) {
                double d[3];
                centre(g, m, x, y, d);
                src[((size_t)g * m + y) * m + x] = env(d);
            }
    /* an 8x8 level of a 16 chain: the box fit gives s ~ 60 there; 8 is a wide lobe */
    double shininess[] = {8, 32, 64, 128};
    ibl_bent_desc half_only = {0.5f, 0.5f, 1.0f};
    for (int i = 0; i < 4; i++) {
        double jumps[4];
        ibl_edge_fixup fixups[4] = {IBL_EDGE_FIXUP_NONE, IBL_EDGE_FIXUP_BENT, IBL_EDGE_FIXUP_BENT,
                                    IBL_EDGE_FIXUP_WARP};
        for (int k = 0; k < 4; k++) {
            phong_level(m, src, n, shininess[i], fixups[k], k == 2 ? &half_only : NULL, out);
            jumps[k] = seam_jump(n, out);
        }
        print_message("phong s=%g (half-angle %.3f rad), %dx%d level from %dx%d: mean seam jump "
                      "none %.5f, bent (default ramp) %.5f, bent (50%% always) %.2e, warp %.2e\n",
                      shininess[i], acos(pow(0.5, 1.0 / shininess[i])), n, n, m, m, jumps[0], jumps[1],
                      jumps[2], jumps[3]);
        /* at 50% (and with the warp) both texels of a seam pair are filtered around the same
         * direction, up to float rounding of the directions: the jump all but vanishes */
        assert_true(jumps[2] < 1e-3 * jumps[0]);
        assert_true(jumps[3] < 1e-3 * jumps[0]);
        /* the default ramp moves toward 100% (edge texels swap places) as the lobe widens;
         * for the lobes such a level carries it must still at least halve the jump */
        if (shininess[i] >= 32) assert_true(jumps[1] < 0.5 * jumps[0]);
    }
    free(src);
    free(out);
}

/* ---- warp ---- */

/* The warp maps texel centre coordinate u to u + a u^3 with a = n^2 / (n-1)^3, so edge
 * texels sit on the face edge, shared with their partner; the lookup inverts it. */
static void warp_directions(void **state)
{
    (void)state;
    /* hand value: n = 4, texel 2: u = 0.25, a = 16/27, u' = 0.25 + (16/27) / 64 */
    double u = 0.25 + 16.0 / 27.0 / 64.0, d[3], e[3];
    ibl_cube_direction_d(IBL_FACE_POS_Z, (u + 1) / 2, (u + 1) / 2, d);
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++) d[i] /= l;
    dir_of(ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_WARP, NULL, IBL_FACE_POS_Z, 4, 2, 2, 0), e);
    assert_true(angle_d(d, e) < 1e-6);
    /* edge texels meet their partners exactly (up to float) */
    for (int n = 2; n <= 16; n *= 2)
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    if (!is_edge(n, x, y)) continue;
                    tref p;
                    nearest_on_other_faces(f, n, x, y, &p, 1);
                    ibl_vec3 a = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_WARP, NULL, f, n, x, y, 0);
                    ibl_vec3 b = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_WARP, NULL, p.face, n, p.x, p.y, 0);
                    assert_true(angle_v(a, b) < 2e-6);
                }
}

static void warp_lookup_round_trip(void **state)
{
    (void)state;
    int sizes[] = {2, 3, 4, 8, 16, 64};
    for (int si = 0; si < 6; si++) {
        int n = sizes[si];
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    ibl_vec3 w = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_WARP, NULL, f, n, x, y, 0);
                    ibl_vec3 l = ibl_edge_fixup_warp_lookup(w, n);
                    /* the lookup lands on the centre of a texel whose warped direction is w:
                     * the texel itself, or at a seam (w exactly on the edge) its partner */
                    float s, t;
                    int g = ibl_cube_face_st(l, &s, &t);
                    int gx = (int)(s * n), gy = (int)(t * n);
                    gx = gx < 0 ? 0 : gx >= n ? n - 1 : gx;
                    gy = gy < 0 ? 0 : gy >= n ? n - 1 : gy;
                    if (!is_edge(n, x, y)) {
                        assert_int_equal(g, f);
                        assert_int_equal(gx, x);
                        assert_int_equal(gy, y);
                    }
                    /* float directions through a cubic and its inverse: 1e-5 rad, far below
                     * the texel pitch 2/n */
                    assert_true(angle_v(l, ibl_cube_texel_direction(g, n, gx, gy)) < 1e-5);
                    assert_true(angle_v(w, ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_WARP, NULL, g, n, gx, gy, 0)) < 1e-5);
                }
        /* a direction on a face edge is looked up at the edge texel centre, u = 1 - 1/n */
        if (n >= 2) {
            ibl_vec3 l = ibl_edge_fixup_warp_lookup((ibl_vec3){1.0f, 0.2f, 1.0f}, n);
            double expect[3] = {1.0 - 1.0 / n, 0, 1.0};
            /* the other coordinate: the inverse of 0.2 under u + a u^3, by bisection */
            double lo = 0, hi = 0.2, a = (double)n * n / pow(n - 1.0, 3);
            for (int it = 0; it < 100; it++) {
                double mid = 0.5 * (lo + hi);
                if (mid + a * mid * mid * mid < 0.2) lo = mid;
                else hi = mid;
            }
            expect[1] = lo;
            double dl[3];
            dir_of(l, dl);
            double el = sqrt(expect[0] * expect[0] + expect[1] * expect[1] + 1.0);
            for (int i = 0; i < 3; i++) expect[i] /= el;
            /* +X face sees (1, 0.2, 1) at sc = -z = -1 or +Z at sc = x = 1: either way the
             * lookup is |u| = 1 - 1/n from that face's centre */
            double alt[3] = {expect[2], expect[1], expect[0]};
            assert_true(fmin(angle_d(dl, expect), angle_d(dl, alt)) < 1e-5);
        }
    }
}

static void apply_arguments(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 2, &cube), IBL_OK);
    fill_random(&cube, 3);
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP, &cube, 2), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP, &cube, -1), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_edge_fixup_apply(ctx, (ibl_edge_fixup)42, &cube, 0), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP, NULL, 0), IBL_ERR_INVALID_ARGUMENT);
    ibl_vec3 z = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_BENT, NULL, 6, 8, 0, 0, 0);
    assert_true(z.x == 0 && z.y == 0 && z.z == 0);
    z = ibl_edge_fixup_texel_direction(IBL_EDGE_FIXUP_NONE, NULL, 0, 8, 8, 0, 0);
    assert_true(z.x == 0 && z.y == 0 && z.z == 0);
    /* bent and warp change nothing on levels larger than 1x1 */
    size_t bytes = ibl_cubemap_floats(8, 2) * sizeof(float);
    float *copy = malloc(bytes);
    assert_non_null(copy);
    memcpy(copy, cube.data, bytes);
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_BENT, &cube, 0), IBL_OK);
    assert_int_equal(ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_WARP, &cube, 1), IBL_OK);
    assert_memory_equal(copy, cube.data, bytes);
    free(copy);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(names),
        cmocka_unit_test(overlap_seams_and_corners),
        cmocka_unit_test(one_by_one_level),
        cmocka_unit_test(overlap2_hand_case),
        cmocka_unit_test(overlap2_random),
        cmocka_unit_test(bent_angles),
        cmocka_unit_test(bent_partners_meet),
        cmocka_unit_test(bent_reduces_seam_jump),
        cmocka_unit_test(warp_directions),
        cmocka_unit_test(warp_lookup_round_trip),
        cmocka_unit_test(apply_arguments),
    };
    (void)PI;
    return cmocka_run_group_tests(tests, NULL, NULL);
}
