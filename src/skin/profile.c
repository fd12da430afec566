/* Diffusion profiles as sums of Gaussians: the JSON table of another profile (jansson, like
 * every JSON file of the library) and the profile's value at a distance. The built-in profile,
 * d'Eon and Luebke's six Gaussians for skin (GPU Gems 3, ch. 14, 2007), is in
 * src/shade/skin.c with the run time that also uses it. */
#include "skin_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "io/json.h"

#include "ibl/io.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

float ibl_skin_profile_eval(const ibl_skin_profile *profile, int channel, float r_mm)
{
    double sum = 0;
    for (int i = 0; i < profile->count; i++) {
        double v = profile->variance_mm2[i];
        sum += profile->weight[i][channel] * exp(-(double)r_mm * r_mm / (2 * v)) / (2 * IBL_PI * v);
    }
    return (float)sum;
}

static void read_gaussians(ibl__json_reader *r, json_t *root, ibl_skin_profile *out)
{
    json_t *list = ibl__json_array(r, root, "", "gaussians");
    if (r->status != IBL_OK) return;
    size_t n = json_array_size(list);
    if (n < 1 || n > IBL_SKIN_MAX_GAUSSIANS) {
        ibl__json_fail(r, "", "gaussians", "has %zu entries (1 to %d)", n, IBL_SKIN_MAX_GAUSSIANS);
        return;
    }
    out->count = (int)n;
    for (size_t i = 0; i < n && r->status == IBL_OK; i++) {
        char path[32];
        snprintf(path, sizeof path, "gaussians[%zu]", i);
        json_t *g = json_array_get(list, i);
        if (!json_is_object(g)) {
            ibl__json_fail(r, "", path, "is not an object");
            return;
        }
        double v = ibl__json_get_number(r, g, path, "variance_mm2");
        if (r->status == IBL_OK && !(v > 0 && v < 1e6)) {
            ibl__json_fail(r, path, "variance_mm2", "must be > 0 (mm^2)");
            return;
        }
        out->variance_mm2[i] = (float)v;
        json_t *w = ibl__json_array(r, g, path, "weights");
        if (r->status != IBL_OK) return;
        if (json_array_size(w) != 3) {
            ibl__json_fail(r, path, "weights", "must hold 3 numbers (red, green, blue)");
            return;
        }
        for (int c = 0; c < 3; c++) {
            json_t *x = json_array_get(w, (size_t)c);
            if (!json_is_number(x) || !(json_number_value(x) >= 0 && json_number_value(x) < 1e6)) {
                ibl__json_fail(r, path, "weights", "must be numbers >= 0");
                return;
            }
            out->weight[i][c] = (float)json_number_value(x);
        }
    }
}

ibl_status ibl_skin_profile_load(ibl_context *ctx, const char *path, ibl_skin_profile *out)
{
    if (!path || !out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "profile: missing argument");
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, path, &bytes, &size);
    if (st != IBL_OK) return st;
    json_t *root = NULL;
    st = ibl__json_parse(ctx, bytes, size, path, &root);
    ibl_free(ctx, bytes);
    if (st != IBL_OK) return st;
    ibl_skin_profile p;
    memset(&p, 0, sizeof p);
    ibl__json_reader r = {ctx, path, IBL_OK};
    if (!json_is_object(root)) ibl__json_fail(&r, "", "", "the profile is not a JSON object");
    else read_gaussians(&r, root, &p);
    json_decref(root);
    if (r.status == IBL_OK) *out = p;
    return r.status;
}
