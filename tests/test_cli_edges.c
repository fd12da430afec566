/* The command line at its edges, each case once a defect: outputs never replace an input,
 * option errors are usage errors (exit 2) found before any work, messages are one line that
 * names the file, JSON stays valid whatever bytes a path holds, a failed write to standard
 * output is an error, new files follow the umask, a FIFO nobody writes does not hang,
 * long paths work, temporaries of killed runs are cleaned. */
#include "test_support.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static void write_env(const char *path)
{
    ibl_context *ctx = test_context(1);
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, 32, 16, &im), IBL_OK);
    for (int i = 0; i < 32 * 16; i++) {
        float *p = im.pixels + i * 4;
        p[0] = 0.5f + (i % 32) / 32.0f, p[1] = 0.3f, p[2] = 1.0f, p[3] = 1.0f;
    }
    assert_int_equal(ibl_write_image(ctx, path, &im, NULL), IBL_OK);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static int one_line(const char *text)
{
    const char *nl = strchr(text, '\n');
    return nl && nl[1] == 0;
}

/* Generated names that would replace an input: refused, the input kept. */
static void outputs_never_replace_inputs(void **state)
{
    (void)state;
    const char *out;
    char in[600], victim[600], dir[600], preview[700];
    snprintf(in, sizeof in, "%s", test_path("victim_l0_px.exr"));
    write_env(in);
    long before = file_size(in);
    /* prefilter's flat outputs: victim.exr -> victim_l0_px.exr ... */
    snprintf(victim, sizeof victim, "%s", test_path("victim.exr"));
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --levels 1 --size 4", in, victim), 2);
    assert_non_null(strstr(out, "would replace the input"));
    assert_int_equal(file_size(in), before);
    /* convert's six faces */
    snprintf(in, sizeof in, "%s", test_path("face_px.exr"));
    write_env(in);
    before = file_size(in);
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --out-layout faces", in,
                                  test_path("face.exr")), 2);
    assert_int_equal(file_size(in), before);
    assert_false(test_file_exists(test_path("face_nx.exr"))); /* nothing of the set */
    /* a bake from a file inside the folder it replaces */
    snprintf(dir, sizeof dir, "%s", test_path("bakedir"));
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --size 8 --preview-width 16", in, dir), 0);
    snprintf(preview, sizeof preview, "%s/environment.png", dir);
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s'", preview, dir), 2);
    assert_true(test_file_exists(preview));
    /* the bake owns its folder: a chain or an irradiance map written there is refused before
     * any work (it would replace a bake file behind the manifest, or be a stranger the next
     * bake of the folder refuses), and the bake's files are left alone */
    char manifest[700], specular[700];
    snprintf(manifest, sizeof manifest, "%s/manifest.json", dir);
    snprintf(specular, sizeof specular, "%s/specular.ktx2", dir);
    before = file_size(manifest);
    long spec_before = file_size(specular);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s/x.ktx2' --size 4", in, dir), 2);
    assert_non_null(strstr(out, "is a bake"));
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 4", in, specular), 2);
    assert_int_equal(test_run_cli(&out, "irradiance -q '%s' -o '%s/irradiance.ktx2'", in, dir), 2);
    assert_int_equal(file_size(manifest), before);
    assert_int_equal(file_size(specular), spec_before);
    assert_false(test_file_exists(test_path("bakedir/x.ktx2")));
    assert_false(test_file_exists(test_path("bakedir/x.manifest.json")));
    /* a chain's STEM.manifest.json replaces only an earlier chain manifest */
    char chain[700], chain_manifest[700];
    snprintf(chain, sizeof chain, "%s", test_path("own.ktx2"));
    snprintf(chain_manifest, sizeof chain_manifest, "%s", test_path("own.manifest.json"));
    FILE *f = fopen(chain_manifest, "w");
    assert_non_null(f);
    fputs("{\"format\": \"someone-else\"}\n", f);
    fclose(f);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 4", in, chain), 2);
    assert_false(test_file_exists(chain));
    remove(chain_manifest);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 4", in, chain), 0);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 4", in, chain), 0);
}

/* Contradictory or invalid options: exit 2 at once, before the input is even read. */
static void option_errors_are_usage_errors(void **state)
{
    (void)state;
    const char *in = test_path("missing-and-never-read.exr"), *o = test_path("o.ktx2");
    static const char *const cases[] = {
        "prefilter '%s' -o '%s' --mapping table",
        "prefilter '%s' -o '%s' --shininess-min 100 --shininess-max 10 --filter phong",
        "prefilter '%s' -o '%s' --mapping table --table nan,1",
        "prefilter '%s' -o '%s' --format rgba8",
        "convert '%s' -o '%s' --format rgba8",
        "convert '%s' -o '%s' --format bc6h --zstd 23",
        "bake '%s' -o '%s' --format rgb16f",
        "prefilter '%s' -o '%s' -qq",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *out;
        int rc = test_run_cli(&out, cases[i], in, o);
        if (rc != 2) fail_msg("'%s': exit %d: %s", cases[i], rc, out);
        assert_true(one_line(out));
        assert_null(strstr(out, "missing-and-never-read.exr: cannot open")); /* not read */
    }
    /* the attached short form of a valued option works: -j1 */
    write_env(test_path("env.exr"));
    const char *out;
    assert_int_equal(test_run_cli(&out, "prefilter -q -j1 '%s' -o '%s' --size 4", test_path("env.exr"), o), 0);
}

/* Messages are one line naming the file, even for a name holding a newline, and for a
 * refusal by the memory budget. */
static void messages_name_the_file(void **state)
{
    (void)state;
    const char *out;
    char odd[600];
    snprintf(odd, sizeof odd, "%s", test_path("two\nlines.exr"));
    FILE *f = fopen(odd, "w");
    fputs("not an image", f);
    fclose(f);
    assert_int_equal(test_run_cli(&out, "info '%s'", odd), 1);
    assert_true(one_line(out));
    assert_non_null(strstr(out, "two\\x0alines.exr"));
    write_env(test_path("env.exr"));
    assert_int_equal(test_run_cli(&out, "prefilter '%s' -o '%s' --size 64 --max-memory 1 -q",
                                  test_path("env.exr"), test_path("big.ktx2")), 1);
    assert_true(one_line(out));
    assert_non_null(strstr(out, "env.exr") ? strstr(out, "env.exr") : strstr(out, "big.ktx2"));
    assert_false(test_file_exists(test_path("big.ktx2")));
}

/* A path that is not UTF-8 still gives valid JSON (the bad bytes become U+FFFD or '?'). */
static void json_with_any_path(void **state)
{
    (void)state;
    char name[600], dir[600];
    snprintf(name, sizeof name, "%s", test_path("caf\xe9\xff.exr"));
    write_env(name);
    const char *out;
    assert_int_equal(test_run_cli(&out, "sh --json -q '%s'", name), 0);
    json_t *j = json_loads(out, 0, NULL);
    assert_non_null(j);
    json_decref(j);
    assert_int_equal(test_run_cli(&out, "info --json -q '%s'", name), 0);
    j = json_loads(out, 0, NULL);
    assert_non_null(j);
    json_decref(j);
    snprintf(dir, sizeof dir, "%s", test_path("utf"));
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --size 8 --preview-width 16", name, dir), 0);
    char manifest[700];
    snprintf(manifest, sizeof manifest, "%s/manifest.json", dir);
    json_error_t err;
    j = json_load_file(manifest, 0, &err);
    if (!j) fail_msg("manifest.json: %s", err.text);
    json_decref(j);
    snprintf(manifest, sizeof manifest, "%s/sh.json", dir);
    j = json_load_file(manifest, 0, &err);
    if (!j) fail_msg("sh.json: %s", err.text);
    json_decref(j);
}

/* Standard output that cannot be written is an error; new files get 0666 minus the umask; a
 * FIFO nothing writes to fails after a bounded wait (10 s) instead of hanging. */
static void the_operating_system(void **state)
{
    (void)state;
    write_env(test_path("env.exr"));
    const char *out;
    char cmd[1300];
    snprintf(cmd, sizeof cmd, "'%s' sh --json -q '%s' > /dev/full 2> '%s'", IBL_CLI_PATH,
             test_path("env.exr"), test_path("err.txt"));
    int rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
    FILE *e = fopen(test_path("err.txt"), "r");
    char line[256] = "";
    assert_non_null(fgets(line, sizeof line, e));
    fclose(e);
    assert_non_null(strstr(line, "standard output"));
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --size 4 & wait; umask 077; %s convert -q '%s' -o '%s' --size 4",
                                  test_path("env.exr"), test_path("a.ktx2"), IBL_CLI_PATH,
                                  test_path("env.exr"), test_path("b.ktx2")), 0);
    struct stat st;
    assert_int_equal(stat(test_path("b.ktx2"), &st), 0);
    assert_int_equal(st.st_mode & 0777, 0600);
    char fifo[600];
    snprintf(fifo, sizeof fifo, "%s", test_path("fifo"));
    snprintf(cmd, sizeof cmd, "mkfifo '%s'", fifo);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "timeout 30 '%s' info '%s' 2> /dev/null", IBL_CLI_PATH, fifo);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1); /* 124 if it had hung */
}

/* A bake folder 1100 characters deep is written and read back; a temporary left by a killed
 * writer (its process gone) is removed by the next write of that name. */
static void long_paths_and_stale_temporaries(void **state)
{
    (void)state;
    char deep[1400];
    snprintf(deep, sizeof deep, "%s", test_tmpdir());
    while (strlen(deep) < 1100) strcat(deep, "/a-folder-with-a-long-name-for-the-path");
    char cmd[1500];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", deep);
    assert_int_equal(system(cmd), 0);
    strcat(deep, "/bake");
    const char *out;
    assert_int_equal(test_run_cli(&out, "bake -q -o '%s' --size 8 --preview-width 16", deep), 0);
    assert_int_equal(test_run_cli(&out, "render -q '%s' -o '%s' --width 16", deep, test_path("r.png")), 0);
    write_env(test_path("env.exr"));
    char stale[600];
    snprintf(stale, sizeof stale, "%s/.t.ktx2.tmp-999999-0", test_tmpdir());
    FILE *f = fopen(stale, "w");
    fputs("half written", f);
    fclose(f);
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s/t.ktx2' --size 4", test_path("env.exr"),
                                  test_tmpdir()), 0);
    assert_false(test_file_exists(stale));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(outputs_never_replace_inputs),
        cmocka_unit_test(option_errors_are_usage_errors),
        cmocka_unit_test(messages_name_the_file),
        cmocka_unit_test(json_with_any_path),
        cmocka_unit_test(the_operating_system),
        cmocka_unit_test(long_paths_and_stale_temporaries),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
