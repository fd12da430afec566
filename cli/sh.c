/* ibl sh: spherical-harmonic coefficients of an environment, in every normalisation. */
#include "cli.h"
#include "input.h"
#include "specular_options.h"

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
    "  --bands N            1..5 (default 3: 9 coefficients)\n"
    "  --window W           none (default), auto (weakest Hanning window keeping the\n"
    "                       irradiance non-negative), or a number: Hanning width W\n"
    "  --fast-centres       the cheap dynamic path: only the six face-centre texels\n"
    "  --fast-means         the same from the six face means (what a 1x1 mip level holds);\n"
    "                       docs/DIFFUSE.md has the errors of both\n"
    "  --json               one JSON object instead of text\n"
    CLI_INPUT_HELP
    "  --target ENGINE      read the environment in the engine's cube frame (docs/ENGINES.md)\n"
    "                       (with an orientation, equirect inputs are projected through a\n"
    "                       cube)\n"
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n"
    "\n"
    "Basis: real, orthonormal, no Condon-Shortley phase, order (l,m) = (0,0) (1,-1) (1,0)\n"
    "(1,1) (2,-2) ...; the formula's x, y, z are the world axes (+Y up). See docs/DIFFUSE.md.\n";

static const char *const coeff_names[IBL_SH_MAX_COEFFS] = {
    "0,0",  "1,-1", "1,0",  "1,1",  "2,-2", "2,-1", "2,0",  "2,1",  "2,2",
    "3,-3", "3,-2", "3,-1", "3,0",  "3,1",  "3,2",  "3,3",  "4,-4", "4,-3",
    "4,-2", "4,-1", "4,0",  "4,1",  "4,2",  "4,3",  "4,4",
};

static void print_text_coeffs(const char *title, const char *sym, const ibl_sh *sh)
{
    printf("%s\n", title);
    for (int i = 0; i < sh->bands * sh->bands; i++)
        printf("  %s(%-5s) %14.7g %14.7g %14.7g\n", sym, coeff_names[i], sh->c[i][0], sh->c[i][1],
               sh->c[i][2]);
}

/* An equirect image read as it is: projected directly with exact pixel solid angles. Returns
 * 1 and fills *image (pixels owned by *tex) if IN is such an image and no orientation is asked
 * for; 0 if IN must go through a cube (then tex is left empty); -1 on a read error. */
static int read_plain_equirect(ibl_context *ctx, const cli_common *common, const char *path,
                               const cli_input_options *o, ibl_texture *tex, ibl_image *image)
{
    if (o->orientation.yaw_degrees != 0 || o->orientation.mirror || o->orientation.z_up ||
        (o->layout != IBL_LAYOUT_AUTO && o->layout != IBL_LAYOUT_EQUIRECT))
        return 0;
    ibl_read_desc rd = {0};
    rd.clamp_infinite = common->clamp;
    ibl_file_info info;
    if (ibl_read_texture(ctx, path, &rd, tex, &info) != IBL_OK) return -1;
    if (tex->kind == IBL_TEXTURE_2D &&
        (o->layout == IBL_LAYOUT_EQUIRECT ||
         ibl_layout_detect(tex->width, tex->height) == IBL_LAYOUT_EQUIRECT)) {
        cli_report_pixels(common, path, &info.pixels);
        image->width = tex->width;
        image->height = tex->height;
        image->pixels = ibl_texture_level(tex, 0, 0);
        return 1;
    }
    ibl_texture_free(ctx, tex);
    return 0;
}

int cli_cmd_sh(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "sh", usage, {0}, {0}, 0};
    int bands = 3, json = 0, fast = 0;
    ibl_sh_window window = IBL_SH_WINDOW_NONE;
    double width = 0;
    cli_input_options io = {0};
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg) || cli_input_option(&a, arg, &io) ||
            cli_target_option(&a, arg, NULL, &io))
            continue;
        if (cli_is(&a, arg, "--bands", NULL)) {
            bands = cli_int(&a, arg, 1, IBL_SH_MAX_BANDS);
        } else if (cli_is(&a, arg, "--window", NULL)) {
            cli_sh_window_value(&a, arg, &window, &width);
        } else if (cli_is(&a, arg, "--json", NULL)) {
            json = 1;
        } else if (cli_is(&a, arg, "--fast-centres", "--fast-centers")) {
            fast = 1;
        } else if (cli_is(&a, arg, "--fast-means", NULL)) {
            fast = 2;
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
    ibl_sh radiance;
    ibl_status st = IBL_OK;
    int plain = fast ? 0 : read_plain_equirect(ctx, &a.common, in, &io, &tex, &equirect);
    if (plain < 0) {
        cli_error("%s", ibl_context_message(ctx));
        ibl_context_destroy(ctx);
        return CLI_EXIT_BAD_INPUT;
    }
    if (!plain) {
        int rc = cli_read_cubemap(ctx, &a.common, in, &io, &cube, NULL);
        if (rc != CLI_EXIT_OK) {
            ibl_context_destroy(ctx);
            return rc;
        }
    }
    const char *method = fast == 1   ? "face-centres"
                         : fast == 2 ? "face-means"
                         : plain     ? "equirect"
                                     : "cube";
    if (fast == 1) st = ibl_sh_project_face_centres(&cube, 0, bands, &radiance);
    else if (fast == 2) st = ibl_sh_project_face_means(&cube, 0, bands, &radiance);
    else if (plain) st = ibl_sh_project_equirect(ctx, &equirect, bands, &radiance);
    else st = ibl_sh_project_cubemap(ctx, &cube, 0, bands, &radiance);
    ibl_sh_window_report rep;
    if (st == IBL_OK) st = ibl_sh_apply_window(&radiance, window, width, &rep);
    ibl_cubemap_free(ctx, &cube);
    ibl_texture_free(ctx, &tex);
    if (st != IBL_OK) {
        cli_report_failure(ctx, in, st);
        ibl_context_destroy(ctx);
        return CLI_EXIT_BAD_INPUT;
    }
    ibl_sh irr, over_pi;
    ibl_sh_radiance_to_irradiance(&radiance, &irr);
    over_pi = irr;
    ibl_sh_scale(&over_pi, 1.0 / 3.14159265358979323846);
    double m[3][4][4];
    ibl_sh_polynomial(&radiance, m);
    if (json) {
        char *text = NULL;
        st = ibl_sh_json(ctx, &radiance, window, &rep, in, method, &text);
        if (st != IBL_OK) {
            cli_report_failure(ctx, in, st);
            ibl_context_destroy(ctx);
            return CLI_EXIT_BAD_INPUT;
        }
        fputs(text, stdout);
        ibl_free(ctx, text);
    } else {
        printf("input: %s (%s projection, %d bands)\n", in, method, bands);
        printf("basis: %s\n", IBL_SH_BASIS_NAME);
        printf("axes: world frame +Y up; the formulas take world x, y, z directly\n");
        if (rep.applied == IBL_SH_WINDOW_HANNING) {
            printf("window: hanning W = %.6g (requested %s), factors", rep.width, ibl_sh_window_name(window));
            for (int l = 0; l < bands; l++) printf(" %.6g", rep.factors[l]);
            printf("; min irradiance %.6g -> %.6g\n", rep.min_irradiance_before,
                   rep.min_irradiance_after);
        } else {
            printf("window: none (requested %s); min irradiance %.6g\n", ibl_sh_window_name(window),
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
