/* ibl convert: any layout or container to any other. */
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
    "  --layout L           layout of IN: auto (default: from the aspect ratio), equirect,\n"
    "                       hcross, vcross, hstrip, vstrip, angular, octahedral\n"
    "  --out-layout L       layout of a flat OUT (default equirect); 'faces' writes six files\n"
    "                       OUT_px.ext OUT_nx.ext OUT_py.ext OUT_ny.ext OUT_pz.ext OUT_nz.ext\n"
    "  --size N             cube face edge (default: from the input's resolution)\n"
    "  --mips               write the full area-correct mip chain (containers)\n"
    "  --format F           pixel format: rgba16f (default for containers), rgba32f, rg11b10f,\n"
    "                       rgb9e5, rg16f, rg32f; rgba16 for 16-bit PNG\n"
    "  --exposure EV        exposure for 8-bit outputs (PNG/JPEG previews; filmic tone map)\n"
    "  --yaw DEG            rotate the environment about the up axis\n"
    "  --mirror             flip left-right\n"
    "  --z-up               the input was made with +Z up\n"
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

static const char *const face_suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};

static int write_faces(ibl_context *ctx, const ibl_cubemap *cube, const char *out,
                       const ibl_write_desc *wd)
{
    ibl_image faces[6];
    ibl_status st = ibl_cubemap_to_faces(ctx, cube, 0, faces);
    if (st != IBL_OK) {
        cli_error("%s: %s", out, ibl_context_message(ctx));
        return CLI_EXIT_BAD_INPUT;
    }
    const char *dot = strrchr(out, '.');
    size_t stem = dot ? (size_t)(dot - out) : strlen(out);
    int rc = CLI_EXIT_OK;
    for (int f = 0; f < 6 && rc == CLI_EXIT_OK; f++) {
        char path[4096];
        snprintf(path, sizeof path, "%.*s_%s%s", (int)stem, out, face_suffix[f], dot ? dot : "");
        if (ibl_write_image(ctx, path, &faces[f], wd) != IBL_OK) {
            cli_error("%s", ibl_context_message(ctx));
            rc = CLI_EXIT_BAD_INPUT;
        }
    }
    for (int f = 0; f < 6; f++) ibl_image_free(ctx, &faces[f]);
    return rc;
}

int cli_cmd_convert(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "convert", usage, {0}, {0}, 0};
    cli_input_options in = {0};
    const char *out = NULL;
    ibl_layout out_layout = IBL_LAYOUT_EQUIRECT;
    int faces = 0, mips = 0;
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    int exposure_given = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg) || cli_input_option(&a, arg, &in)) continue;
        if (cli_is(&a, arg, "--output", "-o")) out = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--size", NULL)) in.size = cli_int(&a, arg, 1, 16384);
        else if (cli_is(&a, arg, "--mips", NULL)) mips = 1;
        else if (cli_is(&a, arg, "--exposure", NULL)) {
            wd.exposure_ev = (float)cli_double(&a, arg, -50, 50);
            exposure_given = 1;
        }
        else if (cli_is(&a, arg, "--format", NULL)) {
            const char *v = cli_value(&a, arg);
            int ok = 0;
            ok = ibl_format_from_name(v, &wd.format);
            if (!ok) cli_usage_error(&a, "unknown pixel format '%s'", v);
        } else if (cli_is(&a, arg, "--out-layout", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "faces") == 0) faces = 1;
            else {
                if (!ibl_layout_from_name(v, &out_layout) || out_layout == IBL_LAYOUT_AUTO ||
                    out_layout == IBL_LAYOUT_CUBE || out_layout == IBL_LAYOUT_FACES)
                    cli_usage_error(&a, "unknown output layout '%s'", v);
            }
        } else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count != 1 && a.positional_count != 6)
        cli_usage_error(&a, "needs one input file, or six face images (+X -X +Y -Y +Z -Z)");
    if (!out) cli_usage_error(&a, "needs an output: -o OUT");
    const char *input = a.positional[0];
    ibl_file_type out_type = cli_check_output(&a, out);

    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_cubemap cube;
    int rc = a.positional_count == 6
                 ? cli_read_cubemap_faces(ctx, &a.common, a.positional, &in, &cube)
                 : cli_read_cubemap(ctx, &a.common, input, &in, &cube, NULL);
    if (rc != CLI_EXIT_OK) {
        ibl_context_destroy(ctx);
        return rc;
    }
    ibl_status st = IBL_OK;
    if (ibl_file_type_is_container(out_type)) {
        ibl_cubemap chain = cube;
        if (mips) {
            st = ibl_cubemap_alloc(ctx, cube.size, ibl_full_mip_count(cube.size), &chain);
            if (st == IBL_OK) {
                memcpy(chain.data, cube.data, ibl_cubemap_floats(cube.size, 1) * sizeof(float));
                st = ibl_cubemap_build_mips(ctx, &chain);
            }
        }
        if (st == IBL_OK) {
            ibl_texture tex = ibl_texture_from_cubemap(&chain);
            ibl_texture_set_metadata(ctx, &tex, "ibl.source", input);
            st = ibl_write_texture(ctx, out, &tex, &wd);
            ibl_texture_free(ctx, &tex);
        }
        if (mips) ibl_cubemap_free(ctx, &chain);
        if (st != IBL_OK) cli_error("%s", ibl_context_message(ctx));
    } else if (faces) {
        rc = write_faces(ctx, &cube, out, &wd);
    } else {
        ibl_from_cube_desc fd;
        memset(&fd, 0, sizeof fd);
        fd.layout = out_layout;
        ibl_image image;
        st = ibl_cubemap_to_image(ctx, &cube, &fd, &image);
        if (st == IBL_OK) {
            if (!exposure_given && cli_is_display_format(out)) wd.exposure_ev = cli_auto_exposure(&image);
            st = ibl_write_image(ctx, out, &image, &wd);
            ibl_image_free(ctx, &image);
        }
        if (st != IBL_OK) cli_error("%s", ibl_context_message(ctx));
    }
    if (st != IBL_OK && rc == CLI_EXIT_OK) rc = CLI_EXIT_BAD_INPUT;
    if (rc == CLI_EXIT_OK)
        cli_info(&a.common, "wrote %s (%dx%d faces) in %.0f ms\n", out, cube.size, cube.size,
                 (cli_seconds() - t0) * 1000.0);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
    return rc;
}
