/* ibl irradiance: the irradiance environment map (diffuse cubemap) of an environment. */
#include "cli.h"
#include "format_options.h"
#include "input.h"
#include "specular_options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl irradiance IN -o OUT [options]\n"
    "\n"
    "Writes the irradiance cubemap of an environment (any layout, or a cube texture). Each\n"
    "texel holds E/pi for the normal through its centre (what a white Lambertian surface\n"
    "reflects) unless --scale full. OUT: .ktx2 .ktx .dds hold the cube; .hdr .exr .pfm .png\n"
    ".jpg get it in --out-layout (default hcross).\n"
    "\n"
    "  -o, --output OUT     output file (required)\n"
    "  --size N             output face edge, 1..64 (default 16)\n"
    "  --method M           convolve (default: reduce to --source-size, then direct\n"
    "                       convolution with exact texel solid angles), sh (SH irradiance\n"
    "                       evaluated per texel), reference (full-resolution double sum: slow)\n"
    "  --source-size N      convolve: reduced radiance face edge, 1..64 (default 8); the\n"
    "                       input is first read as a cube of 8 times that edge\n"
    "  --scale S            over-pi (default) or full (E itself)\n"
    "  --bands N            sh: 1..5 (default 3)\n"
    "  --window W           sh: none (default), auto, or a Hanning width\n"
    "  --format F           storage format (rgba16f, rgba32f, rg11b10f, rgb9e5, bc6h, astc4x4,\n"
    "                       rgbm, ...: see 'ibl convert --help')\n"
    CLI_FORMAT_HELP
    "  --out-layout NAME    flat outputs: hcross (default), vcross, hstrip, vstrip, equirect\n"
    CLI_INPUT_HELP
    "  --target ENGINE      read the environment in the engine's cube frame (docs/ENGINES.md)\n"
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

int cli_cmd_irradiance(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "irradiance", usage, {0}, {0}, 0};
    const char *out_path = NULL;
    ibl_irradiance_desc d = {0};
    ibl_write_desc wd = {0};
    cli_input_options io = {0};
    ibl_layout out_layout = IBL_LAYOUT_HCROSS;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg) || cli_input_option(&a, arg, &io) ||
            cli_format_option(&a, arg, &wd) || cli_target_option(&a, arg, NULL, &io))
            continue;
        if (cli_is(&a, arg, "--output", "-o")) {
            out_path = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--size", NULL)) {
            d.size = cli_int(&a, arg, 1, 64);
        } else if (cli_is(&a, arg, "--source-size", NULL)) {
            d.source_size = cli_int(&a, arg, 1, 64);
        } else if (cli_is(&a, arg, "--bands", NULL)) {
            d.sh_bands = cli_int(&a, arg, 1, IBL_SH_MAX_BANDS);
        } else if (cli_is(&a, arg, "--method", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "convolve") == 0) d.method = IBL_IRRADIANCE_CONVOLVE;
            else if (strcmp(v, "sh") == 0) d.method = IBL_IRRADIANCE_SH;
            else if (strcmp(v, "reference") == 0) d.method = IBL_IRRADIANCE_REFERENCE;
            else cli_usage_error(&a, "--method wants convolve, sh or reference, not '%s'", v);
        } else if (cli_is(&a, arg, "--scale", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "over-pi") == 0) d.scale = IBL_IRRADIANCE_SCALE_OVER_PI;
            else if (strcmp(v, "full") == 0) d.scale = IBL_IRRADIANCE_SCALE_FULL;
            else cli_usage_error(&a, "--scale wants over-pi or full, not '%s'", v);
        } else if (cli_is(&a, arg, "--window", NULL)) {
            cli_sh_window_value(&a, arg, &d.sh_window, &d.sh_window_width);
        } else if (cli_is(&a, arg, "--format", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_format_from_name(v, &wd.format)) cli_usage_error(&a, "unknown format '%s'", v);
        } else if (cli_is(&a, arg, "--out-layout", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_layout_from_name(v, &out_layout) || out_layout == IBL_LAYOUT_AUTO ||
                out_layout == IBL_LAYOUT_FACES ||
                out_layout == IBL_LAYOUT_CUBE)
                cli_usage_error(&a, "unknown output layout '%s'", v);
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "wants exactly one input file");
    if (!out_path) cli_usage_error(&a, "wants an output file (-o OUT)");
    ibl_file_type out_type = cli_check_output(&a, out_path);
    if (!ibl_file_type_writes_format(out_type, wd.format))
        cli_usage_error(&a, "%s cannot store %s pixels", out_path, ibl_format_name(wd.format));
    cli_format_check(&a, &wd, out_type, out_path);
    cli_check_not_in_bake(&a, out_path);
    const char *in = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_cubemap cube = {0}, result = {0};
    ibl_image flat = {0};
    /* convolve only needs the radiance at its reduced size: reading the input at 8x that edge
     * (64 by default) keeps the area-correct reduction and skips most of the conversion */
    if (d.method == IBL_IRRADIANCE_CONVOLVE) io.size = 8 * (d.source_size ? d.source_size : 8);
    int rc = cli_read_cubemap(ctx, &a.common, in, &io, &cube, NULL);
    if (rc != CLI_EXIT_OK) {
        ibl_context_destroy(ctx);
        return rc;
    }
    ibl_write_report report = {0};
    wd.report = &report;
    ibl_status st = ibl_irradiance_cubemap(ctx, &cube, &d, &result);
    if (st == IBL_OK) {
        if (ibl_file_type_is_container(out_type)) {
            ibl_texture t = ibl_texture_from_cubemap(&result);
            t.format = wd.format;
            st = ibl_texture_set_metadata(ctx, &t, "ibl.irradiance",
                                          d.scale == IBL_IRRADIANCE_SCALE_FULL ? "E" : "E/pi");
            if (st == IBL_OK) {
                t.owns_metadata = 1;
                st = ibl_write_texture(ctx, out_path, &t, &wd);
            }
            t.owns_data = 0;
            ibl_texture_free(ctx, &t);
        } else {
            ibl_from_cube_desc fd = {0};
            fd.layout = out_layout;
            st = ibl_cubemap_to_image(ctx, &result, &fd, &flat);
            if (st == IBL_OK) st = ibl_write_image(ctx, out_path, &flat, &wd);
        }
    }
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &result);
    ibl_image_free(ctx, &flat);
    if (st != IBL_OK) {
        cli_report_failure(ctx, out_path, st);
        ibl_context_destroy(ctx);
        return cli_exit_code(st);
    }
    cli_warn_clamped(&a.common, out_path, &report, wd.format);
    static const char *const methods[] = {"convolve", "sh", "reference"};
    cli_info(&a.common, "%s: %dx%dx6 irradiance (%s, %s) in %.3f s\n", out_path,
             d.size ? d.size : 16, d.size ? d.size : 16, methods[d.method],
             d.scale == IBL_IRRADIANCE_SCALE_FULL ? "E" : "E/pi", cli_seconds() - t0);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
