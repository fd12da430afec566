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
/* the punctual lights (shader_cases_light.c) */
extern const shader_case shader_light_cases[];
extern const int shader_light_case_count;

/* generators shared by the case tables (shader_cases.c) */
float sc_rnd(uint64_t *s);
float sc_pick(int i, uint64_t *s, const float *edges, int n, float lo, float hi);
float sc_pick_log(int i, uint64_t *s, const float *edges, int n, float lo, float hi);
int sc_pick_int(uint64_t *s, int count);
void sc_gen_dir(int i, uint64_t *s, float *d);
void sc_gen_material(int i, uint64_t *s, float *x);  /* 11 floats */
ibl_material sc_material_of(const float *x);
void sc_gen_surface(int i, uint64_t *s, float *x);   /* 12 floats */
ibl_surface sc_surface_of(const float *x);
ibl_vec3 sc_v3(const float *x);
void sc_put3(float *y, ibl_vec3 v);

#endif
