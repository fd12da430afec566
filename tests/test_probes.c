/* Probe-set files (include/ibl/probes.h, docs/PROBES.md): a complete set read back field by
 * field with its defaults, the blend order, and one case per error: each gives exactly one
 * line naming the file and the field's JSON path. */
#include "test_support.h"

#include "ibl/probes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char valid_set[] =
    "{\"format\": \"ibl-probes\", \"version\": 1,\n"
    " \"global\": {\"environment\": \"sky\", \"sky\": {\"sun_elevation\": 20, \"sun_azimuth\": 90},\n"
    "            \"size\": 64, \"preset\": \"filament\"},\n"
    " \"probes\": [\n"
    "  {\"name\": \"hall\", \"position\": [0, 1.5, 0],\n"
    "   \"influence\": {\"shape\": \"box\", \"half_extent\": [4, 2, 3], \"blend\": 0.5},\n"
    "   \"proxy\": {\"shape\": \"box\", \"center\": [0, 1.4, 0], \"half_extent\": [4, 1.5, 3]},\n"
    "   \"capture\": \"infinite\", \"size\": 32, \"priority\": 2},\n"
    "  {\"name\": \"alcove\", \"position\": [1, 1, 1],\n"
    "   \"influence\": {\"shape\": \"sphere\", \"radius\": 1.5}},\n"
    "  {\"name\": \"nook\", \"position\": [2, 1, 1],\n"
    "   \"influence\": {\"shape\": \"sphere\", \"center\": [2, 1, 1], \"radius\": 1}}\n"
    " ]}\n";

static void valid_file(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_parse(ctx, valid_set, strlen(valid_set), "set.json", "/scenes", &set), IBL_OK);
    assert_null(set.global.environment);
    assert_near(set.global.sky.sun_elevation_deg, 20, 0);
    assert_near(set.global.sky.sun_azimuth_deg, 90, 0);
    assert_near(set.global.sky.turbidity, 3, 0);
    assert_int_equal(set.global.size, 64);
    assert_string_equal(set.global.preset, "filament");
    assert_int_equal(set.probe_count, 3);
    const ibl_local_probe *h = &set.probes[0], *a = &set.probes[1];
    assert_string_equal(h->name, "hall");
    assert_int_equal(h->influence.shape, IBL_VOLUME_BOX);
    assert_near(h->influence.center.y, 1.5, 0); /* defaults to the position */
    assert_near(h->influence.half_extent.z, 3, 0);
    assert_near(h->influence.blend_distance, 0.5, 0);
    assert_near(h->proxy.center.y, 1.4f, 0);
    assert_near(h->proxy.half_extent.y, 1.5, 0);
    assert_int_equal(h->capture, IBL_CAPTURE_INFINITE);
    assert_int_equal(h->size, 32);
    assert_int_equal(h->priority, 2);
    /* defaults: far plane, 128, gltf, priority 0, the proxy is the influence volume */
    assert_int_equal(a->capture, IBL_CAPTURE_FAR_PLANE);
    assert_int_equal(a->size, 128);
    assert_string_equal(a->preset, "gltf");
    assert_int_equal(a->priority, 0);
    assert_int_equal(a->proxy.shape, IBL_VOLUME_SPHERE);
    assert_near(a->proxy.radius, 1.5, 0);
    assert_near(a->proxy.blend_distance, 0, 0);
    /* order: priority first, then the smaller volume */
    int order[3];
    ibl_probe_set_order(&set, order);
    assert_int_equal(order[0], 0);
    assert_int_equal(order[1], 2);
    assert_int_equal(order[2], 1);
    ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
}

static void environment_path(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *text = "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": "
                       "{\"environment\": \"hdri/sky.exr\", \"yaw\": 45}, \"probes\": []}";
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_parse(ctx, text, strlen(text), "s.json", "/scenes", &set), IBL_OK);
    assert_string_equal(set.global.environment, "/scenes/hdri/sky.exr");
    assert_near(set.global.yaw_degrees, 45, 0);
    assert_int_equal(set.global.size, 256);
    assert_int_equal(set.probe_count, 0);
    ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
}

/* A valid set with one piece of text replaced. */
typedef struct error_case {
    const char *from, *to;
    const char *message;
} error_case;

static const error_case cases[] = {
    {"\"ibl-probes\"", "\"ibl-bake\"", "set.json: format: expected \"ibl-probes\""},
    {"\"version\": 1", "\"version\": 2", "set.json: version: version 2 is not supported (this reader: 1)"},
    {"\"version\": 1,", "", "set.json: version: missing"},
    {"\"global\": {", "\"globl\": 0, \"global\": {", "set.json: globl: unknown field"},
    {"\"environment\": \"sky\"", "\"environment\": 3", "set.json: global.environment: expected a string"},
    {"\"sun_elevation\": 20", "\"sun_elevation\": 95", "set.json: global.sky.sun_elevation: must be in (0, 90] degrees"},
    {"\"sun_azimuth\"", "\"sun_azimut\"", "set.json: global.sky.sun_azimut: unknown field"},
    {"\"size\": 64", "\"size\": 48", "set.json: global.size: must be a power of two from 4 to 4096"},
    {"\"filament\"", "\"frostbite\"", NULL /* prefix checked below */},
    {"\"probes\": [", "\"probes\": {\"a\": [", NULL},
    {"{\"name\": \"hall\"", "7, {\"name\": \"hall\"", "set.json: probes[0]: expected an object"},
    {"\"name\": \"alcove\"", "\"name\": \"al cove\"", "set.json: probes[1].name: must be 1 to 63 of A-Z a-z 0-9 _ - (it names a file)"},
    {"\"name\": \"nook\"", "\"name\": \"hall\"", "set.json: probes[2].name: \"hall\" is also the name of probes[0]"},
    {"\"position\": [0, 1.5, 0]", "\"position\": [0, 1.5]", "set.json: probes[0].position: expected an array of 3 numbers"},
    {"\"position\": [0, 1.5, 0]", "\"position\": [0, \"up\", 0]", "set.json: probes[0].position[1]: expected a finite number"},
    {"\"position\": [1, 1, 1]", "\"location\": [1, 1, 1]", "set.json: probes[1].location: unknown field"},
    {"\"position\": [2, 1, 1]", "\"position\": [9, 1, 1]", "set.json: probes[2].position: outside the probe's influence volume"},
    {"\"radius\": 1.5", "\"radius\": 0", "set.json: probes[1].influence.radius: must be > 0"},
    {"\"radius\": 1.5", "\"radius\": 1.5, \"half_extent\": [1, 1, 1]", "set.json: probes[1].influence.half_extent: a sphere has a radius, not half_extent"},
    {"\"shape\": \"sphere\", \"radius\": 1.5", "\"shape\": \"cone\", \"radius\": 1.5", "set.json: probes[1].influence.shape: expected \"sphere\" or \"box\", not \"cone\""},
    {"\"half_extent\": [4, 2, 3]", "\"half_extent\": [4, -2, 3]", "set.json: probes[0].influence.half_extent: every half extent must be > 0"},
    {"\"blend\": 0.5", "\"blend\": 2.5", "set.json: probes[0].influence.blend: must be from 0 to 2 (the volume's half size)"},
    {"\"influence\": {\"shape\": \"sphere\", \"radius\": 1.5}", "\"inf\": 1", "set.json: probes[1].inf: unknown field"},
    {"\"half_extent\": [4, 1.5, 3]}", "\"half_extent\": [4, 1.5, 3], \"blend\": 1}", "set.json: probes[0].proxy.blend: a parallax proxy has no blend margin"},
    {"\"center\": [0, 1.4, 0]", "\"center\": [0, 9, 0]", "set.json: probes[0].position: outside the probe's parallax proxy"},
    {"\"capture\": \"infinite\"", "\"capture\": \"far\"", "set.json: probes[0].capture: expected \"far-plane\" or \"infinite\", not \"far\""},
    {"\"size\": 32", "\"size\": 8192", "set.json: probes[0].size: expected a whole number from 1 to 4096"},
    {"\"priority\": 2", "\"priority\": 2.5", "set.json: probes[0].priority: expected a whole number from -1000000 to 1000000"},
    {"]}\n", "]", "set.json: line 13, column 2: '}' expected near end of file"},
};

static char *replace(const char *text, const char *from, const char *to)
{
    const char *at = strstr(text, from);
    assert_non_null(at);
    size_t n = strlen(text) - strlen(from) + strlen(to) + 1;
    char *out = malloc(n);
    snprintf(out, n, "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
    return out;
}

static void each_error(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char *text = replace(valid_set, cases[i].from, cases[i].to);
        ibl_probe_set set;
        ibl_status st = ibl_probe_set_parse(ctx, text, strlen(text), "set.json", ".", &set);
        const char *msg = ibl_context_message(ctx);
        if (st != IBL_ERR_FORMAT) fprintf(stderr, "case %zu: status %d, '%s'\n", i, st, msg);
        assert_int_equal(st, IBL_ERR_FORMAT);
        assert_null(strchr(msg, '\n'));
        assert_int_equal(set.probe_count, 0); /* nothing left behind */
        assert_null(set.probes);
        if (cases[i].message) {
            if (strcmp(msg, cases[i].message) != 0) fprintf(stderr, "case %zu: '%s'\n", i, msg);
            assert_string_equal(msg, cases[i].message);
        } else {
            assert_true(strncmp(msg, "set.json: ", 10) == 0);
        }
        free(text);
    }
    /* the unknown preset lists the known ones */
    char *text = replace(valid_set, "\"filament\"", "\"frostbite\"");
    ibl_probe_set set;
    assert_int_equal(ibl_probe_set_parse(ctx, text, strlen(text), "set.json", ".", &set), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "set.json: global.preset: unknown preset \"frostbite\" (known: "));
    free(text);
    ibl_context_destroy(ctx);
}

static void file_errors(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe_set set;
    const char *missing = test_path("missing.json");
    assert_int_not_equal(ibl_probe_set_load(ctx, missing, &set), IBL_OK);
    assert_non_null(strstr(ibl_context_message(ctx), missing));
    const char *path = test_path("probes.json");
    FILE *f = fopen(path, "wb");
    fputs(valid_set, f);
    fclose(f);
    assert_int_equal(ibl_probe_set_load(ctx, path, &set), IBL_OK);
    assert_string_equal(set.path, path);
    ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(valid_file),
        cmocka_unit_test(environment_path),
        cmocka_unit_test(each_error),
        cmocka_unit_test(file_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
