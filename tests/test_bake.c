/* The bake module: every filter, mapping and preset round-trips through the folder (the level
 * table, the units, the AmbientBRDF axis), the manifest's errors name the field, the folder
 * is replaced as one transaction, and parts load from separate files. */
#include "test_support.h"

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

/* A small environment with structure (a bright lobe and a colour gradient). */
static void environment(ibl_context *ctx, int size, ibl_cubemap *env)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, size, 1, env), IBL_OK);
    test_fill_smooth(env);
}

/* Small tables keep the sanitizer build fast; the axes are what is checked. */
static ibl_bake_desc small_desc(void)
{
    ibl_bake_desc d;
    memset(&d, 0, sizeof d);
    d.lut_size = 8;
    d.irradiance_size = 4;
    d.preview_width = 16;
    d.ambient.size_nv = 4;
    d.ambient.size_shininess = 6;
    d.ambient.size_f0 = 2;
    d.ambient.order = 6;
    return d;
}

/* The loaded bake describes the same chain, bit for bit, and its probe the same mapping. */
static void assert_same_bake(ibl_context *ctx, const ibl_bake_data *a, const ibl_bake_data *b)
{
    const ibl_specular_info *x = &a->specular_info, *y = &b->specular_info;
    assert_int_equal(x->filter, y->filter);
    assert_int_equal(x->mapping, y->mapping);
    assert_int_equal(x->levels, y->levels);
    assert_int_equal(x->size, y->size);
    assert_int_equal(x->mirror, y->mirror);
    assert_true(x->blinn_factor == y->blinn_factor);
    for (int l = 0; l < x->levels; l++) {
        assert_true(x->roughness[l] == y->roughness[l]);
        assert_true(x->shininess[l] == y->shininess[l]);
    }
    assert_int_equal(b->specular.levels, a->specular.levels);
    ibl_probe p, q;
    assert_int_equal(ibl_bake_probe(ctx, a, &p), IBL_OK);
    assert_int_equal(ibl_bake_probe(ctx, b, &q), IBL_OK);
    assert_int_equal(p.mapping.levels, q.mapping.levels);
    for (int l = 0; l < p.mapping.levels; l++) {
        assert_true(p.mapping.roughness[l] == q.mapping.roughness[l]);
        assert_true(p.mapping.shininess[l] == q.mapping.shininess[l]);
    }
    assert_int_equal(p.ambient_brdf.data != NULL, q.ambient_brdf.data != NULL);
    if (p.ambient_brdf.data) {
        const ibl_table_axis *s = &p.ambient_brdf.shininess, *t = &q.ambient_brdf.shininess;
        assert_int_equal(s->count, t->count);
        assert_true(s->first == t->first && s->last == t->last && s->logarithmic == t->logarithmic);
    }
    /* the texels, through half-float storage (relative 2^-11) */
    for (int l = 0; l < x->levels; l++) {
        int n = ibl_level_size(x->size, l);
        const float *u = ibl_cubemap_face(&a->specular, l, 0), *v = ibl_cubemap_face(&b->specular, l, 0);
        for (size_t i = 0; i < (size_t)6 * n * n * 4; i++) assert_near(v[i], u[i], 1e-3 * (1 + fabs(u[i])));
    }
}

/* Units: a Phong-family level k serves the material of shininess blinn_factor x its kernel's
 * exponent (a phong chain's levels are kernel exponents; blinn, box and gauss chains' are the
 * material's shininess already), the probe finds level k at that
 * shininess, and the AmbientBRDF lookup at a row's shininess is that row's exact albedo
 * (float64 ibl_ambient_brdf, through half storage): the axis is the material's. */
static void assert_units(ibl_context *ctx, const ibl_bake_data *b, const ibl_bake_desc *d)
{
    const ibl_specular_info *info = &b->specular_info;
    ibl_probe p;
    assert_int_equal(ibl_bake_probe(ctx, b, &p), IBL_OK);
    if (info->filter == IBL_FILTER_GGX) {
        for (int l = 0; l < info->levels; l++)
            if (l == 0 || info->roughness[l] > info->roughness[l - 1])
                assert_near(ibl_probe_lod_from_roughness(&p, info->roughness[l]), l, 1e-4);
        return;
    }
    for (int l = 0; l < info->levels; l++) {
        if (!(info->shininess[l] > 0)) continue; /* the mirror level */
        float s = info->filter == IBL_FILTER_PHONG ? info->shininess[l] * info->blinn_factor : info->shininess[l];
        assert_true(p.mapping.shininess[l] == s);
        if (l == 0 || p.mapping.shininess[l] < p.mapping.shininess[l - 1])
            assert_near(ibl_probe_lod_from_shininess(&p, s), l, 1e-4);
    }
    assert_non_null(p.ambient_brdf.data);
    const ibl_ambient_brdf_view *ab = &p.ambient_brdf;
    /* whatever the chain's range, the rows' centres span every material: 1 to 100000 unless
     * the desc says otherwise (a shininess-1 material on a box chain still reads its albedo) */
    double lo = d->ambient.shininess_min > 0 ? d->ambient.shininess_min : 1.0;
    double hi = d->ambient.shininess_max > lo ? d->ambient.shininess_max : 100000.0;
    assert_near(ibl_table_axis_value(&ab->shininess, 0), lo, 1e-4 * lo);
    assert_near(ibl_table_axis_value(&ab->shininess, ab->shininess.count - 1), hi, 1e-4 * hi);
    for (int j = 0; j < ab->shininess.count; j++) {
        float s = ibl_table_axis_value(&ab->shininess, j);
        for (int i = 0; i < ab->n_dot_v.count; i++) {
            float nv = ibl_table_axis_value(&ab->n_dot_v, i), f0 = ibl_table_axis_value(&ab->f0, 0);
            double want = ibl_ambient_brdf(nv, s, f0, d->ambient.normalization, d->ambient.order);
            assert_near(ibl_ambient_brdf_lookup(ab, nv, s, f0), want, 2e-3 + 2e-3 * want);
        }
    }
}

static void round_trip(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *d,
                       const char *label)
{
    ibl_bake_data made, loaded, parts;
    ibl_status st = ibl_bake_compute(ctx, env, d, &made);
    if (st != IBL_OK) fail_msg("%s: %s", label, ibl_context_message(ctx));
    const char *dir = test_path("bake");
    assert_int_equal(ibl_bake_write(ctx, &made, dir), IBL_OK);
    if (ibl_bake_load(ctx, dir, NULL, &loaded) != IBL_OK) fail_msg("%s: %s", label, ibl_context_message(ctx));
    assert_same_bake(ctx, &made, &loaded);
    assert_units(ctx, &loaded, d);
    /* the KTX2 chain alone describes itself */
    char path[1024];
    snprintf(path, sizeof path, "%s/specular.ktx2", dir);
    ibl_bake_parts bp = {.specular = path};
    assert_int_equal(ibl_bake_load_parts(ctx, &bp, NULL, &parts), IBL_OK);
    assert_int_equal(parts.specular_info.levels, made.specular_info.levels);
    for (int l = 0; l < made.specular_info.levels; l++) {
        assert_true(parts.specular_info.roughness[l] == made.specular_info.roughness[l]);
        assert_true(parts.specular_info.shininess[l] == made.specular_info.shininess[l]);
    }
    ibl_bake_free(ctx, &parts);
    ibl_bake_free(ctx, &loaded);
    ibl_bake_free(ctx, &made);
}

static void every_filter_and_mapping(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    ibl_cubemap env;
    environment(ctx, 32, &env);
    static const ibl_specular_mapping mappings[] = {
        IBL_MAPPING_DEFAULT, IBL_MAPPING_TRIACE, IBL_MAPPING_LINEAR, IBL_MAPPING_FILAMENT,
        IBL_MAPPING_UNREAL, IBL_MAPPING_UNITY, IBL_MAPPING_BABYLON, IBL_MAPPING_TABLE};
    for (int f = 0; f < IBL_FILTER_COUNT; f++)
        for (size_t m = 0; m < sizeof mappings / sizeof mappings[0]; m++)
            for (int mirror = 0; mirror < 2; mirror++) {
                ibl_bake_desc d = small_desc();
                d.specular.filter = (ibl_specular_filter)f;
                d.specular.mapping = mappings[m];
                d.specular.size = 16;
                d.specular.mirror = mirror;
                float table[5] = {0.0f, 0.3f, 0.5f, 0.8f, 1.0f}, shininess[5] = {800, 200, 50, 10, 2};
                if (mappings[m] == IBL_MAPPING_TABLE) {
                    d.specular.table = f == IBL_FILTER_GGX ? table : shininess;
                    d.specular.table_count = 5;
                    d.specular.levels = 5;
                }
                char label[64];
                snprintf(label, sizeof label, "%s/%s/%d", ibl_specular_filter_name(d.specular.filter),
                         ibl_specular_mapping_name(mappings[m]), mirror);
                round_trip(ctx, &env, &d, label);
            }
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

static void every_preset(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    ibl_cubemap env;
    environment(ctx, 32, &env);
    for (const char *const *name = ibl_specular_preset_names(); *name; name++) {
        ibl_bake_desc d = small_desc();
        assert_true(ibl_specular_preset(*name, &d.specular));
        /* the preset's own levels and mapping at a test-sized chain */
        if (d.specular.size > 16) d.specular.size = 16;
        d.preset = *name;
        round_trip(ctx, &env, &d, *name);
    }
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

/* The tri-Ace mapping ends the chain at the range's bottom instead of repeating it, and an
 * explicit level count past that is refused. */
static void triace_levels_distinct(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_specular_desc d = {.filter = IBL_FILTER_PHONG, .size = 256};
    ibl_specular_info info;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_OK);
    assert_int_equal(info.levels, 6); /* 1000 250 62.5 15.6 3.9 1 */
    for (int l = 1; l < info.levels; l++) assert_true(info.shininess[l] < info.shininess[l - 1]);
    assert_near(info.shininess[5], 1.0, 0);
    d.mirror = 1;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_OK);
    assert_int_equal(info.levels, 7);
    d.levels = 9;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "distinct"));
    ibl_context_destroy(ctx);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *t = calloc(1, (size_t)n + 1);
    assert_int_equal(fread(t, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    return t;
}

/* Replaces the first `from` in the manifest with `to` and loads; returns the status. */
static ibl_status load_edited(ibl_context *ctx, const char *dir, const char *original,
                              const char *from, const char *to)
{
    const char *at = strstr(original, from);
    assert_non_null(at);
    size_t n = strlen(original) + strlen(to) + 1;
    char *edited = malloc(n);
    snprintf(edited, n, "%.*s%s%s", (int)(at - original), original, to, at + strlen(from));
    char path[1024];
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    write_text(path, edited);
    free(edited);
    ibl_bake_data b;
    ibl_status st = ibl_bake_load(ctx, dir, NULL, &b);
    if (st == IBL_OK) ibl_bake_free(ctx, &b);
    return st;
}

/* A manifest that is wrong says where: the file, then the field's path or the line. */
static void manifest_errors(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap env;
    environment(ctx, 16, &env);
    ibl_bake_desc d = small_desc();
    d.specular.filter = IBL_FILTER_PHONG;
    const char *dir = test_path("bad");
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_OK);
    char path[1024];
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    char *original = read_text(path);
    static const struct {
        const char *from, *to, *message;
    } cases[] = {
        {"\"version\": 1", "\"version\": 99", "version: 99 is newer"},
        {"\"format\": \"ibl-bake\"", "\"format\": \"other\"", "format: not an ibl bake manifest"},
        {"\"filter\": \"phong\"", "\"filter\": \"fuzzy\"", "specular.filter: unknown filter"},
        {"\"specular.ktx2\"", "\"../../etc/passwd\"", "specular.files: '../../etc/passwd' is not a file"},
        {"\"phong_exponent\": ", "\"phong_exponent\": -", "specular.levels[0].phong_exponent: must be"},
        {"\"level_count\": ", "\"level_count\" ", "line "}, /* a syntax error */
        {"\"count\": 4", "\"count\": \"four\"", "brdf.ambient_brdf.n_dot_v.count: expected a whole"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        assert_int_equal(load_edited(ctx, dir, original, cases[i].from, cases[i].to), IBL_ERR_FORMAT);
        const char *m = ibl_context_message(ctx);
        if (!strstr(m, cases[i].message) || strncmp(m, path, strlen(path)) != 0)
            fail_msg("case %zu: '%s'", i, m);
    }
    /* a texture that does not match what the manifest says it holds */
    write_text(path, original);
    char spec[1024], irr[1024];
    snprintf(spec, sizeof spec, "%s/specular.ktx2", dir);
    snprintf(irr, sizeof irr, "%s/irradiance.ktx2", dir);
    assert_int_equal(rename(irr, spec), 0);
    ibl_bake_data b;
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &b), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "specular.ktx2: holds"));
    free(original);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

static int count_entries(const char *dir, const char *prefix)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -c '^%s' > '%s/count.txt'", dir, prefix, test_tmpdir());
    if (system(cmd) < 0) return -1;
    char path[1200];
    snprintf(path, sizeof path, "%s/count.txt", test_tmpdir());
    char *t = read_text(path);
    int n = atoi(t);
    free(t);
    return n;
}

static int cancel_always(void *user, const char *stage, double fraction)
{
    (void)user, (void)stage, (void)fraction;
    return 1;
}

/* The folder is replaced whole: an old bake goes, foreign files are never deleted, a second
 * writer is refused while the lock is held, killed writers' staging folders are cleaned, a
 * cancelled bake leaves the old one. */
static void folder_transaction(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap env;
    environment(ctx, 16, &env);
    ibl_bake_desc d = small_desc();
    d.specular.size = 8;
    const char *root = test_path("tx");
    assert_int_equal(mkdir(root, 0777), 0);
    char dir[1024], other[1200], lock[1100], stale[1100];
    snprintf(dir, sizeof dir, "%s/bake", root);
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_OK);
    /* a new bake replaces the old: a part it no longer has is gone, nothing is left beside */
    d.ambient_brdf = -1;
    d.specular.filter = IBL_FILTER_PHONG;
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_OK);
    snprintf(other, sizeof other, "%s/ambient_brdf.ktx2", dir);
    assert_false(test_file_exists(other));
    assert_int_equal(count_entries(root, "\\.bake\\."), 0);
    /* a foreign file: refused, and the folder is as it was */
    snprintf(other, sizeof other, "%s/notes.txt", dir);
    write_text(other, "mine");
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(ctx), "notes.txt"));
    assert_true(test_file_exists(other));
    unlink(other);
    /* another writer holds the lock */
    snprintf(lock, sizeof lock, "%s/.bake.lock", root);
    int fd = open(lock, O_RDWR | O_CREAT, 0666);
    assert_true(fd >= 0 && flock(fd, LOCK_EX) == 0);
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(ctx), "being written by another process"));
    close(fd);
    /* the staging folder of a killed writer is removed by the next one */
    snprintf(stale, sizeof stale, "%s/.bake.staging-999999", root);
    assert_int_equal(mkdir(stale, 0777), 0);
    snprintf(other, sizeof other, "%s/specular.ktx2", stale);
    write_text(other, "half");
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, NULL), IBL_OK);
    assert_int_equal(count_entries(root, "\\.bake\\."), 0);
    /* cancelled at the last moment: the old bake stays, complete, and no folder is left */
    ibl_context *cancelling;
    ibl_context_desc cd = {.threads = 1, .progress = cancel_always};
    assert_int_equal(ibl_context_create(&cd, &cancelling), IBL_OK);
    assert_int_equal(ibl_bake(cancelling, &env, &d, dir, NULL), IBL_ERR_CANCELLED);
    assert_non_null(strstr(ibl_context_message(cancelling), dir));
    snprintf(other, sizeof other, "%s/never", root);
    assert_int_equal(ibl_bake(cancelling, &env, &d, other, NULL), IBL_ERR_CANCELLED);
    assert_false(test_file_exists(other));
    ibl_context_destroy(cancelling);
    assert_int_equal(count_entries(root, "\\.bake\\."), 0);
    ibl_bake_data b;
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &b), IBL_OK);
    assert_int_equal(b.specular_info.filter, IBL_FILTER_PHONG);
    ibl_bake_free(ctx, &b);
    /* through a symbolic link: the linked folder is replaced, the link stays a link */
    snprintf(other, sizeof other, "%s/link", root);
    assert_int_equal(symlink("bake", other), 0);
    d.specular.filter = IBL_FILTER_GGX;
    assert_int_equal(ibl_bake(ctx, &env, &d, other, NULL), IBL_OK);
    struct stat ls;
    assert_int_equal(lstat(other, &ls), 0);
    assert_true(S_ISLNK(ls.st_mode));
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &b), IBL_OK);
    assert_int_equal(b.specular_info.filter, IBL_FILTER_GGX);
    ibl_bake_free(ctx, &b);
    assert_int_equal(count_entries(root, "\\.bake\\."), 0);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

/* Parts in separate files: a chain without ibl's metadata takes the caller's mapping (or
 * roughness k/(levels-1)); the tables' texels come back at their texel centres; without an
 * irradiance map the SH of the chain's sharpest level gives the diffuse. */
static void parts_from_files(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap chain;
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 5, &chain), IBL_OK);
    for (int k = 0; k < 5; k++) {
        int n = ibl_level_size(16, k);
        float *f = ibl_cubemap_face(&chain, k, 0);
        for (size_t i = 0; i < (size_t)6 * n * n; i++)
            for (int c = 0; c < 4; c++) f[i * 4 + c] = (float)(k + 1);
    }
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBA32F};
    ibl_texture tex = ibl_texture_from_cubemap(&chain);
    assert_int_equal(ibl_write_texture(ctx, test_path("spec.ktx2"), &tex, &wd), IBL_OK);
    ibl_image lut;
    ibl_brdf_lut_desc ld = {.size = 16};
    assert_int_equal(ibl_brdf_lut(ctx, &ld, &lut), IBL_OK);
    ibl_write_image(ctx, test_path("lut.ktx2"), &lut, &wd);
    ibl_ambient_brdf_desc ad = {.size_nv = 8, .size_shininess = 8, .size_f0 = 4};
    ibl_texture vol;
    assert_int_equal(ibl_ambient_brdf_volume(ctx, &ad, &vol), IBL_OK);
    assert_int_equal(ibl_write_texture(ctx, test_path("amb.ktx2"), &vol, &wd), IBL_OK);

    ibl_bake_parts parts = {.specular = test_path("spec.ktx2"), .splitsum = test_path("lut.ktx2"),
                            .ambient_brdf = test_path("amb.ktx2")};
    ibl_bake_data b;
    assert_int_equal(ibl_bake_load_parts(ctx, &parts, NULL, &b), IBL_OK);
    ibl_probe p;
    assert_int_equal(ibl_bake_probe(ctx, &b, &p), IBL_OK);
    assert_int_equal(p.mapping.levels, 5);
    for (int k = 0; k < 5; k++) {
        float out[3];
        assert_near(ibl_probe_lod_from_roughness(&p, k / 4.0f), k, 1e-6);
        ibl_probe_sample_specular(&p, (float)k, (ibl_vec3){0.2f, 0.3f, -0.9f}, out);
        assert_near(out[0], k + 1, 0);
    }
    float irr[3];
    ibl_probe_irradiance(&p, (ibl_vec3){0, 1, 0}, irr);
    assert_near(irr[0], 1.0, 1e-5); /* SH of the constant level 0 */
    float a, bb;
    ibl_splitsum_lookup(&p.splitsum, 5.5f / 16, 9.5f / 16, &a, &bb);
    assert_near(a, ibl_image_texel(&lut, 5, 9)[0], 1e-6);
    assert_near(bb, ibl_image_texel(&lut, 5, 9)[1], 1e-6);
    float sh3 = (float)ibl_ambient_brdf_row_shininess(&ad, 3);
    assert_near(ibl_ambient_brdf_lookup(&p.ambient_brdf, 2.5f / 8, sh3, 1.5f / 4),
                vol.data[(((size_t)1 * 8 + 3) * 8 + 2) * 4], 1e-5);
    ibl_bake_free(ctx, &b);
    /* the caller's mapping in material shininess */
    parts.mapping.levels = 5;
    const float s[5] = {1e6f, 500, 100, 20, 2};
    for (int k = 0; k < 5; k++) parts.mapping.shininess[k] = s[k];
    assert_int_equal(ibl_bake_load_parts(ctx, &parts, NULL, &b), IBL_OK);
    assert_int_equal(ibl_bake_probe(ctx, &b, &p), IBL_OK);
    assert_near(ibl_probe_lod_from_shininess(&p, 100), 2.0, 1e-5);
    ibl_bake_free(ctx, &b);
    /* a 2D file is not a chain; a missing one is an I/O error naming it */
    parts.specular = test_path("lut.ktx2");
    assert_int_equal(ibl_bake_load_parts(ctx, &parts, NULL, &b), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "lut.ktx2"));
    parts.specular = test_path("none.ktx2");
    assert_int_equal(ibl_bake_load_parts(ctx, &parts, NULL, &b), IBL_ERR_IO);
    assert_int_equal(ibl_bake_load(ctx, test_tmpdir(), NULL, &b), IBL_ERR_IO); /* no manifest */
    ibl_texture_free(ctx, &vol);
    ibl_image_free(ctx, &lut);
    ibl_cubemap_free(ctx, &chain);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_filter_and_mapping),
        cmocka_unit_test(every_preset),
        cmocka_unit_test(triace_levels_distinct),
        cmocka_unit_test(manifest_errors),
        cmocka_unit_test(folder_transaction),
        cmocka_unit_test(parts_from_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
