/* The options of the compressed and 8-bit HDR storage formats, shared by the commands that
 * write textures (convert, prefilter, irradiance, bake). */
#ifndef IBL_CLI_FORMAT_OPTIONS_H
#define IBL_CLI_FORMAT_OPTIONS_H

#include "cli.h"

#define CLI_FORMAT_HELP                                                                        \
    "  --quality Q          BC6H / ASTC encoder effort: fast, default or thorough\n"                   \
    "  --zstd [LEVEL]       KTX2 Zstandard supercompression, level 1..22 (default 3)\n"         \
    "  --rgbm-range R       RGBM's range: the largest value stored (default 8)\n"             \
    "  --dds-header H       DDS header: auto (default: the legacy FourCC header where the\n"   \
    "                       format has one, else DX10), legacy or dx10\n"                      \
    "  --ktx1-gltype T      KTX1 rg11b10f glType: spec (default, 0x8C3B) or cmgen (0x8C3A,\n"  \
    "                       what Filament's reader needs)\n"

/* Handles --quality, --zstd [LEVEL], --rgbm-range, --dds-header and --ktx1-gltype into wd;
 * returns 1 if arg was one. */
int cli_format_option(cli_args *a, const char *arg, ibl_write_desc *wd);
/* Usage errors for options that do not apply to the output type. */
void cli_format_check(cli_args *a, const ibl_write_desc *wd, ibl_file_type type, const char *out);

#endif
