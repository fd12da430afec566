/* BRDF table outputs: the C header / text writer (ibl_write_table) and `ibl lut` to every
 * container, read back through the library's readers and compared with the in-memory
 * tables; exit codes and one-line errors. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    size_t got = fread(s, 1, (size_t)n, f);
    s[got] = 0;
    fclose(f);
    return s;
}

/* The text table parses back to the exact floats (9 significant digits round-trip). */
static void text_table_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_brdf_lut_desc d = {.size = 6};
    ibl_image im;
    assert_int_equal(ibl_brdf_lut(ctx, &d, &im), IBL_OK);
    ibl_texture t = {.kind = IBL_TEXTURE_2D, .width = 6, .height = 6, .depth = 1, .levels = 1,
                     .data = im.pixels};
    const char *path = test_path("lut.txt");
    assert_int_equal(ibl_write_table(ctx, path, &t, 2, NULL, "hello */ world\nline two"), IBL_OK);
    char *s = slurp(path);
    assert_non_null(s);
    assert_non_null(strstr(s, "# line two"));
    int rows = 0;
    for (char *line = strtok(s, "\n"); line; line = strtok(NULL, "\n")) {
        if (line[0] == '#') continue;
        int x, y;
        float a, b;
        assert_int_equal(sscanf(line, "%d %d %g %g", &x, &y, &a, &b), 4);
        assert_true(a == ibl_image_texel(&im, x, y)[0]);
        assert_true(b == ibl_image_texel(&im, x, y)[1]);
        rows++;
    }
    assert_int_equal(rows, 36);
    free(s);
    /* C header: declaration, comment kept closed, one initialiser per texel */
    const char *hpath = test_path("lut.h");
    assert_int_equal(ibl_write_table(ctx, hpath, &t, 2, "my_lut", "a */ b"), IBL_OK);
    s = slurp(hpath);
    assert_non_null(strstr(s, "static const float my_lut[6][6][2] = {"));
    assert_null(strstr(s, "a */ b"));
    int braces = 0;
    for (char *p = s; *p; p++) braces += *p == '{';
    assert_int_equal(braces, 1 + 6 + 36);
    free(s);
    assert_int_equal(ibl_write_table(ctx, hpath, &t, 2, "1bad", NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_write_table(ctx, hpath, &t, 5, NULL, NULL), IBL_ERR_INVALID_ARGUMENT);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* `ibl lut` to KTX2 (rg16f default, rg32f), DDS and EXR: read back and compare with the
 * library's table. rg32f and EXR float are exact; half floats within their rounding
 * (relative 2^-11, so 5e-4 absolute for values <= 1). */
static void cli_containers(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_brdf_lut_desc d = {.size = 16, .visibility = IBL_VISIBILITY_SEPARABLE};
    ibl_image ref;
    assert_int_equal(ibl_brdf_lut(ctx, &d, &ref), IBL_OK);
    const char *out;
    struct {
        const char *name, *extra;
        ibl_format fmt;
        double tol;
    } cases[] = {{"s.ktx2", "", IBL_FORMAT_RG16F, 5e-4},
                 {"s32.ktx2", "--format rg32f", IBL_FORMAT_RG32F, 0},
                 {"s.dds", "", IBL_FORMAT_RG16F, 5e-4},
                 {"s.exr", "", IBL_FORMAT_DEFAULT, 0},
                 {"s.png", "", IBL_FORMAT_DEFAULT, 1.0 / 65535}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *path = test_path(cases[c].name);
        int rc = test_run_cli(&out, "lut -q -o '%s' --kind splitsum-separable --size 16 %s", path,
                              cases[c].extra);
        assert_int_equal(rc, 0);
        ibl_texture t;
        ibl_file_info info;
        assert_int_equal(ibl_read_texture(ctx, path, NULL, &t, &info), IBL_OK);
        assert_int_equal(t.width, 16);
        assert_int_equal(t.height, 16);
        if (cases[c].fmt != IBL_FORMAT_DEFAULT) assert_int_equal(info.format, cases[c].fmt);
        for (int y = 0; y < 16; y++)
            for (int x = 0; x < 16; x++)
                for (int k = 0; k < 2; k++)
                    assert_near(t.data[(y * 16 + x) * 4 + k], ibl_image_texel(&ref, x, y)[k],
                                cases[c].tol);
        ibl_texture_free(ctx, &t);
    }
    ibl_image_free(ctx, &ref);

    /* the AmbientBRDF volume as a 3D KTX2 */
    ibl_ambient_brdf_desc ad = {.size_nv = 8, .size_shininess = 8, .size_f0 = 4};
    ibl_texture vol, back;
    assert_int_equal(ibl_ambient_brdf_volume(ctx, &ad, &vol), IBL_OK);
    const char *vpath = test_path("v.ktx2");
    assert_int_equal(test_run_cli(&out, "lut -q -o '%s' --kind ambient-brdf --size 8 --f0-steps 4 --format rg32f",
                                  vpath), 0);
    assert_int_equal(ibl_read_texture(ctx, vpath, NULL, &back, NULL), IBL_OK);
    assert_int_equal(back.kind, IBL_TEXTURE_3D);
    assert_int_equal(back.depth, 4);
    for (size_t i = 0; i < (size_t)8 * 8 * 4; i++) {
        assert_true(back.data[i * 4] == vol.data[i * 4]);
        assert_true(back.data[i * 4 + 1] == vol.data[i * 4 + 1]);
    }
    ibl_texture_free(ctx, &back);
    ibl_texture_free(ctx, &vol);
    ibl_context_destroy(ctx);
}

static void cli_errors(void **state)
{
    (void)state;
    const char *out;
    assert_int_equal(test_run_cli(&out, "lut --size 8"), 2);
    assert_non_null(strstr(out, "missing -o"));
    assert_int_equal(test_run_cli(&out, "lut -o '%s' --kind nope", test_path("x.ktx2")), 2);
    assert_int_equal(test_run_cli(&out, "lut -o '%s' --f0-steps 4", test_path("x.ktx2")), 2);
    assert_int_equal(test_run_cli(&out, "lut -o '%s' --kind ambient-brdf --shininess-range 9:3",
                                  test_path("x.ktx2")), 2);
    assert_int_equal(test_run_cli(&out, "lut -o '%s' --channels a,zz", test_path("x.ktx2")), 2);
    assert_int_equal(test_run_cli(&out, "lut -q -o '%s/no/such/dir/x.ktx2' --size 4", test_tmpdir()), 1);
    /* one line, naming the file */
    assert_non_null(strstr(out, "x.ktx2"));
    int lines = 0;
    for (const char *p = out; *p; p++) lines += *p == '\n';
    assert_int_equal(lines, 1);
    assert_int_equal(test_run_cli(&out, "lut -q -o '%s' --size 4 --channels sheen,a,1",
                                  test_path("c.txt")), 0);
    assert_true(test_file_exists(test_path("c.txt")));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(text_table_round_trip),
        cmocka_unit_test(cli_containers),
        cmocka_unit_test(cli_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
