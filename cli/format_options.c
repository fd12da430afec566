/* The storage-format options shared by the writing commands: see format_options.h. */
#include "format_options.h"

#include <ctype.h>
#include <string.h>

static int is_number(const char *s)
{
    if (!s || !*s) return 0;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s)) return 0;
    return 1;
}

int cli_format_option(cli_args *a, const char *arg, ibl_write_desc *wd)
{
    if (cli_is(a, arg, "--quality", NULL)) {
        const char *v = cli_value(a, arg);
        if (!ibl_quality_from_name(v, &wd->quality))
            cli_usage_error(a, "--quality wants fast, default or thorough, not '%s'", v);
        return 1;
    }
    if (cli_is(a, arg, "--rgbm-range", NULL)) {
        wd->rgbm_range = (float)cli_double(a, arg, 1.0 / 64.0, 65504.0);
        return 1;
    }
    if (cli_is(a, arg, "--dds-header", NULL)) {
        const char *v = cli_value(a, arg);
        if (strcmp(v, "auto") == 0) wd->dds_header = IBL_DDS_HEADER_AUTO;
        else if (strcmp(v, "legacy") == 0) wd->dds_header = IBL_DDS_HEADER_LEGACY;
        else if (strcmp(v, "dx10") == 0) wd->dds_header = IBL_DDS_HEADER_DX10;
        else cli_usage_error(a, "--dds-header wants auto, legacy or dx10, not '%s'", v);
        return 1;
    }
    if (cli_is(a, arg, "--ktx1-gltype", NULL)) {
        const char *v = cli_value(a, arg);
        if (strcmp(v, "spec") == 0) wd->ktx1_cmgen_types = 0;
        else if (strcmp(v, "cmgen") == 0) wd->ktx1_cmgen_types = 1;
        else cli_usage_error(a, "--ktx1-gltype wants spec or cmgen, not '%s'", v);
        return 1;
    }
    if (cli_is(a, arg, "--zstd", NULL)) {
        /* the level is optional: "--zstd", "--zstd 9", "--zstd=9" */
        if (strchr(arg, '=') || (a->index < a->argc && is_number(a->argv[a->index])))
            wd->zstd_level = cli_int(a, "--zstd", 1, 22);
        else
            wd->zstd_level = 3;
        return 1;
    }
    return 0;
}

void cli_format_check(cli_args *a, const ibl_write_desc *wd, ibl_file_type type, const char *out)
{
    if (wd->zstd_level && type != IBL_FILE_KTX2)
        cli_usage_error(a, "--zstd needs a .ktx2 output, not %s", out);
    if (wd->dds_header && type != IBL_FILE_DDS)
        cli_usage_error(a, "--dds-header needs a .dds output, not %s", out);
    if (wd->dds_header == IBL_DDS_HEADER_LEGACY && type == IBL_FILE_DDS && wd->format &&
        wd->format != IBL_FORMAT_RGBA16F && wd->format != IBL_FORMAT_RGBA32F &&
        wd->format != IBL_FORMAT_RG16F && wd->format != IBL_FORMAT_RG32F)
        cli_usage_error(a, "--dds-header legacy: %s has no legacy FourCC (rgba16f, rgba32f, rg16f "
                           "and rg32f have one)", ibl_format_name(wd->format));
    if (wd->ktx1_cmgen_types && (type != IBL_FILE_KTX1 || wd->format != IBL_FORMAT_RG11B10F))
        cli_usage_error(a, "--ktx1-gltype cmgen applies to a .ktx output in --format rg11b10f");
    if (wd->rgbm_range > 0.0f && wd->format != IBL_FORMAT_RGBM)
        cli_usage_error(a, "--rgbm-range applies to --format rgbm only");
    if (wd->quality != IBL_QUALITY_DEFAULT && !ibl_format_is_block(wd->format))
        cli_usage_error(a, "--quality applies to the block formats (bc6h, bc6h-signed, astc4x4 .. "
                           "astc8x8), not %s", ibl_format_name(wd->format));
}
