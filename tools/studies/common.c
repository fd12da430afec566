/* Shared pieces of the studies: fragments, inputs, timing, and the float64 reference
 * convolution of a piecewise-constant cube (the independent yardstick of the kernel studies). */
#include "studies.h"
#include "bench_timing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

FILE *study_fragment(const study_env *env, const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.md", env->out_dir, name);
    FILE *f = fopen(path, "w");
    if (!f) fprintf(stderr, "studies: cannot write %s\n", path);
    return f;
}

int study_fragment_close(const study_env *env, FILE *f, const char *study)
{
    fprintf(f, "\nMeasured on %s, %s, by `make studies`; this study alone: "
               "`build/tools/studies/ibl_studies --hdri HDRI_DIR --out DIR --study %s`.\n",
            env->machine, env->date, study);
    return fclose(f) == 0 ? 0 : 1;
}

int study_fail(const study_env *env, const char *what, ibl_status st)
{
    fprintf(stderr, "studies: %s: %s (%s)\n", what, ibl_context_message(env->ctx), ibl_status_name(st));
    return 1;
}

int study_write_picture(const study_env *env, const char *name, const ibl_image *image)
{
    if (!env->image_dir) return 0;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", env->image_dir, name);
    ibl_write_desc wd = {.tonemap = IBL_TONEMAP_NONE};
    ibl_status st = ibl_write_image(env->ctx, path, image, &wd);
    return st == IBL_OK ? 0 : study_fail(env, path, st);
}

int study_load_cube(const study_env *env, const char *name, int size, ibl_cubemap *out)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", env->hdri_dir, name);
    ibl_image image;
    ibl_status st = ibl_read_image(env->ctx, path, NULL, &image, NULL);
    if (st != IBL_OK) return study_fail(env, path, st);
    st = ibl_image_to_cubemap(env->ctx, &image, &(ibl_to_cube_desc){.size = size}, out);
    ibl_image_free(env->ctx, &image);
    return st == IBL_OK ? 0 : study_fail(env, path, st);
}

double study_now_ms(void) { return bench_now_ms(); }

double study_median(double *values, int count) { return bench_median(values, count); }

double study_luminance(const float *rgb)
{
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

double study_luminance_d(const double *rgb)
{
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

void study_sphere_points(int n, double (*dirs)[3])
{
    const double golden = 3.0 - sqrt(5.0); /* turns of the golden angle, x pi */
    for (int i = 0; i < n; i++) {
        double z = 1.0 - (2.0 * i + 1.0) / n;
        double r = sqrt(1.0 - z * z), phi = M_PI * golden * i;
        dirs[i][0] = r * cos(phi);
        dirs[i][1] = z;
        dirs[i][2] = r * sin(phi);
    }
}

/* The solid angle of the face-plane rectangle [0,u] x [0,v] seen from the cube's centre
 * (a face at distance 1): atan(u v / sqrt(1 + u^2 + v^2)). */
static double corner_area(double u, double v)
{
    return atan2(u * v, sqrt(1.0 + u * u + v * v));
}

static double rect_solid_angle(double u0, double v0, double u1, double v1)
{
    return corner_area(u1, v1) - corner_area(u0, v1) - corner_area(u1, v0) + corner_area(u0, v0);
}

int study_quad_build(const ibl_cubemap *src, int k, study_quad *q)
{
    int n = src->size;
    q->count = 6 * n * n * k * k;
    q->dir = malloc((size_t)q->count * sizeof *q->dir);
    q->omega = malloc((size_t)q->count * sizeof *q->omega);
    q->rgb = malloc((size_t)q->count * sizeof *q->rgb);
    if (!q->dir || !q->omega || !q->rgb) {
        study_quad_free(q);
        return 1;
    }
    int m = n * k, i = 0;
    for (int f = 0; f < 6; f++) {
        const float *face = ibl_cubemap_face(src, 0, f);
        for (int y = 0; y < m; y++)
            for (int x = 0; x < m; x++, i++) {
                double s0 = (double)x / m, s1 = (double)(x + 1) / m;
                double t0 = (double)y / m, t1 = (double)(y + 1) / m;
                double d[3];
                /* the library's face convention (cubemap.h), which is not what is measured */
                ibl_cube_direction_d(f, 0.5 * (s0 + s1), 0.5 * (t0 + t1), d);
                double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (int c = 0; c < 3; c++) q->dir[i][c] = d[c] / len;
                q->omega[i] = fabs(rect_solid_angle(2 * s0 - 1, 2 * t0 - 1, 2 * s1 - 1, 2 * t1 - 1));
                q->rgb[i] = face + 4 * ((size_t)(y / k) * n + (size_t)(x / k));
            }
    }
    return 0;
}

void study_quad_free(study_quad *q)
{
    free(q->dir);
    free(q->omega);
    free((void *)q->rgb);
    memset(q, 0, sizeof *q);
}

void study_convolve(const study_quad *q, const double r[3], study_kernel_fn kernel, double param,
                    double x_min, double out[3])
{
    double sum[3] = {0, 0, 0}, wsum = 0.0;
    for (int i = 0; i < q->count; i++) {
        const double *d = q->dir[i];
        double x = r[0] * d[0] + r[1] * d[1] + r[2] * d[2];
        if (x <= x_min) continue;
        double w = kernel(x, param) * q->omega[i];
        const float *c = q->rgb[i];
        sum[0] += w * c[0];
        sum[1] += w * c[1];
        sum[2] += w * c[2];
        wsum += w;
    }
    for (int c = 0; c < 3; c++) out[c] = wsum > 0.0 ? sum[c] / wsum : 0.0;
}

double study_kernel_phong(double x, double n)
{
    return x > 0.0 ? pow(x, n) : 0.0;
}

double study_kernel_blinn_n1(double x, double s)
{
    double c2 = 0.5 * (1.0 + x); /* cos^2(theta / 2) */
    return c2 > 0.0 ? pow(c2, 0.5 * s) : 0.0;
}

double study_phong_cut(double n)
{
    return n > 0.0 ? exp(log(1e-16) / n) : 0.0;
}
