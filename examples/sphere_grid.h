/* Draws the sphere grid of `ibl render` with examples/sphere_grid.frag into an offscreen
 * RGBA32F framebuffer and reads it back as a linear ibl_image (top row first): used by
 * examples/render_spheres.c and by tests/test_shaders.c, which compares it with ibl_render. */
#ifndef IBL_EXAMPLES_SPHERE_GRID_H
#define IBL_EXAMPLES_SPHERE_GRID_H

#include "gl_probe.h"

/* ibl_glsl and frag: the texts of shaders/ibl.glsl and sphere_grid.frag. lights (optional:
 * NULL for none) is the light block (ibl_shader_lights_fill), bound at uniform binding 2. hit
 * (optional, width * height) receives 1 where a sphere was hit. Returns IBL_OK, or an error
 * with the compiler's log in `log`. */
ibl_status sg_render(const glh_context *c, ibl_context *ctx, const glp_probe *probe,
                     const ibl_shader_lights *lights, const char *ibl_glsl, const char *frag,
                     int width, int height, ibl_image *out, unsigned char *hit, char *log,
                     size_t log_size);

#endif
