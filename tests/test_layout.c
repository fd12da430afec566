/* Layouts <-> cubes: conventions (an asymmetric picture), orientation, round trips, energy of
 * equirect -> cube against the exact sum over the source pixels, anti-aliasing, detection and
 * refusal of bad sizes, and bit-identical results at any thread count. The references are the
 * test's own formulas for the documented conventions (docs/CONVENTIONS.md), not the library's. */
#include "test_support.h"
#include "core/cpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* ---- the test's own conventions ---- */

/* Equirect: centre column -Z, u = 3/4 is +X, top row +Y. */
static void eq_dir(double u, double v, double d[3])
{
    double phi = 2 * PI * (u - 0.5), theta = PI * v;
    d[0] = sin(theta) * sin(phi);
    d[1] = cos(theta);
    d[2] = -sin(theta) * cos(phi);
}

/* A smooth, positive, asymmetric function of direction (RGBA). */
static void smooth_fn(const double d[3], float out[4])
{
    out[0] = (float)(1.0 + 0.5 * d[0] + 0.25 * d[1] * d[2]);
    out[1] = (float)(1.0 + 0.4 * d[1] - 0.2 * d[0] * d[0]);
    out[2] = (float)(0.8 + 0.3 * d[2] + 0.1 * d[0] * d[1]);
    out[3] = 1.0f;
}

/* A picture of any sphere layout filled with fn at pixel centres (0 outside the map). */
static ibl_image make_sphere_image(ibl_context *ctx, ibl_layout layout, int w, int h,
                                   void (*fn)(const double *, float *))
{
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, w, h, &im), IBL_OK);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double u = (x + 0.5) / w, v = (y + 0.5) / h, d[3];
            float *p = ibl_image_texel(&im, x, y);
            if (layout == IBL_LAYOUT_EQUIRECT) {
                eq_dir(u, v, d);
            } else {
                ibl_vec3 dv;
                if (!ibl_layout_direction(layout, (float)u, (float)v, &dv)) continue;
                d[0] = dv.x;
                d[1] = dv.y;
                d[2] = dv.z;
            }
            fn(d, p);
        }
    return im;
}

static void make_cube(ibl_context *ctx, int n, void (*fn)(const double *, float *), ibl_cubemap *c)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, c), IBL_OK);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                ibl_vec3 v = ibl_cube_texel_direction(f, n, x, y);
                double d[3] = {v.x, v.y, v.z};
                fn(d, ibl_cubemap_face(c, 0, f) + ((size_t)y * n + x) * 4);
            }
}

static double max_diff(const float *a, const float *b, size_t texels)
{
    double m = 0;
    for (size_t i = 0; i < texels * 4; i++) {
        double e = fabs((double)a[i] - b[i]);
        if (e > m) m = e;
    }
    return m;
}

/* ---- names, detection, refusals ---- */

static void names_and_detection(void **state)
{
    (void)state;
    ibl_layout all[] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_HCROSS, IBL_LAYOUT_VCROSS,
                        IBL_LAYOUT_HSTRIP,   IBL_LAYOUT_VSTRIP, IBL_LAYOUT_ANGULAR,
                        IBL_LAYOUT_OCTAHEDRAL, IBL_LAYOUT_FACES, IBL_LAYOUT_CUBE};
    ibl_layout l = IBL_LAYOUT_AUTO;
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        assert_true(ibl_layout_from_name(ibl_layout_name(all[i]), &l));
        assert_int_equal(l, all[i]);
    }
    assert_string_equal(ibl_layout_name(IBL_LAYOUT_EQUIRECT), "equirect");
    assert_true(ibl_layout_from_name("HCross", &l));
    assert_int_equal(l, IBL_LAYOUT_HCROSS);
    assert_true(ibl_layout_from_name("latlong", &l));
    assert_int_equal(l, IBL_LAYOUT_EQUIRECT);
    assert_false(ibl_layout_from_name("nonsense", &l));
    assert_false(ibl_layout_from_name(NULL, &l));
    assert_int_equal(l, IBL_LAYOUT_EQUIRECT); /* untouched by a failed parse */

    assert_int_equal(ibl_layout_detect(2048, 1024), IBL_LAYOUT_EQUIRECT);
    assert_int_equal(ibl_layout_detect(400, 300), IBL_LAYOUT_HCROSS);
    assert_int_equal(ibl_layout_detect(300, 400), IBL_LAYOUT_VCROSS);
    assert_int_equal(ibl_layout_detect(600, 100), IBL_LAYOUT_HSTRIP);
    assert_int_equal(ibl_layout_detect(100, 600), IBL_LAYOUT_VSTRIP);
    assert_int_equal(ibl_layout_detect(256, 256), IBL_LAYOUT_ANGULAR);
    assert_int_equal(ibl_layout_detect(401, 300), IBL_LAYOUT_AUTO);
    assert_int_equal(ibl_layout_detect(100, 37), IBL_LAYOUT_AUTO);
    assert_int_equal(ibl_layout_detect(0, 0), IBL_LAYOUT_AUTO);
    assert_int_equal(ibl_layout_detect(-2, -1), IBL_LAYOUT_AUTO);
}

static void bad_sizes_refused(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im;
    ibl_cubemap cube;
    assert_int_equal(ibl_image_alloc(ctx, 96, 96, &im), IBL_OK);
    ibl_to_cube_desc d = {0};
    /* a square picture is not a cross, a strip or an equirect */
    ibl_layout wrong[] = {IBL_LAYOUT_HCROSS, IBL_LAYOUT_VCROSS, IBL_LAYOUT_HSTRIP,
                          IBL_LAYOUT_VSTRIP, IBL_LAYOUT_EQUIRECT};
    for (size_t i = 0; i < sizeof wrong / sizeof wrong[0]; i++) {
        d.layout = wrong[i];
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cube), IBL_ERR_INVALID_ARGUMENT);
        assert_null(cube.data);
        assert_true(strstr(ibl_context_message(ctx), "96x96") != NULL);
    }
    d.layout = IBL_LAYOUT_FACES;
    assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cube), IBL_ERR_INVALID_ARGUMENT);
    d.layout = IBL_LAYOUT_ANGULAR;
    d.size = -4;
    assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cube), IBL_ERR_INVALID_ARGUMENT);
    ibl_image_free(ctx, &im);

    /* undetectable aspect ratio with AUTO; zero size */
    assert_int_equal(ibl_image_alloc(ctx, 100, 37, &im), IBL_OK);
    assert_int_equal(ibl_image_to_cubemap(ctx, &im, NULL, &cube), IBL_ERR_INVALID_ARGUMENT);
    ibl_image_free(ctx, &im);
    ibl_image empty = {0, 0, NULL};
    assert_int_equal(ibl_image_to_cubemap(ctx, &empty, NULL, &cube), IBL_ERR_INVALID_ARGUMENT);
    float one[4] = {1, 1, 1, 1};
    ibl_image zero_w = {0, 1, one};
    assert_int_equal(ibl_image_to_cubemap(ctx, &zero_w, NULL, &cube), IBL_ERR_INVALID_ARGUMENT);

    /* faces of different sizes */
    ibl_image faces[6];
    for (int f = 0; f < 6; f++) assert_int_equal(ibl_image_alloc(ctx, 8, 8, &faces[f]), IBL_OK);
    ibl_image keep = faces[3];
    assert_int_equal(ibl_image_alloc(ctx, 4, 4, &faces[3]), IBL_OK);
    assert_int_equal(ibl_faces_to_cubemap(ctx, faces, NULL, &cube), IBL_ERR_INVALID_ARGUMENT);
    assert_true(strstr(ibl_context_message(ctx), "-Y") != NULL);
    ibl_image_free(ctx, &faces[3]);
    faces[3] = keep;
    for (int f = 0; f < 6; f++) ibl_image_free(ctx, &faces[f]);

    /* from a cube: layout required, widths must fit the layout */
    ibl_cubemap c;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &c), IBL_OK);
    ibl_from_cube_desc fd = {0};
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, NULL, &im), IBL_ERR_INVALID_ARGUMENT);
    fd.layout = IBL_LAYOUT_FACES;
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_ERR_INVALID_ARGUMENT);
    fd.layout = IBL_LAYOUT_HCROSS;
    fd.width = 30; /* not a multiple of 4 */
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_ERR_INVALID_ARGUMENT);
    fd.layout = IBL_LAYOUT_EQUIRECT;
    fd.width = 31; /* odd */
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_ERR_INVALID_ARGUMENT);
    fd.width = 0;
    fd.level = 1; /* only one level */
    assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_ERR_INVALID_ARGUMENT);
    ibl_cubemap_free(ctx, &c);
    ibl_context_destroy(ctx);
}

/* ---- conventions ---- */

static void check_dir(ibl_layout layout, float u, float v, double x, double y, double z)
{
    ibl_vec3 d;
    assert_true(ibl_layout_direction(layout, u, v, &d));
    /* float evaluation of sin/cos: 1e-6 */
    assert_near(d.x, x, 1e-6);
    assert_near(d.y, y, 1e-6);
    assert_near(d.z, z, 1e-6);
}

static void sphere_layout_conventions(void **state)
{
    (void)state;
    /* equirect: centre -Z, right quarter +X, left quarter -X, edges +Z, top +Y, bottom -Y */
    check_dir(IBL_LAYOUT_EQUIRECT, 0.5f, 0.5f, 0, 0, -1);
    check_dir(IBL_LAYOUT_EQUIRECT, 0.75f, 0.5f, 1, 0, 0);
    check_dir(IBL_LAYOUT_EQUIRECT, 0.25f, 0.5f, -1, 0, 0);
    check_dir(IBL_LAYOUT_EQUIRECT, 0.0f, 0.5f, 0, 0, 1);
    check_dir(IBL_LAYOUT_EQUIRECT, 0.5f, 0.0f, 0, 1, 0);
    check_dir(IBL_LAYOUT_EQUIRECT, 0.5f, 1.0f, 0, -1, 0);
    /* angular: centre -Z, r = 1/2 is 90 degrees away: right +X, up +Y; the rim is +Z */
    check_dir(IBL_LAYOUT_ANGULAR, 0.5f, 0.5f, 0, 0, -1);
    check_dir(IBL_LAYOUT_ANGULAR, 0.75f, 0.5f, 1, 0, 0);
    check_dir(IBL_LAYOUT_ANGULAR, 0.5f, 0.25f, 0, 1, 0);
    check_dir(IBL_LAYOUT_ANGULAR, 1.0f, 0.5f, 0, 0, 1);
    assert_false(ibl_layout_direction(IBL_LAYOUT_ANGULAR, 0.0f, 0.0f, NULL));
    /* octahedral: centre +Y, right +X, bottom +Z, top -Z, left -X, corners -Y */
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 0.5f, 0.5f, 0, 1, 0);
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 1.0f, 0.5f, 1, 0, 0);
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 0.5f, 1.0f, 0, 0, 1);
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 0.5f, 0.0f, 0, 0, -1);
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 0.0f, 0.5f, -1, 0, 0);
    check_dir(IBL_LAYOUT_OCTAHEDRAL, 0.0f, 1.0f, 0, -1, 0);
    /* angular: theta = pi r exactly (Debevec), at an arbitrary point */
    {
        ibl_vec3 d;
        float u = 0.7f, v = 0.4f;
        double a = 2 * u - 1, b = 2 * v - 1, r = sqrt(a * a + b * b);
        assert_true(ibl_layout_direction(IBL_LAYOUT_ANGULAR, u, v, &d));
        assert_near(acos(-d.z) / PI, r, 1e-6);
    }
    /* direction -> uv -> direction for random directions */
    ibl_layout sph[] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_ANGULAR, IBL_LAYOUT_OCTAHEDRAL};
    srand(3);
    for (int l = 0; l < 3; l++)
        for (int i = 0; i < 2000; i++) {
            ibl_vec3 d = {rand() / (float)RAND_MAX - 0.5f, rand() / (float)RAND_MAX - 0.5f,
                          rand() / (float)RAND_MAX - 0.5f}, back;
            float len = sqrtf(d.x * d.x + d.y * d.y + d.z * d.z), u, v;
            if (len < 0.05f) continue;
            d.x /= len; d.y /= len; d.z /= len;
            assert_true(ibl_layout_uv(sph[l], d, &u, &v));
            assert_true(u >= 0 && u <= 1 && v >= 0 && v <= 1);
            assert_true(ibl_layout_direction(sph[l], u, v, &back));
            /* float round trip; the angular map's rim region amplifies: 1e-3 */
            assert_near(back.x, d.x, 1e-3);
            assert_near(back.y, d.y, 1e-3);
            assert_near(back.z, d.z, 1e-3);
        }
}

/* The six axis colours, distinct in every channel pattern. */
static const float axis_colour[6][4] = {
    {1, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}, {1, 1, 0, 1}, {1, 0, 1, 1}, {0, 1, 1, 1}};

static int major_axis(const double d[3])
{
    double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
    if (ax >= ay && ax >= az) return d[0] >= 0 ? 0 : 1;
    if (ay >= az) return d[1] >= 0 ? 2 : 3;
    return d[2] >= 0 ? 4 : 5;
}

static void axis_fn(const double d[3], float out[4]) { memcpy(out, axis_colour[major_axis(d)], 16); }
/* Encodes the direction itself (plus an offset to stay positive). */
static void dir_fn(const double d[3], float out[4])
{
    for (int i = 0; i < 3; i++) out[i] = (float)(d[i] + 2.0);
    out[3] = 1.0f;
}

/* Mean of the central 4x4 texels of a face. */
static void face_centre(const ibl_cubemap *c, int face, float out[4])
{
    int n = c->size;
    double acc[4] = {0, 0, 0, 0};
    for (int y = n / 2 - 2; y < n / 2 + 2; y++)
        for (int x = n / 2 - 2; x < n / 2 + 2; x++)
            for (int i = 0; i < 4; i++) acc[i] += ibl_cubemap_face(c, 0, face)[((size_t)y * n + x) * 4 + i];
    for (int i = 0; i < 4; i++) out[i] = (float)(acc[i] / 16);
}

/* expected[world face] = the picture axis whose colour must appear there */
static void check_axis_faces(ibl_context *ctx, const ibl_image *im, ibl_orientation o,
                             const int expected[6])
{
    ibl_to_cube_desc d = {0};
    d.size = 16;
    d.orientation = o;
    ibl_cubemap c;
    assert_int_equal(ibl_image_to_cubemap(ctx, im, &d, &c), IBL_OK);
    for (int f = 0; f < 6; f++) {
        float got[4];
        face_centre(&c, f, got);
        for (int i = 0; i < 4; i++) assert_near(got[i], axis_colour[expected[f]][i], 1e-5);
    }
    ibl_cubemap_free(ctx, &c);
}

/* The asymmetric picture: each axis's colour placed by the documented equirect convention. */
static void asymmetric_equirect(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_image im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, 128, 64, axis_fn);
    ibl_orientation none = {0, 0, 0};
    const int same[6] = {0, 1, 2, 3, 4, 5};
    check_axis_faces(ctx, &im, none, same);
    /* yaw +90 (counter-clockwise from above): +X -> -Z, -Z -> -X, -X -> +Z, +Z -> +X */
    ibl_orientation yaw = {90.0f, 0, 0};
    const int yawed[6] = {/* +X shows */ 4, /* -X */ 5, 2, 3, /* +Z */ 1, /* -Z */ 0};
    check_axis_faces(ctx, &im, yaw, yawed);
    /* mirror: x -> -x */
    ibl_orientation mir = {0, 1, 0};
    const int mirrored[6] = {1, 0, 2, 3, 4, 5};
    check_axis_faces(ctx, &im, mir, mirrored);
    /* z-up: picture (x, y, z) -> world (x, z, -y): world +Y shows picture +Z, world -Z shows
     * picture +Y, world -Y shows picture -Z, world +Z shows picture -Y */
    ibl_orientation zup = {0, 0, 1};
    const int zupped[6] = {0, 1, 4, 5, 3, 2};
    check_axis_faces(ctx, &im, zup, zupped);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* Every texel of the cube holds (about) its own direction, or the documented transform of it:
 * nothing is mirrored or turned inside a face either. */
static void direction_image_texelwise(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_image im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, 256, 128, dir_fn);
    for (int mode = 0; mode < 5; mode++) {
        ibl_to_cube_desc d = {0};
        d.size = 16;
        if (mode == 1) d.orientation.yaw_degrees = 90;
        if (mode == 2) d.orientation.mirror = 1;
        if (mode == 3) d.orientation.z_up = 1;
        if (mode == 4) d.orientation.yaw_degrees = 30;
        ibl_cubemap c;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &c), IBL_OK);
        double worst = 0;
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < 16; y++)
                for (int x = 0; x < 16; x++) {
                    ibl_vec3 w = ibl_cube_texel_direction(f, 16, x, y);
                    double e[3]; /* the picture direction seen at world w */
                    if (mode == 0) { e[0] = w.x; e[1] = w.y; e[2] = w.z; }
                    if (mode == 1) { e[0] = -w.z; e[1] = w.y; e[2] = w.x; }
                    if (mode == 2) { e[0] = -w.x; e[1] = w.y; e[2] = w.z; }
                    if (mode == 3) { e[0] = w.x; e[1] = -w.z; e[2] = w.y; }
                    if (mode == 4) {
                        double c30 = cos(PI / 6), s30 = sin(PI / 6);
                        /* world = Ry(30) p  =>  p = Ry(-30) w */
                        e[0] = c30 * w.x - s30 * w.z;
                        e[1] = w.y;
                        e[2] = s30 * w.x + c30 * w.z;
                    }
                    const float *p = ibl_cubemap_face(&c, 0, f) + ((size_t)y * 16 + x) * 4;
                    for (int i = 0; i < 3; i++) {
                        double err = fabs(p[i] - 2.0 - e[i]);
                        if (err > worst) worst = err;
                    }
                }
        /* the texel value is the mean of a linear function over the texel's footprint: it
         * differs from the centre direction by the footprint's curvature, < 0.01 at 16 */
        assert_true(worst < 0.01);
        ibl_cubemap_free(ctx, &c);
        /* and the public orientation functions agree with the same formulas */
        ibl_vec3 px = {1, 0, 0}, w = ibl_orientation_apply(&d.orientation, px);
        ibl_vec3 back = ibl_orientation_invert(&d.orientation, w);
        assert_near(back.x, 1, 1e-6);
        assert_near(back.y, 0, 1e-6);
        assert_near(back.z, 0, 1e-6);
    }
    ibl_orientation yaw = {90, 0, 0}, zup = {0, 0, 1};
    ibl_vec3 px = {1, 0, 0}, pz = {0, 0, 1};
    ibl_vec3 w = ibl_orientation_apply(&yaw, px);
    assert_near(w.z, -1, 1e-6);
    w = ibl_orientation_apply(&zup, pz);
    assert_near(w.y, 1, 1e-6);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* Crosses and strips: the documented cell of each face, and the 180-degree -Z of the vcross. */
static void cube_layout_cells(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int n = 4;
    ibl_cubemap c;
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &c), IBL_OK);
    /* texel value = (face, x, y, 1) */
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                float *p = ibl_cubemap_face(&c, 0, f) + ((size_t)y * n + x) * 4;
                p[0] = (float)f; p[1] = (float)x; p[2] = (float)y; p[3] = 1;
            }
    struct { ibl_layout l; int cols, rows; int cell[6][2]; int rot_negz; } table[] = {
        {IBL_LAYOUT_HCROSS, 4, 3, {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {3, 1}}, 0},
        {IBL_LAYOUT_VCROSS, 3, 4, {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {1, 3}}, 1},
        {IBL_LAYOUT_HSTRIP, 6, 1, {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {4, 0}, {5, 0}}, 0},
        {IBL_LAYOUT_VSTRIP, 1, 6, {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}}, 0},
    };
    for (int t = 0; t < 4; t++) {
        ibl_from_cube_desc fd = {0};
        fd.layout = table[t].l;
        ibl_image im;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_OK);
        assert_int_equal(im.width, table[t].cols * n);
        assert_int_equal(im.height, table[t].rows * n);
        assert_int_equal(ibl_layout_detect(im.width, im.height), table[t].l);
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    const float *p = ibl_image_texel(&im, table[t].cell[f][0] * n + x,
                                                     table[t].cell[f][1] * n + y);
                    int rot = f == 5 && table[t].rot_negz;
                    assert_int_equal((int)p[0], f);
                    assert_int_equal((int)p[1], rot ? n - 1 - x : x);
                    assert_int_equal((int)p[2], rot ? n - 1 - y : y);
                }
        /* back to a cube: bit-exact */
        ibl_cubemap back;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, NULL, &back), IBL_OK);
        assert_int_equal(back.size, n);
        assert_memory_equal(back.data, c.data, (size_t)6 * n * n * 4 * sizeof(float));
        ibl_cubemap_free(ctx, &back);
        ibl_image_free(ctx, &im);
    }
    /* six faces out and in: bit-exact */
    ibl_image faces[6];
    assert_int_equal(ibl_cubemap_to_faces(ctx, &c, 0, faces), IBL_OK);
    ibl_cubemap back;
    assert_int_equal(ibl_faces_to_cubemap(ctx, faces, NULL, &back), IBL_OK);
    assert_memory_equal(back.data, c.data, (size_t)6 * n * n * 4 * sizeof(float));
    ibl_cubemap_free(ctx, &back);
    for (int f = 0; f < 6; f++) ibl_image_free(ctx, &faces[f]);
    ibl_cubemap_free(ctx, &c);
    ibl_context_destroy(ctx);
}

/* The vcross/hcross are seamless: across every edge drawn in the figure, neighbouring pixels
 * of the two cells look in nearly the same direction. */
static void cross_seams(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int n = 16;
    ibl_cubemap c;
    make_cube(ctx, n, dir_fn, &c);
    ibl_layout ls[2] = {IBL_LAYOUT_HCROSS, IBL_LAYOUT_VCROSS};
    for (int t = 0; t < 2; t++) {
        ibl_from_cube_desc fd = {0};
        fd.layout = ls[t];
        ibl_image im;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_OK);
        int seams = 0;
        for (int y = 0; y < im.height; y++)
            for (int x = 0; x < im.width; x++) {
                const float *p = ibl_image_texel(&im, x, y);
                if (p[3] == 0) continue;
                for (int k = 0; k < 2; k++) {
                    int nx = x + (k == 0), ny = y + (k == 1);
                    if (nx >= im.width || ny >= im.height) continue;
                    const float *q = ibl_image_texel(&im, nx, ny);
                    if (q[3] == 0) continue;
                    double dd = 0;
                    for (int i = 0; i < 3; i++) dd += (p[i] - q[i]) * (p[i] - q[i]);
                    /* neighbours are about 2/n apart (plus the diagonal on a cube edge) */
                    assert_true(sqrt(dd) < 3.0 / n);
                    if ((x + 1) % n == 0 || (y + 1) % n == 0) seams++;
                }
            }
        assert_true(seams > 0);
        ibl_image_free(ctx, &im);
    }
    ibl_cubemap_free(ctx, &c);
    ibl_context_destroy(ctx);
}

/* ---- round trips ---- */

static void layout_cube_layout(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    struct { ibl_layout l; int w, h; double tol; } cases[] = {
        /* two resamplings of a smooth function (second derivatives <= 0.5) by filters about
         * one pixel wide: errors of order pixel^2 (0.05 rad)^2 plus the curvature of the
         * footprints; 0.01 is 1% of the signal */
        {IBL_LAYOUT_EQUIRECT, 128, 64, 0.01},
        {IBL_LAYOUT_OCTAHEDRAL, 64, 64, 0.01},
        /* the angular map's rim squeezes a whole cube face (+Z) into a thin ring */
        {IBL_LAYOUT_ANGULAR, 128, 128, 0.02},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ibl_image im = make_sphere_image(ctx, cases[i].l, cases[i].w, cases[i].h, smooth_fn);
        ibl_cubemap c;
        ibl_to_cube_desc td = {0};
        td.layout = cases[i].l;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &td, &c), IBL_OK);
        ibl_from_cube_desc fd = {0};
        fd.layout = cases[i].l;
        fd.width = cases[i].w;
        ibl_image back;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &back), IBL_OK);
        assert_int_equal(back.width, im.width);
        assert_int_equal(back.height, im.height);
        double worst = 0;
        for (int y = 0; y < im.height; y++)
            for (int x = 0; x < im.width; x++) {
                const float *a = ibl_image_texel(&im, x, y), *b = ibl_image_texel(&back, x, y);
                if (a[3] == 0) continue; /* outside the angular disk */
                double e = max_diff(a, b, 1);
                if (e > worst) worst = e;
            }
        print_message("%s -> cube %d -> %s: max error %.5f\n", ibl_layout_name(cases[i].l), c.size,
                      ibl_layout_name(cases[i].l), worst);
        assert_true(worst < cases[i].tol);
        ibl_image_free(ctx, &back);
        ibl_image_free(ctx, &im);
        ibl_cubemap_free(ctx, &c);
    }
    ibl_context_destroy(ctx);
}

static void cube_layout_cube(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int n = 32;
    ibl_cubemap c;
    make_cube(ctx, n, smooth_fn, &c);
    ibl_layout all[] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_ANGULAR, IBL_LAYOUT_OCTAHEDRAL,
                        IBL_LAYOUT_HCROSS,   IBL_LAYOUT_VCROSS,  IBL_LAYOUT_HSTRIP,
                        IBL_LAYOUT_VSTRIP};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        ibl_from_cube_desc fd = {0};
        fd.layout = all[i];
        ibl_image im;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_OK);
        ibl_to_cube_desc td = {0};
        td.layout = all[i];
        ibl_cubemap back;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &td, &back), IBL_OK);
        assert_int_equal(back.size, n); /* natural sizes invert each other */
        double worst = max_diff(c.data, back.data, (size_t)6 * n * n);
        print_message("cube %d -> %s %dx%d -> cube: max error %.5f\n", n,
                      ibl_layout_name(all[i]), im.width, im.height, worst);
        if (i >= 3) assert_true(worst == 0.0); /* cube layouts only copy texels */
        else assert_true(worst < 0.01);          /* as in layout_cube_layout */
        ibl_cubemap_free(ctx, &back);
        ibl_image_free(ctx, &im);
    }
    /* oriented round trip: the same orientation out and back in cancels */
    ibl_layout two[] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_HCROSS};
    for (int i = 0; i < 2; i++) {
        ibl_from_cube_desc fd = {0};
        fd.layout = two[i];
        fd.orientation.yaw_degrees = 90;
        fd.orientation.mirror = 1;
        fd.orientation.z_up = 1;
        ibl_image im;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_OK);
        ibl_to_cube_desc td = {0};
        td.orientation = fd.orientation;
        ibl_cubemap back;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &td, &back), IBL_OK);
        double worst = max_diff(c.data, back.data, (size_t)6 * n * n);
        /* quarter turns of a cross are texel permutations: exact */
        if (two[i] == IBL_LAYOUT_HCROSS) assert_true(worst == 0.0);
        else assert_true(worst < 0.01);
        ibl_cubemap_free(ctx, &back);
        ibl_image_free(ctx, &im);
    }
    ibl_cubemap_free(ctx, &c);
    ibl_context_destroy(ctx);
}

/* ---- energy ---- */

/* Exact sum over the equirect pixels of L * (2 pi / W) (cos theta0 - cos theta1). */
static double equirect_energy(const ibl_image *im, int ch)
{
    double acc = 0;
    for (int y = 0; y < im->height; y++) {
        double w = 2 * PI / im->width * (cos(PI * y / im->height) - cos(PI * (y + 1) / im->height));
        double row = 0;
        for (int x = 0; x < im->width; x++) row += ibl_image_texel(im, x, y)[ch];
        acc += row * w;
    }
    return acc;
}

static double cube_energy(const ibl_cubemap *c, int ch)
{
    int n = c->size;
    double acc = 0;
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++)
                acc += ibl_cubemap_face(c, 0, f)[((size_t)y * n + x) * 4 + ch] *
                       ibl_cube_texel_solid_angle(n, x, y);
    return acc;
}

static void equirect_energy_kept(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int W = 512, H = 256;
    ibl_image smooth = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, W, H, smooth_fn);
    int sizes[3] = {16, 64, 256};
    for (int s = 0; s < 3; s++) {
        ibl_to_cube_desc d = {0};
        d.size = sizes[s];
        ibl_cubemap c;
        assert_int_equal(ibl_image_to_cubemap(ctx, &smooth, &d, &c), IBL_OK);
        for (int ch = 0; ch < 3; ch++) {
            double a = equirect_energy(&smooth, ch), b = cube_energy(&c, ch);
            print_message("smooth, cube %d, channel %d: energy ratio %.6f\n", sizes[s], ch, b / a);
            assert_true(fabs(b / a - 1) < 0.005);
        }
        ibl_cubemap_free(ctx, &c);
    }
    /* a constant stays constant (every texel is a normalised weighted mean): float rounding */
    for (size_t i = 0; i < (size_t)W * H * 4; i++) smooth.pixels[i] = 0.75f;
    for (int s = 0; s < 3; s++) {
        ibl_to_cube_desc d = {0};
        d.size = sizes[s];
        ibl_cubemap c;
        assert_int_equal(ibl_image_to_cubemap(ctx, &smooth, &d, &c), IBL_OK);
        size_t n = (size_t)6 * sizes[s] * sizes[s] * 4;
        for (size_t i = 0; i < n; i++) assert_near(c.data[i], 0.75, 1e-5);
        ibl_cubemap_free(ctx, &c);
    }
    ibl_image_free(ctx, &smooth);

    /* a small sun: 3x3 pixels of 1e5 on a dim sky (0.1), at several places: the equator, the
     * longitude seam, mid and high latitudes, touching the north pole (rows 0-2), near the
     * south pole */
    ibl_image sun;
    assert_int_equal(ibl_image_alloc(ctx, W, H, &sun), IBL_OK);
    struct { int x, y; double tol; } spots[] = {
        /* within 0.5%, the acceptance bound of a conversion, at any cube size; (10, 30)
         * straddles the edge of the directly integrated polar region at cube 16 (3 texels =
         * 20 degrees) */
        {256, 128, 0.005}, {0, 100, 0.005}, {300, 60, 0.005}, {77, 20, 0.005},
        {400, 1, 0.005},   {10, 7, 0.005},  {100, 254, 0.005}, {10, 30, 0.005},
    };
    for (size_t p = 0; p < sizeof spots / sizeof spots[0]; p++) {
        for (size_t i = 0; i < (size_t)W * H * 4; i++) sun.pixels[i] = 0.1f;
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int x = (spots[p].x + dx + W) % W, y = spots[p].y + dy;
                ibl_image_texel(&sun, x, y)[0] = 1e5f;
            }
        double ref = equirect_energy(&sun, 0);
        for (int s = 0; s < 3; s++) {
            ibl_to_cube_desc d = {0};
            d.size = sizes[s];
            ibl_cubemap c;
            assert_int_equal(ibl_image_to_cubemap(ctx, &sun, &d, &c), IBL_OK);
            double got = cube_energy(&c, 0);
            print_message("sun at (%d,%d), cube %d: energy ratio %.5f\n", spots[p].x, spots[p].y,
                          sizes[s], got / ref);
            assert_true(fabs(got / ref - 1) < spots[p].tol);
            ibl_cubemap_free(ctx, &c);
        }
    }
    ibl_image_free(ctx, &sun);
    ibl_context_destroy(ctx);
}

/* ---- against a brute-force footprint integral ---- */

/* A positive function with detail at about 10 degrees (RGBA). */
static void wavy_fn(const double d[3], float out[4])
{
    double w = sin(23.0 * d[0] + 1.0) * cos(19.0 * d[2]) + 0.5 * sin(29.0 * d[1]);
    out[0] = (float)(1.0 + 0.4 * w);
    out[1] = (float)(1.0 + 0.3 * d[0] - 0.2 * w * d[2]);
    out[2] = (float)(0.7 + 0.2 * d[1] * d[1]);
    out[3] = 1.0f;
}

/* The documented reconstruction at picture position (x, y) in pixels (centres at k + 1/2):
 * linear between pixel centres in longitude (wrapping) and in latitude, except in the R rows
 * next to each pole, which are constant bands (the first interpolated row is flat on its half
 * next to them; src/layout/equirect/area_windows.c, row_share). */
static double reconstruct(const ibl_image *im, int ch, double x, double y)
{
    int W = im->width, H = im->height, R = H / 4 < 12 ? H / 4 : 12;
    double fx = x - 0.5, x0 = floor(fx), ax = fx - x0;
    int c0 = ((int)x0 % W + W) % W, c1 = (c0 + 1) % W;
    int r0, r1;
    double ay;
    if (y < R + 0.5 || y >= H - R - 0.5) {
        r0 = r1 = y < R ? (int)y : y < R + 0.5 ? R : y < H - R ? H - R - 1 : (int)y;
        if (r0 > H - 1) r0 = r1 = H - 1;
        ay = 0;
    } else {
        double fy = y - 0.5, y0 = floor(fy);
        r0 = (int)y0;
        r1 = r0 + 1;
        ay = fy - y0;
    }
    double top = ibl_image_texel(im, c0, r0)[ch] * (1 - ax) + ibl_image_texel(im, c1, r0)[ch] * ax;
    double bot = ibl_image_texel(im, c0, r1)[ch] * (1 - ax) + ibl_image_texel(im, c1, r1)[ch] * ax;
    return top * (1 - ay) + bot * ay;
}

/* Each texel should be the solid-angle-weighted mean of the reconstruction over its footprint.
 * The reference integrates it by brute force in double: S x S points per texel on the face
 * plane, weighted by dA / |p|^3, each mapped to the picture by the test's own convention
 * (eq_dir inverted); texels near the poles, integrated from the pixels as boxes, are left out.
 * The library's windows reach a little past the footprint (each sample cell's bounding box in
 * longitude and latitude; whole source columns for texels around the poles), a blur under a
 * pixel whose first-order effects cancel: measured max 0.0013 and mean 0.00012 on values near
 * 1 (0.0011 and 0.00011 before the per-column windows). A window half a pixel off in longitude
 * gives max 0.006 - 0.019, so the bounds are 0.003 and 0.0003. The cube sizes put the texels
 * that take per-column windows (those spanning many columns around the poles) in the constant
 * bands (96), in the interpolated rows (40), and take k x k grids elsewhere (all three). */
static void equirect_footprint_reference(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int W = 512, H = 256;
    ibl_image im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, W, H, wavy_fn);
    int sizes[3] = {96, 40, 24};
    for (int si = 0; si < 3; si++) {
        int n = sizes[si], S = 24;
        /* 1.5 x the radius of the polar region: 3 texels or 4 rows */
        double pole_rows = 1.5 * fmax(atan(6.0 / n), 4 * PI / H) * H / PI;
        ibl_to_cube_desc d = {0};
        d.size = n;
        ibl_cubemap c;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &c), IBL_OK);
        double worst = 0, sum = 0;
        int count = 0;
        int faces[3] = {IBL_FACE_POS_Y, IBL_FACE_NEG_Y, IBL_FACE_POS_X};
        for (int fi = 0; fi < 3; fi++)
            for (int ty = 0; ty < n; ty += 3)
                for (int tx = 0; tx < n; tx += 3) {
                    double acc[3] = {0, 0, 0}, wsum = 0, ymax = 0;
                    for (int j = 0; j < S; j++)
                        for (int i = 0; i < S; i++) {
                            double p[3];
                            ibl_cube_direction_d(faces[fi], (tx + (i + 0.5) / S) / n,
                                                 (ty + (j + 0.5) / S) / n, p);
                            double l2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
                            double w = 1.0 / (l2 * sqrt(l2));
                            double l = sqrt(l2);
                            double theta = acos(p[1] / l), phi = atan2(p[0], -p[2]);
                            double x = (phi / (2 * PI) + 0.5) * W, y = theta / PI * H;
                            /* skip the directly integrated polar region (pixels as boxes) */
                            if (fmin(y, H - y) < pole_rows) ymax = -1e9;
                            for (int ch = 0; ch < 3; ch++)
                                acc[ch] += w * reconstruct(&im, ch, x, y);
                            wsum += w;
                        }
                    if (ymax < 0) continue;
                    const float *got =
                        ibl_cubemap_face(&c, 0, faces[fi]) + ((size_t)ty * n + tx) * 4;
                    for (int ch = 0; ch < 3; ch++) {
                        double e = fabs(got[ch] - acc[ch] / wsum);
                        worst = fmax(worst, e);
                        sum += e;
                        count++;
                    }
                }
        print_message("equirect %dx%d -> cube %d against the footprint integral: max %.4f, mean "
                      "%.5f over %d values\n", W, H, n, worst, sum / count, count);
        assert_true(count > 100);
        assert_true(worst < 0.003);
        assert_true(sum / count < 0.0003);
        ibl_cubemap_free(ctx, &c);
    }
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);

    /* the same bits at 1, 2 and 8 threads, turned (the faces around the poles keep level
     * axes, so they still take per-column windows) */
    ibl_cubemap cubes[3];
    int threads[3] = {1, 2, 8};
    for (int t = 0; t < 3; t++) {
        ctx = test_context(threads[t]);
        im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, W, H, wavy_fn);
        ibl_to_cube_desc d = {0};
        d.size = 40;
        d.orientation.yaw_degrees = 17;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cubes[t]), IBL_OK);
        ibl_image_free(ctx, &im);
        ibl_context_destroy(ctx);
    }
    for (int t = 1; t < 3; t++)
        assert_memory_equal(cubes[0].data, cubes[t].data, (size_t)6 * 40 * 40 * 4 * sizeof(float));
    for (int t = 0; t < 3; t++) ibl_cubemap_free(NULL, &cubes[t]);
}

/* The AVX2 kernels of the equirect conversion and the portable kernels give the same bits (the
 * same float operations in the same order, no fused multiply-adds). A default context runs the
 * AVX2 kernels wherever the CPU has AVX2 and FMA, a context created with IBL_KERNELS_PORTABLE
 * the portable ones (on other CPUs both run the portable ones). Sizes with one to several
 * samples per texel axis, the polar regions and per-column windows; turned frames: yaw (the
 * polar faces keep level axes), z-up and a mirror (a general frame). */
static void equirect_simd_paths_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_context_desc pd = {0};
    pd.threads = 2;
    pd.kernels = IBL_KERNELS_PORTABLE;
    ibl_context *portable;
    assert_int_equal(ibl_context_create(&pd, &portable), IBL_OK);
    assert_false(ibl__cpu_has(portable, IBL__CPU_AVX2_FMA));
    int W = 512, H = 256;
    ibl_image im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, W, H, wavy_fn);
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) ibl_image_texel(&im, 300 + dx, 60 + dy)[0] = 1e5f;
    print_message("AVX2 kernels %s\n", ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA) ? "present" : "absent");
    int sizes[3] = {128, 40, 16};
    ibl_orientation ors[3] = {{0, 0, 0}, {17, 0, 0}, {-40, 1, 1}};
    for (int si = 0; si < 3; si++)
        for (int oi = 0; oi < 3; oi++) {
            int n = sizes[si];
            ibl_to_cube_desc d = {0};
            d.size = n;
            d.orientation = ors[oi];
            ibl_cubemap a, b;
            assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &a), IBL_OK);
            assert_int_equal(ibl_image_to_cubemap(portable, &im, &d, &b), IBL_OK);
            assert_memory_equal(a.data, b.data, (size_t)6 * n * n * 4 * sizeof(float));
            ibl_cubemap_free(ctx, &a);
            ibl_cubemap_free(ctx, &b);
        }
    ibl_image_free(ctx, &im);
    ibl_context_destroy(portable);
    ibl_context_destroy(ctx);
}

/* ---- aliasing ---- */

static void no_aliasing(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    /* a pixel checkerboard equirect -> small cube: every texel is about the mean 0.5 */
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 512, 256, &im), IBL_OK);
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 512; x++) {
            float *p = ibl_image_texel(&im, x, y);
            p[0] = p[1] = p[2] = (float)((x + y) & 1);
            p[3] = 1;
        }
    ibl_to_cube_desc d = {0};
    d.size = 8;
    ibl_cubemap c;
    assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &c), IBL_OK);
    double worst = 0;
    for (size_t i = 0; i < (size_t)6 * 8 * 8; i++) worst = fmax(worst, fabs(c.data[i * 4] - 0.5));
    print_message("checker equirect -> cube 8: max deviation from 0.5: %.4f\n", worst);
    /* a texel spans ~20 rows: an unfiltered point sample would be 0 or 1 */
    assert_true(worst < 0.05);
    ibl_cubemap_free(ctx, &c);
    ibl_image_free(ctx, &im);

    /* a texel checkerboard cube -> small equirect / octahedral / angular */
    int n = 64;
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &c), IBL_OK);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                float *p = ibl_cubemap_face(&c, 0, f) + ((size_t)y * n + x) * 4;
                p[0] = p[1] = p[2] = (float)((x + y) & 1);
                p[3] = 1;
            }
    ibl_layout ls[3] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_OCTAHEDRAL, IBL_LAYOUT_ANGULAR};
    for (int l = 0; l < 3; l++) {
        ibl_from_cube_desc fd = {0};
        fd.layout = ls[l];
        fd.width = 32;
        assert_int_equal(ibl_cubemap_to_image(ctx, &c, &fd, &im), IBL_OK);
        worst = 0;
        for (int y = 0; y < im.height; y++)
            for (int x = 0; x < im.width; x++) {
                const float *p = ibl_image_texel(&im, x, y);
                if (p[3] == 0) continue;
                worst = fmax(worst, fabs(p[0] - 0.5));
            }
        print_message("checker cube %d -> %s 32: max deviation %.4f\n", n, ibl_layout_name(ls[l]), worst);
        assert_true(worst < 0.05);
        ibl_image_free(ctx, &im);
    }
    ibl_cubemap_free(ctx, &c);
    ibl_context_destroy(ctx);
}

/* ---- the solid-angle-weighted mean of a picture ---- */

/* 1 above the horizon, 0 below; 1/2 on it (the octahedral map's pixels whose centres are on
 * the horizon are cut in half by it) */
static void above_horizon_fn(const double d[3], float out[4])
{
    out[0] = out[1] = out[2] = fabs(d[1]) < 1e-6 ? 0.5f : d[1] > 0.0 ? 1.0f : 0.0f;
    out[3] = 1.0f;
}

static void constant_fn(const double d[3], float out[4])
{
    (void)d;
    out[0] = 0.3f;
    out[1] = 0.6f;
    out[2] = 1.25f;
    out[3] = 1.0f;
}

/* The integral of sin(theta) over [a, b] by Simpson's rule (64 panels): the test's own
 * solid angle of an equirect row, independent of the library's cosine difference. */
static double simpson_sin(double a, double b)
{
    enum { PANELS = 64 };
    double h = (b - a) / PANELS, sum = sin(a) + sin(b);
    for (int i = 1; i < PANELS; i++) sum += (i & 1 ? 4.0 : 2.0) * sin(a + i * h);
    return sum * h / 3.0;
}

/* The test's own solid angle of cube texel (x, y) of an n x n face: dA / (1 + s^2 + t^2)^(3/2)
 * summed over 32 x 32 cells of the texel. */
static double texel_solid_angle_brute(int n, int x, int y)
{
    enum { CELLS = 32 };
    double step = 2.0 / n / CELLS, sum = 0.0;
    for (int j = 0; j < CELLS; j++)
        for (int i = 0; i < CELLS; i++) {
            double s = -1.0 + 2.0 * x / n + (i + 0.5) * step;
            double t = -1.0 + 2.0 * y / n + (j + 0.5) * step;
            sum += step * step / pow(1.0 + s * s + t * t, 1.5);
        }
    return sum;
}

/* ibl_image_mean: an equirect against a float64 brute force with the test's own pixel solid
 * angles (a noisy picture with a bright pixel next to the pole); a cross against one with the
 * test's own texel solid angles. */
static void image_mean_brute_force(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int W = 256, H = 128;
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, W, H, &im), IBL_OK);
    unsigned state_lcg = 12345u;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = ibl_image_texel(&im, x, y);
            for (int c = 0; c < 4; c++) {
                state_lcg = state_lcg * 1664525u + 1013904223u;
                p[c] = (float)(state_lcg >> 8) / (float)(1u << 23);
            }
        }
    ibl_image_texel(&im, 40, 1)[0] = 1e4f;
    double want[4] = {0, 0, 0, 0}, wsum = 0.0;
    for (int y = 0; y < H; y++) {
        double omega = 2.0 * PI / W * simpson_sin(PI * y / H, PI * (y + 1) / H);
        for (int x = 0; x < W; x++) {
            for (int c = 0; c < 4; c++) want[c] += omega * ibl_image_texel(&im, x, y)[c];
            wsum += omega;
        }
    }
    assert_near(wsum, 4.0 * PI, 1e-12);
    double got[4];
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_AUTO, got), IBL_OK);
    for (int c = 0; c < 4; c++) assert_near(got[c], want[c] / wsum, 1e-12 * want[c] / wsum);
    print_message("equirect mean %.9f (brute force %.9f)\n", got[0], want[0] / wsum);
    ibl_image_free(ctx, &im);

    /* a horizontal cross of a wavy environment: exact texel solid angles */
    int n = 8;
    ibl_cubemap cube;
    make_cube(ctx, n, wavy_fn, &cube);
    ibl_from_cube_desc fd = {0};
    fd.layout = IBL_LAYOUT_HCROSS;
    assert_int_equal(ibl_cubemap_to_image(ctx, &cube, &fd, &im), IBL_OK);
    double cw[4] = {0, 0, 0, 0}, csum = 0.0;
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double omega = texel_solid_angle_brute(n, x, y);
                const float *p = ibl_cubemap_face(&cube, 0, f) + ((size_t)y * n + x) * 4;
                for (int c = 0; c < 4; c++) cw[c] += omega * p[c];
                csum += omega;
            }
    assert_near(csum, 4.0 * PI, 1e-4);
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_HCROSS, got), IBL_OK);
    for (int c = 0; c < 4; c++) assert_near(got[c], cw[c] / csum, 1e-5);
    ibl_image_free(ctx, &im);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

/* ibl_image_mean, analytic cases: a constant picture gives the constant in every layout; one
 * that is 1 above the horizon and 0 below gives 1/2 (exactly where the horizon is a pixel
 * edge: the equirect and the cube layouts; within the resampling's blur for the angular and
 * octahedral maps, whose horizon crosses pixels). Bad arguments are refused. */
static void image_mean_analytic(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_layout sphere[3] = {IBL_LAYOUT_EQUIRECT, IBL_LAYOUT_ANGULAR, IBL_LAYOUT_OCTAHEDRAL};
    int widths[3] = {128, 128, 64};
    double half_tol[3] = {1e-12, 1e-5, 1e-5};
    double got[4];
    for (int l = 0; l < 3; l++) {
        int w = widths[l], h = sphere[l] == IBL_LAYOUT_EQUIRECT ? w / 2 : w;
        ibl_image im = make_sphere_image(ctx, sphere[l], w, h, constant_fn);
        assert_int_equal(ibl_image_mean(ctx, &im, sphere[l], got), IBL_OK);
        assert_near(got[0], 0.3f, 1e-6);
        assert_near(got[1], 0.6f, 1e-6);
        assert_near(got[2], 1.25f, 1e-6);
        ibl_image_free(ctx, &im);
        im = make_sphere_image(ctx, sphere[l], w, h, above_horizon_fn);
        assert_int_equal(ibl_image_mean(ctx, &im, sphere[l], got), IBL_OK);
        print_message("%s: upper hemisphere mean %.12f\n", ibl_layout_name(sphere[l]), got[0]);
        assert_near(got[0], 0.5, half_tol[l]);
        ibl_image_free(ctx, &im);
    }
    ibl_layout cells[4] = {IBL_LAYOUT_HCROSS, IBL_LAYOUT_VCROSS, IBL_LAYOUT_HSTRIP,
                           IBL_LAYOUT_VSTRIP};
    for (int l = 0; l < 4; l++) {
        ibl_cubemap cube;
        make_cube(ctx, 16, above_horizon_fn, &cube);
        ibl_from_cube_desc fd = {0};
        fd.layout = cells[l];
        ibl_image im;
        assert_int_equal(ibl_cubemap_to_image(ctx, &cube, &fd, &im), IBL_OK);
        assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_AUTO, got), IBL_OK);
        assert_near(got[0], 0.5, 1e-12);
        ibl_image_free(ctx, &im);
        ibl_cubemap_free(ctx, &cube);
    }
    /* refusals: no output, a layout that is not one picture, a size that fits nothing */
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &im), IBL_OK);
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_EQUIRECT, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_FACES, got), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_HCROSS, got), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_image_mean(ctx, NULL, IBL_LAYOUT_AUTO, got), IBL_ERR_INVALID_ARGUMENT);
    ibl_image_free(ctx, &im);
    assert_int_equal(ibl_image_alloc(ctx, 50, 37, &im), IBL_OK);
    assert_int_equal(ibl_image_mean(ctx, &im, IBL_LAYOUT_AUTO, got), IBL_ERR_INVALID_ARGUMENT);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* ---- determinism ---- */

static void identical_at_any_thread_count(void **state)
{
    (void)state;
    int threads[3] = {1, 2, 8};
    ibl_cubemap cubes[3];
    ibl_image pics[3];
    for (int t = 0; t < 3; t++) {
        ibl_context *ctx = test_context(threads[t]);
        ibl_image im = make_sphere_image(ctx, IBL_LAYOUT_EQUIRECT, 256, 128, smooth_fn);
        ibl_to_cube_desc d = {0};
        d.size = 32;
        d.orientation.yaw_degrees = 17;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cubes[t]), IBL_OK);
        ibl_from_cube_desc fd = {0};
        fd.layout = IBL_LAYOUT_OCTAHEDRAL;
        assert_int_equal(ibl_cubemap_to_image(ctx, &cubes[t], &fd, &pics[t]), IBL_OK);
        ibl_image_free(ctx, &im);
        ibl_context_destroy(ctx);
    }
    for (int t = 1; t < 3; t++) {
        assert_memory_equal(cubes[0].data, cubes[t].data, (size_t)6 * 32 * 32 * 4 * sizeof(float));
        assert_memory_equal(pics[0].pixels, pics[t].pixels,
                            (size_t)pics[0].width * pics[0].height * 4 * sizeof(float));
    }
    for (int t = 0; t < 3; t++) {
        ibl_cubemap_free(NULL, &cubes[t]);
        ibl_image_free(NULL, &pics[t]);
    }
}

/* ibl_layout_cube_size says the edge ibl_image_to_cubemap makes when asked for none: checked by
 * converting an image of every single-picture layout at several sizes (AUTO: detected), and 0
 * for a size the layout does not fit and for the layouts that are not one picture. */
static void cube_size_without_converting(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static const struct {
        ibl_layout layout;
        int w, h;
    } cases[] = {
        {IBL_LAYOUT_EQUIRECT, 64, 32},  {IBL_LAYOUT_EQUIRECT, 100, 50}, {IBL_LAYOUT_EQUIRECT, 200, 100},
        {IBL_LAYOUT_HCROSS, 64, 48},    {IBL_LAYOUT_VCROSS, 48, 64},    {IBL_LAYOUT_HSTRIP, 96, 16},
        {IBL_LAYOUT_VSTRIP, 16, 96},    {IBL_LAYOUT_ANGULAR, 60, 60},   {IBL_LAYOUT_OCTAHEDRAL, 40, 40},
        {IBL_LAYOUT_AUTO, 128, 64},     {IBL_LAYOUT_AUTO, 96, 72},      {IBL_LAYOUT_AUTO, 30, 180},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ibl_image im;
        assert_int_equal(ibl_image_alloc(ctx, cases[i].w, cases[i].h, &im), IBL_OK);
        ibl_cubemap cube;
        ibl_to_cube_desc d = {.layout = cases[i].layout};
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &d, &cube), IBL_OK);
        if (ibl_layout_cube_size(cases[i].layout, cases[i].w, cases[i].h) != cube.size)
            fail_msg("case %zu: %d, the conversion made %d", i,
                     ibl_layout_cube_size(cases[i].layout, cases[i].w, cases[i].h), cube.size);
        ibl_cubemap_free(ctx, &cube);
        ibl_image_free(ctx, &im);
    }
    assert_int_equal(ibl_layout_cube_size(IBL_LAYOUT_HCROSS, 64, 64), 0);
    assert_int_equal(ibl_layout_cube_size(IBL_LAYOUT_AUTO, 70, 13), 0);
    assert_int_equal(ibl_layout_cube_size(IBL_LAYOUT_FACES, 64, 64), 0);
    assert_int_equal(ibl_layout_cube_size(IBL_LAYOUT_CUBE, 64, 64), 0);
    assert_int_equal(ibl_layout_cube_size(IBL_LAYOUT_EQUIRECT, 0, 0), 0);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(names_and_detection),
        cmocka_unit_test(bad_sizes_refused),
        cmocka_unit_test(sphere_layout_conventions),
        cmocka_unit_test(asymmetric_equirect),
        cmocka_unit_test(direction_image_texelwise),
        cmocka_unit_test(cube_layout_cells),
        cmocka_unit_test(cross_seams),
        cmocka_unit_test(layout_cube_layout),
        cmocka_unit_test(cube_layout_cube),
        cmocka_unit_test(equirect_energy_kept),
        cmocka_unit_test(equirect_footprint_reference),
        cmocka_unit_test(equirect_simd_paths_agree),
        cmocka_unit_test(no_aliasing),
        cmocka_unit_test(image_mean_brute_force),
        cmocka_unit_test(image_mean_analytic),
        cmocka_unit_test(identical_at_any_thread_count),
        cmocka_unit_test(cube_size_without_converting),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
