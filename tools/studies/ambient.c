/* Study 4: tri-Ace 2010's AmbientBRDF ("AmbientBRDF comparison": off / on) and its two
 * diffuse sources ("Optimize diffuse term": SH lighting instead of the irradiance map), measured
 * against the Monte Carlo reference of the same scene (render.h: the full BRDF against the
 * unfiltered environment, no split sum, no tables). The probe is the one `ibl render` makes
 * of an environment (ibl_render_bake_desc); the four variants change only what the talk
 * changes: the AmbientBRDF volume present or not (without it the runtime uses F0 in its place,
 * as a renderer without the table would), and the diffuse read from the irradiance cube or
 * from the 9 SH coefficients of the radiance. Errors are those of `ibl render --report`: the
 * relative error of each sphere's mean RGB, runtime (4 x 4 rays per pixel) minus reference. */
#include "studies.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { VARIANTS = 4, MAX_OBJECTS = 64 };

static const char *const variant_label[VARIANTS] = {
    "irradiance map, AmbientBRDF on", "SH, AmbientBRDF on", "irradiance map, AmbientBRDF off",
    "SH, AmbientBRDF off"};

typedef struct scene_errors {
    double diffuse[2][2]; /* irradiance map, SH: mean signed and RMS relative error of E/pi */
    int objects;
    ibl_render_object obj[MAX_OBJECTS];
    double err[VARIANTS][MAX_OBJECTS]; /* relative error of the sphere's mean RGB */
} scene_errors;

static void probe_variant(const ibl_probe *base, int v, ibl_probe *out)
{
    *out = *base;
    if (v == 1 || v == 3) out->sh_kind = IBL_SH_KIND_RADIANCE; /* the diffuse from SH9 */
    if (v >= 2) memset(&out->ambient_brdf, 0, sizeof out->ambient_brdf);
}

/* Per-object relative error of the mean RGB of image a against reference b. */
static void object_errors(const ibl_image *a, const ibl_image *b, const int *ids, int objects, double *err)
{
    for (int o = 0; o < objects; o++) {
        double sa = 0.0, sb = 0.0;
        for (size_t i = 0; i < (size_t)a->width * a->height; i++) {
            if (ids[i] != o) continue;
            for (int c = 0; c < 3; c++) sa += a->pixels[4 * i + c], sb += b->pixels[4 * i + c];
        }
        err[o] = sb > 0.0 ? (sa - sb) / sb : 0.0;
    }
}

static double cosine_kernel(double x, double unused)
{
    (void)unused;
    return x;
}

/* The diffuse sources alone: E(n)/pi from the probe's irradiance map and from its SH9, against
 * the float64 sum (1/pi) sum_t L_t max(n.d_t, 0) omega_t over a 64² cube of the same HDRI
 * (the cosine is smooth: 64² faces resolve it), at 1536 normals. */
static int diffuse_check(const study_env *env, const char *hdri, const ibl_probe *probe, scene_errors *se)
{
    enum { NORMALS = 1536 };
    ibl_cubemap cube;
    if (study_load_cube(env, hdri, 64, &cube)) return 1;
    study_quad q;
    static double dirs[NORMALS][3];
    int rc = study_quad_build(&cube, 1, &q);
    if (!rc) study_sphere_points(NORMALS, dirs);
    ibl_probe sh = *probe;
    sh.sh_kind = IBL_SH_KIND_RADIANCE;
    double sum[2] = {0, 0}, sum2[2] = {0, 0};
    for (int i = 0; i < NORMALS && !rc; i++) {
        double e[3], wsum = 0.0;
        for (int t = 0; t < q.count; t++) {
            double x = dirs[i][0] * q.dir[t][0] + dirs[i][1] * q.dir[t][1] + dirs[i][2] * q.dir[t][2];
            if (x > 0.0) wsum += x * q.omega[t];
        }
        study_convolve(&q, dirs[i], cosine_kernel, 0.0, 0.0, e); /* normalised: times wsum / pi */
        double ref = study_luminance_d(e) * wsum / M_PI;
        ibl_vec3 n = {(float)dirs[i][0], (float)dirs[i][1], (float)dirs[i][2]};
        float got[2][3];
        ibl_probe_irradiance(probe, n, got[0]);
        ibl_probe_irradiance(&sh, n, got[1]);
        for (int k = 0; k < 2; k++) {
            double rel = (study_luminance(got[k]) - ref) / ref;
            sum[k] += rel, sum2[k] += rel * rel;
        }
    }
    for (int k = 0; k < 2; k++) se->diffuse[k][0] = sum[k] / NORMALS, se->diffuse[k][1] = sqrt(sum2[k] / NORMALS);
    study_quad_free(&q);
    ibl_cubemap_free(env->ctx, &cube);
    return rc;
}

static int measure(const study_env *env, const char *hdri, scene_errors *se)
{
    ibl_cubemap cube;
    if (study_load_cube(env, hdri, 0, &cube)) return 1;
    ibl_bake_desc bd;
    ibl_bake_data bake;
    ibl_render_bake_desc(&cube, 0, &bd);
    ibl_status st = ibl_bake_compute(env->ctx, &cube, &bd, &bake);
    ibl_cubemap_free(env->ctx, &cube);
    if (st != IBL_OK) return study_fail(env, hdri, st);
    ibl_probe probe;
    st = ibl_bake_probe(env->ctx, &bake, &probe);
    int w = 512, h = 256; /* narrower spheres alias a window's mirror reflection */
    int *ids = malloc(sizeof(int) * (size_t)w * h);
    ibl_image ref = {0};
    ibl_render_desc rd = {.width = w, .height = h, .reference = 1,
                          .reference_samples = env->quick ? 16 : 64};
    if (st == IBL_OK && !ids) st = IBL_ERR_OUT_OF_MEMORY;
    if (st == IBL_OK) st = ibl_render(env->ctx, &probe, &rd, &ref, ids);
    se->objects = ibl_render_scene_objects(se->obj, MAX_OBJECTS);
    for (int v = 0; v < VARIANTS && st == IBL_OK; v++) {
        ibl_probe pv;
        probe_variant(&probe, v, &pv);
        ibl_image img;
        ibl_render_desc fd = {.width = w, .height = h, .supersample = 4};
        st = ibl_render(env->ctx, &pv, &fd, &img, NULL);
        if (st != IBL_OK) break;
        object_errors(&img, &ref, ids, se->objects, se->err[v]);
        ibl_image_free(env->ctx, &img);
    }
    free(ids);
    ibl_image_free(env->ctx, &ref);
    if (st == IBL_OK && diffuse_check(env, hdri, &probe, se)) st = IBL_ERR_OUT_OF_MEMORY;
    ibl_bake_free(env->ctx, &bake);
    return st == IBL_OK ? 0 : study_fail(env, hdri, st);
}

/* The Blinn-Phong row (the material AmbientBRDF is for) and the dielectric row (diffuse-heavy:
 * where SH and the irradiance map differ); the metals have no diffuse and no AmbientBRDF. */
static int shown(const ibl_render_object *o)
{
    return o->material.model == IBL_MATERIAL_BLINN_PHONG || o->material.metallic == 0.0f;
}

static void write_table(FILE *md, const char *hdri, const scene_errors *se)
{
    fprintf(md, "\n%s:\n\n| sphere |", hdri);
    for (int v = 0; v < VARIANTS; v++) fprintf(md, " %s |", variant_label[v]);
    fprintf(md, "\n|---|");
    for (int v = 0; v < VARIANTS; v++) fprintf(md, "---|");
    fprintf(md, "\n");
    double worst[VARIANTS] = {0}, sum2[VARIANTS] = {0};
    int count = 0;
    for (int o = 0; o < se->objects; o++) {
        if (!shown(&se->obj[o])) continue;
        count++;
        fprintf(md, "| %s |", se->obj[o].label);
        for (int v = 0; v < VARIANTS; v++) {
            double e = se->err[v][o];
            fprintf(md, " %+.2f%% |", 100 * e);
            sum2[v] += e * e;
            if (fabs(e) > worst[v]) worst[v] = fabs(e);
        }
        fprintf(md, "\n");
    }
    fprintf(md, "| RMS over these spheres |");
    for (int v = 0; v < VARIANTS; v++) fprintf(md, " %.2f%% |", 100 * sqrt(sum2[v] / count));
    fprintf(md, "\n| worst \\|error\\| |");
    for (int v = 0; v < VARIANTS; v++) fprintf(md, " %.2f%% |", 100 * worst[v]);
    fprintf(md, "\n\nThe diffuse sources alone against the float64 irradiance (E/π at 1536 normals): "
                "irradiance map mean %+.2f%%, RMS %.2f%%; SH9 mean %+.2f%%, RMS %.2f%%.\n",
            100 * se->diffuse[0][0], 100 * se->diffuse[0][1], 100 * se->diffuse[1][0], 100 * se->diffuse[1][1]);
}

int study_ambient(const study_env *env)
{
    static const char *const hdris[] = {"forest.exr", "sunset.exr", "interior.exr"};
    FILE *md = study_fragment(env, "ambient");
    if (!md) return 1;
    /* what "AmbientBRDF off" puts F0 in place of */
    static const double shin[] = {1, 10, 50, 200, 1000, 100000};
    fprintf(md, "The value F0 stands in for without the volume, the directional albedo of the "
                "specular term (`ibl_ambient_brdf`, tri-Ace normalisation, F0 = 1):\n\n| n·v |");
    for (int j = 0; j < 6; j++) fprintf(md, " s = %g |", shin[j]);
    fprintf(md, "\n|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 2; k++) {
        double nv = k ? 0.5 : 1.0;
        fprintf(md, "| %g |", nv);
        for (int j = 0; j < 6; j++)
            fprintf(md, " %.3f |", ibl_ambient_brdf(nv, shin[j], 1.0, IBL_BLINN_TRIACE_FIT, 0));
        fprintf(md, "\n");
    }
    fprintf(md, "\nRelative error of each sphere's mean radiance against the Monte Carlo reference "
                "(512×256, %d reference iterations per pixel):\n", env->quick ? 16 : 64);
    int rc = 0;
    for (size_t i = 0; i < sizeof hdris / sizeof hdris[0] && !rc; i++) {
        scene_errors *se = calloc(1, sizeof *se);
        rc = se ? measure(env, hdris[i], se) : 1;
        if (!rc) write_table(md, hdris[i], se);
        free(se);
    }
    if (rc) {
        fclose(md);
        return rc;
    }
    return study_fragment_close(env, md, "ambient");
}
