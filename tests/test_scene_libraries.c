/* Embree and Assimp are loaded when a scene needs them (src/scene/libraries.h), not with the
 * program: this test program, linked with the library, has neither in its address space
 * until it makes a scene (Embree) or reads a scene file (Assimp); the scenes then work as
 * before (a ray hits the triangle where geometry says, an OBJ reads back its triangle), and a
 * second scene after the first is destroyed loads them again. The CLI, linked the same way,
 * starts without them. */
#include "test_support.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Whether a file whose name contains `name` is mapped into process `pid` ("self": this one). */
static int mapped(const char *pid, const char *name)
{
    char path[64];
    snprintf(path, sizeof path, "/proc/%s/maps", pid);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[1024];
    int found = 0;
    while (!found && fgets(line, sizeof line, f)) found = strstr(line, name) != NULL;
    fclose(f);
    return found;
}

/* One triangle in the plane z = 1 covering the origin's direction (0, 0, 1). */
static ibl_scene *one_triangle(ibl_context *ctx)
{
    static const float positions[9] = {-1, -1, 1, 2, -1, 1, -1, 2, 1};
    static const uint32_t indices[3] = {0, 1, 2};
    ibl_scene_material m = ibl_scene_material_default();
    ibl_scene_desc d = {0};
    d.vertex_count = 3;
    d.triangle_count = 1;
    d.positions = positions;
    d.indices = indices;
    d.materials = &m;
    d.material_count = 1;
    ibl_scene *s = NULL;
    assert_int_equal(ibl_scene_create(ctx, &d, &s), IBL_OK);
    return s;
}

static void loaded_on_first_use(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    assert_false(mapped("self", "libembree3"));
    assert_false(mapped("self", "libassimp"));

    ibl_scene *s = one_triangle(ctx);
    assert_true(mapped("self", "libembree3"));
    assert_false(mapped("self", "libassimp"));
    /* the ray along +z meets the plane z = 1 at distance 1 (float: exact) */
    ibl_scene_hit hit;
    assert_int_equal(ibl_scene_intersect(s, (ibl_vec3){0, 0, 0}, (ibl_vec3){0, 0, 1}, 0.0f, 10.0f, &hit), 1);
    assert_float_equal(hit.t, 1.0f, 0.0f);
    assert_int_equal(ibl_scene_occluded(s, (ibl_vec3){0, 0, 0}, (ibl_vec3){0, 0, -1}, 0.0f, 10.0f), 0);
    ibl_scene_destroy(s);

    /* a second scene after the first is gone */
    s = one_triangle(ctx);
    assert_int_equal(ibl_scene_occluded(s, (ibl_vec3){0, 0, 0}, (ibl_vec3){0, 0, 1}, 0.0f, 10.0f), 1);
    ibl_scene_destroy(s);

    const char *obj = test_path("triangle.obj");
    FILE *f = fopen(obj, "w");
    assert_non_null(f);
    fputs("v -1 -1 1\nv 2 -1 1\nv -1 2 1\nf 1 2 3\n", f);
    fclose(f);
    assert_int_equal(ibl_scene_load(ctx, obj, &s), IBL_OK);
    assert_true(mapped("self", "libassimp"));
    ibl_scene_info info;
    ibl_scene_get_info(s, &info);
    assert_int_equal(info.triangle_count, 1);
    assert_float_equal(info.bounds_max[0], 2.0f, 0.0f);
    ibl_scene_destroy(s);
    ibl_context_destroy(ctx);
}

/* The objects the dynamic loader maps for the CLI (LD_TRACE_LOADED_OBJECTS: what ldd prints,
 * without running it): libjansson as a check that the list is read, no Embree nor Assimp. */
static void cli_starts_without_them(void **state)
{
    (void)state;
    char command[1024];
    snprintf(command, sizeof command, "LD_TRACE_LOADED_OBJECTS=1 '%s' 2>&1", IBL_CLI_PATH);
    FILE *p = popen(command, "r");
    assert_non_null(p);
    char line[1024];
    int jansson = 0, scene_libraries = 0;
    while (fgets(line, sizeof line, p)) {
        jansson |= strstr(line, "libjansson") != NULL;
        scene_libraries |= strstr(line, "libembree") || strstr(line, "libassimp") || strstr(line, "libtbb");
    }
    assert_int_equal(pclose(p), 0);
    assert_true(jansson);
    assert_false(scene_libraries);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(loaded_on_first_use),
        cmocka_unit_test(cli_starts_without_them),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
