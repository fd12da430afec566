/* The command-line tool end to end: conversions keep the radiance, and bad input gives a
 * one-line message naming the file, exit 1 (2 for usage), and no output file. */
#include "test_support.h"

#include <jansson.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

static void write_bytes(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, n, f), n);
    fclose(f);
}

static size_t read_bytes(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(buf, 1, cap, f);
    fclose(f);
    return n;
}

/* A PFM (little-endian, "PF") of w x h with every texel set to v, except texel 0 = first. */
static void write_pfm(const char *path, int w, int h, float first, float v)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "PF\n%d %d\n-1.0\n", w, h);
    for (int i = 0; i < w * h * 3; i++) {
        float x = i < 3 ? first : v;
        fwrite(&x, 4, 1, f);
    }
    fclose(f);
}

/* The number at key (or the first element of the array at key) of a JSON object's text. */
static double json_number(const char *json, const char *key)
{
    json_error_t err;
    json_t *root = json_loads(json, 0, &err);
    if (!root) fail_msg("not JSON (%s): %s", err.text, json);
    json_t *v = json_object_get(root, key);
    if (json_is_array(v)) v = json_array_get(v, 0);
    if (!json_is_number(v)) fail_msg("no number at %s", key);
    double x = json_number_value(v);
    json_decref(root);
    return x;
}

/* Element i of the array at key. */
static double json_element(const char *json, const char *key, size_t i)
{
    json_t *root = json_loads(json, 0, NULL);
    assert_non_null(root);
    json_t *v = json_array_get(json_object_get(root, key), i);
    assert_true(json_is_number(v));
    double x = json_number_value(v);
    json_decref(root);
    return x;
}

static void expect_bad_input(int want_rc, const char *needle, const char *fmt, const char *arg1,
                             const char *arg2)
{
    const char *out = NULL;
    int rc = test_run_cli(&out, fmt, arg1, arg2);
    if (rc != want_rc || count_lines(out) != 1 || (needle && !strstr(out, needle)))
        fail_msg("ibl %s: exit %d (want %d), output:\n%s", fmt, rc, want_rc, out);
}

static void usage_errors(void **state)
{
    (void)state;
    const char *out;
    assert_int_equal(test_run_cli(&out, "convert --frobnicate x.hdr -o y.ktx2"), 2);
    assert_int_equal(count_lines(out), 1);
    assert_int_equal(test_run_cli(&out, "no-such-command"), 2);
    assert_int_equal(test_run_cli(&out, "convert"), 2);
    assert_int_equal(test_run_cli(&out, "--version"), 0);
    assert_non_null(strstr(out, IBL_VERSION_STRING));
    assert_int_equal(test_run_cli(&out, "convert --help"), 0);
    assert_non_null(strstr(out, "usage: ibl convert"));
    assert_int_equal(test_run_cli(&out, "convert in.hdr -o out.ktx2 --size banana"), 2);
}

static void bad_inputs(void **state)
{
    (void)state;
    const char *missing = test_path("missing.hdr");
    char out[512];
    snprintf(out, sizeof out, "%s", test_path("out.ktx2"));
    expect_bad_input(1, missing, "convert '%s' -o '%s'", missing, out);
    assert_false(test_file_exists(out));

    const char *garbage = test_path("garbage.exr");
    write_bytes(garbage, "this is not an image at all, just text\n", 40);
    expect_bad_input(1, garbage, "convert '%s' -o '%s'", garbage, out);
    assert_false(test_file_exists(out));

    /* truncated copies of a real file */
    static char buf[1 << 20];
    size_t n = read_bytes(test_data("studio.exr"), buf, sizeof buf);
    assert_true(n > 1000);
    size_t cuts[] = {4, 100, n / 2, n - 10};
    for (int i = 0; i < 4; i++) {
        const char *cut = test_path("cut.exr");
        write_bytes(cut, buf, cuts[i]);
        expect_bad_input(1, cut, "convert '%s' -o '%s'", cut, out);
        assert_false(test_file_exists(out));
    }

    /* infinities are refused unless --clamp; NaN and negatives are fixed with a warning */
    const char *inf = test_path("inf.pfm");
    write_pfm(inf, 64, 32, INFINITY, 1.0f);
    expect_bad_input(1, "infinite", "convert '%s' -o '%s'", inf, out);
    assert_false(test_file_exists(out));
    const char *text;
    assert_int_equal(test_run_cli(&text, "convert --clamp '%s' -o '%s'", inf, out), 0);
    assert_true(test_file_exists(out));
    remove(out);
    const char *nan = test_path("nan.pfm");
    write_pfm(nan, 64, 32, NAN, 1.0f);
    assert_int_equal(test_run_cli(&text, "convert '%s' -o '%s'", nan, out), 0);
    assert_non_null(strstr(text, "NaN"));
    remove(out);

    /* an image whose layout cannot be told */
    const char *odd = test_path("odd.pfm");
    write_pfm(odd, 37, 11, 1.0f, 1.0f);
    expect_bad_input(1, odd, "convert '%s' -o '%s'", odd, out);

    /* output equal to the input; unwritable output folder */
    const char *sky = test_path("same.pfm");
    write_pfm(sky, 64, 32, 1.0f, 1.0f);
    expect_bad_input(2, NULL, "convert '%s' -o '%s'", sky, sky);
    expect_bad_input(1, "/nonexistent-dir/x.ktx2", "convert '%s' -o '%s'", sky, "/nonexistent-dir/x.ktx2");
}

/* A failed run never damages an existing output file. */
static void existing_output_kept(void **state)
{
    (void)state;
    const char *out = test_path("keep.ktx2");
    write_bytes(out, "precious", 8);
    const char *garbage = test_path("garbage2.hdr");
    write_bytes(garbage, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000000 +X 100000000\n", 62);
    expect_bad_input(1, garbage, "convert '%s' -o '%s'", garbage, out);
    char buf[16];
    assert_int_equal(read_bytes(out, buf, sizeof buf), 8);
    assert_memory_equal(buf, "precious", 8);
}

/* Converting each real HDRI to a 256-face RGBA32F KTX2 keeps the
 * solid-angle-weighted mean radiance within 0.5%, and `ibl info` agrees on both files. */
static void conversion_keeps_mean_radiance(void **state)
{
    (void)state;
    const char *names[] = {"city.exr", "forest.exr", "interior.exr", "night.exr", "studio.exr", "sunset.exr"};
    for (int i = 0; i < 6; i++) {
        const char *in = test_data(names[i]);
        const char *out = test_path("conv.ktx2");
        const char *text;
        int rc = test_run_cli(&text, "convert -q '%s' -o '%s' --size 256 --format rgba32f", in, out);
        if (rc != 0) fail_msg("convert %s: %s", names[i], text);
        static char a[4096], b[4096];
        assert_int_equal(test_run_cli(&text, "info --json '%s'", in), 0);
        snprintf(a, sizeof a, "%s", text);
        assert_int_equal(test_run_cli(&text, "info --json '%s'", out), 0);
        snprintf(b, sizeof b, "%s", text);
        double la = json_number(a, "mean_luminance"), lb = json_number(b, "mean_luminance");
        assert_true(la > 0);
        if (fabs(lb / la - 1.0) > 0.005) fail_msg("%s: mean luminance %g -> %g", names[i], la, lb);
        assert_non_null(strstr(b, "\"format\": \"rgba32f\""));
        assert_non_null(strstr(b, "\"kind\": \"cube\""));
    }
}

static void sky_and_round_trips(void **state)
{
    (void)state;
    const char *sky = test_path("sky.exr");
    const char *text;
    assert_int_equal(test_run_cli(&text, "sky -q -o '%s' --size 256", sky), 0);
    const char *containers[] = {"c.ktx2", "c.dds", "c.ktx"};
    for (int i = 0; i < 3; i++) {
        const char *cube = test_path(containers[i]);
        int rc = test_run_cli(&text, "convert -q '%s' -o '%s' --mips --format rgba32f", sky, cube);
        if (rc) fail_msg("%s", text);
        const char *back = test_path("back.exr");
        rc = test_run_cli(&text, "convert -q '%s' -o '%s'", cube, back);
        if (rc) fail_msg("%s", text);
        assert_true(test_file_exists(back));
    }
    const char *faces = test_path("f.pfm");
    assert_int_equal(test_run_cli(&text, "convert -q '%s' -o '%s' --out-layout faces --size 16", sky, faces), 0);
    assert_true(test_file_exists(test_path("f_px.pfm")));
    assert_true(test_file_exists(test_path("f_nz.pfm")));
    const char *png = test_path("preview.png");
    assert_int_equal(test_run_cli(&text, "convert -q '%s' -o '%s' --out-layout hcross --size 32", sky, png), 0);
    assert_true(test_file_exists(png));
}

static int files_equal(const char *a, const char *b)
{
    static char x[1 << 22], y[1 << 22];
    size_t na = read_bytes(a, x, sizeof x), nb = read_bytes(b, y, sizeof y);
    return na > 0 && na == nb && memcmp(x, y, na) == 0;
}

/* Every command's output is bit-identical at any thread count. */
static void identical_at_any_thread_count(void **state)
{
    (void)state;
    const char *text;
    const char *in = test_data("studio.exr");
    /* each: the subcommand (%d = threads, then the input's and the output's %s, or only the
     * output's when it takes no input) and the output name */
    const struct {
        const char *args;
        const char *out;
        int has_input;
    } commands[] = {
        {"convert -q -j %d '%s' -o '%s' --size 64 --mips --format rgba32f", "t.ktx2", 1},
        {"convert -q -j %d '%s' -o '%s' --out-layout hcross --size 32", "t.exr", 1},
        {"irradiance -q -j %d '%s' -o '%s' --format rgba32f", "i.ktx2", 1},
        {"prefilter -q -j %d '%s' -o '%s' --size 16 --format rgba32f", "p.ktx2", 1},
        {"lut -q -j %d --size 32 -o '%s' --format rg32f", "l.ktx2", 0},
        {"sky -q -j %d --size 64 -o '%s'", "s.pfm", 0},
        {"render -q -j %d '%s' -o '%s' --width 64 --specular-size 16", "r.pfm", 1},
    };
    static const int threads[3] = {1, 2, 8};
    for (size_t c = 0; c < sizeof commands / sizeof commands[0]; c++) {
        char first[512];
        for (int t = 0; t < 3; t++) {
            char name[64];
            snprintf(name, sizeof name, "%d-%s", threads[t], commands[c].out);
            const char *out = test_path(name);
            char args[1024];
            if (commands[c].has_input) snprintf(args, sizeof args, commands[c].args, threads[t], in, out);
            else snprintf(args, sizeof args, commands[c].args, threads[t], out);
            int rc = test_run_cli(&text, "%s", args);
            if (rc) fail_msg("%s: %s", args, text);
            if (t == 0) snprintf(first, sizeof first, "%s", out);
            else if (!files_equal(first, out)) fail_msg("%s differs from %s", out, first);
        }
    }
}

/* `ibl prefilter` prepares the chain beside the input's reading when the header tells the
 * cube's edge (more than one thread, no --max-memory, a small input, a chain of 256 or more:
 * cli/prefilter.c), and one after the other otherwise: the same bytes either way, for an
 * equirect EXR at its own edge and at --source-size, a cube KTX2 and an hcross HDR (each
 * layout's edge from the header: cli_input_cube_size). */
static void prefilter_prepared_beside_the_read(void **state)
{
    (void)state;
    const char *text;
    const char *studio = test_data("studio.exr");
    char cube[512], cross[512]; /* test_path's buffer is reused by the next call */
    snprintf(cube, sizeof cube, "%s", test_path("side-cube.ktx2"));
    snprintf(cross, sizeof cross, "%s", test_path("side-cross.hdr"));
    assert_int_equal(test_run_cli(&text, "convert -q '%s' -o '%s' --size 256 --format rgba32f", studio, cube), 0);
    assert_int_equal(test_run_cli(&text, "convert -q '%s' -o '%s' --out-layout hcross --size 96", studio, cross), 0);
    const struct {
        const char *in, *extra;
    } cases[] = {{studio, ""}, {studio, "--source-size 384"}, {cube, ""}, {cross, ""}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *runs[3] = {"-j 1", "-j 2", "-j 2 --max-memory 4000"};
        char first[512];
        for (int r = 0; r < 3; r++) {
            char name[64];
            snprintf(name, sizeof name, "side-%zu-%d.ktx2", c, r);
            const char *out = test_path(name);
            int rc = test_run_cli(&text, "prefilter -q %s '%s' -o '%s' --size 256 --levels 3 %s",
                                  runs[r], cases[c].in, out, cases[c].extra);
            if (rc) fail_msg("case %zu %s: %s", c, runs[r], text);
            if (r == 0) snprintf(first, sizeof first, "%s", out);
            else if (!files_equal(first, out)) fail_msg("case %zu: %s differs from %s", c, out, first);
        }
    }
}

/* The memory budget refuses an input that would need more, with a clear message. */
static void memory_limit(void **state)
{
    (void)state;
    const char *text;
    const char *out = test_path("mem.ktx2");
    int rc = test_run_cli(&text, "convert '%s' -o '%s' --max-memory 1", test_data("studio.exr"), out);
    assert_int_equal(rc, 1);
    assert_int_equal(count_lines(text), 1);
    assert_non_null(strstr(text, "memory budget"));
    assert_false(test_file_exists(out));
}

/* Ctrl-C during a long run leaves no output and no temporary file (exit 130). A background
 * job of a non-interactive shell starts with SIGINT ignored, so the signal is sent only once
 * the command has installed its handler (SigCgt in /proc, bit 2 for SIGINT): on a loaded host
 * an ASan build took longer than a fixed wait to get there, and the ignored signal let it
 * finish with 0. */
static void interrupt_leaves_nothing(void **state)
{
    (void)state;
    const char *out = test_path("interrupted.exr");
    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "'%s' sky -q -o '%s' --size 4096 2>/dev/null & pid=$!; i=0; while [ $i -lt 400 ]; do "
             "c=$(awk '/^SigCgt/{print $2}' /proc/$pid/status 2>/dev/null); "
             "[ -n \"$c\" ] && [ $((0x$c & 2)) -ne 0 ] && break; sleep 0.05; i=$((i+1)); done; "
             "sleep 0.3; kill -INT $pid; wait $pid; "
             "echo \"rc=$?\"; ls -a '%s' | grep -c interrupted",
             IBL_CLI_PATH, out, test_tmpdir());
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf - 1, p);
    buf[n] = 0;
    pclose(p);
    if (!strstr(buf, "rc=130")) fail_msg("expected exit 130 after SIGINT, got: %s", buf);
    assert_non_null(strstr(buf, "\n0\n"));
    assert_false(test_file_exists(out));
}

/* Six face images in, and the ways they can fail to fit together. */
static void six_faces(void **state)
{
    (void)state;
    const char *text;
    const char *names[6] = {"px.pfm", "nx.pfm", "py.pfm", "ny.pfm", "pz.pfm", "nz.pfm"};
    char paths[6][512];
    for (int f = 0; f < 6; f++) {
        snprintf(paths[f], sizeof paths[f], "%s", test_path(names[f]));
        write_pfm(paths[f], 16, 16, (float)(f + 1), (float)(f + 1));
    }
    const char *out = test_path("faces.ktx2");
    int rc = test_run_cli(&text, "convert -q '%s' '%s' '%s' '%s' '%s' '%s' -o '%s' --format rgba32f",
                          paths[0], paths[1], paths[2], paths[3], paths[4], paths[5], out);
    if (rc) fail_msg("%s", text);
    /* each face keeps its own constant: the +Z face (5.0) is found where the cube's +Z is */
    assert_int_equal(test_run_cli(&text, "info --json '%s'", out), 0);
    for (size_t c = 0; c < 3; c++) {
        assert_near(json_element(text, "max", c), 6, 0);
        assert_near(json_element(text, "min", c), 1, 0);
    }
    /* a non-square face, then a face of another size: exit 1, one line naming that file */
    write_pfm(paths[3], 16, 8, 1.0f, 1.0f);
    rc = test_run_cli(&text, "convert '%s' '%s' '%s' '%s' '%s' '%s' -o '%s'", paths[0], paths[1],
                      paths[2], paths[3], paths[4], paths[5], test_path("bad.ktx2"));
    assert_int_equal(rc, 1);
    assert_int_equal(count_lines(text), 1);
    assert_non_null(strstr(text, paths[3]));
    assert_non_null(strstr(text, "square"));
    write_pfm(paths[3], 8, 8, 1.0f, 1.0f);
    rc = test_run_cli(&text, "convert '%s' '%s' '%s' '%s' '%s' '%s' -o '%s'", paths[0], paths[1],
                      paths[2], paths[3], paths[4], paths[5], test_path("bad.ktx2"));
    assert_int_equal(rc, 1);
    assert_int_equal(count_lines(text), 1);
    assert_non_null(strstr(text, paths[3]));
    assert_false(test_file_exists(test_path("bad.ktx2")));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(usage_errors),
        cmocka_unit_test(bad_inputs),
        cmocka_unit_test(existing_output_kept),
        cmocka_unit_test(conversion_keeps_mean_radiance),
        cmocka_unit_test(sky_and_round_trips),
        cmocka_unit_test(identical_at_any_thread_count),
        cmocka_unit_test(prefilter_prepared_beside_the_read),
        cmocka_unit_test(memory_limit),
        cmocka_unit_test(interrupt_leaves_nothing),
        cmocka_unit_test(six_faces),
    };
    return cmocka_run_group_tests_name("cli", tests, NULL, NULL);
}
