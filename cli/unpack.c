/* ibl unpack: the four maps of a texture `ibl pack` wrote (Daqi 2016's channel layout), as
 * separate grey PNGs. A thin client of ibl_unpack_material_channels. */
#include "input.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl unpack PACKED.png -o PREFIX [--depth 8|16]\n"
    "\n"
    "Splits a packed material texture (R metalness, G roughness, B ambient occlusion, A\n"
    "transmittance; `ibl pack`) into PREFIX_metalness.png, PREFIX_roughness.png,\n"
    "PREFIX_ao.png and PREFIX_transmittance.png: grey (R = G = B), linear PNG of the input's\n"
    "depth unless --depth says otherwise. The codes are copied exactly. Every file appears at\n"
    "once, or none.\n"
    "\n"
    "  -o, --output PREFIX   path prefix of the four maps\n"
    "  --depth 8|16          bits per channel (default: the input's)\n"
    "  -q: see 'ibl --help'\n";

static const char *const suffixes[4] = {"metalness", "roughness", "ao", "transmittance"};

int cli_cmd_unpack(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "unpack", usage, {0}, {0}, 0};
    const char *prefix = NULL;
    int depth = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o")) prefix = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--depth", NULL)) {
            depth = cli_int(&a, arg, 8, 16);
            if (depth != 8 && depth != 16) cli_usage_error(&a, "--depth is 8 or 16, not %d", depth);
        } else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count != 1) cli_usage_error(&a, "wants exactly one packed texture");
    if (!prefix) cli_usage_error(&a, "needs an output prefix: -o PREFIX");
    const char *in = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    ibl_read_desc rd = {.as_data = 1};
    ibl_file_info info;
    ibl_image packed = {0}, maps[4] = {{0}};
    ibl_status st = ibl_read_image(ctx, in, &rd, &packed, &info);
    const char *failed = in;
    if (st == IBL_OK) st = ibl_unpack_material_channels(ctx, &packed, maps);
    ibl_output_set *set = NULL;
    if (st == IBL_OK) st = ibl_output_set_create(ctx, &set);
    if (st == IBL_OK) st = ibl_output_set_protect(set, in);
    int bits = depth ? depth : info.format == IBL_FORMAT_RGBA16_UNORM ? 16 : 8;
    ibl_write_desc wd = {.format = bits == 16 ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA8_UNORM};
    char path[4200];
    for (int i = 0; i < 4 && st == IBL_OK; i++) {
        snprintf(path, sizeof path, "%s_%s.png", prefix, suffixes[i]);
        failed = path;
        st = ibl_output_set_add_image(set, path, &maps[i], &wd);
    }
    if (st == IBL_OK) st = ibl_output_set_commit(set);
    if (set) ibl_output_set_destroy(set);
    if (st != IBL_OK) cli_report_failure(ctx, failed, st);
    else cli_info(&a.common, "%s_{metalness,roughness,ao,transmittance}.png: %dx%d, %d-bit\n",
                  prefix, packed.width, packed.height, bits);
    for (int i = 0; i < 4; i++) ibl_image_free(ctx, &maps[i]);
    ibl_image_free(ctx, &packed);
    ibl_context_destroy(ctx);
    return st == IBL_OK ? CLI_EXIT_OK : cli_exit_code(st);
}
