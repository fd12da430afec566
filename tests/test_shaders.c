/* shaders/ibl.glsl and ibl.hlsl against the C runtime (include/ibl/shade.h) on a real OpenGL
 * driver: Mesa's llvmpipe through a headless EGL context (tests/support/gl_harness.c). */
#include "test_support.h"
#include "gl_harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct fixture {
    glh_context gl;
} fixture;

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    char why[512];
    if (!f) return -1;
    if (glh_create(&f->gl, why, sizeof why) != 0) {
        /* no silent skip: the reason names the Debian package to install */
        print_error("no headless OpenGL 4.5 context: %s\n", why);
        free(f);
        return -1;
    }
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    glh_destroy(&f->gl);
    free(f);
    return 0;
}

static void gl_context(void **state)
{
    fixture *f = *state;
    print_message("renderer: %s, %s\n", f->gl.renderer, f->gl.version);
    assert_non_null(strstr(f->gl.version, "4.5"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gl_context),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
