/*
 * tools/studies: the measurements behind docs/STUDIES.md. Each study checks one claim of
 * Gotanda and Shoji (tri-Ace), "Real-time Physically Based Rendering - Implementation"
 * (2010) against an independent reference computed here in float64 (brute-force quadrature or
 * a closed form), and writes its tables as a Markdown fragment that tools/studies/run.sh
 * splices into docs/STUDIES.md. Only the public API (include/ibl) is used.
 */
#ifndef IBL_STUDIES_H
#define IBL_STUDIES_H

#include "ibl/ibl.h"

#include <stdio.h>

/* What every study gets: a one-thread context, where the test HDRIs are, where fragments go,
 * and the provenance line (machine, date) written under each table. */
typedef struct study_env {
    ibl_context *ctx;
    const char *hdri_dir;
    const char *out_dir;
    const char *image_dir; /* pictures (docs/images); NULL: none are written            */
    const char *machine;
    const char *date;
    int quick; /* smaller sample counts (for a smoke run; the docs use the full run)   */
} study_env;

/* ---- the studies (one file each) ---- */
int study_kernels(const study_env *env);      /* kernels.c: box / Gaussian / Phong chains   */
int study_blinn_factor(const study_env *env); /* blinn_factor.c: the 4.2 of the fit        */
int study_artefact(const study_env *env);     /* artefact.c: the HDR IBL artefact table     */
int study_ambient(const study_env *env);      /* ambient.c: AmbientBRDF, SO, SH vs IEM      */
int study_speed(const study_env *env);        /* speed.c: the six presets' timings          */

/* ---- common.c ---- */

/* Opens OUT_DIR/name.md for writing; prints the reason and returns NULL on failure. */
FILE *study_fragment(const study_env *env, const char *name);
/* Closes a fragment after the provenance line: machine, date and the command of the study. */
int study_fragment_close(const study_env *env, FILE *f, const char *study);
/* Writes a display-referred image (ibl_render_tonemap) to IMAGE_DIR/name; a no-op without an
 * image directory. */
int study_write_picture(const study_env *env, const char *name, const ibl_image *image);
/* Reads HDRI_DIR/name and converts it to a one-level cube of face edge size. */
int study_load_cube(const study_env *env, const char *name, int size, ibl_cubemap *out);
/* Prints the context's last message and returns 1 (for `return study_fail(...)`). */
int study_fail(const study_env *env, const char *what, ibl_status st);
double study_now_ms(void);
double study_median(double *values, int count); /* sorts values */
double study_luminance(const float *rgb);       /* Rec. 709 weights */
double study_luminance_d(const double *rgb);
/* n points spread evenly over the sphere (Fibonacci lattice; unit vectors). */
void study_sphere_points(int n, double (*dirs)[3]);

/* ---- the float64 reference convolution (common.c) ---- */

/* A source cube flattened into sub-texels: the centre direction, the exact solid angle (the
 * spherical rectangle's closed form, computed here) and the texel's RGB, each texel split
 * k x k. Built once per source and subdivision. */
typedef struct study_quad {
    int count;
    double (*dir)[3];
    double *omega;
    const float **rgb; /* the source texel each sub-texel lies in */
} study_quad;

int study_quad_build(const ibl_cubemap *src, int k, study_quad *q);
void study_quad_free(study_quad *q);
/* The normalised convolution sum_t L_t w(R.d_t) omega_t / sum_t w omega_t of one direction.
 * kernel(x, param) returns the lobe's weight for x = R.d in [-1, 1]; sub-texels with
 * x <= x_min are skipped (pass the x below which the weight is under 1e-16 of its peak). */
typedef double (*study_kernel_fn)(double x, double param);
void study_convolve(const study_quad *q, const double r[3], study_kernel_fn kernel, double param,
                    double x_min, double out[3]);
/* The x_min of a Phong lobe of exponent n (weight 1e-16 of the peak), 0 for n <= 0. */
double study_phong_cut(double n);
double study_kernel_phong(double x, double n);     /* max(x, 0)^n                     */
double study_kernel_blinn_n1(double x, double s);  /* cos(theta/2)^s = ((1+x)/2)^(s/2) */

#endif
