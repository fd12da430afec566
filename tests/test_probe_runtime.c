/* The probe run time (ibl_cull_probes, ibl_probes_shade, ibl_parallax_correct; docs/PROBES.md
 * "Run time"):
 *  - a box room: the parallax-corrected direction points from the capture position at the
 *    analytic hit of the reflected ray with the room's walls;
 *  - the blend's weights: local shares plus the global remainder sum to 1;
 *  - a probe whose alpha is 0 in a direction gives it to the next probe;
 *  - culling: exact lists equal a brute-force per-pixel test; conservative lists contain them;
 *    the three sorts give the same lists. */
#include "test_support.h"

#include "ibl/probes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static ibl_vec3 v3(float x, float y, float z)
{
    ibl_vec3 v = {x, y, z};
    return v;
}

static void box_room_parallax(void **state)
{
    (void)state;
    /* room [-2, 2] x [0, 3] x [-1, 1], probe at (0.5, 1.5, 0) */
    ibl_volume room = {.shape = IBL_VOLUME_BOX, .center = {0, 1.5f, 0}, .half_extent = {2, 1.5f, 1}};
    ibl_vec3 probe = v3(0.5f, 1.5f, 0);
    struct { ibl_vec3 p, r, hit; } cases[] = {
        {{-1, 1, 0}, {1, 0, 0}, {2, 1, 0}},                /* to the +X wall           */
        {{1, 0.5f, 0.5f}, {0, 1, 0}, {1, 3, 0.5f}},        /* to the ceiling          */
        {{0, 1, 0}, {0.6f, 0, 0.8f}, {0.75f, 1, 1}},       /* t = 1.25 to the +Z wall */
        {{-1.5f, 2, -0.5f}, {-0.8f, 0, -0.6f}, {-2, 2, -0.875f}}, /* -X wall first at t = 0.625 */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ibl_vec3 d = ibl_parallax_correct(&room, probe, cases[i].p, cases[i].r);
        ibl_vec3 want = {cases[i].hit.x - probe.x, cases[i].hit.y - probe.y, cases[i].hit.z - probe.z};
        float len = sqrtf(want.x * want.x + want.y * want.y + want.z * want.z);
        assert_near(d.x, want.x / len, 1e-5);
        assert_near(d.y, want.y / len, 1e-5);
        assert_near(d.z, want.z / len, 1e-5);
    }
}

/* A probe bake in memory: count layers of constant colour (alpha per layer, or 0 toward +X
 * when half_open), roughness mapping 0..1, spheres of influence. */
typedef struct mem_bake {
    ibl_context *ctx;
    ibl_probe_bake_data bake;
    ibl_probe global, locals[3];
    ibl_cubemap global_cube;
    float lut[2 * 2 * 2];
} mem_bake;

static void fill_layer(ibl_cubemap *c, const float rgb[3], int open_plus_x)
{
    for (int l = 0; l < c->levels; l++)
        for (int f = 0; f < 6; f++) {
            int n = ibl_level_size(c->size, l);
            float *t = ibl_cubemap_face(c, l, f);
            float a = open_plus_x && f == 0 ? 0.0f : 1.0f;
            for (int i = 0; i < n * n; i++)
                for (int k = 0; k < 4; k++) t[4 * i + k] = k < 3 ? a * rgb[k] : a;
        }
}

static void make_bake(mem_bake *m, int count, int open_first)
{
    memset(m, 0, sizeof *m);
    m->ctx = test_context(1);
    ibl_probe_bake_data *b = &m->bake;
    b->count = count;
    b->records = calloc((size_t)count, sizeof *b->records);
    b->chains = calloc((size_t)count, sizeof *b->chains);
    b->mapping.levels = 3;
    for (int l = 0; l < 3; l++) b->mapping.roughness[l] = (float)l / 2.0f;
    static const float colours[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < count; i++) {
        assert_int_equal(ibl_cubemap_alloc(m->ctx, 4, 3, &b->chains[i]), IBL_OK);
        fill_layer(&b->chains[i], colours[i], open_first && i == 0);
        ibl_probe_record *r = &b->records[i];
        r->position = v3(0, 0, 0);
        r->influence = (ibl_volume){.shape = IBL_VOLUME_SPHERE, .radius = 1.0f + (float)i, .blend_distance = 0.5f};
        r->proxy = r->influence;
        r->layer = i;
        /* SH of a constant: c x sqrt(4 pi) in (0,0); coverage likewise */
        for (int k = 0; k < 3; k++) r->sh[0][k] = colours[i][k] * 3.5449077f;
        r->sh[0][3] = 3.5449077f;
    }
    assert_int_equal(ibl_cubemap_alloc(m->ctx, 4, 3, &m->global_cube), IBL_OK);
    fill_layer(&m->global_cube, (float[3]){0.5f, 0.5f, 0.5f}, 0);
    m->global.specular = m->global_cube;
    m->global.mapping = b->mapping;
    m->global.sh_kind = IBL_SH_KIND_RADIANCE;
    for (int k = 0; k < 3; k++) m->global.sh[0][k] = 0.5f * 3.5449077f;
    for (int i = 0; i < 8; i++) m->lut[i] = (i % 2) ? 0.0f : 1.0f; /* A = 1, B = 0 */
    m->global.splitsum = (ibl_splitsum_view){m->lut, 2, {2, 0, 1, 0}, {2, 0, 1, 0}};
    assert_int_equal(ibl_probe_validate(m->ctx, &m->global), IBL_OK);
    assert_int_equal(ibl_probe_bake_locals(m->ctx, b, &m->global, m->locals), IBL_OK);
}

static void free_bake(mem_bake *m)
{
    for (int i = 0; i < m->bake.count; i++) ibl_cubemap_free(m->ctx, &m->bake.chains[i]);
    free(m->bake.chains);
    free(m->bake.records);
    ibl_cubemap_free(m->ctx, &m->global_cube);
    ibl_context_destroy(m->ctx);
}

/* Specular of a white metal mirror (F0 = 1, A = 1, B = 0): the blended radiance itself. */
static void shade_at(mem_bake *m, ibl_vec3 p, ibl_vec3 n, const ibl_probe_blend_desc *bd,
                     ibl_shade_result *r, ibl_probe_blend_info *info)
{
    ibl_material mat = ibl_material_gltf((float[3]){1, 1, 1}, 1.0f, 0.0f);
    ibl_surface s = {.n = n, .v = n};
    ibl_shade_desc sd = {.mirror_direction = 1};
    int list[3] = {0, 1, 2};
    ibl_probes_shade(&m->bake, &m->global, m->locals, list, m->bake.count, bd, &sd, &mat, p, &s, r, info);
}

static void weights_sum_to_one(void **state)
{
    (void)state;
    mem_bake m;
    make_bake(&m, 3, 0);
    /* along a line through the three nested spheres' margins, the result is the weighted sum of
     * the colours (red, green, blue) and grey (global): shares recovered from the channels */
    for (int i = 0; i <= 40; i++) {
        float x = 3.2f * (float)i / 40.0f;
        ibl_vec3 p = v3(x, 0, 0);
        ibl_shade_result r;
        ibl_probe_blend_info info;
        shade_at(&m, p, v3(0, 1, 0), NULL, &r, &info);
        float w[3];
        int order[3] = {0, 1, 2};
        ibl_volume vols[3] = {m.bake.records[0].influence, m.bake.records[1].influence, m.bake.records[2].influence};
        float global = ibl_volume_blend(vols, order, 3, p, w);
        assert_near(w[0] + w[1] + w[2] + global, 1.0, 1e-6);
        assert_near(info.specular_global, global, 1e-5);
        for (int k = 0; k < 3; k++) assert_near(r.specular[k], w[k] + 0.5f * global, 1e-4);
    }
    free_bake(&m);
}

static void alpha_gives_way(void **state)
{
    (void)state;
    mem_bake m;
    make_bake(&m, 2, 1); /* layer 0 (red) sees nothing toward +X */
    ibl_vec3 p = v3(0.1f, 0, 0);
    ibl_shade_result r;
    ibl_probe_blend_info info;
    /* toward +X: red gives way to green (weight 1 inside its core) */
    shade_at(&m, p, v3(1, 0, 0), NULL, &r, &info);
    assert_near(r.specular[0], 0.0, 1e-5);
    assert_near(r.specular[1], 1.0, 1e-5);
    assert_int_equal(info.heaviest, 1);
    /* toward +Y: red itself */
    shade_at(&m, p, v3(0, 1, 0), NULL, &r, &info);
    assert_near(r.specular[0], 1.0, 1e-5);
    assert_near(r.specular[1], 0.0, 1e-5);
    /* without alpha the hole shows black */
    ibl_probe_blend_desc no_alpha = {.no_alpha = 1};
    shade_at(&m, p, v3(1, 0, 0), &no_alpha, &r, &info);
    assert_near(r.specular[0] + r.specular[1] + r.specular[2], 0.0, 1e-5);
    free_bake(&m);
}

/* ---- culling ---------------------------------------------------------------------------------- */

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static float frand(uint32_t *s)
{
    return (float)lcg(s) / 16777216.0f;
}

static void culling(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_camera cam = {.position = {0, 1.5f, 6}, .forward = {0, -0.1f, -1}, .up = {0, 1, 0},
                      .fov_y_degrees = 70, .width = 160, .height = 96};
    /* a depth buffer: a floor, a back wall and a sphere-ish bump, some sky */
    float *depth = malloc(sizeof(float) * 160 * 96);
    ibl_vec3 r, u, f;
    ibl_camera_basis(&cam, &r, &u, &f);
    for (int y = 0; y < 96; y++)
        for (int x = 0; x < 160; x++) {
            ibl_vec3 ray = ibl_camera_ray(&cam, x + 0.5f, y + 0.5f);
            float t = 1e30f;
            if (ray.y < 0) t = fminf(t, -cam.position.y / ray.y);      /* floor y = 0 */
            if (ray.z < 0) t = fminf(t, (-4.0f - cam.position.z) / ray.z); /* wall z = -4 */
            if (x > 100 && y < 20) t = 1e30f;                          /* a window of sky */
            depth[y * 160 + x] = t < 1e29f ? t : 0.0f;
        }
    uint32_t seed = 7;
    enum { N = 24 };
    ibl_volume vols[N];
    for (int i = 0; i < N; i++) {
        ibl_vec3 c = v3(-5 + 10 * frand(&seed), 3 * frand(&seed), -4 + 8 * frand(&seed));
        if (i % 2) vols[i] = (ibl_volume){.shape = IBL_VOLUME_SPHERE, .center = c, .radius = 0.3f + 1.5f * frand(&seed)};
        else vols[i] = (ibl_volume){.shape = IBL_VOLUME_BOX, .center = c,
                                    .half_extent = {0.2f + frand(&seed), 0.2f + frand(&seed), 0.2f + frand(&seed)}};
    }
    ibl_tile_lists exact[3], cons;
    ibl_cull_stats stats[3], cstats;
    for (int s = 0; s < 3; s++) {
        ibl_cull_desc d = {.tile_size = 16, .sort = (ibl_tile_sort)s, .exact = 1};
        assert_int_equal(ibl_cull_probes(ctx, &cam, depth, vols, N, &d, &exact[s], &stats[s]), IBL_OK);
    }
    ibl_cull_desc cd = {.tile_size = 16};
    assert_int_equal(ibl_cull_probes(ctx, &cam, depth, vols, N, &cd, &cons, &cstats), IBL_OK);
    /* the sorts agree; rank sorts compare n^2, odd-even n(n-1)/2 */
    for (int s = 1; s < 3; s++) {
        assert_memory_equal(exact[s].offsets, exact[0].offsets, sizeof(int) * (size_t)(exact[0].tiles_x * exact[0].tiles_y + 1));
        assert_memory_equal(exact[s].indices, exact[0].indices, sizeof(int) * (size_t)stats[0].entries);
    }
    assert_true(stats[1].compares == stats[2].compares && stats[0].compares <= stats[1].compares);
    /* brute force: per tile, the probes whose volume holds some pixel's point, ascending */
    long long extra = 0;
    for (int ty = 0; ty < exact[0].tiles_y; ty++)
        for (int tx = 0; tx < exact[0].tiles_x; tx++) {
            int t = ty * exact[0].tiles_x + tx, want[N], n = 0;
            for (int i = 0; i < N; i++) {
                int in = 0;
                for (int y = ty * 16; y < ty * 16 + 16 && y < 96 && !in; y++)
                    for (int x = tx * 16; x < tx * 16 + 16 && x < 160 && !in; x++) {
                        float d = depth[y * 160 + x];
                        if (d <= 0) continue;
                        ibl_vec3 ray = ibl_camera_ray(&cam, x + 0.5f, y + 0.5f);
                        ibl_vec3 p = v3(cam.position.x + d * ray.x, cam.position.y + d * ray.y, cam.position.z + d * ray.z);
                        in = ibl_volume_weight(&vols[i], p) > 0.0f;
                    }
                if (in) want[n++] = i;
            }
            int got = exact[0].offsets[t + 1] - exact[0].offsets[t];
            assert_int_equal(got, n);
            if (n) assert_memory_equal(exact[0].indices + exact[0].offsets[t], want, sizeof(int) * (size_t)n);
            /* the conservative list holds them all, in order */
            const int *c = cons.indices + cons.offsets[t];
            int cn = cons.offsets[t + 1] - cons.offsets[t], k = 0;
            for (int i = 0; i < cn && k < n; i++) k += c[i] == want[k];
            assert_int_equal(k, n);
            for (int i = 1; i < cn; i++) assert_true(c[i - 1] < c[i]);
            extra += cn - n;
        }
    print_message("culling: %lld exact entries, %lld conservative (+%lld), tests %lld, "
                  "compares odd-even %lld rank %lld\n", stats[0].entries, cstats.entries, extra,
                  cstats.tests, stats[0].compares, stats[1].compares);
    for (int s = 0; s < 3; s++) ibl_tile_lists_free(ctx, &exact[s]);
    ibl_tile_lists_free(ctx, &cons);
    free(depth);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(box_room_parallax),
        cmocka_unit_test(weights_sum_to_one),
        cmocka_unit_test(alpha_gives_way),
        cmocka_unit_test(culling),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
