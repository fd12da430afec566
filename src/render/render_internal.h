/* Internal pieces shared by the preview renderer's files. */
#ifndef IBL_RENDER_INTERNAL_H
#define IBL_RENDER_INTERNAL_H

#include "ibl/render.h"
#include "core/numeric.h"

#include <math.h>
#include <stdint.h>

/* Orthonormal tangent frame around a unit vector (Duff et al. 2017, "Building an
 * Orthonormal Basis, Revisited"). */
void ibl__frame(ibl_vec3 n, ibl_vec3 *t, ibl_vec3 *b);
/* Point i of an n-point Hammersley set in [0, 1)^2, rotated by (r0, r1) modulo 1
 * (Cranley-Patterson rotation). */
void ibl__hammersley(uint32_t i, uint32_t n, float r0, float r1, float *u0, float *u1);
/* A well-mixed 32-bit hash (for per-pixel rotations that do not depend on threads). */
uint32_t ibl__hash(uint32_t x);
/* Half vector sampled from the GGX NDF (pdf D(h) n.h), in the frame of n. */
ibl_vec3 ibl__sample_ggx(ibl_vec3 n, float alpha, float u0, float u1);
/* Half vector sampled from the normalised Blinn-Phong NDF ((s + 1)/2pi (n.h)^s). */
ibl_vec3 ibl__sample_phong(ibl_vec3 n, float shininess, float u0, float u1);

/* Draws text with the built-in 5x7 bitmap font (upper case, digits, common punctuation;
 * lower case is drawn as upper case), each font pixel scale x scale image pixels, on a dark
 * box for legibility (text.c: the labels of side-by-side comparisons). */
void ibl__render_text(ibl_image *image, int x, int y, int scale, const char *text,
                      const float rgba[4]);

/* Environment importance sampling (env_sampling.c). */
typedef struct ibl__env_sampler ibl__env_sampler;
ibl__env_sampler *ibl__env_sampler_create(ibl_context *ctx, const ibl_cubemap *env);
void ibl__env_sampler_destroy(ibl_context *ctx, ibl__env_sampler *s);
/* A direction and its density over solid angle. */
ibl_vec3 ibl__env_sampler_sample(const ibl__env_sampler *s, float u0, float u1, float *pdf);
float ibl__env_sampler_pdf(const ibl__env_sampler *s, ibl_vec3 d);

/* Skin (skin.c): a hit on ibl_render_desc.skin's mesh, rays in render space. */
typedef struct ibl__skin_hit {
    ibl_vec3 n, geometric_normal; /* interpolated and the triangle's, facing the ray */
    float uv[2];
    int triangle;
} ibl__skin_hit;
int ibl__skin_intersect(const ibl_render_skin *skin, ibl_vec3 o, ibl_vec3 d, float *t,
                        ibl__skin_hit *out);
/* Radiance toward v (unit, toward the eye) at a hit: ibl_skin_shade plus the specular. */
void ibl__skin_shade(const ibl_probe *probe, const ibl_render_desc *desc, const ibl__skin_hit *h,
                     ibl_vec3 v, float out[3]);

#endif
