/* ibl bake: everything a renderer needs from one environment, in one pass over the input.
 * A thin client of bake.h: the library names the files, writes the manifest and swaps the
 * folder in whole. */
#include "bake_probes.h"
#include "format_options.h"
#include "input.h"
#include "specular_options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl bake [IN] -o DIR [options]\n"
    "\n"
    "Bakes an environment into the folder DIR: the prefiltered specular chain (specular.ktx2\n"
    "and .dds), the irradiance map (irradiance.ktx2 and .dds), the SH in every normalisation\n"
    "(sh.json), the BRDF tables (brdf_lut.ktx2, brdf_extra.ktx2, ambient_brdf.ktx2), a\n"
    "preview of the environment (environment.png) and manifest.json, which lists every file\n"
    "and the exact parameters (docs/FORMATS.md). Without IN the built-in clear sky is baked.\n"
    "\n"
    "DIR is replaced whole, as one step: it always holds one complete bake, the old or the\n"
    "new, even if ibl is killed. It must be new, empty, or an earlier bake; a folder holding\n"
    "other files is refused.\n"
    "\n"
    "  -o, --output DIR       the bake folder\n"
    CLI_TARGET_HELP
    CLI_SPECULAR_HELP
    "  --irradiance-size N    irradiance face edge (default 16)\n"
    "  --sh-bands N           1..5 (default 3)\n"
    "  --window W             SH window: none (default), auto, or a Hanning width\n"
    "  --lut-size N           split-sum table edge (default 128)\n"
    "  --format F             pixel format of the cube textures: rgba16f (default), rgba32f,\n"
    "                         rg11b10f, rgb9e5, bc6h, bc6h-signed; astc4x4 .. astc8x8 and\n"
    "                         rgbm, rgbd, rgbe (KTX2 only: the bake writes no DDS)\n"
    "  --quality Q            BC6H / ASTC encoder effort: fast, default or thorough\n"
    "  --zstd [LEVEL]         Zstandard supercompression of the KTX2 files, level 1..22\n"
    "                         (default 3; DDS files have none)\n"
    "  --rgbm-range R         RGBM's range: the largest value stored (default 8), for\n"
    "                         --format rgbm and the RGBM PNG of --out-layout atlas\n"
    "  --working-size N       face edge the input is read at (default: the chain's, at least\n"
    "                         128; 256 without --size)\n"
    "  --preview-width W      width of environment.png (default 1024; 0: no preview)\n"
    "  --out-layout L         cube (default), or atlas: the chain also as Daqi 2016's 2D mip\n"
    "                         atlas, specular_atlas.ktx2 (--format) and specular_atlas.png\n"
    "                         (8-bit RGBM), its coordinate table in the manifest's \"atlas\"\n"
    "                         and the KTX2's key ibl.atlas (docs/ATLAS.md)\n"
    "  --units U              nits (cd/m^2) or kcd (kcd/m^2): the units of every output,\n"
    "                         recorded in the manifest. The built-in sky is made in kcd/m^2\n"
    "                         and scaled (nits: x 1000); a file's values are taken to be in\n"
    "                         U already (stated, not scaled). Default: kcd for the sky,\n"
    "                         unstated for a file\n"
    "  --dds-header H         auto (default: legacy FourCC header where the format has one,\n"
    "                         else DX10), legacy or dx10\n"
    CLI_INPUT_HELP
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n"
    "\n"
    "The default chain is the gltf preset: GGX, 256 texels, roughness = level / (levels - 1).\n"
    CLI_PROBE_BAKE_HELP;

typedef struct bake_options {
    const char *dir;
    int units_nits;     /* --units: 1 nits (cd/m^2), 0 kcd/m^2, -1 not given */
    cli_input_options input;
    cli_specular_options specular;
    ibl_bake_desc desc;
    cli_probe_bake_options probes;
    ibl_write_desc storage; /* --quality, --zstd, --rgbm-range */
} bake_options;

static void parse(cli_args *a, bake_options *o)
{
    const char *arg;
    while ((arg = cli_next(a))) {
        if (cli_common_option(a, arg) || cli_input_option(a, arg, &o->input) ||
            cli_specular_option(a, arg, &o->specular) || cli_format_option(a, arg, &o->storage))
            continue;
        const ibl_target_profile *target = cli_target_option(a, arg, &o->specular, &o->input);
        if (target) {
            o->desc.target = target->target;
            o->desc.format = target->format;
            o->desc.containers = target->containers;
            continue;
        }
        if (cli_is(a, arg, "--output", "-o")) o->dir = o->probes.dir = cli_value(a, arg);
        else if (cli_is(a, arg, "--units", NULL)) {
            const char *v = cli_value(a, arg);
            if (strcmp(v, "nits") == 0) o->units_nits = 1;
            else if (strcmp(v, "kcd") == 0) o->units_nits = 0;
            else cli_usage_error(a, "--units wants nits (cd/m^2) or kcd (kcd/m^2), not '%s'", v);
        }
        else if (cli_is(a, arg, "--dds-header", NULL)) {
            const char *v = cli_value(a, arg);
            if (strcmp(v, "auto") == 0) o->desc.dds_header = IBL_DDS_HEADER_AUTO;
            else if (strcmp(v, "legacy") == 0) o->desc.dds_header = IBL_DDS_HEADER_LEGACY;
            else if (strcmp(v, "dx10") == 0) o->desc.dds_header = IBL_DDS_HEADER_DX10;
            else cli_usage_error(a, "--dds-header wants auto, legacy or dx10, not '%s'", v);
        }
        else if (cli_is(a, arg, "--probes", NULL)) o->probes.probes = cli_value(a, arg);
        else if (cli_is(a, arg, "--captures", NULL)) o->probes.captures = cli_value(a, arg);
        else if (cli_is(a, arg, "--scene", NULL)) o->probes.scene = cli_value(a, arg);
        else if (cli_is(a, arg, "--shard", NULL)) cli_shard_value(a, arg, &o->probes.shard, &o->probes.shards);
        else if (cli_flag(a, arg, "--merge", NULL)) o->probes.merge = 1;
        else if (cli_is(a, arg, "--irradiance-size", NULL)) o->desc.irradiance_size = cli_int(a, arg, 1, 64);
        else if (cli_is(a, arg, "--sh-bands", NULL)) o->desc.sh_bands = cli_int(a, arg, 1, IBL_SH_MAX_BANDS);
        else if (cli_is(a, arg, "--lut-size", NULL)) o->desc.lut_size = cli_int(a, arg, 2, 4096);
        else if (cli_is(a, arg, "--working-size", NULL)) o->input.size = cli_int(a, arg, 1, 16384);
        else if (cli_is(a, arg, "--preview-width", NULL)) {
            int w = cli_int(a, arg, 0, 16384);
            o->desc.preview_width = w > 0 ? w : -1;
        }
        else if (cli_is(a, arg, "--out-layout", NULL)) {
            const char *v = cli_value(a, arg);
            if (strcmp(v, "atlas") == 0) o->desc.atlas = 1;
            else if (strcmp(v, "cube") != 0) cli_usage_error(a, "--out-layout wants cube or atlas, not '%s'", v);
        }
        else if (cli_is(a, arg, "--window", NULL))
            cli_sh_window_value(a, arg, &o->desc.sh_window, &o->desc.sh_window_width);
        else if (cli_is(a, arg, "--format", NULL)) {
            const char *v = cli_value(a, arg);
            if (!ibl_format_from_name(v, &o->desc.format) ||
                !ibl_file_type_writes_format(IBL_FILE_KTX2, o->desc.format))
                cli_usage_error(a, "--format wants rgba16f, rgba32f, rg11b10f, rgb9e5, rg16f, "
                                   "rg32f, bc6h, bc6h-signed, astc4x4 .. astc8x8, rgbm, rgbd or "
                                   "rgbe, not '%s'", v);
            /* DDS has no key/value data to name an 8-bit encoding: those bakes are KTX2 only */
            if (!ibl_file_type_writes_format(IBL_FILE_DDS, o->desc.format)) o->desc.containers = IBL_BAKE_KTX2;
            else if (o->desc.target == IBL_TARGET_NONE) o->desc.containers = 0;
        } else {
            cli_positional_or_unknown(a, arg);
        }
    }
    if (a->positional_count > 1) cli_usage_error(a, "takes at most one input file");
    ibl_format f = o->desc.format ? o->desc.format : IBL_FORMAT_RGBA16F;
    if (o->desc.dds_header == IBL_DDS_HEADER_LEGACY && f != IBL_FORMAT_RGBA16F &&
        f != IBL_FORMAT_RGBA32F)
        cli_usage_error(a, "--dds-header legacy: %s has no legacy DDS FourCC (rgba16f and "
                           "rgba32f have one)", ibl_format_name(f));
    if (!o->dir) cli_usage_error(a, "needs an output folder: -o DIR");
    /* the same rules as convert and prefilter, for the bake's KTX2 files */
    o->storage.format = o->desc.format;
    ibl_write_desc check = o->storage;
    if (o->desc.atlas) check.rgbm_range = 0.0f; /* the atlas PNG is RGBM whatever --format */
    cli_format_check(a, &check, IBL_FILE_KTX2, o->dir);
    if (o->probes.probes && (o->storage.quality || o->storage.zstd_level || o->storage.rgbm_range > 0.0f))
        cli_usage_error(a, "--quality, --zstd and --rgbm-range apply to an environment bake, not "
                           "to --probes (whose parts and array use the encoders' defaults)");
    o->desc.quality = o->storage.quality;
    o->desc.zstd_level = o->storage.zstd_level;
    o->desc.rgbm_range = o->storage.rgbm_range;
    if (a->positional_count) cli_check_not_inside(a, a->positional[0], o->dir);
    o->desc.specular = cli_specular_resolve(a, &o->specular, o->desc.target ? NULL : "gltf");
    o->desc.preset = o->specular.preset ? o->specular.preset : o->desc.target ? NULL : "gltf";
    if (!o->input.size) {
        int s = o->desc.specular.size;
        o->input.size = s > 0 ? (s < 128 ? 128 : s) : 256;
    }
}

/* IN read as a cube of the working size, or the built-in sky. */
static int read_input(ibl_context *ctx, const cli_args *a, bake_options *o, ibl_sky_desc *sky,
                      ibl_cubemap *env)
{
    if (a->positional_count) {
        o->desc.source.name = a->positional[0];
        o->desc.source.orientation = o->input.orientation;
        ibl_layout layout = IBL_LAYOUT_AUTO;
        o->input.chain = &o->desc.specular;
        int rc = cli_read_cubemap(ctx, &a->common, a->positional[0], &o->input, env, &layout);
        o->desc.source.layout = layout;
        o->desc.specular_sources = o->input.sources;
        return rc;
    }
    memset(sky, 0, sizeof *sky);
    sky->width = 4 * o->input.size;
    o->desc.source.sky = sky;
    o->desc.source.layout = IBL_LAYOUT_EQUIRECT;
    o->desc.source.orientation = o->input.orientation;
    return cli_read_sky(ctx, sky, &o->input, env);
}

/* --units: the outputs' units in the manifest; the sky (made in kcd/m^2) scaled to them. */
static void apply_units(bake_options *o, int is_sky, ibl_cubemap *env)
{
    if (o->units_nits < 0) {
        o->desc.units = is_sky ? "kcd/m^2" : NULL;
        return;
    }
    o->desc.units = o->units_nits ? "cd/m^2" : "kcd/m^2";
    if (!is_sky || !o->units_nits) return;
    size_t n = ibl_cubemap_floats(env->size, env->levels);
    for (size_t i = 0; i < n; i++)
        if (i % 4 != 3) env->data[i] *= 1000.0f; /* kcd/m^2 -> cd/m^2; alpha stays */
}

/* The environment: IN read as a cube of the working size, or the built-in sky. */
static int read_environment(ibl_context *ctx, const cli_args *a, bake_options *o,
                            ibl_sky_desc *sky, ibl_cubemap *env)
{
    int rc = read_input(ctx, a, o, sky, env);
    if (rc == CLI_EXIT_OK) apply_units(o, a->positional_count == 0, env);
    return rc;
}


static void print_summary(const cli_common *c, const char *dir, const ibl_bake_data *b)
{
    if (c->quiet) return;
    const ibl_specular_info *info = &b->specular_info;
    fprintf(stderr, "baked %s into %s/ in %.0f ms:\n", b->source_name, dir, b->timing_ms.total);
    fprintf(stderr, "  %-10s %8.1f ms\n  %-10s %8.1f ms\n  %-10s %8.1f ms\n  %-10s %8.1f ms\n",
            "specular", b->timing_ms.specular, "diffuse", b->timing_ms.diffuse, "brdf",
            b->timing_ms.brdf, "preview", b->timing_ms.preview);
    fprintf(stderr, "  specular: %s, %d levels of %d..%d texels, mapping %s\n",
            ibl_specular_filter_name(info->filter), info->levels, info->size,
            ibl_level_size(info->size, info->levels - 1), ibl_specular_mapping_name(info->mapping));
    const char *names[16];
    int n = ibl_bake_files(b, names, 16);
    for (int i = 0; i < n && i < 16; i++) fprintf(stderr, "  %s/%s\n", dir, names[i]);
}

int cli_cmd_bake(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "bake", usage, {0}, {0}, 0};
    bake_options o;
    memset(&o, 0, sizeof o);
    o.units_nits = -1;
    parse(&a, &o);
    if (o.probes.probes) {
        if (a.positional_count) cli_usage_error(&a, "--probes takes no input file (the set names its global probe)");
        if (o.desc.atlas) cli_usage_error(&a, "--out-layout atlas is for one environment, not --probes");
        if (o.desc.target) cli_usage_error(&a, "--target makes a single environment's bake, not a probe array's");
        o.probes.format = o.desc.format;
        o.probes.lut_size = o.desc.lut_size;
        return cli_bake_probes(&a, &o.probes);
    }
    if (o.probes.captures || o.probes.scene || o.probes.shards || o.probes.merge)
        cli_usage_error(&a, "--captures, --scene, --shard and --merge need --probes SET");
    ibl_context *ctx = cli_context(&a.common);
    ibl_sky_desc sky;
    ibl_cubemap env = {0};
    int rc = read_environment(ctx, &a, &o, &sky, &env);
    if (rc == CLI_EXIT_OK) cli_specular_check(&a, ctx, &o.desc.specular, env.size);
    ibl_bake_data bake;
    ibl_status st = IBL_OK;
    if (rc == CLI_EXIT_OK) {
        st = ibl_bake(ctx, &env, &o.desc, o.dir, &bake);
        if (st == IBL_OK && bake.clamped_texels)
            cli_info(&a.common, "ibl: warning: %s: %llu texels above %g were stored as %g (the "
                                "largest %s value; --format rgba32f keeps them)\n", o.dir,
                     (unsigned long long)bake.clamped_texels,
                     (double)ibl_format_max_value(bake.format), (double)ibl_format_max_value(bake.format),
                     ibl_format_name(bake.format));
        if (st == IBL_OK && a.positional_count)
            cli_warn_upsampling(&a.common, a.positional[0], &o.input, bake.specular_info.size);
        if (st == IBL_OK) print_summary(&a.common, o.dir, &bake);
        else cli_report_failure(ctx, o.dir, st), rc = cli_exit_code(st);
        if (st == IBL_OK) ibl_bake_free(ctx, &bake);
    }
    ibl_specular_sources_destroy(o.input.sources);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
    return rc;
}
