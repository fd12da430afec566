/* A probe (include/ibl/shade.h) on the GPU for shaders/ibl.glsl: the textures with the
 * sampler state the shaders expect and the uniform block of include/ibl/shader.h. The part
 * of examples/render_spheres.c an engine copies; tests/test_shaders.c runs it too.
 *
 * Binding table (docs/SHADERS.md):
 *   texture unit 0  samplerCube  specular      the prefiltered chain, every level, trilinear
 *   texture unit 1  samplerCube  mirror        unfiltered environment (1x1 black if none)
 *   texture unit 2  samplerCube  irradiance    E/pi cube (1x1 black if the probe uses SH)
 *   texture unit 3  sampler2D    splitsum      RG = A, B; bilinear, clamp
 *   texture unit 4  sampler3D    ambient_brdf  R = AmbientBRDF; trilinear, clamp
 *   uniform block binding 0      ibl_probe     ibl_shader_probe (std140)
 * Every texture is RGBA32F, clamp to edge; cubes need GL_TEXTURE_CUBE_MAP_SEAMLESS (enabled
 * by glp_probe_upload), which Vulkan and Direct3D always do. */
#ifndef IBL_EXAMPLES_GL_PROBE_H
#define IBL_EXAMPLES_GL_PROBE_H

#include "gl_harness.h"
#include "ibl/ibl.h"

enum { GLP_UNIT_SPECULAR, GLP_UNIT_MIRROR, GLP_UNIT_IRRADIANCE, GLP_UNIT_SPLITSUM,
       GLP_UNIT_AMBIENT_BRDF, GLP_UNIT_COUNT };
enum { GLP_BLOCK_PROBE = 0 };

typedef struct glp_probe {
    GLuint texture[GLP_UNIT_COUNT];
    GLuint block; /* uniform buffer holding `data` */
    ibl_shader_probe data;
} glp_probe;

/* Uploads every part of a validated probe; returns IBL_OK or the reason in ctx. */
ibl_status glp_probe_upload(const glh_gl *gl, ibl_context *ctx, const ibl_probe *probe,
                            glp_probe *out);
/* Binds the textures to units 0..4 and the block to binding 0. */
void glp_probe_bind(const glh_gl *gl, const glp_probe *p);
void glp_probe_free(const glh_gl *gl, glp_probe *p);

/* A cube texture of `levels` levels of a cubemap (RGBA32F), trilinear when levels > 1. */
GLuint glp_cube_texture(const glh_gl *gl, const ibl_cubemap *cube, int levels);
/* A 2D RGBA32F texture of an image (its first row at t = 0), bilinear, clamp to edge. */
GLuint glp_image_texture(const glh_gl *gl, const ibl_image *image);

#endif
