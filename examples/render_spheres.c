/* The smallest complete integration of ibl's runtime shaders in an OpenGL program: load a
 * bake folder, upload it (gl_probe.c), draw the sphere grid of `ibl render` with
 * shaders/ibl.glsl + sphere_grid.frag offscreen (sphere_grid.c) and write a PNG tone-mapped
 * exactly as `ibl render` does, so the two pictures can be compared.
 *
 *   make demo
 *   build/examples/render_spheres out/demo/bake out/demo/gl.png     (compare with preview.png)
 *
 * The OpenGL 4.5 context is headless (EGL surfaceless, tests/support/gl_harness.c); in an
 * engine, everything after glh_create is what to copy. */
#include "gl_harness.h"
#include "gl_probe.h"
#include "sphere_grid.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef IBL_SHADER_DIR
#define IBL_SHADER_DIR "shaders"
#endif
#ifndef IBL_EXAMPLES_DIR
#define IBL_EXAMPLES_DIR "examples"
#endif

static char *read_named(const char *dir, const char *name)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char *s = glh_read_text(path);
    if (!s) fprintf(stderr, "render_spheres: cannot read %s\n", path);
    return s;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: render_spheres BAKE_DIR OUT.png [WIDTH [HEIGHT]]\n"
                        "  draws the sphere grid of `ibl render BAKE_DIR` with OpenGL\n"
                        "  (shaders from $IBL_SHADER_DIR, default %s)\n", IBL_SHADER_DIR);
        return 2;
    }
    int width = argc > 3 ? atoi(argv[3]) : 1024, height = argc > 4 ? atoi(argv[4]) : width / 2;
    if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
        fprintf(stderr, "render_spheres: bad size %dx%d\n", width, height);
        return 2;
    }
    const char *shader_dir = getenv("IBL_SHADER_DIR") ? getenv("IBL_SHADER_DIR") : IBL_SHADER_DIR;
    char *glsl = read_named(shader_dir, "ibl.glsl");
    char *frag = read_named(IBL_EXAMPLES_DIR, "sphere_grid.frag");
    if (!glsl || !frag) return 1;

    glh_context gl;
    char why[512];
    if (glh_create(&gl, why, sizeof why) != 0) {
        fprintf(stderr, "render_spheres: no OpenGL 4.5 context: %s\n", why);
        return 1;
    }
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) return 1;
    int rc = 1;
    ibl_bake_data bake;
    ibl_probe probe;
    glp_probe gpu;
    ibl_image image;
    char log[8192] = "";
    memset(&bake, 0, sizeof bake);
    memset(&gpu, 0, sizeof gpu);
    /* 1. the bake folder -> the probe (plain data) -> textures and the uniform block */
    if (ibl_bake_load(ctx, argv[1], NULL, &bake) != IBL_OK ||
        ibl_bake_probe(ctx, &bake, &probe) != IBL_OK ||
        glp_probe_upload(&gl.gl, ctx, &probe, &gpu) != IBL_OK) {
        fprintf(stderr, "render_spheres: %s\n", ibl_context_message(ctx));
        goto done;
    }
    /* 2. draw, read back the linear image */
    if (sg_render(&gl, ctx, &gpu, NULL, glsl, frag, width, height, &image, NULL, log,
                  sizeof log) != IBL_OK) {
        fprintf(stderr, "render_spheres: drawing failed: %s\n", log);
        goto done;
    }
    /* 3. tone-map as `ibl render` does (automatic exposure, the filmic curve, sRGB PNG) */
    ibl_render_tonemap(&image, ibl_image_auto_exposure(&image));
    ibl_write_desc wd = {.tonemap = IBL_TONEMAP_NONE};
    if (ibl_write_image(ctx, argv[2], &image, &wd) != IBL_OK)
        fprintf(stderr, "render_spheres: %s\n", ibl_context_message(ctx));
    else
        rc = 0;
    ibl_image_free(ctx, &image);
done:
    glp_probe_free(&gl.gl, &gpu);
    glh_destroy(&gl);
    ibl_bake_free(ctx, &bake);
    ibl_context_destroy(ctx);
    free(glsl);
    free(frag);
    return rc;
}
