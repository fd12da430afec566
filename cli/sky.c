/* ibl sky: the built-in physically based clear sky (Preetham et al. 1999 + sun disk + ground). */
#include "cli.h"
#include "ibl/sky.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl sky -o OUT [options]\n"
    "\n"
    "Renders the built-in clear sky (Preetham et al. 1999 daylight model, a sun disk of\n"
    "realistic radiance and a Lambertian ground) as an equirectangular image (width x width/2).\n"
    "Units and conventions: docs/CONVENTIONS.md.\n"
    "\n"
    "  -o, --output PATH      output image (.exr .hdr .pfm; .png for a tone-mapped preview)\n"
    "  --sun-elevation DEG    sun height above the horizon (default 35)\n"
    "  --sun-azimuth DEG      sun direction about the up axis (default 0: the image centre)\n"
    "  --turbidity T          haze, 2 (clear) .. 10 (hazy) (default 3)\n"
    "  --ground-albedo A      ground reflectance (default 0.3)\n"
    "  --size W               image width (default 1024)\n"
    "  --exposure EV          exposure for .png/.jpg previews\n"
    "  -q, -j N: see 'ibl --help'\n";

int cli_cmd_sky(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "sky", usage, {0}, {0}, 0};
    ibl_sky_desc d;
    memset(&d, 0, sizeof d);
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    const char *out = NULL;
    int exposure_given = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o")) out = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--sun-elevation", NULL)) d.sun_elevation_deg = (float)cli_double(&a, arg, 0.01, 90);
        else if (cli_is(&a, arg, "--sun-azimuth", NULL)) d.sun_azimuth_deg = (float)cli_double(&a, arg, -360, 360);
        else if (cli_is(&a, arg, "--turbidity", NULL)) d.turbidity = (float)cli_double(&a, arg, 1.7, 10);
        else if (cli_is(&a, arg, "--ground-albedo", NULL)) d.ground_albedo = (float)cli_double(&a, arg, 0, 1);
        else if (cli_is(&a, arg, "--size", NULL)) d.width = cli_int(&a, arg, 8, 16384);
        else if (cli_is(&a, arg, "--exposure", NULL)) {
            wd.exposure_ev = (float)cli_double(&a, arg, -50, 50);
            exposure_given = 1;
        }
        else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count) cli_usage_error(&a, "takes no input file");
    if (!out) cli_usage_error(&a, "needs an output: -o OUT");
    if (ibl_file_type_from_path(out) == IBL_FILE_UNKNOWN)
        cli_usage_error(&a, "cannot tell the format of %s from its extension", out);
    ibl_context *ctx = cli_context(&a.common);
    ibl_image image;
    ibl_status st = ibl_sky_render(ctx, &d, &image);
    if (st == IBL_OK) {
        if (!exposure_given && cli_is_display_format(out)) wd.exposure_ev = ibl_image_auto_exposure(&image);
        st = ibl_write_image(ctx, out, &image, &wd);
        ibl_image_free(ctx, &image);
    }
    if (st != IBL_OK) {
        cli_error("%s", ibl_context_message(ctx));
        ibl_context_destroy(ctx);
        return cli_exit_code(st);
    }
    cli_info(&a.common, "wrote %s\n", out);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
