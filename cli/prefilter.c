/* ibl prefilter: the prefiltered (mipmapped) radiance environment map of an environment. */
#include "format_options.h"
#include "input.h"
#include "specular_options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char usage[] =
    "usage: ibl prefilter IN -o OUT [options]\n"
    "\n"
    "Writes the prefiltered specular chain of an environment (any layout, or a cube texture):\n"
    "level l holds the environment convolved with the lobe of level l's roughness (GGX) or\n"
    "shininess (Phong family). OUT .ktx2 .ktx .dds hold every face and level in one file (KTX2\n"
    "also describes its levels in its metadata, ibl.specular.*); .exr .hdr .pfm .png get one\n"
    "image per face and level, STEM_l<level>_<face>.EXT with <face> in px nx py ny pz nz.\n"
    "STEM.manifest.json beside OUT lists the files, the filter, the mapping and every level's\n"
    "roughness or shininess (docs/FORMATS.md). Every file appears at once, or none. OUT may\n"
    "not be in a bake folder (only 'ibl bake' writes there), and an existing STEM.manifest.json\n"
    "is replaced only when it is a chain manifest.\n"
    "With --out-layout atlas, OUT (.ktx2 .exr .png) is one 2D image holding every level as\n"
    "Daqi 2016's mip atlas; its coordinate table goes to the manifest's \"atlas\" and, in a\n"
    "KTX2, to the key ibl.atlas (docs/ATLAS.md). PNG atlases are 8-bit RGBM unless --format\n"
    "rgba8 asks for a tone-mapped picture of it.\n"
    "\n"
    "  -o, --output OUT     output file\n"
    "  --out-layout L       cube (default: a cube container or one image per face and level)\n"
    "                       or atlas (one 2D image, levels >= 2 at level 2's size)\n"
    CLI_SPECULAR_HELP
    "  --format F           storage format (rgba16f, rgba32f, rg11b10f, rgb9e5, rg16f, rg32f,\n"
    "                       bc6h, bc6h-signed for containers; rgbm, rgbd, rgbe for KTX2; rgb32f,\n"
    "                       rgb16f, rgba16f, rgba32f for EXR)\n"
    CLI_FORMAT_HELP
    "  --source-size N      face edge the input is converted to first (default: its own)\n"
    CLI_INPUT_HELP
    CLI_TARGET_HELP
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

static const char *const face_names[6] = {"px", "nx", "py", "ny", "pz", "nz"};

/* OUT without its extension, and the extension with its dot. */
static void split_ext(const char *path, char *stem, size_t cap, const char **ext)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash)) dot = path + strlen(path);
    snprintf(stem, cap, "%.*s", (int)(dot - path), path);
    *ext = dot;
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* The chain into the set: one container, or one image per face and level; their base names
 * (for the manifest) go to names[], allocated. */
static ibl_status add_chain(ibl_context *ctx, ibl_output_set *set, const char *out,
                            const ibl_cubemap *chain, const ibl_specular_info *info,
                            const ibl_write_desc *wd, char **names, int *count)
{
    *count = 0;
    if (ibl_file_type_is_container(ibl_file_type_from_path(out))) {
        ibl_texture t = ibl_texture_from_cubemap(chain);
        ibl_status st = ibl_specular_set_metadata(ctx, info, &t);
        if (st == IBL_OK) st = ibl_output_set_add_texture(set, out, &t, wd);
        ibl_texture_free(ctx, &t); /* the metadata */
        if (!(names[(*count)++] = strdup(base_name(out)))) st = IBL_ERR_OUT_OF_MEMORY;
        return st;
    }
    char stem[4096], path[4200];
    const char *ext;
    split_ext(out, stem, sizeof stem, &ext);
    ibl_status st = IBL_OK;
    for (int l = 0; st == IBL_OK && l < chain->levels; l++) {
        ibl_image faces[6] = {{0}};
        st = ibl_cubemap_to_faces(ctx, chain, l, faces);
        for (int f = 0; f < 6; f++) {
            snprintf(path, sizeof path, "%s_l%d_%s%s", stem, l, face_names[f], ext);
            if (st == IBL_OK) st = ibl_output_set_add_image(set, path, &faces[f], wd);
            if (st == IBL_OK && !(names[(*count)++] = strdup(base_name(path))))
                st = IBL_ERR_OUT_OF_MEMORY;
            ibl_image_free(ctx, &faces[f]);
        }
    }
    return st;
}

/* The chain as one 2D atlas into the set (a KTX2 also carries the table and the levels'
 * description in its key/value data); *layout receives the table. */
static ibl_status add_atlas(ibl_context *ctx, ibl_output_set *set, const char *out,
                            const ibl_cubemap *chain, const ibl_specular_info *info,
                            const ibl_write_desc *wd, ibl_atlas_layout *layout, char **names,
                            int *count)
{
    ibl_image atlas;
    *count = 0;
    ibl_status st = ibl_atlas_pack(ctx, chain, NULL, &atlas, layout);
    if (st != IBL_OK) return st;
    ibl_write_desc d = *wd;
    if (ibl_file_type_from_path(out) == IBL_FILE_PNG && d.format == IBL_FORMAT_DEFAULT)
        d.format = IBL_FORMAT_RGBM;
    if (d.format == IBL_FORMAT_RGBA8_SRGB) d.exposure_ev = ibl_image_auto_exposure(&atlas);
    if (ibl_file_type_from_path(out) == IBL_FILE_KTX2) {
        ibl_texture t = {.kind = IBL_TEXTURE_2D, .width = atlas.width, .height = atlas.height,
                         .depth = 1, .levels = 1, .data = atlas.pixels};
        char *table = NULL;
        st = ibl_atlas_layout_to_json(ctx, layout, &table);
        if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, &t, "ibl.atlas", table);
        if (st == IBL_OK) st = ibl_specular_set_metadata(ctx, info, &t);
        if (st == IBL_OK) st = ibl_output_set_add_texture(set, out, &t, &d);
        ibl_texture_free(ctx, &t); /* the metadata */
        ibl_free(ctx, table);
    } else {
        st = ibl_output_set_add_image(set, out, &atlas, &d);
    }
    ibl_image_free(ctx, &atlas);
    if (st == IBL_OK && !(names[(*count)++] = strdup(base_name(out)))) st = IBL_ERR_OUT_OF_MEMORY;
    return st;
}

/* The chain and its manifest, all or nothing. */
static ibl_status write_outputs(ibl_context *ctx, const char *in, const char *out,
                                const ibl_cubemap *chain, const ibl_specular_info *info,
                                const ibl_specular_desc *d, const ibl_write_desc *wd, int atlas)
{
    ibl_output_set *set;
    ibl_status st = ibl_output_set_create(ctx, &set);
    if (st != IBL_OK) return st;
    char *names[6 * IBL_MAX_LEVELS] = {0};
    int count = 0;
    st = ibl_output_set_protect(set, in);
    ibl_atlas_layout layout;
    if (st == IBL_OK && atlas) st = add_atlas(ctx, set, out, chain, info, wd, &layout, names, &count);
    else if (st == IBL_OK) st = add_chain(ctx, set, out, chain, info, wd, names, &count);
    char *json = NULL;
    if (st == IBL_OK && atlas)
        st = ibl_atlas_chain_manifest(ctx, info, d->edge_fixup, wd->format, &layout,
                                      (const char *const *)names, count, &json);
    else if (st == IBL_OK)
        st = ibl_chain_manifest(ctx, info, d->edge_fixup, wd->format, (const char *const *)names,
                                count, &json);
    for (int i = 0; i < count; i++) free(names[i]);
    if (st == IBL_OK) {
        char stem[4096], path[4200];
        const char *ext;
        split_ext(out, stem, sizeof stem, &ext);
        snprintf(path, sizeof path, "%s.manifest.json", stem);
        st = ibl_output_set_add(set, path, json, strlen(json));
    }
    ibl_free(ctx, json);
    if (st == IBL_OK) st = ibl_output_set_commit(set);
    ibl_output_set_destroy(set);
    return st;
}

/* The input's reading and conversion, and the chain's preparation (ibl_specular_prepare):
 * the second needs only the cube's edge, which the file's header gives, so both run as the
 * two tasks of one parallel-for. The preparation's loops then fill the time the decoder
 * leaves a thread idle (a DWAB file's bands are 256 rows each: two unequal tasks for a
 * 1024x512 input; PNG, JPEG and HDR files decode on one thread). */
typedef struct read_and_prepare {
    ibl_context *ctx;
    const cli_common *common;
    const char *path;
    cli_input_options *input;
    const ibl_specular_desc *desc;
    int source_size;
    ibl_cubemap *cube;
    int read_rc;
    ibl_specular_prepared *prepared;
    ibl_status prepare_status;
} read_and_prepare;

static void read_and_prepare_task(void *arg, int index)
{
    read_and_prepare *j = arg;
    if (index == 0)
        j->read_rc = cli_read_cubemap(j->ctx, j->common, j->path, j->input, j->cube, NULL);
    else
        j->prepare_status = ibl_specular_prepare(j->ctx, j->desc, j->source_size, &j->prepared);
}

/* Side by side, the input's float texels and the plan's memory are held at once, where one
 * after the other the plan takes the pages the freed image leaves (the CLI's arena reuses
 * them): above this size the fresh pages cost more than the overlap gains (the 1024 chain
 * from a 4096x2048 EXR, a 128 MiB image: 1.20 s against 1.12, peak 416 MB against 310; the
 * 512 chain from 2048x1024, 32 MiB: the same time, 120 MB against 101; the 256 chain from
 * 1024x512, 8 MiB: 87 ms against 92, 44 MB against 46 (docs/PERFORMANCE.md). */
#define OVERLAP_MAX_INPUT_BYTES ((uint64_t)16 << 20)
/* Below this chain edge the plan is small and so is the gain, while the plan's memory, held
 * beside the decode's buffers, raises the peak: the 128 chain from 1024x512 gained 1 ms of 63
 * and its peak rose from 32 to 36 MB (the 64 chain's too), where the 256 chain's peak comes
 * later, in level 1's weights, and does not move. */
#define OVERLAP_MIN_CHAIN 256

static uint64_t input_float_bytes(const ibl_file_info *head)
{
    uint64_t texels = (uint64_t)head->width * (uint64_t)head->height;
    if (head->kind == IBL_TEXTURE_CUBE) texels *= 6;
    if (head->depth > 1) texels *= (uint64_t)head->depth;
    return texels * 4 * sizeof(float);
}

/* Reads the input into cube and prepares the chain d for it: side by side when the header
 * tells the cube's edge, the input is small (OVERLAP_MAX_INPUT_BYTES), the chain is not
 * (OVERLAP_MIN_CHAIN) and no memory budget was asked for (the two would hold memory at once,
 * and the budget's verdict should not depend on that); one after the other otherwise.
 * Returns the exit code; on success *prepared is set. */
static int read_and_prepare_input(cli_args *a, ibl_context *ctx, const char *in,
                                  const char *out, cli_input_options *io, const ibl_specular_desc *d,
                                  ibl_cubemap *cube, ibl_specular_prepared **prepared)
{
    *prepared = NULL;
    ibl_file_info head;
    int predicted = 0;
    struct stat st; /* a pipe's head, once read, is gone: only regular files */
    int small_chain = d->size > 0 && d->size < OVERLAP_MIN_CHAIN; /* 0: the source's edge */
    if (a->common.max_memory_mib <= 0 && ibl_context_threads(ctx) > 1 && !small_chain &&
        stat(in, &st) == 0 && S_ISREG(st.st_mode) && ibl_read_info(ctx, in, &head) == IBL_OK &&
        input_float_bytes(&head) <= OVERLAP_MAX_INPUT_BYTES) {
        predicted = cli_input_cube_size(io, &head);
        if (d->size <= 0 && predicted < OVERLAP_MIN_CHAIN) predicted = 0;
    }
    read_and_prepare job = {ctx, &a->common, in, io, d, predicted, cube, 0, NULL, IBL_OK};
    if (predicted > 0) {
        cli_specular_check(a, ctx, d, predicted);
        ibl_parallel_for(ctx, 2, read_and_prepare_task, &job);
    } else {
        read_and_prepare_task(&job, 0);
    }
    if (job.read_rc != CLI_EXIT_OK) {
        ibl_specular_prepared_destroy(job.prepared);
        return job.read_rc;
    }
    if (predicted != cube->size) { /* not prepared, or for another edge */
        ibl_specular_prepared_destroy(job.prepared);
        cli_specular_check(a, ctx, d, cube->size);
        job.prepared = NULL;
        job.source_size = cube->size;
        read_and_prepare_task(&job, 1);
    }
    if (job.prepare_status != IBL_OK) {
        ibl_specular_prepared_destroy(job.prepared);
        ibl_specular_sources_destroy(io->sources);
        io->sources = NULL;
        ibl_cubemap_free(ctx, cube);
        cli_report_failure(ctx, out, job.prepare_status);
        return cli_exit_code(job.prepare_status);
    }
    *prepared = job.prepared;
    return CLI_EXIT_OK;
}

int cli_cmd_prefilter(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "prefilter", usage, {0}, {0}, 0};
    const char *out = NULL;
    cli_specular_options so;
    memset(&so, 0, sizeof so);
    ibl_write_desc wd = {0};
    cli_input_options io = {0};
    int atlas = 0;
    const ibl_target_profile *target = NULL, *t;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg) || cli_input_option(&a, arg, &io) ||
            cli_specular_option(&a, arg, &so) || cli_format_option(&a, arg, &wd))
            continue;
        if ((t = cli_target_option(&a, arg, &so, &io))) {
            target = t;
            continue;
        }
        if (cli_is(&a, arg, "--output", "-o")) {
            out = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--out-layout", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "atlas") == 0) atlas = 1;
            else if (strcmp(v, "cube") == 0) atlas = 0;
            else cli_usage_error(&a, "--out-layout wants cube or atlas, not '%s'", v);
        } else if (cli_is(&a, arg, "--source-size", NULL)) {
            io.size = cli_int(&a, arg, 1, 16384);
        } else if (cli_is(&a, arg, "--format", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_format_from_name(v, &wd.format)) cli_usage_error(&a, "unknown format '%s'", v);
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "wants exactly one input file");
    if (!out) cli_usage_error(&a, "wants an output file (-o OUT)");
    ibl_file_type type = cli_check_output(&a, out);
    if (atlas && type != IBL_FILE_KTX2 && type != IBL_FILE_EXR && type != IBL_FILE_PNG)
        cli_usage_error(&a, "%s: an atlas is written as .ktx2, .exr or .png", out);
    if (atlas && type == IBL_FILE_PNG && wd.format != IBL_FORMAT_DEFAULT &&
        wd.format != IBL_FORMAT_RGBM && wd.format != IBL_FORMAT_RGBA8_SRGB)
        cli_usage_error(&a, "%s: a PNG atlas is rgbm (default) or rgba8 (a tone-mapped picture)", out);
    if (atlas && type == IBL_FILE_PNG && wd.format == IBL_FORMAT_DEFAULT) wd.format = IBL_FORMAT_RGBM;
    if (!(atlas && type == IBL_FILE_PNG) && !ibl_file_type_writes_format(type, wd.format))
        cli_usage_error(&a, "%s cannot store %s pixels", out, ibl_format_name(wd.format));
    cli_format_check(&a, &wd, type, out);
    /* a KTX1 chain for Filament: cmgen's glType for rg11b10f, the only one Filament reads */
    if (target && target->target == IBL_TARGET_FILAMENT && type == IBL_FILE_KTX1) wd.ktx1_cmgen_types = 1;
    cli_check_not_in_bake(&a, out);
    {
        char stem[4096], manifest[4200];
        const char *ext;
        split_ext(out, stem, sizeof stem, &ext);
        snprintf(manifest, sizeof manifest, "%s.manifest.json", stem);
        cli_check_manifest_replaceable(&a, manifest, "ibl-chain");
    }
    ibl_specular_desc d = cli_specular_resolve(&a, &so, NULL);
    const char *in = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_cubemap cube = {0}, chain = {0};
    io.chain = &d;
    ibl_specular_prepared *prepared = NULL;
    int rc = read_and_prepare_input(&a, ctx, in, out, &io, &d, &cube, &prepared);
    if (rc != CLI_EXIT_OK) {
        ibl_context_destroy(ctx);
        return rc;
    }
    double t_read = cli_seconds();
    ibl_specular_info info;
    ibl_status st = ibl_specular_prefilter_prepared(prepared, &cube, &chain, &info);
    ibl_specular_prepared_destroy(prepared);
    if (st == IBL_OK) st = ibl_specular_sources_apply(io.sources, &chain);
    ibl_specular_sources_destroy(io.sources);
    double t_filter = cli_seconds();
    ibl_cubemap_free(ctx, &cube);
    if (st == IBL_OK) cli_warn_upsampling(&a.common, in, &io, info.size);
    if (st == IBL_OK) st = write_outputs(ctx, in, out, &chain, &info, &d, &wd, atlas);
    ibl_cubemap_free(ctx, &chain);
    if (st != IBL_OK) {
        cli_report_failure(ctx, out, st);
        ibl_context_destroy(ctx);
        return cli_exit_code(st);
    }
    double t1 = cli_seconds();
    cli_info(&a.common,
             "%s: %dx%dx6, %d levels, %s %s (%s mapping) in %.3f s (read and plan %.3f, filter %.3f, "
             "write %.3f)\n",
             out, info.size, info.size, info.levels, ibl_specular_filter_name(info.filter),
             d.method == IBL_METHOD_REFERENCE ? "reference" : d.dynamic ? "dynamic plan" : "fast",
             ibl_specular_mapping_name(info.mapping), t1 - t0, t_read - t0, t_filter - t_read,
             t1 - t_filter);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
