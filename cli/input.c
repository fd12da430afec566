#include "input.h"

#include <math.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

int cli_input_option(cli_args *a, const char *arg, cli_input_options *o)
{
    if (cli_is(a, arg, "--layout", NULL)) {
        const char *v = cli_value(a, arg);
        if (!ibl_layout_from_name(v, &o->layout))
            cli_usage_error(a, "unknown layout '%s' (equirect, hcross, vcross, hstrip, vstrip, "
                               "angular, octahedral, auto)", v);
        return 1;
    }
    if (cli_is(a, arg, "--yaw", NULL)) {
        o->orientation.yaw_degrees = (float)cli_double(a, arg, -3600, 3600);
        return 1;
    }
    if (cli_is(a, arg, "--mirror-input", NULL)) {
        o->orientation.mirror = 1;
        return 1;
    }
    if (cli_is(a, arg, "--z-up", NULL)) {
        o->orientation.z_up = 1;
        return 1;
    }
    return 0;
}

/* The face edge a flat input's pixels carry: its pixels per 90 degrees at the horizon for
 * the sphere layouts (equirect, angular: W/4; octahedral: centre to edge, W/2, spans 90
 * degrees), a cell's edge for the cube layouts. */
static int layout_detail(ibl_layout layout, int width, int height)
{
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT:
    case IBL_LAYOUT_ANGULAR: return width / 4;
    case IBL_LAYOUT_OCTAHEDRAL: return width / 2;
    case IBL_LAYOUT_HCROSS: return width / 4;
    case IBL_LAYOUT_VCROSS: return height / 4;
    case IBL_LAYOUT_HSTRIP: return width / 6;
    case IBL_LAYOUT_VSTRIP: return width;
    default: return 0; /* unknown: no warning */
    }
}

void cli_warn_upsampling(const cli_common *c, const char *path, const cli_input_options *o,
                         int out_size)
{
    if (o->detail > 0 && out_size > o->detail)
        cli_info(c, "ibl: warning: %s: a %d-texel cube from an input that carries about %d texels "
                    "per face edge; the extra texels are interpolated, not detail (use --size %d "
                    "or a larger input)\n", path, out_size, o->detail, o->detail);
}

int cli_input_cube_size(const cli_input_options *o, const ibl_file_info *info)
{
    if (info->kind == IBL_TEXTURE_CUBE) return o->size > 0 ? o->size : info->width;
    if (info->kind != IBL_TEXTURE_2D) return 0;
    int natural = ibl_layout_cube_size(o->layout, info->width, info->height);
    return natural > 0 && o->size > 0 ? o->size : natural;
}

int cli_read_cubemap(ibl_context *ctx, const cli_common *c, const char *path,
                     cli_input_options *o, ibl_cubemap *out, ibl_layout *layout_out)
{
    ibl_texture tex;
    memset(out, 0, sizeof *out);
    int rc = cli_read_input_texture(ctx, c, path, &tex);
    return rc == CLI_EXIT_OK ? cli_texture_to_cubemap(ctx, path, o, &tex, out, layout_out) : rc;
}

int cli_read_input_texture(ibl_context *ctx, const cli_common *c, const char *path, ibl_texture *tex)
{
    ibl_read_desc rd = {.clamp_infinite = c->clamp};
    ibl_file_info info;
    ibl_status st = ibl_read_texture(ctx, path, &rd, tex, &info);
#if defined(__GLIBC__)
    /* OpenEXR's decoders allocate with malloc (about three chunks a reader, one reader a
     * thread: 19 MB at the peak for a 1024x512 DWAB file on two threads) and free it all, but
     * glibc keeps the pages of its heaps for later mallocs that a command, whose large blocks
     * come from cli/arena.c, never makes: 3.5 MB of the 256 GGX chain's peak RSS on one thread,
     * 6.9 MB on two (docs/PERFORMANCE.md "At large sizes"). */
    malloc_trim(0);
#endif
    if (st != IBL_OK) {
        cli_error("%s", ibl_context_message(ctx));
        return cli_exit_code(st) == CLI_EXIT_USAGE ? CLI_EXIT_BAD_INPUT : cli_exit_code(st);
    }
    cli_report_pixels(c, path, &info.pixels);
    return CLI_EXIT_OK;
}

int cli_texture_to_cubemap(ibl_context *ctx, const char *path, cli_input_options *o,
                           ibl_texture *texture, ibl_cubemap *out, ibl_layout *layout_out)
{
    ibl_texture tex = *texture;
    ibl_status st;
    memset(out, 0, sizeof *out);
    if (tex.kind == IBL_TEXTURE_CUBE_ARRAY) {
        ibl_texture_free(ctx, &tex);
        cli_error("%s: a cube-map array of %d layers is not one environment ('ibl convert' "
                  "copies it to another container)", path, texture->depth);
        return CLI_EXIT_BAD_INPUT;
    }
    if (tex.kind == IBL_TEXTURE_CUBE) {
        ibl_cubemap view;
        ibl_cubemap_from_texture(&tex, &view);
        o->detail = view.size;
        int size = o->size > 0 ? o->size : view.size;
        st = ibl_cubemap_alloc(ctx, size, 1, out);
        int reoriented = o->orientation.mirror || o->orientation.z_up ||
                         o->orientation.yaw_degrees != 0.0f;
        if (st == IBL_OK && !reoriented) {
            if (size == view.size) memcpy(out->data, view.data, ibl_cubemap_floats(size, 1) * sizeof(float));
            else st = ibl_cubemap_resample(ctx, &view, out);
        } else if (st == IBL_OK) {
            /* a rotated or mirrored cube: bilinear samples of the source at each texel */
            for (int f = 0; f < 6; f++) {
                float *p = ibl_cubemap_face(out, 0, f);
                for (int y = 0; y < size; y++)
                    for (int x = 0; x < size; x++, p += 4) {
                        ibl_vec3 d = ibl_cube_texel_direction(f, size, x, y);
                        ibl_cubemap_sample_bilinear(&view, 0, ibl_orientation_invert(&o->orientation, d), p);
                    }
            }
        }
        if (layout_out) *layout_out = IBL_LAYOUT_CUBE;
        ibl_texture_free(ctx, &tex);
        if (st != IBL_OK) {
            cli_error("%s: %s", path, ibl_context_message(ctx));
            return CLI_EXIT_BAD_INPUT;
        }
        return CLI_EXIT_OK;
    }
    if (tex.kind != IBL_TEXTURE_2D) {
        ibl_texture_free(ctx, &tex);
        cli_error("%s: a 3D texture is not an environment", path);
        return CLI_EXIT_BAD_INPUT;
    }
    ibl_image image = {tex.width, tex.height, ibl_texture_level(&tex, 0, 0)};
    ibl_to_cube_desc d;
    memset(&d, 0, sizeof d);
    d.layout = o->layout ? o->layout : ibl_layout_detect(image.width, image.height);
    o->detail = layout_detail(d.layout, image.width, image.height);
    d.size = o->size;
    d.orientation = o->orientation;
    if (d.layout == IBL_LAYOUT_AUTO) {
        ibl_texture_free(ctx, &tex);
        cli_error("%s: cannot tell the layout of a %dx%d image (use --layout)", path, image.width,
                  image.height);
        return CLI_EXIT_BAD_INPUT;
    }
    st = ibl_image_to_cubemap(ctx, &image, &d, out);
    if (st == IBL_OK && o->chain) {
        st = ibl_specular_sources_create(ctx, &image, &d, out, o->chain, &o->sources);
        if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    }
    ibl_texture_free(ctx, &tex);
    if (st != IBL_OK) {
        cli_error("%s: %s", path, ibl_context_message(ctx));
        return CLI_EXIT_BAD_INPUT;
    }
    if (layout_out) *layout_out = d.layout;
    return CLI_EXIT_OK;
}

int cli_read_sky(ibl_context *ctx, const ibl_sky_desc *desc, const cli_input_options *o,
                 ibl_cubemap *out)
{
    int size = o->size > 0 ? o->size : 256;
    ibl_sky_desc d = {0};
    if (desc) d = *desc;
    if (!d.width) d.width = 4 * size; /* two equirect pixels per cube texel along the equator */
    ibl_image image;
    ibl_status st = ibl_sky_render(ctx, &d, &image);
    if (st == IBL_OK) {
        ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT, .size = size, .orientation = o->orientation};
        st = ibl_image_to_cubemap(ctx, &image, &cd, out);
        ibl_image_free(ctx, &image);
    }
    if (st != IBL_OK) cli_report_failure(ctx, "built-in sky", st);
    return cli_exit_code(st);
}

ibl_file_type cli_check_output(const cli_args *a, const char *output)
{
    ibl_file_type type = ibl_file_type_from_path(output);
    if (type == IBL_FILE_UNKNOWN)
        cli_usage_error(a, "cannot tell the container of %s from its extension", output);
    for (int i = 0; i < a->positional_count; i++) cli_check_distinct(a, a->positional[i], output);
    return type;
}

void cli_check_distinct(const cli_args *a, const char *input, const char *output)
{
    struct stat si, so;
    if (strcmp(input, output) == 0 ||
        (stat(input, &si) == 0 && stat(output, &so) == 0 && si.st_dev == so.st_dev &&
         si.st_ino == so.st_ino))
        cli_usage_error(a, "the output %s is the input file; choose another name", output);
}

int cli_read_cubemap_faces(ibl_context *ctx, const cli_common *c, const char *const paths[6],
                           const cli_input_options *o, ibl_cubemap *out)
{
    static const char *const names[6] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};
    ibl_read_desc rd = {.clamp_infinite = c->clamp};
    ibl_image faces[6];
    memset(faces, 0, sizeof faces);
    memset(out, 0, sizeof *out);
    int rc = CLI_EXIT_OK;
    for (int f = 0; f < 6 && rc == CLI_EXIT_OK; f++) {
        ibl_file_info info;
        ibl_status st = ibl_read_image(ctx, paths[f], &rd, &faces[f], &info);
        if (st != IBL_OK) {
            cli_error("%s", ibl_context_message(ctx));
            rc = CLI_EXIT_BAD_INPUT;
            break;
        }
        cli_report_pixels(c, paths[f], &info.pixels);
        /* name the file, not just the face, when the sizes do not fit together */
        if (faces[f].width != faces[f].height) {
            cli_error("%s: the %s face is %dx%d; faces must be square", paths[f], names[f],
                      faces[f].width, faces[f].height);
            rc = CLI_EXIT_BAD_INPUT;
        } else if (f > 0 && faces[f].width != faces[0].width) {
            cli_error("%s: the %s face is %dx%d but %s is %dx%d; all faces must have one size",
                      paths[f], names[f], faces[f].width, faces[f].height, paths[0],
                      faces[0].width, faces[0].height);
            rc = CLI_EXIT_BAD_INPUT;
        }
    }
    if (rc == CLI_EXIT_OK) {
        ibl_to_cube_desc d;
        memset(&d, 0, sizeof d);
        d.size = o->size;
        d.orientation = o->orientation;
        if (ibl_faces_to_cubemap(ctx, faces, &d, out) != IBL_OK) {
            cli_error("%s: %s", paths[0], ibl_context_message(ctx));
            rc = CLI_EXIT_BAD_INPUT;
        }
    }
    for (int f = 0; f < 6; f++) ibl_image_free(ctx, &faces[f]);
    return rc;
}

void cli_check_not_inside(const cli_args *a, const char *input, const char *folder)
{
    char parent[4096];
    const char *slash = strrchr(input, '/');
    if (slash) snprintf(parent, sizeof parent, "%.*s", (int)(slash - input + 1), input);
    else snprintf(parent, sizeof parent, ".");
    struct stat si, sf;
    if (stat(input, &si) == 0 && stat(parent, &si) == 0 && stat(folder, &sf) == 0 &&
        si.st_dev == sf.st_dev && si.st_ino == sf.st_ino)
        cli_usage_error(a, "the input %s is inside %s, which the bake replaces whole; move it or "
                           "bake elsewhere", input, folder);
}

/* The "format" value of a manifest file (first 4 KiB), or "" when it has none; -1 when the
 * file cannot be read (absent). */
static int manifest_format(const char *path, char *format, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    char head[4096];
    size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[n] = 0;
    format[0] = 0;
    const char *key = strstr(head, "\"format\"");
    if (!key) return 0;
    const char *q = strchr(key + 8, '"');
    const char *end = q ? strchr(q + 1, '"') : NULL;
    if (q && end && (size_t)(end - q - 1) < cap) snprintf(format, cap, "%.*s", (int)(end - q - 1), q + 1);
    return 0;
}

void cli_check_not_in_bake(const cli_args *a, const char *output)
{
    char manifest[4200], format[64];
    const char *slash = strrchr(output, '/');
    if (slash) snprintf(manifest, sizeof manifest, "%.*smanifest.json", (int)(slash - output + 1), output);
    else snprintf(manifest, sizeof manifest, "manifest.json");
    if (manifest_format(manifest, format, sizeof format) == 0 && strcmp(format, "ibl-bake") == 0)
        cli_usage_error(a, "%s: its folder is a bake (%s); only 'ibl bake' writes there, so write "
                           "this output elsewhere", output, manifest);
}

void cli_check_manifest_replaceable(const cli_args *a, const char *path, const char *format)
{
    char found[64];
    if (manifest_format(path, found, sizeof found) == 0 && strcmp(found, format) != 0)
        cli_usage_error(a, "%s exists and is not an %s manifest (%s); it is not replaced: choose "
                           "another output name", path, format, found[0] ? found : "no format");
}
