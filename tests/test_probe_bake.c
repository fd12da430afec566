/* The probe-array bake (ibl_probe_bake, docs/PROBES.md "The probe bake"):
 *  - KTX2 cube-map arrays read back bit for bit (rgba32f) and as written (rgba16f);
 *  - a bake read back: layers in blend order, each the coverage-aware chain of its capture, the
 *    std430 records decoding to the set's numbers;
 *  - shards + merge give the same bytes as one run, and a re-run reuses every part;
 *  - bad inputs: one line naming the file and field, no folder. */
#include "test_support.h"

#include "ibl/probes.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char SET[] =
    "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": {\"size\": 16},"
    " \"probes\": ["
    "  {\"name\": \"big\", \"position\": [0, 1, 0], \"size\": 8,"
    "   \"influence\": {\"shape\": \"box\", \"half_extent\": [3, 1, 3], \"blend\": 0.5}},"
    "  {\"name\": \"ball\", \"position\": [1, 1, 0], \"size\": 8,"
    "   \"influence\": {\"shape\": \"sphere\", \"radius\": 0.8, \"blend\": 0.2}},"
    "  {\"name\": \"first\", \"position\": [-1, 1, 0], \"size\": 8, \"priority\": 2,"
    "   \"influence\": {\"shape\": \"sphere\", \"radius\": 0.9}}]}";

static void fill_capture(ibl_cubemap *c, int seed)
{
    size_t n = (size_t)6 * c->size * c->size;
    for (size_t i = 0; i < n; i++) {
        float a = (i + (size_t)seed) % 5 == 0 ? 0.0f : 1.0f; /* some uncovered texels */
        c->data[4 * i + 0] = a * (0.2f + 0.1f * (float)seed);
        c->data[4 * i + 1] = a * (float)(i % 7) / 7.0f;
        c->data[4 * i + 2] = a * 0.5f;
        c->data[4 * i + 3] = a;
    }
}

typedef struct fixture {
    ibl_context *ctx;
    ibl_probe_set set;
    ibl_cubemap env, caps[3];
    ibl_bake_desc global;
} fixture;

static void setup(fixture *f)
{
    memset(f, 0, sizeof *f);
    f->ctx = test_context(2);
    assert_int_equal(ibl_probe_set_parse(f->ctx, SET, strlen(SET), "set.json", ".", &f->set), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(f->ctx, 16, 1, &f->env), IBL_OK);
    test_fill_smooth(&f->env);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(ibl_cubemap_alloc(f->ctx, 8, 1, &f->caps[i]), IBL_OK);
        fill_capture(&f->caps[i], i);
    }
    assert_true(ibl_specular_preset("gltf", &f->global.specular));
    f->global.specular.size = 16;
    f->global.lut_size = 8;
    f->global.irradiance_size = 4;
    f->global.ambient_brdf = -1;
    f->global.preview_width = -1;
}

static void teardown(fixture *f)
{
    for (int i = 0; i < 3; i++) ibl_cubemap_free(f->ctx, &f->caps[i]);
    ibl_cubemap_free(f->ctx, &f->env);
    ibl_probe_set_free(f->ctx, &f->set);
    ibl_context_destroy(f->ctx);
}

static ibl_status bake(fixture *f, const char *dir, int shard, int shards, int merge,
                       ibl_probe_bake_report *rep)
{
    ibl_probe_bake_desc d = {.cubes = f->caps, .shard = shard, .shards = shards, .merge = merge,
                             .global = &f->global};
    return ibl_probe_bake(f->ctx, &f->set, shards ? NULL : &f->env, &d, dir, rep);
}

static void cube_array_roundtrip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap cubes[3];
    for (int i = 0; i < 3; i++) {
        assert_int_equal(ibl_cubemap_alloc(ctx, 8, 4, &cubes[i]), IBL_OK);
        size_t n = ibl_cubemap_floats(8, 4);
        for (size_t k = 0; k < n; k++) cubes[i].data[k] = (float)((k * 31 + (size_t)i * 7) % 97) / 13.0f;
    }
    for (int pass = 0; pass < 2; pass++) {
        ibl_write_desc wd = {.format = pass ? IBL_FORMAT_RGBA16F : IBL_FORMAT_RGBA32F};
        void *bytes;
        size_t size;
        assert_int_equal(ibl_encode_cube_array(ctx, cubes, 3, NULL, 0, &wd, &bytes, &size), IBL_OK);
        const unsigned char *b = bytes;
        assert_int_equal(b[32], 3); /* layerCount */
        assert_int_equal(b[36], 6); /* faceCount */
        ibl_cubemap *back;
        int count;
        assert_int_equal(ibl_decode_cube_array(ctx, bytes, size, "a.ktx2", &back, &count, NULL), IBL_OK);
        assert_int_equal(count, 3);
        for (int i = 0; i < 3; i++) {
            assert_int_equal(back[i].levels, 4);
            size_t n = ibl_cubemap_floats(8, 4);
            for (size_t k = 0; k < n; k++) /* values are multiples of 1/13 below 7.5: 16f keeps 2^-8 */
                assert_true(fabsf(back[i].data[k] - cubes[i].data[k]) <= (pass ? 4e-3f : 0.0f));
            ibl_cubemap_free(ctx, &back[i]);
        }
        ibl_free(ctx, back);
        ibl_free(ctx, bytes);
    }
    for (int i = 0; i < 3; i++) ibl_cubemap_free(ctx, &cubes[i]);
    ibl_context_destroy(ctx);
}

static void bake_and_load(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    const char *dir = test_path("bake");
    ibl_probe_bake_report rep;
    assert_int_equal(bake(&f, dir, 0, 0, 0, &rep), IBL_OK);
    assert_int_equal(rep.computed, 3);
    ibl_probe_bake_data b;
    assert_int_equal(ibl_probe_bake_load(f.ctx, dir, &b), IBL_OK);
    assert_int_equal(b.count, 3);
    int order[3];
    ibl_probe_set_order(&f.set, order);
    /* priority 2 first, then the smaller sphere, then the box */
    assert_int_equal(order[0], 2);
    assert_int_equal(order[1], 1);
    assert_int_equal(order[2], 0);
    for (int l = 0; l < 3; l++) {
        const ibl_local_probe *p = &f.set.probes[order[l]];
        const ibl_probe_record *r = &b.records[l];
        assert_string_equal(r->name, p->name);
        assert_int_equal(r->layer, l);
        assert_int_equal(r->priority, p->priority);
        assert_int_equal(r->influence.shape, p->influence.shape);
        assert_true(r->position.x == p->position.x && r->influence.radius == p->influence.radius);
        assert_true(r->influence.blend_distance == p->influence.blend_distance);
        assert_true(r->influence_size == ibl_volume_size(&p->influence));
        /* the layer is the capture's coverage-aware chain, stored as rgba16f */
        ibl_cubemap chain;
        assert_int_equal(ibl_capture_prefilter(f.ctx, &f.caps[order[l]], "gltf", &chain), IBL_OK);
        assert_int_equal(b.chains[l].levels, chain.levels);
        size_t n = ibl_cubemap_floats(chain.size, chain.levels);
        for (size_t k = 0; k < n; k++)
            assert_true(fabsf(b.chains[l].data[k] - chain.data[k]) <= 1e-3f * (1.0f + fabsf(chain.data[k])));
        ibl_cubemap_free(f.ctx, &chain);
        /* SH (0,0) of the coverage: 4 pi x mean alpha x Y00 (a fifth of the texels uncovered) */
        double m[4];
        ibl_cubemap_mean(&f.caps[order[l]], 0, m);
        assert_near(r->sh[0][3], 4.0 * 3.14159265358979 * m[3] * 0.282095, 2e-2);
    }
    assert_int_equal(b.mapping.levels, b.chains[0].levels);
    ibl_probe_bake_free(f.ctx, &b);
    teardown(&f);
}

static int read_all(const char *path, unsigned char **bytes, size_t *size)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return 0;
    fseek(fp, 0, SEEK_END);
    *size = (size_t)ftell(fp);
    fseek(fp, 0, SEEK_SET);
    *bytes = malloc(*size + 1);
    size_t got = fread(*bytes, 1, *size, fp);
    fclose(fp);
    return got == *size;
}

/* Every file of a equals the file of that name in b, and they hold the same names. */
static void assert_same_folders(const char *a, const char *b)
{
    int na = 0, nb = 0;
    for (int side = 0; side < 2; side++) {
        DIR *d = opendir(side ? b : a);
        assert_non_null(d);
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (e->d_name[0] == '.') continue;
            if (side) { nb++; continue; }
            na++;
            char pa[4096], pb[4096];
            snprintf(pa, sizeof pa, "%s/%s", a, e->d_name);
            snprintf(pb, sizeof pb, "%s/%s", b, e->d_name);
            unsigned char *x = NULL, *y = NULL;
            size_t sx = 0, sy = 0;
            assert_true(read_all(pa, &x, &sx));
            if (!read_all(pb, &y, &sy)) fail_msg("%s: missing", pb);
            if (sx != sy || memcmp(x, y, sx) != 0) fail_msg("%s differs from %s", pa, pb);
            free(x);
            free(y);
        }
        closedir(d);
    }
    assert_int_equal(na, nb);
}

static void shard_merge_identity(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    const char *one = test_path("one"), *sharded = test_path("sharded");
    ibl_probe_bake_report rep;
    assert_int_equal(bake(&f, one, 0, 0, 0, &rep), IBL_OK);
    int total = 0;
    for (int s = 1; s <= 2; s++) {
        assert_int_equal(bake(&f, sharded, s, 2, 0, &rep), IBL_OK);
        total += rep.computed;
    }
    assert_int_equal(total, 3);
    assert_int_equal(bake(&f, sharded, 0, 0, 1, &rep), IBL_OK);
    assert_int_equal(rep.computed, 0);
    assert_same_folders(one, sharded);
    /* a re-run filters nothing and changes nothing */
    assert_int_equal(bake(&f, sharded, 0, 0, 0, &rep), IBL_OK);
    assert_int_equal(rep.computed, 0);
    assert_int_equal(rep.reused, 3);
    assert_same_folders(one, sharded);
    teardown(&f);
}

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

static void errors(void **state)
{
    (void)state;
    fixture f;
    setup(&f);
    struct stat st;
    /* a merge without its parts: names the part and the probe, writes nothing */
    const char *dir = test_path("nothing");
    assert_int_equal(bake(&f, dir, 0, 0, 1, NULL), IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(f.ctx), "missing: the part of probe first"));
    assert_int_not_equal(stat(dir, &st), 0);
    /* a shard number out of range */
    assert_int_equal(bake(&f, dir, 3, 2, 0, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_int_not_equal(stat(dir, &st), 0);
    /* two presets cannot share one array */
    snprintf(f.set.probes[1].preset, sizeof f.set.probes[1].preset, "unreal");
    assert_int_equal(bake(&f, dir, 0, 0, 0, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(f.ctx), "set.json: probes[1].preset"));
    assert_int_not_equal(stat(dir, &st), 0);
    teardown(&f);
    /* the CLI: one line, exit 1 or 2, no folder */
    const char *out;
    const char *cli_dir = test_path("cli");
    assert_int_equal(test_run_cli(&out, "bake -q --probes %s/../../examples/rooms/probes.json "
                                        "--captures %s/none -o %s", IBL_TEST_DATA, IBL_TEST_DATA, cli_dir), 1);
    assert_int_equal(count_lines(out), 1);
    assert_non_null(strstr(out, "none/"));
    assert_int_not_equal(stat(cli_dir, &st), 0);
    assert_int_equal(test_run_cli(&out, "bake -q --probes x.json -o %s --shard 3/2", cli_dir), 2);
    assert_int_equal(test_run_cli(&out, "bake -q --captures c -o %s", cli_dir), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cube_array_roundtrip),
        cmocka_unit_test(bake_and_load),
        cmocka_unit_test(shard_merge_identity),
        cmocka_unit_test(errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
