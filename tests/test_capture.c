/* Probe capture (include/ibl/probes.h, docs/PROBES.md "Capture") against references that do
 * not come from the tracer:
 *  - the furnace: a closed box whose every wall emits Le and reflects a Lambertian albedo rho
 *    holds the radiance Le (1 + rho + ... + rho^N) after N bounces, exactly, everywhere;
 *  - one emitting ceiling over a Lambertian floor, direct light only: the floor's radiance is
 *    rho Le F / 1 with F the closed-form point-to-rectangle form factor, averaged in float64
 *    over each texel's footprint;
 *  - coverage alpha of far-plane captures in a room with an opening;
 *  - bit-identical captures at 1 and 2 threads (the sample scene, through the glTF loader);
 *  - the CLI: bad scene and probe files give one line and leave no output. */
#include "test_support.h"

#include "ibl/probes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const double PI = 3.14159265358979323846;

/* ---- scenes built in memory ---------------------------------------------------------------- */

typedef struct box_scene {
    float pos[6 * 4 * 3];
    uint32_t idx[6 * 6];
    int mat[12];
    int tris;
} box_scene;

/* The six walls of [-1, 1]^3 facing inward (their front faces emit toward the centre);
 * wall_material[face] is a material index, or -1 to leave that wall out (an opening).
 * Faces in cube order: +X -X +Y -Y +Z -Z. */
static void make_box(box_scene *b, const int wall_material[6])
{
    b->tris = 0;
    for (int f = 0, v = 0; f < 6; f++) {
        if (wall_material[f] < 0) continue;
        int axis = f / 2;
        float side = f % 2 ? -1.0f : 1.0f;
        int u = (axis + 1) % 3, w = (axis + 2) % 3;
        const float cu[4] = {-1, 1, 1, -1}, cw[4] = {-1, -1, 1, 1};
        for (int c = 0; c < 4; c++) {
            float *p = b->pos + 3 * (v + c);
            p[axis] = side;
            p[u] = cu[c];
            p[w] = cw[c];
        }
        /* corners go counter-clockwise around +axis; inward means toward -side */
        uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        if (side > 0) q[1] = 2, q[2] = 1, q[4] = 3, q[5] = 2;
        for (int k = 0; k < 6; k++) b->idx[3 * b->tris + k] = (uint32_t)v + q[k];
        b->mat[b->tris] = b->mat[b->tris + 1] = wall_material[f];
        b->tris += 2;
        v += 4;
    }
}

static ibl_scene *box_scene_create(ibl_context *ctx, box_scene *b, const int walls[6],
                                   const ibl_scene_material *mats, int mat_count)
{
    make_box(b, walls);
    ibl_scene_desc d;
    memset(&d, 0, sizeof d);
    d.vertex_count = 2 * b->tris; /* 4 per wall */
    d.triangle_count = b->tris;
    d.positions = b->pos;
    d.indices = b->idx;
    d.material_ids = b->mat;
    d.materials = mats;
    d.material_count = mat_count;
    d.name = "box";
    ibl_scene *s = NULL;
    assert_int_equal(ibl_scene_create(ctx, &d, &s), IBL_OK);
    return s;
}

static ibl_local_probe centre_probe(ibl_capture_mode mode, int size)
{
    ibl_local_probe p;
    memset(&p, 0, sizeof p);
    snprintf(p.name, sizeof p.name, "centre");
    p.influence.shape = IBL_VOLUME_BOX;
    p.influence.half_extent = (ibl_vec3){1, 1, 1};
    p.proxy = p.influence;
    p.capture = mode;
    p.size = size;
    return p;
}

static ibl_scene_material lambert(float albedo, float emit)
{
    ibl_scene_material m = ibl_scene_material_default();
    m.diffuse_only = 1;
    m.base_color[0] = m.base_color[1] = m.base_color[2] = albedo;
    m.emissive[0] = m.emissive[1] = m.emissive[2] = emit;
    return m;
}

static void constant_env(ibl_context *ctx, ibl_cubemap *env, float v)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, env), IBL_OK);
    test_fill_cube(env, v, v, v);
}

/* ---- the furnace ----------------------------------------------------------------------------- */

static void furnace(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    const float rho = 0.6f, le = 1.5f;
    ibl_scene_material m = lambert(rho, le);
    box_scene b;
    const int walls[6] = {0, 0, 0, 0, 0, 0};
    ibl_scene *s = box_scene_create(ctx, &b, walls, &m, 1);
    ibl_cubemap env;
    constant_env(ctx, &env, 100.0f); /* sealed out: must not show */
    ibl_local_probe p = centre_probe(IBL_CAPTURE_FAR_PLANE, 4);
    const int bounces[4] = {IBL_CAPTURE_NO_BOUNCE, 1, 2, 5};
    for (int k = 0; k < 4; k++) {
        int n = bounces[k] < 0 ? 0 : bounces[k];
        double want = 0.0;
        for (int i = 0; i <= n; i++) want += le * pow(rho, i);
        /* BRDF sampling only: every path returns exactly the truncated series */
        ibl_capture_desc d = {.bounces = bounces[k], .samples = 8, .no_light_sampling = 1};
        ibl_cubemap cube;
        assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
        for (size_t i = 0; i < 6 * 16; i++) {
            for (int c = 0; c < 3; c++) assert_near(cube.data[4 * i + c], want, 2e-6 * want);
            assert_near(cube.data[4 * i + 3], 1.0, 0);
        }
        ibl_cubemap_free(ctx, &cube);
        /* with emitter and environment sampling (MIS): unbiased, within the noise */
        d.no_light_sampling = 0;
        d.samples = 64;
        assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
        double mean[4];
        ibl_cubemap_mean(&cube, 0, mean);
        if (getenv("IBL_TEST_VERBOSE")) fprintf(stderr, "furnace N=%d: mean %.5f want %.5f (%+.3f%%)\n", n, mean[0], want, 100 * (mean[0] / want - 1));
        assert_near(mean[0], want, 0.01 * want);
        for (size_t i = 0; i < 6 * 16; i++) assert_near(cube.data[4 * i], want, 0.06 * want);
        ibl_cubemap_free(ctx, &cube);
    }
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- an emitting ceiling over a Lambertian floor ---------------------------------------------- */

/* Form factor from a point to a parallel rectangle of sides a x b at height h whose corner is
 * straight above the point (e.g. Howell's catalogue of configuration factors, B-3). */
static double corner_factor(double a, double b, double h)
{
    if (a <= 0.0 || b <= 0.0) return 0.0;
    double x = a / h, y = b / h, sx = sqrt(1 + x * x), sy = sqrt(1 + y * y);
    return (x / sx * atan(y / sx) + y / sy * atan(x / sy)) / (2.0 * PI);
}

/* ... from a point (px, pz) of the floor y = -1 to the ceiling [-1, 1]^2 at y = 1 */
static double ceiling_factor(double px, double pz)
{
    double f = 0.0;
    const double xs[2] = {1.0 - px, 1.0 + px}, zs[2] = {1.0 - pz, 1.0 + pz};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) f += corner_factor(xs[i], zs[j], 2.0);
    return f;
}

static void emitting_ceiling(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    const float rho = 0.7f, le = 2.0f;
    ibl_scene_material mats[2] = {lambert(rho, 0.0f), lambert(0.0f, le)};
    box_scene b;
    const int walls[6] = {0, 0, 1, 0, 0, 0}; /* +Y, the ceiling, emits */
    ibl_scene *s = box_scene_create(ctx, &b, walls, mats, 2);
    ibl_cubemap env;
    constant_env(ctx, &env, 0.0f);
    ibl_local_probe p = centre_probe(IBL_CAPTURE_FAR_PLANE, 4);
    ibl_capture_desc d = {.bounces = 1, .samples = 1024, .seed = 7};
    ibl_cubemap cube;
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
    const float *face = ibl_cubemap_face(&cube, 0, IBL_FACE_NEG_Y);
    double sum = 0.0, sum_ref = 0.0;
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            /* float64 reference: L = rho Le F at the floor point each direction of the texel
             * sees (the capture jitters uniformly in the face's s, t: so does this mean) */
            double ref = 0.0;
            const int g = 64;
            for (int j = 0; j < g; j++)
                for (int i = 0; i < g; i++) {
                    double dir[3];
                    ibl_cube_direction_d(IBL_FACE_NEG_Y, (x + (i + 0.5) / g) / 4.0,
                                         (y + (j + 0.5) / g) / 4.0, dir);
                    double t = 1.0 / -dir[1];
                    ref += rho * le * ceiling_factor(dir[0] * t, dir[2] * t);
                }
            ref /= g * g;
            double got = face[(y * 4 + x) * 4];
            if (getenv("IBL_TEST_VERBOSE")) fprintf(stderr, "texel %d %d: %.5f ref %.5f (%+.2f%%)\n", x, y, got, ref, 100 * (got / ref - 1));
            assert_near(got, ref, 0.05 * ref);
            sum += got;
            sum_ref += ref;
        }
    assert_near(sum, sum_ref, 0.015 * sum_ref);
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- coverage alpha ---------------------------------------------------------------------------- */

static void face_alpha(const ibl_cubemap *c, int face, double *lo, double *hi, double *rgb_max)
{
    const float *t = ibl_cubemap_face(c, 0, face);
    *lo = 1e9, *hi = -1e9, *rgb_max = 0;
    for (int i = 0; i < c->size * c->size; i++) {
        *lo = fmin(*lo, t[4 * i + 3]);
        *hi = fmax(*hi, t[4 * i + 3]);
        *rgb_max = fmax(*rgb_max, t[4 * i]);
    }
}

static void far_plane_alpha(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    ibl_scene_material m = lambert(0.5f, 1.0f);
    box_scene b;
    const int walls[6] = {-1, 0, 0, 0, 0, 0}; /* the +X wall is an opening */
    ibl_scene *s = box_scene_create(ctx, &b, walls, &m, 1);
    ibl_cubemap env;
    constant_env(ctx, &env, 3.0f);
    ibl_capture_desc d = {.bounces = IBL_CAPTURE_NO_BOUNCE, .samples = 16};
    /* far plane: the +X face looks through the opening at nothing the probe owns */
    ibl_local_probe p = centre_probe(IBL_CAPTURE_FAR_PLANE, 8);
    ibl_cubemap cube;
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
    double lo, hi, rgb;
    for (int f = 0; f < 6; f++) {
        face_alpha(&cube, f, &lo, &hi, &rgb);
        if (f == IBL_FACE_POS_X) {
            assert_near(hi, 0.0, 0); /* uncovered: alpha 0 and premultiplied black */
            assert_near(rgb, 0.0, 0);
        } else {
            assert_near(lo, 1.0, 0);
        }
    }
    ibl_cubemap_free(ctx, &cube);
    /* infinite: the same face shows the environment, alpha 1 */
    p.capture = IBL_CAPTURE_INFINITE;
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
    face_alpha(&cube, IBL_FACE_POS_X, &lo, &hi, &rgb);
    assert_near(lo, 1.0, 0);
    assert_near(cube.data[4 * 8 * 8 * IBL_FACE_POS_X], 3.0, 1e-6);
    ibl_cubemap_free(ctx, &cube);
    /* an influence sphere smaller than the room owns no wall: alpha 0 everywhere */
    p.capture = IBL_CAPTURE_FAR_PLANE;
    p.influence.shape = IBL_VOLUME_SPHERE;
    p.influence.radius = 0.5f;
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cube), IBL_OK);
    double mean[4];
    ibl_cubemap_mean(&cube, 0, mean);
    assert_near(mean[3], 0.0, 0);
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- premultiplied filtering: uncovered directions go to the next probe ------------------------- */

static void alpha_gives_way(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    ibl_scene_material m = lambert(0.5f, 1.0f);
    box_scene b;
    const int walls[6] = {-1, 0, 0, 0, 0, 0}; /* +X open: alpha 0 there */
    ibl_scene *s = box_scene_create(ctx, &b, walls, &m, 1);
    ibl_cubemap env, cap, chain;
    constant_env(ctx, &env, 3.0f);
    ibl_local_probe p = centre_probe(IBL_CAPTURE_FAR_PLANE, 16);
    ibl_capture_desc d = {.bounces = IBL_CAPTURE_NO_BOUNCE, .samples = 4};
    assert_int_equal(ibl_capture_probe(ctx, s, &env, &p, 0, &d, &cap), IBL_OK);
    assert_int_equal(ibl_capture_prefilter(ctx, &cap, "gltf", &chain), IBL_OK);
    assert_true(chain.levels > 2);
    /* every covered direction sees radiance 1, so premultiplied RGB equals alpha at every
     * level: filtering spreads coverage, never black light */
    size_t texels = ibl_cubemap_floats(chain.size, chain.levels) / 4;
    double min_a = 1, max_a = 0;
    for (size_t i = 0; i < texels; i++) {
        float a = chain.data[4 * i + 3];
        assert_near(chain.data[4 * i], a, 2e-3);
        min_a = fmin(min_a, a), max_a = fmax(max_a, a);
    }
    assert_true(min_a < 0.01 && max_a > 0.99);
    /* the rough end mixes: toward the opening alpha is between 0 and 1 */
    float t[4];
    ibl_cubemap_sample_nearest(&chain, chain.levels - 1, (ibl_vec3){1, 0, 0}, t);
    assert_true(t[3] > 0.05f && t[3] < 0.95f);
    /* blend: this probe first, then a probe of constant colour, then the global probe */
    const float next[4] = {0.2f, 0.5f, 0.9f, 1.0f}, global[3] = {5, 5, 5};
    const float weights[2] = {1.0f, 1.0f};
    float look[2][4], out[3];
    memcpy(look[1], next, sizeof next);
    ibl_cubemap_sample_nearest(&chain, 0, (ibl_vec3){1, 0, 0}, look[0]); /* uncovered */
    assert_near(look[0][3], 0.0, 1e-6);
    float rest = ibl_capture_blend((const float(*)[4])look, weights, 2, global, out);
    assert_near(rest, 0.0, 0);
    for (int c = 0; c < 3; c++) assert_near(out[c], next[c], 1e-6); /* the next probe's */
    ibl_cubemap_sample_nearest(&chain, 0, (ibl_vec3){-1, 0, 0}, look[0]); /* covered */
    rest = ibl_capture_blend((const float(*)[4])look, weights, 2, global, out);
    assert_near(rest, 0.0, 1e-5);
    for (int c = 0; c < 3; c++) assert_near(out[c], 1.0, 1e-5); /* this probe's own */
    /* half coverage, half influence: 0.5 of this probe's light, 0.75 left for the next */
    const float half[2][4] = {{0.5f, 0.5f, 0.5f, 0.5f}, {0.2f, 0.5f, 0.9f, 1.0f}};
    const float w2[2] = {1.0f, 0.0f};
    rest = ibl_capture_blend(half, w2, 2, global, out);
    assert_near(rest, 0.5, 1e-6); /* the second has no influence: the rest is the sky's */
    assert_near(out[0], 0.5 + 0.5 * 5, 1e-5);
    ibl_cubemap_free(ctx, &chain);
    ibl_cubemap_free(ctx, &cap);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* ---- the sample scene: glTF loading, threads --------------------------------------------------- */

#define ROOMS IBL_TEST_DATA "/../../examples/rooms"

static void sample_scene_threads(void **state)
{
    (void)state;
    ibl_context *c1 = test_context(1), *c2 = test_context(2);
    ibl_scene *s;
    assert_int_equal(ibl_scene_load_gltf(c1, ROOMS "/scene.gltf", &s), IBL_OK);
    ibl_scene_info info;
    ibl_scene_get_info(s, &info);
    assert_int_equal(info.triangle_count, 1624);
    assert_int_equal(info.emissive_triangle_count, 4);
    assert_int_equal(info.texture_count, 1);
    int lamp = -1;
    for (int i = 0; i < info.material_count; i++)
        if (strcmp(ibl_scene_get_material(s, i)->name, "warm_lamp") == 0) lamp = i;
    assert_true(lamp >= 0); /* KHR_materials_emissive_strength 40 x the factor */
    assert_near(ibl_scene_get_material(s, lamp)->emissive[1], 40 * 0.75, 1e-4);
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_load(c1, ROOMS "/probes.json", &set), IBL_OK);
    ibl_cubemap env;
    set.global.size = 32;
    assert_int_equal(ibl_probe_set_environment(c1, &set, &env), IBL_OK);
    ibl_capture_desc d = {.samples = 4, .size = 8, .bounces = 2};
    for (int i = 0; i < set.probe_count; i++) {
        ibl_cubemap a, b;
        assert_int_equal(ibl_capture_probe(c1, s, &env, &set.probes[i], i, &d, &a), IBL_OK);
        assert_int_equal(ibl_capture_probe(c2, s, &env, &set.probes[i], i, &d, &b), IBL_OK);
        assert_memory_equal(a.data, b.data, ibl_cubemap_floats(8, 1) * sizeof(float));
        double mean[4];
        ibl_cubemap_mean(&a, 0, mean);
        assert_true(mean[0] > 0.0 && isfinite(mean[0]));
        if (set.probes[i].capture == IBL_CAPTURE_FAR_PLANE) assert_true(mean[3] < 1.0); /* doors */
        ibl_cubemap_free(c1, &a);
        ibl_cubemap_free(c2, &b);
    }
    ibl_cubemap_free(c1, &env);
    ibl_probe_set_free(c1, &set);
    ibl_scene_destroy(s);
    ibl_context_destroy(c1);
    ibl_context_destroy(c2);
}

/* ---- the CLI ------------------------------------------------------------------------------------ */

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void cli_errors(void **state)
{
    (void)state;
    const char *out;
    const char *caps = test_path("caps");
    /* a missing scene, a scene that is not glTF, a bad probe set: one line, no folder */
    assert_int_equal(test_run_cli(&out, "capture -q %s/none.gltf --probes %s/probes.json -o %s",
                                  ROOMS, ROOMS, caps), 1);
    assert_int_equal(count_lines(out), 1);
    assert_non_null(strstr(out, "none.gltf"));
    const char *junk = test_path("junk.gltf");
    write_text(junk, "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{\"primitives\": 7}]}");
    assert_int_equal(test_run_cli(&out, "capture -q %s --probes %s/probes.json -o %s", junk,
                                  ROOMS, caps), 1);
    assert_int_equal(count_lines(out), 1);
    assert_non_null(strstr(out, "junk.gltf"));
    const char *bad = test_path("bad.json");
    write_text(bad, "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": {}, \"probes\": "
                    "[{\"name\": \"a\", \"position\": [0, 1, 0], \"influence\": "
                    "{\"shape\": \"sphere\", \"radius\": -1}}]}");
    assert_int_equal(test_run_cli(&out, "capture -q %s/scene.gltf --probes %s -o %s", ROOMS,
                                  bad, caps), 1);
    assert_int_equal(count_lines(out), 1);
    assert_non_null(strstr(out, "bad.json: probes[0].influence.radius: must be > 0"));
    struct stat st;
    assert_int_not_equal(stat(caps, &st), 0);
    /* usage errors exit 2 */
    assert_int_equal(test_run_cli(&out, "capture %s/scene.gltf -o %s", ROOMS, caps), 2);
    /* a good run, small */
    assert_int_equal(test_run_cli(&out, "capture -q %s/scene.gltf --probes %s/probes.json -o %s "
                                        "--size 4 --samples 1 --bounces 1", ROOMS, ROOMS, caps), 0);
    char path[4096];
    snprintf(path, sizeof path, "%s/captures.json", caps);
    assert_true(test_file_exists(path));
    snprintf(path, sizeof path, "%s/white_room.ktx2", caps);
    assert_true(test_file_exists(path));
    ibl_context *ctx = test_context(1);
    ibl_texture tex;
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &tex, NULL), IBL_OK);
    assert_int_equal(tex.kind, IBL_TEXTURE_CUBE);
    assert_int_equal(tex.width, 4);
    ibl_texture_free(ctx, &tex);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(furnace),
        cmocka_unit_test(emitting_ceiling),
        cmocka_unit_test(far_plane_alpha),
        cmocka_unit_test(alpha_gives_way),
        cmocka_unit_test(sample_scene_threads),
        cmocka_unit_test(cli_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
