/* ibl pack: material maps packed into the channels of one texture (Daqi 2016, "[PBR Series
 * - 6] Improvement of PBR", 6.1: metalness, roughness, ambient occlusion and transmittance
 * in R, G, B and A, so a material needs one texture slot for the four). A thin client of
 * ibl_pack_material_channels. */
#include "input.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl pack [--metal M] [--rough R] [--ao A] [--transmittance T] -o OUT.png\n"
    "\n"
    "Packs one-channel material maps into one texture, Daqi 2016's layout:\n"
    "  R = metalness, G = roughness, B = ambient occlusion, A = transmittance.\n"
    "Each map's red channel is read as data: a PNG's codes divided by 255 or 65535, whatever\n"
    "its sRGB or gAMA chunk says (material maps are not colours); EXR, PFM and HDR values as\n"
    "stored. A map not given is its default constant: metalness 0, roughness 1, AO 1,\n"
    "transmittance 0. The maps must share one size. OUT is a linear PNG (gAMA 1.0), 8-bit or\n"
    "16-bit; `ibl unpack` splits it again, and shaders/ibl_atlas.glsl's ibl_unpack_material\n"
    "reads it (docs/ATLAS.md).\n"
    "\n"
    "  --metal FILE           metalness map\n"
    "  --rough FILE           perceptual roughness map\n"
    "  --ao FILE              ambient occlusion map\n"
    "  --transmittance FILE   transmittance map\n"
    "  -o, --output OUT.png   the packed texture\n"
    "  --depth 8|16           bits per channel (default: 16 if a map is a 16-bit PNG, else 8)\n"
    "  -q: see 'ibl --help'\n";

static const char *const flags[4] = {"--metal", "--rough", "--ao", "--transmittance"};

/* Reads one map as data; *sixteen is set when it is a 16-bit PNG. */
static ibl_status read_map(ibl_context *ctx, const char *path, ibl_image *out, int *sixteen)
{
    if (ibl_file_type_from_path(path) == IBL_FILE_JPEG) {
        cli_error("%s: a JPEG is read as sRGB colour, not data; give the map as PNG", path);
        return IBL_ERR_FORMAT;
    }
    ibl_read_desc rd = {.as_data = 1};
    ibl_file_info info;
    ibl_status st = ibl_read_image(ctx, path, &rd, out, &info);
    if (st != IBL_OK) cli_report_failure(ctx, path, st);
    else if (info.format == IBL_FORMAT_RGBA16_UNORM) *sixteen = 1;
    return st;
}

int cli_cmd_pack(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "pack", usage, {0}, {0}, 0};
    const char *in[4] = {NULL, NULL, NULL, NULL}, *out = NULL;
    int depth = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        int i = 0;
        while (i < 4 && !cli_is(&a, arg, flags[i], NULL)) i++;
        if (i < 4) in[i] = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--output", "-o")) out = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--depth", NULL)) {
            depth = cli_int(&a, arg, 8, 16);
            if (depth != 8 && depth != 16) cli_usage_error(&a, "--depth is 8 or 16, not %d", depth);
        } else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count) cli_usage_error(&a, "takes its maps by flag (--metal, --rough, --ao, --transmittance)");
    if (!in[0] && !in[1] && !in[2] && !in[3]) cli_usage_error(&a, "needs at least one map");
    if (!out) cli_usage_error(&a, "needs an output: -o OUT.png");
    if (cli_check_output(&a, out) != IBL_FILE_PNG) cli_usage_error(&a, "%s: the packed texture is a PNG", out);
    for (int i = 0; i < 4; i++)
        if (in[i]) cli_check_distinct(&a, in[i], out);
    ibl_context *ctx = cli_context(&a.common);
    ibl_image maps[4] = {{0}}, packed = {0};
    int sixteen = 0, first = -1;
    ibl_status st = IBL_OK;
    for (int i = 0; i < 4 && st == IBL_OK; i++) {
        if (!in[i]) continue;
        st = read_map(ctx, in[i], &maps[i], &sixteen);
        if (st != IBL_OK) break;
        if (first < 0) first = i;
        else if (maps[i].width != maps[first].width || maps[i].height != maps[first].height) {
            cli_error("%s: is %dx%d, but %s is %dx%d (the maps must share one size)", in[i],
                      maps[i].width, maps[i].height, in[first], maps[first].width, maps[first].height);
            st = IBL_ERR_FORMAT;
        }
    }
    if (st == IBL_OK) {
        st = ibl_pack_material_channels(ctx, in[0] ? &maps[0] : NULL, in[1] ? &maps[1] : NULL,
                                        in[2] ? &maps[2] : NULL, in[3] ? &maps[3] : NULL, &packed);
        int bits = depth ? depth : sixteen ? 16 : 8;
        ibl_write_desc wd = {.format = bits == 16 ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA8_UNORM};
        if (st == IBL_OK) st = ibl_write_image(ctx, out, &packed, &wd);
        if (st != IBL_OK) cli_report_failure(ctx, out, st);
        else cli_info(&a.common, "%s: %dx%d, %d-bit, R metalness G roughness B AO A transmittance\n",
                      out, packed.width, packed.height, bits);
    }
    for (int i = 0; i < 4; i++) ibl_image_free(ctx, &maps[i]);
    ibl_image_free(ctx, &packed);
    ibl_context_destroy(ctx);
    return st == IBL_OK ? CLI_EXIT_OK : cli_exit_code(st);
}
