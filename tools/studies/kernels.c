/* Study 1: tri-Ace 2010's three prefilter kernels (box mips, per-face 2D Gaussian, spherical
 * Phong) against the exact Phong convolution of the same source cube.
 *
 * For each face size, each chain covers material shininess 1..2000 with the tri-Ace mapping
 * and no edge fixup (the kernels alone). Every level is compared at its texel centres with
 * the float64 convolution of the source by the Phong lobe of the level's own kernel exponent
 * (ibl_specular_level_phong_exponent): sum_t L_t max(R.l_t,0)^n omega_t / sum_t ..., over
 * sub-texels small enough for the lobe, solid angles from the closed form (common.c). */
#include "studies.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define HDRI "forest.exr"

enum { KERNEL_COUNT = 3, MAX_EVAL = 1536 };

static const ibl_specular_filter kernel_filter[KERNEL_COUNT] = {IBL_FILTER_BOX, IBL_FILTER_GAUSS,
                                                                IBL_FILTER_PHONG};
static const char *const kernel_label[KERNEL_COUNT] = {"box", "Gaussian", "Phong"};

typedef struct level_error {
    double shininess; /* material shininess of the level                 */
    double rms, max;  /* relative error of the luminance over the texels  */
} level_error;

/* The sub-texel split that resolves a Phong lobe of exponent n on a face of edge size: a few
 * sub-texels across the lobe's half-width at half maximum. */
static int split_for(int size, double n)
{
    double texel = (M_PI / 2.0) / size;
    double half = n > 1.0 ? acos(pow(0.5, 1.0 / n)) : M_PI / 3.0;
    int k = (int)ceil(4.0 * texel / half);
    return k < 1 ? 1 : k > 16 ? 16 : k;
}

/* The chain of one kernel, material shininess 1..2000 (a phong chain speaks kernel
 * exponents: the same range divided by the fit's factor). */
static ibl_status make_chain(const study_env *env, const ibl_cubemap *src, ibl_specular_filter filter,
                             ibl_cubemap *out, ibl_specular_info *info)
{
    ibl_specular_desc d = {.filter = filter, .size = src->size, .mapping = IBL_MAPPING_TRIACE};
    float f = 4.2f;
    d.shininess_min = filter == IBL_FILTER_PHONG ? 1.0f / f : 1.0f;
    d.shininess_max = filter == IBL_FILTER_PHONG ? 2000.0f / f : 2000.0f;
    return ibl_specular_prefilter(env->ctx, src, &d, out, info);
}

/* Errors of one level against the reference. ref_cache holds the reference values of the
 * previous kernel's level (reused when the exponent is the same). */
static int measure_level(const ibl_cubemap *src, const ibl_cubemap *chain, int level, double n,
                         double *ref, double *ref_n, level_error *e)
{
    int size = ibl_level_size(chain->size, level);
    int stride = size > 16 ? size / 16 : 1;
    int count = 0;
    study_quad q = {0};
    int have_ref = fabs(*ref_n - n) <= 1e-5 * n;
    if (!have_ref && study_quad_build(src, split_for(src->size, n), &q)) return 1;
    double sum2 = 0.0, worst = 0.0;
    for (int f = 0; f < 6; f++) {
        const float *face = ibl_cubemap_face(chain, level, f);
        for (int y = stride / 2; y < size; y += stride)
            for (int x = stride / 2; x < size; x += stride, count++) {
                if (!have_ref) {
                    double r[3], out[3];
                    ibl_cube_direction_d(f, (x + 0.5) / size, (y + 0.5) / size, r);
                    double len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
                    for (int c = 0; c < 3; c++) r[c] /= len;
                    study_convolve(&q, r, study_kernel_phong, n, study_phong_cut(n), out);
                    ref[count] = study_luminance_d(out);
                }
                double got = study_luminance(face + 4 * ((size_t)y * size + x));
                double rel = ref[count] > 0.0 ? (got - ref[count]) / ref[count] : 0.0;
                sum2 += rel * rel;
                if (fabs(rel) > worst) worst = fabs(rel);
            }
    }
    study_quad_free(&q);
    *ref_n = n;
    e->rms = sqrt(sum2 / count);
    e->max = worst;
    return 0;
}

static void print_header(FILE *md)
{
    fprintf(md, "| face | level | shininess (Gaussian, Phong) | box's shininess |");
    for (int k = 0; k < KERNEL_COUNT; k++) fprintf(md, " %s RMS | %s max |", kernel_label[k], kernel_label[k]);
    fprintf(md, "\n|---|---|---|---|");
    for (int k = 0; k < KERNEL_COUNT; k++) fprintf(md, "---|---|");
    fprintf(md, "\n");
}

static void pct(FILE *md, double x)
{
    fprintf(md, x < 0.1 ? " %.2f%% |" : x < 10 ? " %.1f%% |" : " %.0f%% |", 100.0 * x);
}

static int one_size(const study_env *env, int size, FILE *md, double summary[KERNEL_COUNT][2])
{
    ibl_cubemap src;
    if (study_load_cube(env, HDRI, size, &src)) return 1;
    ibl_cubemap chain[KERNEL_COUNT] = {{0}};
    ibl_specular_info info[KERNEL_COUNT];
    level_error err[KERNEL_COUNT][IBL_MAX_LEVELS];
    double *ref = malloc(MAX_EVAL * sizeof *ref), ref_n = -1.0;
    int rc = ref ? 0 : 1;
    int levels = IBL_MAX_LEVELS;
    for (int k = 0; k < KERNEL_COUNT && !rc; k++) {
        ibl_status st = make_chain(env, &src, kernel_filter[k], &chain[k], &info[k]);
        if (st != IBL_OK) rc = study_fail(env, "prefilter", st);
        else if (info[k].levels < levels) levels = info[k].levels;
    }
    /* level by level, so the Gaussian and Phong levels (same exponent) share one reference */
    for (int l = 0; !rc && l < levels; l++)
        for (int k = 0; k < KERNEL_COUNT && !rc; k++) {
            err[k][l].shininess = ibl_specular_level_shininess(&info[k], l);
            double n = ibl_specular_level_phong_exponent(&info[k], l);
            rc = measure_level(&src, &chain[k], l, n, ref, &ref_n, &err[k][l]);
        }
    for (int l = 0; !rc && l < levels; l++) {
        fprintf(md, "| %d | %d (%d²) | %.4g | %.4g |", size, l, ibl_level_size(size, l), err[1][l].shininess,
                err[0][l].shininess);
        for (int k = 0; k < KERNEL_COUNT; k++) {
            pct(md, err[k][l].rms);
            pct(md, err[k][l].max);
            summary[k][0] += err[k][l].rms * err[k][l].rms / levels;
            if (err[k][l].max > summary[k][1]) summary[k][1] = err[k][l].max;
        }
        fprintf(md, "\n");
    }
    free(ref);
    for (int k = 0; k < KERNEL_COUNT; k++) ibl_cubemap_free(env->ctx, &chain[k]);
    ibl_cubemap_free(env->ctx, &src);
    return rc;
}


/* ---- the picture: the three chains and the exact convolution at one material shininess ---- */

enum { PIC_W = 200, PIC_H = 100, PIC_SIZE = 32 };
#define PIC_SHININESS 100.0

/* The runtime's view of a chain: its levels' material shininess, read by shininess. */
static ibl_status chain_probe(const study_env *env, const ibl_cubemap *chain, const ibl_specular_info *info,
                              ibl_probe *p)
{
    memset(p, 0, sizeof *p);
    p->specular = *chain;
    p->specular.owns_data = 0;
    p->mapping.levels = info->levels;
    for (int l = 0; l < info->levels; l++) p->mapping.shininess[l] = ibl_specular_level_shininess(info, l);
    p->sh_kind = IBL_SH_KIND_RADIANCE; /* no diffuse is read */
    return ibl_probe_validate(env->ctx, p);
}

/* Equirect panel k (0..2: the chains through ibl_probe_sample_specular at the probe's lod for
 * PIC_SHININESS; 3: the float64 Phong convolution of exponent PIC_SHININESS / 4.2). */
static int fill_panel(const study_env *env, const ibl_cubemap *src, int k, const ibl_cubemap *chain,
                      const ibl_specular_info *info, ibl_image *out)
{
    ibl_probe probe;
    study_quad q = {0};
    double n = PIC_SHININESS / 4.2;
    ibl_status st = ibl_image_alloc(env->ctx, PIC_W, PIC_H, out);
    if (st == IBL_OK && k < 3) st = chain_probe(env, chain, info, &probe);
    if (st != IBL_OK) return study_fail(env, "kernels picture", st);
    if (k == 3 && study_quad_build(src, split_for(src->size, n), &q)) return 1;
    float lod = k < 3 ? ibl_probe_lod_from_shininess(&probe, (float)PIC_SHININESS) : 0.0f;
    for (int y = 0; y < PIC_H; y++)
        for (int x = 0; x < PIC_W; x++) {
            ibl_vec3 d;
            ibl_layout_direction(IBL_LAYOUT_EQUIRECT, (x + 0.5f) / PIC_W, (y + 0.5f) / PIC_H, &d);
            float *px = ibl_image_texel(out, x, y);
            if (k < 3) {
                ibl_probe_sample_specular(&probe, lod, d, px);
            } else {
                double r[3] = {d.x, d.y, d.z}, rgb[3];
                study_convolve(&q, r, study_kernel_phong, n, study_phong_cut(n), rgb);
                for (int c = 0; c < 3; c++) px[c] = (float)rgb[c];
            }
            px[3] = 1.0f;
        }
    study_quad_free(&q);
    return 0;
}

/* Two labelled pairs stacked: box | Gaussian over Phong | exact. */
static int kernels_picture(const study_env *env)
{
    static const char *const labels[4] = {"box", "gaussian", "phong", "exact phong (float64)"};
    ibl_cubemap src;
    if (study_load_cube(env, HDRI, PIC_SIZE, &src)) return 1;
    ibl_cubemap chain[KERNEL_COUNT] = {{0}};
    ibl_specular_info info[KERNEL_COUNT];
    ibl_image panel[4] = {{0}}, pair[2] = {{0}}, out = {0};
    int rc = 0;
    for (int k = 0; k < 4 && !rc; k++) {
        if (k < KERNEL_COUNT) {
            ibl_status st = make_chain(env, &src, kernel_filter[k], &chain[k], &info[k]);
            if (st != IBL_OK) rc = study_fail(env, "prefilter", st);
        }
        if (!rc) rc = fill_panel(env, &src, k, k < 3 ? &chain[k] : NULL, k < 3 ? &info[k] : NULL, &panel[k]);
    }
    float exposure = rc ? 0.0f : ibl_image_auto_exposure(&panel[3]);
    for (int k = 0; k < 4 && !rc; k++) ibl_render_tonemap(&panel[k], exposure);
    for (int i = 0; i < 2 && !rc; i++) {
        ibl_status st = ibl_render_side_by_side(env->ctx, &panel[2 * i], labels[2 * i], &panel[2 * i + 1],
                                                labels[2 * i + 1], &pair[i]);
        if (st != IBL_OK) rc = study_fail(env, "kernels picture", st);
    }
    if (!rc && ibl_image_alloc(env->ctx, pair[0].width, 2 * pair[0].height + 2, &out) != IBL_OK) rc = 1;
    for (int y = 0; y < out.height && !rc; y++)
        for (int x = 0; x < out.width; x++) {
            const ibl_image *from = y < pair[0].height ? &pair[0] : &pair[1];
            int fy = y < pair[0].height ? y : y - pair[0].height - 2;
            float *px = ibl_image_texel(&out, x, y);
            if (fy < 0) px[0] = px[1] = px[2] = 0.0f, px[3] = 1.0f;
            else memcpy(px, ibl_image_texel(from, x, fy), 4 * sizeof(float));
        }
    if (!rc) rc = study_write_picture(env, "studies_kernels.png", &out);
    ibl_image_free(env->ctx, &out);
    for (int i = 0; i < 2; i++) ibl_image_free(env->ctx, &pair[i]);
    for (int k = 0; k < 4; k++) ibl_image_free(env->ctx, &panel[k]);
    for (int k = 0; k < KERNEL_COUNT; k++) ibl_cubemap_free(env->ctx, &chain[k]);
    ibl_cubemap_free(env->ctx, &src);
    return rc;
}

int study_kernels(const study_env *env)
{
    FILE *md = study_fragment(env, "kernels");
    if (!md) return 1;
    static const int sizes[] = {16, 32, 64};
    int rc = 0;
    print_header(md);
    double summary[3][KERNEL_COUNT][2];
    memset(summary, 0, sizeof summary);
    for (int i = 0; i < 3 && !rc; i++) {
        double t0 = study_now_ms();
        rc = one_size(env, sizes[i], md, summary[i]);
        fprintf(stderr, "studies: kernels %d: %.1f s\n", sizes[i], (study_now_ms() - t0) / 1e3);
    }
    fprintf(md, "\nOver all levels of a size (RMS of the per-level RMS, and the worst texel):\n\n");
    fprintf(md, "| face | box RMS | box max | Gaussian RMS | Gaussian max | Phong RMS | Phong max |\n");
    fprintf(md, "|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < 3 && !rc; i++) {
        fprintf(md, "| %d |", sizes[i]);
        for (int k = 0; k < KERNEL_COUNT; k++) {
            pct(md, sqrt(summary[i][k][0]));
            pct(md, summary[i][k][1]);
        }
        fprintf(md, "\n");
    }
    if (!rc) rc = kernels_picture(env);
    if (rc) {
        fclose(md);
        return rc;
    }
    return study_fragment_close(env, md, "kernels");
}
