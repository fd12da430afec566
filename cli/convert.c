/* ibl convert: any layout or container to any other. */
#include "format_options.h"
#include "input.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl convert IN -o OUT [options]\n"
    "       ibl convert PX NX PY NY PZ NZ -o OUT [options]   (six face images)\n"
    "\n"
    "Converts an environment between layouts and containers. IN is a flat image (.hdr .exr\n"
    ".pfm .png .jpg) in any layout, or a cube texture (.ktx2 .ktx .dds). The container of OUT\n"
    "follows its extension: .ktx2/.ktx/.dds write a cubemap, flat formats a layout.\n"
    "\n"
    "  -o, --output PATH    output file (required)\n"

    "  --out-layout L       layout of a flat OUT (default equirect); 'faces' writes six files\n"
    "                       OUT_px.ext OUT_nx.ext OUT_py.ext OUT_ny.ext OUT_pz.ext OUT_nz.ext\n"
    "  --size N             cube face edge (default: from the input's resolution)\n"
    "  --mips               write the full area-correct mip chain (containers)\n"
    "  --format F           pixel format: rgba16f (default for containers), rgba32f, rg11b10f,\n"
    "                       rgb9e5, rg16f, rg32f, bc6h, bc6h-signed (.ktx2 .dds), rgbm, rgbd,\n"
    "                       rgbe (.ktx2); rgba16 for 16-bit PNG\n"
    CLI_FORMAT_HELP
    "  --exposure EV        exposure for 8-bit outputs (PNG/JPEG previews; filmic tone map)\n"
    CLI_INPUT_HELP
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n"
    "\n"
    "All the files of an output (six faces, say) appear together or not at all.\n";

static const char *const face_suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};

typedef struct convert_options {
    const char *out;
    cli_input_options input;
    ibl_layout out_layout;
    int faces, mips, exposure_given;
    ibl_write_desc wd;
} convert_options;

static void parse(cli_args *a, convert_options *o)
{
    const char *arg;
    while ((arg = cli_next(a))) {
        if (cli_common_option(a, arg) || cli_input_option(a, arg, &o->input) ||
            cli_format_option(a, arg, &o->wd))
            continue;
        if (cli_is(a, arg, "--output", "-o")) o->out = cli_value(a, arg);
        else if (cli_is(a, arg, "--size", NULL)) o->input.size = cli_int(a, arg, 1, 16384);
        else if (cli_flag(a, arg, "--mips", NULL)) o->mips = 1;
        else if (cli_is(a, arg, "--exposure", NULL)) {
            o->wd.exposure_ev = (float)cli_double(a, arg, -50, 50);
            o->exposure_given = 1;
        } else if (cli_is(a, arg, "--format", NULL)) {
            const char *v = cli_value(a, arg);
            if (!ibl_format_from_name(v, &o->wd.format)) cli_usage_error(a, "unknown pixel format '%s'", v);
        } else if (cli_is(a, arg, "--out-layout", NULL)) {
            const char *v = cli_value(a, arg);
            if (strcmp(v, "faces") == 0) o->faces = 1;
            else if (!ibl_layout_from_name(v, &o->out_layout) || o->out_layout == IBL_LAYOUT_AUTO ||
                     o->out_layout == IBL_LAYOUT_CUBE || o->out_layout == IBL_LAYOUT_FACES)
                cli_usage_error(a, "unknown output layout '%s'", v);
        } else {
            cli_positional_or_unknown(a, arg);
        }
    }
    if (a->positional_count != 1 && a->positional_count != 6)
        cli_usage_error(a, "needs one input file, or six face images (+X -X +Y -Y +Z -Z)");
    if (!o->out) cli_usage_error(a, "needs an output: -o OUT");
    ibl_file_type type = cli_check_output(a, o->out);
    if (!ibl_file_type_writes_format(type, o->wd.format))
        cli_usage_error(a, "%s cannot store %s pixels", o->out, ibl_format_name(o->wd.format));
    cli_format_check(a, &o->wd, type, o->out);
    cli_check_not_in_bake(a, o->out);
    if (o->mips && !ibl_file_type_is_container(type))
        cli_usage_error(a, "--mips needs a container output (.ktx2 .ktx .dds)");
}

/* The cube (with its mip chain if asked) as one container. */
static ibl_status add_container(ibl_context *ctx, ibl_output_set *set, const convert_options *o,
                                const char *input, const ibl_cubemap *cube)
{
    ibl_cubemap chain = *cube;
    chain.owns_data = 0;
    ibl_status st = IBL_OK;
    if (o->mips) {
        st = ibl_cubemap_alloc(ctx, cube->size, ibl_full_mip_count(cube->size), &chain);
        if (st == IBL_OK) {
            memcpy(chain.data, cube->data, ibl_cubemap_floats(cube->size, 1) * sizeof(float));
            st = ibl_cubemap_build_mips(ctx, &chain);
        }
    }
    ibl_texture tex = ibl_texture_from_cubemap(&chain);
    if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, &tex, "ibl.source", input);
    if (st == IBL_OK) st = ibl_output_set_add_texture(set, o->out, &tex, &o->wd);
    ibl_texture_free(ctx, &tex);
    if (o->mips) ibl_cubemap_free(ctx, &chain);
    return st;
}

/* Six face images OUT_px.ext ... OUT_nz.ext. */
static ibl_status add_faces(ibl_context *ctx, ibl_output_set *set, const convert_options *o,
                            const ibl_cubemap *cube)
{
    ibl_image faces[6];
    ibl_status st = ibl_cubemap_to_faces(ctx, cube, 0, faces);
    if (st != IBL_OK) return st;
    const char *dot = strrchr(o->out, '.'), *slash = strrchr(o->out, '/');
    if (dot && slash && dot < slash) dot = NULL;
    size_t stem = dot ? (size_t)(dot - o->out) : strlen(o->out);
    for (int f = 0; f < 6; f++) {
        char path[4200];
        snprintf(path, sizeof path, "%.*s_%s%s", (int)stem, o->out, face_suffix[f], dot ? dot : "");
        if (st == IBL_OK) st = ibl_output_set_add_image(set, path, &faces[f], &o->wd);
        ibl_image_free(ctx, &faces[f]);
    }
    return st;
}

/* The cube in a flat layout (tone-mapped at the automatic exposure for 8-bit outputs). */
static ibl_status add_layout(ibl_context *ctx, ibl_output_set *set, convert_options *o,
                             const ibl_cubemap *cube)
{
    ibl_from_cube_desc fd = {.layout = o->out_layout};
    ibl_image image;
    ibl_status st = ibl_cubemap_to_image(ctx, cube, &fd, &image);
    if (st != IBL_OK) return st;
    if (!o->exposure_given && cli_is_display_format(o->out)) o->wd.exposure_ev = ibl_image_auto_exposure(&image);
    st = ibl_output_set_add_image(set, o->out, &image, &o->wd);
    ibl_image_free(ctx, &image);
    return st;
}

/* A cube-map array (KTX2 or DDS) to another container, layer for layer, every level it has,
 * in the asked format; tex is freed. Resizing, mips and reorienting work on one cube, so they
 * are refused here. */
static int convert_cube_array(ibl_context *ctx, const cli_args *a, const convert_options *o,
                              const char *input, ibl_texture *tex)
{
    ibl_file_type type = ibl_file_type_from_path(o->out);
    const char *refused = type != IBL_FILE_KTX2 && type != IBL_FILE_DDS ? "an output other than .ktx2 or .dds"
                          : o->input.size ? "--size"
                          : o->mips ? "--mips"
                          : o->input.orientation.mirror || o->input.orientation.z_up ||
                                    o->input.orientation.yaw_degrees != 0.0f
                              ? "--yaw, --mirror-input or --z-up"
                              : NULL;
    if (refused) {
        cli_error("%s: a cube-map array of %d layers converts only to .ktx2 or .dds, as it is "
                  "(not with %s)", input, tex->depth, refused);
        ibl_texture_free(ctx, tex);
        return CLI_EXIT_USAGE;
    }
    double t0 = cli_seconds();
    ibl_write_report report = {0};
    ibl_write_desc wd = o->wd;
    wd.report = &report;
    ibl_output_set *set;
    ibl_status st = ibl_output_set_create(ctx, &set);
    if (st == IBL_OK) st = ibl_output_set_protect(set, input);
    if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, tex, "ibl.source", input);
    if (st == IBL_OK) st = ibl_output_set_add_texture(set, o->out, tex, &wd);
    if (st == IBL_OK) st = ibl_output_set_commit(set);
    ibl_output_set_destroy(set);
    int rc = CLI_EXIT_OK;
    if (st != IBL_OK) {
        cli_report_failure(ctx, o->out, st);
        rc = cli_exit_code(st);
    } else {
        cli_warn_clamped(&a->common, o->out, &report, wd.format);
        cli_info(&a->common, "wrote %s (%d layers of %dx%d faces, %d levels) in %.0f ms\n", o->out,
                 tex->depth, tex->width, tex->width, tex->levels, (cli_seconds() - t0) * 1000.0);
    }
    ibl_texture_free(ctx, tex);
    return rc;
}

int cli_cmd_convert(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "convert", usage, {0}, {0}, 0};
    convert_options o;
    memset(&o, 0, sizeof o);
    o.out_layout = IBL_LAYOUT_EQUIRECT;
    parse(&a, &o);
    const char *input = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_cubemap cube;
    ibl_texture tex;
    int rc;
    if (a.positional_count == 6) {
        rc = cli_read_cubemap_faces(ctx, &a.common, a.positional, &o.input, &cube);
    } else {
        rc = cli_read_input_texture(ctx, &a.common, input, &tex);
        if (rc == CLI_EXIT_OK && tex.kind == IBL_TEXTURE_CUBE_ARRAY) {
            rc = convert_cube_array(ctx, &a, &o, input, &tex);
            ibl_context_destroy(ctx);
            return rc;
        }
        if (rc == CLI_EXIT_OK) rc = cli_texture_to_cubemap(ctx, input, &o.input, &tex, &cube, NULL);
    }
    if (rc != CLI_EXIT_OK) {
        ibl_context_destroy(ctx);
        return rc;
    }
    if (a.positional_count == 1) cli_warn_upsampling(&a.common, input, &o.input, cube.size);
    ibl_write_report report = {0};
    o.wd.report = &report;
    ibl_output_set *set;
    ibl_status st = ibl_output_set_create(ctx, &set);
    for (int i = 0; st == IBL_OK && i < a.positional_count; i++) st = ibl_output_set_protect(set, a.positional[i]);
    if (st == IBL_OK) {
        if (ibl_file_type_is_container(ibl_file_type_from_path(o.out))) st = add_container(ctx, set, &o, input, &cube);
        else if (o.faces) st = add_faces(ctx, set, &o, &cube);
        else st = add_layout(ctx, set, &o, &cube);
    }
    if (st == IBL_OK) st = ibl_output_set_commit(set);
    ibl_output_set_destroy(set);
    if (st != IBL_OK) {
        cli_report_failure(ctx, o.out, st);
        rc = cli_exit_code(st);
    } else {
        cli_warn_clamped(&a.common, o.out, &report, o.wd.format);
        cli_info(&a.common, "wrote %s (%dx%d faces) in %.0f ms\n", o.out, cube.size, cube.size,
                 (cli_seconds() - t0) * 1000.0);
    }
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
    return rc;
}
