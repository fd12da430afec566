/* ibl sh: spherical-harmonic coefficients of an environment, in every normalisation. */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl sh IN [options]\n"
    "\n"
    "Projects an environment (equirect, cross, strip, angular, octahedral image, or a cube\n"
    "texture .ktx2/.ktx/.dds) on real spherical harmonics and prints the radiance\n"
    "coefficients, the irradiance coefficients, irradiance/pi and the Ramamoorthi-Hanrahan\n"
    "9-term matrices. Equirect images are projected directly with exact pixel solid angles;\n"
    "everything else as a cube at its native resolution with exact texel solid angles.\n"
    "\n"
    "  --bands N          1..5 (default 3: 9 coefficients)\n"
    "  --window W         none (default), auto (weakest Hanning window keeping the\n"
    "                     irradiance non-negative), or a number: Hanning width W\n"
    "  --fast-centres     the cheap dynamic path: only the six face-centre texels\n"
    "  --layout NAME      input layout when not detectable (equirect, hcross, vcross,\n"
    "                     hstrip, vstrip, angular, octahedral)\n"
    "  --json             one JSON object instead of text\n"
    "\n"
    "Basis: real, orthonormal, no Condon-Shortley phase, order (l,m) = (0,0) (1,-1) (1,0)\n"
    "(1,1) (2,-2) ...; the formula's x, y, z are the world axes (+Y up). See docs/DIFFUSE.md.\n";

static const char *const coeff_names[IBL_SH_MAX_COEFFS] = {
    "0,0",  "1,-1", "1,0",  "1,1",  "2,-2", "2,-1", "2,0",  "2,1",  "2,2",
    "3,-3", "3,-2", "3,-1", "3,0",  "3,1",  "3,2",  "3,3",  "4,-4", "4,-3",
    "4,-2", "4,-1", "4,0",  "4,1",  "4,2",  "4,3",  "4,4",
};

static void print_json_coeffs(const char *key, const ibl_sh *sh, int last)
{
    printf("  \"%s\": [", key);
    for (int i = 0; i < sh->bands * sh->bands; i++)
        printf("%s[%.9g, %.9g, %.9g]", i ? ", " : "", sh->c[i][0], sh->c[i][1], sh->c[i][2]);
    printf("]%s\n", last ? "" : ",");
}

static void print_text_coeffs(const char *title, const char *sym, const ibl_sh *sh)
{
    printf("%s\n", title);
    for (int i = 0; i < sh->bands * sh->bands; i++)
        printf("  %s(%-5s) %14.7g %14.7g %14.7g\n", sym, coeff_names[i], sh->c[i][0], sh->c[i][1],
               sh->c[i][2]);
}

static const char *window_name(ibl_sh_window w)
{
    return w == IBL_SH_WINDOW_HANNING ? "hanning" : w == IBL_SH_WINDOW_AUTO ? "auto" : "none";
}

/* Reads IN as a cube (cube textures and non-equirect layouts) or keeps an equirect image for
 * direct projection. On success exactly one of *cube / *equirect is filled. */
static ibl_status read_environment(ibl_context *ctx, const cli_common *common, const char *path,
                                   ibl_layout layout, int want_cube, ibl_texture *tex,
                                   ibl_cubemap *cube, ibl_image *equirect, int *is_cube)
{
    ibl_read_desc rd = {0};
    rd.clamp_infinite = common->clamp;
    ibl_file_info info;
    ibl_status st = ibl_read_texture(ctx, path, &rd, tex, &info);
    if (st != IBL_OK) return st;
    cli_report_pixels(common, path, &info.pixels);
    if (tex->kind == IBL_TEXTURE_CUBE) {
        *is_cube = 1;
        return ibl_cubemap_from_texture(tex, cube);
    }
    if (tex->kind != IBL_TEXTURE_2D)
        return ibl_fail(ctx, IBL_ERR_UNSUPPORTED, "%s: a 3D texture is not an environment", path);
    ibl_image image = {tex->width, tex->height, ibl_texture_level(tex, 0, 0)};
    if (layout == IBL_LAYOUT_AUTO) layout = ibl_layout_detect(image.width, image.height);
    if (layout == IBL_LAYOUT_AUTO)
        return ibl_fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: cannot tell the layout of a %dx%d image (use --layout)", path,
                        image.width, image.height);
    if (layout == IBL_LAYOUT_EQUIRECT && !want_cube) {
        *is_cube = 0;
        *equirect = image;
        return IBL_OK;
    }
    ibl_to_cube_desc cd = {0};
    cd.layout = layout;
    *is_cube = 1;
    st = ibl_image_to_cubemap(ctx, &image, &cd, cube);
    if (st != IBL_OK) return st;
    /* the cube now owns its pixels; the flat image is no longer needed */
    ibl_texture_free(ctx, tex);
    return IBL_OK;
}

int cli_cmd_sh(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "sh", usage, {0}, {0}, 0};
    int bands = 3, json = 0, fast = 0;
    ibl_sh_window window = IBL_SH_WINDOW_NONE;
    double width = 0;
    ibl_layout layout = IBL_LAYOUT_AUTO;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--bands", NULL)) {
            bands = cli_int(&a, arg, 1, IBL_SH_MAX_BANDS);
        } else if (cli_is(&a, arg, "--window", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "none") == 0) {
                window = IBL_SH_WINDOW_NONE;
            } else if (strcmp(v, "auto") == 0) {
                window = IBL_SH_WINDOW_AUTO;
            } else {
                char *end = NULL;
                width = strtod(v, &end);
                if (!*v || *end || !(width > 0 && width < 1e6))
                    cli_usage_error(&a, "--window wants auto, none or a positive width, not '%s'", v);
                window = IBL_SH_WINDOW_HANNING;
            }
        } else if (cli_is(&a, arg, "--json", NULL)) {
            json = 1;
        } else if (cli_is(&a, arg, "--fast-centres", "--fast-centers")) {
            fast = 1;
        } else if (cli_is(&a, arg, "--layout", NULL)) {
            const char *v = cli_value(&a, arg);
            layout = ibl_layout_from_name(v);
            if (layout == IBL_LAYOUT_AUTO || layout == IBL_LAYOUT_FACES || layout == IBL_LAYOUT_CUBE)
                cli_usage_error(&a, "unknown layout '%s'", v);
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "wants exactly one input file");
    const char *in = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    ibl_texture tex = {0};
    ibl_cubemap cube = {0};
    ibl_image equirect = {0};
    int is_cube = 0;
    ibl_sh radiance;
    ibl_status st = read_environment(ctx, &a.common, in, layout, fast, &tex, &cube, &equirect, &is_cube);
    const char *method = fast ? "face-centres" : is_cube ? "cube" : "equirect";
    if (st == IBL_OK) {
        if (fast) st = ibl_sh_project_face_centres(&cube, 0, bands, &radiance);
        else if (is_cube) st = ibl_sh_project_cubemap(ctx, &cube, 0, bands, &radiance);
        else st = ibl_sh_project_equirect(ctx, &equirect, bands, &radiance);
    }
    ibl_sh_window_report rep;
    if (st == IBL_OK) st = ibl_sh_apply_window(&radiance, window, width, &rep);
    if (is_cube && cube.owns_data) ibl_cubemap_free(ctx, &cube);
    ibl_texture_free(ctx, &tex);
    if (st != IBL_OK) {
        const char *msg = ibl_context_message(ctx);
        if (msg && *msg) cli_error("%s", msg);
        else cli_error("%s: %s", in, ibl_status_name(st));
        ibl_context_destroy(ctx);
        return cli_exit_code(st) == CLI_EXIT_USAGE ? CLI_EXIT_BAD_INPUT : cli_exit_code(st);
    }
    ibl_sh irr, over_pi;
    ibl_sh_irradiance(&radiance, &irr);
    over_pi = irr;
    ibl_sh_scale(&over_pi, 1.0 / 3.14159265358979323846);
    double m[3][4][4];
    ibl_sh_polynomial(&radiance, m);
    if (json) {
        printf("{\n");
        printf("  \"input\": \"");
        for (const char *p = in; *p; p++) {
            if (*p == '"' || *p == '\\') putchar('\\');
            if ((unsigned char)*p >= 0x20) putchar(*p);
        }
        printf("\",\n  \"projection\": \"%s\",\n", method);
        printf("  \"bands\": %d,\n", bands);
        printf("  \"basis\": \"%s\",\n", IBL_SH_BASIS_NAME);
        printf("  \"condon_shortley_phase\": false,\n");
        printf("  \"order\": \"index l*l+l+m: (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) "
               "(2,2) ...\",\n");
        printf("  \"axes\": {\"up\": \"+y\", \"frame\": \"right-handed world frame, +Y up\", "
               "\"formula_x\": \"+x\", \"formula_y\": \"+y\", \"formula_z\": \"+z\", "
               "\"note\": \"the R&H formulas take the world x, y, z directly; their polar axis z is "
               "the horizontal world +Z and up enters through y (L1-1, L2-2, L2-1)\"},\n");
        printf("  \"window\": {\"requested\": \"%s\", \"applied\": \"%s\", \"width\": %.9g, "
               "\"factors\": [",
               window_name(window), window_name(rep.applied), rep.width);
        for (int l = 0; l < bands; l++) printf("%s%.9g", l ? ", " : "", rep.factors[l]);
        printf("], \"min_irradiance_before\": %.9g, \"min_irradiance_after\": %.9g},\n",
               rep.min_irradiance_before, rep.min_irradiance_after);
        printf("  \"cosine_factors\": [");
        for (int l = 0; l < bands; l++) printf("%s%.17g", l ? ", " : "", ibl_sh_cosine_factor(l));
        printf("],\n");
        print_json_coeffs("radiance", &radiance, 0);
        print_json_coeffs("irradiance", &irr, 0);
        print_json_coeffs("irradiance_over_pi", &over_pi, 0);
        printf("  \"polynomial\": {\"form\": \"E(n) = [x y z 1] M [x y z 1]^T (irradiance, R&H 2001 "
               "eq. 12, first 9 coefficients)\", \"constants\": [%g, %g, %g, %g, %g], \"matrix\": {",
               IBL_SH_RH_C1, IBL_SH_RH_C2, IBL_SH_RH_C3, IBL_SH_RH_C4, IBL_SH_RH_C5);
        static const char *const ch[3] = {"r", "g", "b"};
        for (int c = 0; c < 3; c++) {
            printf("%s\"%s\": [", c ? ", " : "", ch[c]);
            for (int i = 0; i < 4; i++)
                printf("%s[%.9g, %.9g, %.9g, %.9g]", i ? ", " : "", m[c][i][0], m[c][i][1],
                       m[c][i][2], m[c][i][3]);
            printf("]");
        }
        printf("}}\n}\n");
    } else {
        printf("input: %s (%s projection, %d bands)\n", in, method, bands);
        printf("basis: %s\n", IBL_SH_BASIS_NAME);
        printf("axes: world frame +Y up; the formulas take world x, y, z directly\n");
        if (rep.applied == IBL_SH_WINDOW_HANNING) {
            printf("window: hanning W = %.6g (requested %s), factors", rep.width, window_name(window));
            for (int l = 0; l < bands; l++) printf(" %.6g", rep.factors[l]);
            printf("; min irradiance %.6g -> %.6g\n", rep.min_irradiance_before,
                   rep.min_irradiance_after);
        } else {
            printf("window: none (requested %s); min irradiance %.6g\n", window_name(window),
                   rep.min_irradiance_before);
        }
        print_text_coeffs("radiance L_lm:", "L", &radiance);
        print_text_coeffs("irradiance E_lm = A_l L_lm (A = pi, 2pi/3, pi/4, 0, -pi/24):", "E", &irr);
        print_text_coeffs("irradiance / pi (white Lambertian exitance):", "E/pi", &over_pi);
        printf("polynomial (R&H 2001): E(n) = [x y z 1] M [x y z 1]^T, c1..c5 = %g %g %g %g %g\n",
               IBL_SH_RH_C1, IBL_SH_RH_C2, IBL_SH_RH_C3, IBL_SH_RH_C4, IBL_SH_RH_C5);
        static const char *const ch[3] = {"red", "green", "blue"};
        for (int c = 0; c < 3; c++) {
            printf("  M %s:\n", ch[c]);
            for (int i = 0; i < 4; i++)
                printf("    %14.7g %14.7g %14.7g %14.7g\n", m[c][i][0], m[c][i][1], m[c][i][2],
                       m[c][i][3]);
        }
    }
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
