/* Shared by tests/test_shaders.c and its case table (shader_cases.c). */
#ifndef IBL_SHADER_TEST_H
#define IBL_SHADER_TEST_H

#include "gl_harness.h"
#include "gl_probe.h"
#include "ibl/ibl.h"

#include <stdint.h>

typedef struct fixture {
    glh_context gl;
    ibl_context *ctx;
    ibl_bake_data bake;
    ibl_probe probe;   /* forest on a 32 cube, baked as `ibl render` bakes */
    ibl_cubemap env;
    glp_probe gpu;
    ibl_image atlas;   /* the probe's chain as Daqi 2016's atlas */
    ibl_atlas_layout atlas_layout;
    GLuint atlas_texture, atlas_block;
    char *glsl; /* shaders/ibl.glsl */
} fixture;

/* One GLSL function against its C twin: gen fills n_in floats for sample i, the GLSL body
 * reads them with X(k) / I(k) / V(k) and writes n_out floats with Y(k, v); ref computes the
 * same in C. A sample passes when |gpu - c| <= abs_tol + extra_abs(x) + rel_tol |c|. */
typedef struct shader_case {
    const char *name;
    int n_in, n_out;
    const char *glsl;
    void (*gen)(const fixture *f, int i, uint64_t *rng, float *x);
    void (*ref)(const fixture *f, const float *x, float *y);
    double abs_tol, rel_tol;
    const char *why;
    double (*extra_abs)(const float *x); /* optional: added to abs_tol for this input */
} shader_case;

extern const shader_case shader_cases[];
extern const int shader_case_count;

#endif
