/* A scene through a camera: the path-traced view (ibl_trace_view) and the probe-lit render
 * (ibl_probe_render, `ibl render SCENE --probes DIR`), against references that come from
 * neither:
 *  - the furnace: inside a closed box whose walls all emit Le and reflect a Lambertian albedo
 *    rho, a path of at most N reflections carries Le (1 + rho + ... + rho^N), in every pixel;
 *  - the probe-lit furnace: a probe captured at the box's centre with N bounces holds that
 *    constant; a wall lit by it shows Le + rho L_N = L_(N+1), the same series one term longer;
 *  - a box with one open side under a constant sky: the probe render's regions;
 *  - the probe set's "view" and the CLI (default view, comparisons, the reference's table,
 *    bad input: one line and no output). */
#include "test_support.h"

#include "ibl/probes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- a box [-1, 1]^3 seen from inside ---------------------------------------------------- */

typedef struct walls {
    float positions[24 * 3];
    uint32_t indices[36];
    int materials[12];
    int triangles;
} walls;

/* Wall k lies on the plane where axis k/2 equals +1 (k even) or -1 (k odd), wound so that
 * its front faces the centre; open[k] leaves it out. */
static void build_walls(walls *w, const int open[6])
{
    int v = 0;
    w->triangles = 0;
    for (int k = 0; k < 6; k++) {
        if (open && open[k]) continue;
        int axis = k / 2;
        float s = k % 2 ? -1.0f : 1.0f;
        int a = (axis + 1) % 3, b = (axis + 2) % 3;
        static const float corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int c = 0; c < 4; c++) {
            float *p = w->positions + 3 * (v + c);
            p[axis] = s, p[a] = corner[c][0], p[b] = corner[c][1];
        }
        /* (a, b) corners turn counter-clockwise about +axis: reverse them on the + wall so
         * that the front looks toward -axis, into the box */
        static const uint32_t ccw[6] = {0, 1, 2, 0, 2, 3}, cw[6] = {0, 2, 1, 0, 3, 2};
        for (int i = 0; i < 6; i++) w->indices[3 * w->triangles + i] = (uint32_t)v + (s > 0 ? cw[i] : ccw[i]);
        w->materials[w->triangles] = w->materials[w->triangles + 1] = 0;
        w->triangles += 2;
        v += 4;
    }
}

static ibl_scene *box_scene(ibl_context *ctx, walls *w, const int open[6], float rho, float le)
{
    build_walls(w, open);
    ibl_scene_material m = ibl_scene_material_default();
    m.diffuse_only = 1;
    for (int c = 0; c < 3; c++) m.base_color[c] = rho, m.emissive[c] = le;
    ibl_scene_desc d;
    memset(&d, 0, sizeof d);
    d.vertex_count = 2 * w->triangles;
    d.triangle_count = w->triangles;
    d.positions = w->positions;
    d.indices = w->indices;
    d.material_ids = w->materials;
    d.materials = &m;
    d.material_count = 1;
    ibl_scene *s = NULL;
    assert_int_equal(ibl_scene_create(ctx, &d, &s), IBL_OK);
    return s;
}

static ibl_camera centre_camera(int width, int height)
{
    ibl_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.forward = (ibl_vec3){1.0f, 0.3f, 0.2f}; /* three walls in view */
    cam.up = (ibl_vec3){0, 1, 0};
    cam.fov_y_degrees = 90.0f;
    cam.width = width;
    cam.height = height;
    return cam;
}

static double series(double le, double rho, int n)
{
    double sum = 0.0;
    for (int i = 0; i <= n; i++) sum += le * pow(rho, i);
    return sum;
}

static void constant_cube(ibl_context *ctx, int size, float v, ibl_cubemap *out)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, size, 1, out), IBL_OK);
    test_fill_cube(out, v, v, v);
}

/* ---- ibl_trace_view ----------------------------------------------------------------------- */

static void trace_view_furnace(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2), *one = test_context(1);
    const float rho = 0.6f, le = 1.5f;
    walls w;
    ibl_scene *s = box_scene(ctx, &w, NULL, rho, le);
    ibl_cubemap env;
    constant_cube(ctx, 8, 100.0f, &env); /* sealed out: any leak shows */
    ibl_camera cam = centre_camera(24, 16);
    const int bounces[3] = {IBL_CAPTURE_NO_BOUNCE, 1, 3};
    for (int k = 0; k < 3; k++) {
        double want = series(le, rho, bounces[k] < 0 ? 0 : bounces[k]);
        ibl_trace_desc d = {.bounces = bounces[k], .samples = 32, .seed = 7};
        ibl_image img, again;
        assert_int_equal(ibl_trace_view(ctx, s, &env, &cam, &d, &img), IBL_OK);
        double mean = 0.0, worst = 0.0;
        for (int i = 0; i < cam.width * cam.height; i++) {
            worst = fmax(worst, fabs(img.pixels[4 * i] / want - 1.0));
            const float *p = img.pixels + 4 * i;
            if (bounces[k] < 0) /* emission only: exact but for float rounding */
                for (int c = 0; c < 3; c++) assert_near(p[c], want, 1e-6 * want);
            /* one pixel: 32 paths of emitter + sky sampling with MIS; measured within 7.5% */
            assert_near(p[0], want, 0.12 * want);
            mean += p[0];
        }
        mean /= cam.width * cam.height;
        if (getenv("IBL_TEST_VERBOSE"))
            fprintf(stderr, "trace furnace N=%d: %.5f want %.5f (%+.3f%%), worst pixel %.2f%%\n", bounces[k], mean,
                    want, 100 * (mean / want - 1), 100 * worst);
        /* 12288 paths: measured -0.10% and -0.05% */
        assert_near(mean, want, 0.01 * want);
        /* the same bits on one thread */
        assert_int_equal(ibl_trace_view(one, s, &env, &cam, &d, &again), IBL_OK);
        assert_memory_equal(img.pixels, again.pixels, sizeof(float) * 4 * 24 * 16);
        ibl_image_free(ctx, &img);
        ibl_image_free(one, &again);
    }
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(one);
    ibl_context_destroy(ctx);
}

/* An open box (+Y missing) under a constant sky, no emission, rho 0.5, one bounce: a pixel
 * that looks out sees the sky exactly, and the mean over the walls stays within the sky's
 * radiance and zero (what goes in must come out less). */
static void trace_view_sky(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    walls w;
    const int open[6] = {0, 0, 1, 0, 0, 0};
    ibl_scene *s = box_scene(ctx, &w, open, 0.5f, 0.0f);
    ibl_cubemap env;
    constant_cube(ctx, 8, 2.0f, &env);
    ibl_camera cam = centre_camera(16, 16);
    cam.forward = (ibl_vec3){0, 1, 0}; /* straight up through the opening, 90 degrees */
    cam.up = (ibl_vec3){0, 0, -1};
    ibl_trace_desc d = {.bounces = 1, .samples = 16};
    ibl_image img;
    assert_int_equal(ibl_trace_view(ctx, s, &env, &cam, &d, &img), IBL_OK);
    /* the centre pixels' every jittered ray leaves through the opening (it spans 90 degrees) */
    for (int y = 6; y < 10; y++)
        for (int x = 6; x < 10; x++) assert_near(img.pixels[4 * (y * 16 + x)], 2.0, 0);
    ibl_image_free(ctx, &img);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- ibl_probe_render --------------------------------------------------------------------- */

static const char FURNACE_SET[] =
    "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": {\"size\": 8},"
    " \"view\": {\"position\": [0, 0, 0], \"target\": [1, 0.3, 0.2], \"fov\": 90},"
    " \"probes\": [{\"name\": \"centre\", \"position\": [0, 0, 0], \"size\": 8,"
    "  \"influence\": {\"shape\": \"box\", \"half_extent\": [1.2, 1.2, 1.2], \"blend\": 0.1},"
    "  \"proxy\": {\"shape\": \"box\", \"half_extent\": [1, 1, 1]}}]}";

static void small_global(ibl_bake_desc *g)
{
    memset(g, 0, sizeof *g);
    assert_true(ibl_specular_preset("gltf", &g->specular));
    g->specular.size = 8;
    g->lut_size = 8;
    g->irradiance_size = 4;
    g->ambient_brdf = -1;
    g->preview_width = -1;
}

static void probe_render_furnace(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const float rho = 0.5f, le = 1.0f;
    const int n = 2;
    walls w;
    ibl_scene *s = box_scene(ctx, &w, NULL, rho, le);
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_parse(ctx, FURNACE_SET, strlen(FURNACE_SET), "furnace.json", ".", &set), IBL_OK);
    assert_true(set.has_view);
    assert_near(set.view.fov_y_degrees, 90.0, 0);
    ibl_cubemap env, capture;
    constant_cube(ctx, 8, 1.0f, &env);
    /* BRDF sampling only: every texel is the series to N exactly */
    ibl_capture_desc cd = {.bounces = n, .samples = 4, .no_light_sampling = 1};
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &set.probes[0], 0, &cd, &capture), IBL_OK);
    ibl_bake_desc global;
    small_global(&global);
    ibl_probe_bake_desc bd = {.cubes = &capture, .global = &global};
    const char *dir = test_path("furnace_bake");
    assert_int_equal(ibl_probe_bake(ctx, &set, &env, &bd, dir, NULL), IBL_OK);
    ibl_probe_bake_data bake;
    assert_int_equal(ibl_probe_bake_load(ctx, dir, &bake), IBL_OK);
    ibl_camera cam = centre_camera(32, 24);
    ibl_image img;
    int regions[32 * 24];
    assert_int_equal(ibl_probe_render(ctx, s, &bake, &cam, NULL, &img, regions), IBL_OK);
    double want = series(le, rho, n + 1), worst = 0.0;
    for (int i = 0; i < 32 * 24 * 4; i++)
        if (i % 4 != 3) worst = fmax(worst, fabs(img.pixels[i] / want - 1.0));
    if (getenv("IBL_TEST_VERBOSE")) fprintf(stderr, "probe-lit furnace: worst %.2e relative\n", worst);
    for (int i = 0; i < 32 * 24; i++) {
        /* rgba16f storage of the chain (1.75 is exact in half; other constants would round by
         * up to 2^-11) and the SH's float sums: measured 3.2e-7 relative */
        for (int c = 0; c < 3; c++) assert_near(img.pixels[4 * i + c], want, 1e-3 * want);
        assert_int_equal(regions[i], 0);
    }
    /* without the probe's own light (alpha ignored makes no difference here: every alpha
     * is 1) the comparison switches must leave a constant constant */
    ibl_probe_render_desc rd;
    memset(&rd, 0, sizeof rd);
    rd.blend.no_parallax = rd.blend.no_alpha = 1;
    ibl_image off;
    assert_int_equal(ibl_probe_render(ctx, s, &bake, &cam, &rd, &off, NULL), IBL_OK);
    for (int i = 0; i < 32 * 24 * 4; i++) assert_near(off.pixels[i], img.pixels[i], 1e-3 * want);
    ibl_image_free(ctx, &off);
    ibl_image_free(ctx, &img);
    ibl_probe_bake_free(ctx, &bake);
    ibl_cubemap_free(ctx, &capture);
    ibl_cubemap_free(ctx, &env);
    ibl_probe_set_free(ctx, &set);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* A probe whose far-plane capture sees a room with its ceiling open: looking out, the render
 * shows the global probe (background); the walls belong to the probe's region. */
static void probe_render_regions(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    walls w;
    const int open[6] = {0, 0, 1, 0, 0, 0};
    ibl_scene *s = box_scene(ctx, &w, open, 0.5f, 0.0f);
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_parse(ctx, FURNACE_SET, strlen(FURNACE_SET), "open.json", ".", &set), IBL_OK);
    ibl_cubemap env, capture;
    constant_cube(ctx, 8, 3.0f, &env);
    ibl_capture_desc cd = {.bounces = 1, .samples = 4};
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &set.probes[0], 0, &cd, &capture), IBL_OK);
    ibl_bake_desc global;
    small_global(&global);
    ibl_probe_bake_desc bd = {.cubes = &capture, .global = &global};
    const char *dir = test_path("open_bake");
    assert_int_equal(ibl_probe_bake(ctx, &set, &env, &bd, dir, NULL), IBL_OK);
    ibl_probe_bake_data bake;
    assert_int_equal(ibl_probe_bake_load(ctx, dir, &bake), IBL_OK);
    ibl_camera cam = centre_camera(16, 16);
    cam.forward = (ibl_vec3){0, 1, 0};
    cam.up = (ibl_vec3){0, 0, -1};
    cam.fov_y_degrees = 120.0f; /* the opening spans 90: the corners see the walls */
    ibl_image img;
    int regions[256];
    assert_int_equal(ibl_probe_render(ctx, s, &bake, &cam, NULL, &img, regions), IBL_OK);
    /* the centre looks out through the opening: the global probe's level 0 (the constant 3,
     * rgba16f: exact); the corners hit walls */
    assert_int_equal(regions[8 * 16 + 8], IBL_REGION_BACKGROUND);
    assert_near(img.pixels[4 * (8 * 16 + 8)], 3.0, 1e-3);
    assert_int_equal(regions[0], 0);
    assert_int_equal(regions[255], 0);
    ibl_image_free(ctx, &img);
    ibl_probe_bake_free(ctx, &bake);
    ibl_cubemap_free(ctx, &capture);
    ibl_cubemap_free(ctx, &env);
    ibl_probe_set_free(ctx, &set);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- the set's view and the CLI ----------------------------------------------------------- */

static void set_view_errors(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static const char *const bad[][2] = {
        {"\"view\": {\"position\": [0, 0, 0], \"target\": [0, 0, 0]}", "view.target: must differ"},
        {"\"view\": {\"position\": [0, 0, 0], \"target\": [1, 0, 0], \"fov\": 180}", "view.fov: must be between"},
        {"\"view\": {\"position\": [0, 0, 0], \"target\": [1, 0, 0], \"zoom\": 2}", "view.zoom: unknown field"},
        {"\"view\": {\"target\": [1, 0, 0]}", "view.position: missing"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": {}, %s, \"probes\": []}", bad[i][0]);
        ibl_probe_set set;
        assert_int_not_equal(ibl_probe_set_parse(ctx, text, strlen(text), "v.json", ".", &set), IBL_OK);
        const char *msg = ibl_context_message(ctx);
        if (!strstr(msg, bad[i][1])) fail_msg("'%s' lacks '%s'", msg, bad[i][1]);
    }
    ibl_context_destroy(ctx);
}

/* Copies a probe-set file with every "size": N written as "size": 8. */
static void cut_sizes(const char *from, const char *to)
{
    FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
    assert_non_null(in);
    assert_non_null(out);
    static const char key[] = "\"size\": ";
    size_t matched = 0;
    int c;
    while ((c = fgetc(in)) != EOF) {
        if (matched == sizeof key - 1 && c >= '0' && c <= '9') continue; /* the old digits */
        if (matched == sizeof key - 1) fputc('8', out), matched = 0;
        fputc(c, out);
        matched = c == key[matched] ? matched + 1 : c == key[0];
    }
    fclose(in);
    assert_int_equal(fclose(out), 0);
}

static void cli_render_probes(void **state)
{
    (void)state;
    const char *out;
    char scene[1024], set[1024], sample_set[1024];
    snprintf(scene, sizeof scene, "%s/../../examples/rooms/scene.gltf", IBL_TEST_DATA);
    snprintf(sample_set, sizeof sample_set, "%s/../../examples/rooms/probes.json", IBL_TEST_DATA);
    /* the sample set with every cube edge cut to 8: the global probe's bake at 128 would take
     * most of the test's time under ASan */
    snprintf(set, sizeof set, "%s", test_path("rooms.json"));
    cut_sizes(sample_set, set);
    int rc;
    const char *caps = test_path("rooms_caps"), *bake = test_path("rooms_bake");
    rc = test_run_cli(&out, "capture -q '%s' --probes '%s' -o '%s' --samples 2 --bounces 1",
                          scene, set, caps);
    if (rc != 0) fail_msg("%s", out);
    char caps_dir[1024];
    snprintf(caps_dir, sizeof caps_dir, "%s", caps);
    assert_int_equal(test_run_cli(&out, "bake -q --probes '%s' --captures '%s' -o '%s'", set, caps_dir, bake), 0);
    char bake_dir[1024];
    snprintf(bake_dir, sizeof bake_dir, "%s", bake);
    /* the set's view, the reference and its table */
    const char *png = test_path("rooms.png");
    rc = test_run_cli(&out, "render -q '%s' --probes '%s' --set '%s' -o '%s' --width 48 --reference --samples 2",
                          scene, bake_dir, set, png);
    if (rc != 0) fail_msg("%s", out);
    assert_non_null(strstr(out, "white_room"));
    assert_non_null(strstr(out, "all surfaces"));
    ibl_image img;
    ibl_context *ctx = test_context(1);
    assert_int_equal(ibl_read_image(ctx, png, NULL, &img, NULL), IBL_OK);
    assert_true(img.width > 2 * 48); /* two images side by side */
    ibl_image_free(ctx, &img);
    /* a comparison without a set: the scene's centre */
    png = test_path("rooms_alpha.exr");
    rc = test_run_cli(&out, "render -q '%s' --probes '%s' -o '%s' --width 32 --compare alpha", scene, bake_dir, png);
    if (rc != 0) fail_msg("%s", out);
    assert_true(test_file_exists(png));
    /* bad input: one line naming the file, no output */
    png = test_path("none.png");
    rc = test_run_cli(&out, "render -q '%s' --probes '%s/nothing' -o '%s'", scene, bake_dir, png);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(out, "nothing"));
    assert_int_equal(strchr(out, '\n') - out + 1, (long)strlen(out));
    assert_false(test_file_exists(png));
    rc = test_run_cli(&out, "render -q '%s' --probes '%s' -o '%s' --compare shininess", scene, bake_dir, png);
    assert_int_equal(rc, 2);
    assert_false(test_file_exists(png));
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(trace_view_furnace),
        cmocka_unit_test(trace_view_sky),
        cmocka_unit_test(probe_render_furnace),
        cmocka_unit_test(probe_render_regions),
        cmocka_unit_test(set_view_errors),
        cmocka_unit_test(cli_render_probes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
