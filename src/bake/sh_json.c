/* The JSON form of an SH set: what `ibl sh --json` prints and a bake's sh.json holds, so a
 * renderer can take the coefficients in the normalisation it uses (radiance for three.js's
 * LightProbe, irradiance/pi for a Lambertian term, the R&H 2001 matrices for GLSL). */
#include "ibl/sh.h"
#include "ibl/target.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "io/json.h"

const char *ibl_sh_window_name(ibl_sh_window window)
{
    switch (window) {
    case IBL_SH_WINDOW_NONE: return "none";
    case IBL_SH_WINDOW_HANNING: return "hanning";
    case IBL_SH_WINDOW_AUTO: return "auto";
    }
    return "unknown";
}

static json_t *coefficients(const ibl_sh *sh)
{
    json_t *a = json_array();
    for (int i = 0; i < sh->bands * sh->bands; i++) {
        json_t *rgb = json_array();
        for (int c = 0; c < 3; c++) ibl__json_append(rgb, ibl__json_number(sh->c[i][c]));
        ibl__json_append(a, rgb);
    }
    return a;
}

static json_t *window_object(ibl_sh_window requested, const ibl_sh_window_report *rep, int bands)
{
    json_t *w = json_object();
    ibl__json_set(w, "requested", ibl__json_string(ibl_sh_window_name(requested)));
    ibl__json_set(w, "applied", ibl__json_string(ibl_sh_window_name(rep->applied)));
    ibl__json_set(w, "width", ibl__json_number(rep->width));
    json_t *f = json_array();
    for (int l = 0; l < bands; l++) ibl__json_append(f, ibl__json_number(rep->factors[l]));
    ibl__json_set(w, "factors", f);
    ibl__json_set(w, "min_irradiance_before", ibl__json_number(rep->min_irradiance_before));
    ibl__json_set(w, "min_irradiance_after", ibl__json_number(rep->min_irradiance_after));
    return w;
}

static json_t *polynomial(const ibl_sh *radiance)
{
    double m[3][4][4];
    ibl_sh_polynomial(radiance, m);
    json_t *p = json_object();
    ibl__json_set(p, "form", ibl__json_string("E(n) = [x y z 1] M [x y z 1]^T (irradiance, "
                                              "R&H 2001 eq. 12, first 9 coefficients)"));
    json_t *k = json_array();
    const double constants[5] = {IBL_SH_RH_C1, IBL_SH_RH_C2, IBL_SH_RH_C3, IBL_SH_RH_C4,
                                 IBL_SH_RH_C5};
    for (int i = 0; i < 5; i++) ibl__json_append(k, ibl__json_number(constants[i]));
    ibl__json_set(p, "constants", k);
    json_t *matrix = json_object();
    static const char *const channel[3] = {"r", "g", "b"};
    for (int c = 0; c < 3; c++) {
        json_t *rows = json_array();
        for (int i = 0; i < 4; i++) {
            json_t *row = json_array();
            for (int j = 0; j < 4; j++) ibl__json_append(row, ibl__json_number(m[c][i][j]));
            ibl__json_append(rows, row);
        }
        ibl__json_set(matrix, channel[c], rows);
    }
    ibl__json_set(p, "matrix", matrix);
    return p;
}

/* The SH in the form each engine takes (ibl/target.h), each labelled with its basis,
 * normalisation, sign convention and frame. */
static json_t *engine_forms(ibl_context *ctx, const ibl_sh *radiance)
{
    static const struct { const char *key; ibl_target_sh_form form; } forms[] = {
        {"three", IBL_TARGET_SH_THREE},
        {"babylon", IBL_TARGET_SH_BABYLON},
        {"gltf", IBL_TARGET_SH_GLTF_IRRADIANCE},
        {"filament", IBL_TARGET_SH_FILAMENT},
        {"unity", IBL_TARGET_SH_UNITY}};
    json_t *o = json_object();
    for (size_t i = 0; i < sizeof forms / sizeof forms[0]; i++) {
        ibl_target_sh sh;
        if (ibl_target_sh_form_of(ctx, forms[i].form, radiance, &sh) != IBL_OK) continue;
        json_t *e = json_object();
        ibl__json_set(e, "engine", ibl__json_string(sh.engine));
        ibl__json_set(e, "basis", ibl__json_string(sh.basis));
        ibl__json_set(e, "normalisation", ibl__json_string(sh.normalisation));
        ibl__json_set(e, "signs", ibl__json_string(sh.signs));
        ibl__json_set(e, "frame", ibl__json_string(sh.frame));
        json_t *names = json_array(), *values = json_array();
        for (int k = 0; k < sh.count; k++) {
            ibl__json_append(names, ibl__json_string(sh.names[k]));
            json_t *rgb = json_array();
            for (int c = 0; c < 3; c++) ibl__json_append(rgb, ibl__json_number(sh.values[k][c]));
            ibl__json_append(values, rgb);
        }
        ibl__json_set(e, "names", names);
        ibl__json_set(e, "values", values);
        ibl__json_set(o, forms[i].key, e);
    }
    return o;
}

ibl_status ibl_sh_json(ibl_context *ctx, const ibl_sh *radiance, ibl_sh_window requested,
                       const ibl_sh_window_report *window, const char *input,
                       const char *projection, char **json)
{
    if (!json) return IBL_ERR_INVALID_ARGUMENT;
    *json = NULL;
    if (!radiance || radiance->bands < 1 || radiance->bands > IBL_SH_MAX_BANDS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh: no coefficients to write");
    ibl_sh_window_report none = {0};
    if (!window) {
        none.applied = IBL_SH_WINDOW_NONE;
        for (int l = 0; l < IBL_SH_MAX_BANDS; l++) none.factors[l] = 1.0;
        none.min_irradiance_before = none.min_irradiance_after = ibl_sh_min_irradiance(radiance);
        window = &none;
    }
    ibl_sh irradiance, over_pi;
    ibl_sh_radiance_to_irradiance(radiance, &irradiance);
    over_pi = irradiance;
    ibl_sh_scale(&over_pi, IBL_INV_PI);
    int bands = radiance->bands;

    json_t *o = json_object();
    if (input) ibl__json_set(o, "input", ibl__json_string(input));
    if (projection) ibl__json_set(o, "projection", ibl__json_string(projection));
    ibl__json_set(o, "bands", ibl__json_number(bands));
    ibl__json_set(o, "basis", ibl__json_string(IBL_SH_BASIS_NAME));
    ibl__json_set(o, "condon_shortley_phase", ibl__json_bool(0));
    ibl__json_set(o, "order", ibl__json_string("index l*l+l+m: (0,0) (1,-1) (1,0) (1,1) (2,-2) "
                                               "(2,-1) (2,0) (2,1) (2,2) ..."));
    json_t *axes = json_object();
    ibl__json_set(axes, "up", ibl__json_string("+y"));
    ibl__json_set(axes, "frame", ibl__json_string("right-handed world frame, +Y up"));
    ibl__json_set(axes, "note", ibl__json_string(
                                    "the formulas take the world x, y, z directly; the R&H "
                                    "polar axis z is the horizontal world +Z and up enters "
                                    "through y (L1-1, L2-2, L2-1)"));
    ibl__json_set(o, "axes", axes);
    ibl__json_set(o, "window", window_object(requested, window, bands));
    json_t *cosine = json_array();
    for (int l = 0; l < bands; l++) ibl__json_append(cosine, ibl__json_number(ibl_sh_cosine_factor(l)));
    ibl__json_set(o, "cosine_factors", cosine);
    ibl__json_set(o, "radiance", coefficients(radiance));
    ibl__json_set(o, "irradiance", coefficients(&irradiance));
    ibl__json_set(o, "irradiance_over_pi", coefficients(&over_pi));
    ibl__json_set(o, "polynomial", polynomial(radiance));
    if (bands >= 3) ibl__json_set(o, "engines", engine_forms(ctx, radiance));
    return ibl__json_text(ctx, o, "sh", json);
}
