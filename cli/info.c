/* ibl info: what a file holds and what its pixels look like. */
#include "input.h"
#include "core/numeric.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl info FILE [--layout L] [--json]\n"
    "\n"
    "Prints the size, layout, pixel format, mip levels, min/max/mean per channel, the\n"
    "solid-angle-weighted mean radiance (what a white diffuse sphere would average), the counts\n"
    "of NaN/infinite/negative pixels and the metadata of an image or texture.\n"
    "\n"
    "  --layout L   layout of a flat image (default: from the aspect ratio)\n"
    "  --json       one JSON object on stdout\n";


/* Solid-angle-weighted mean of an equirect image: each row's pixels subtend
 * (2 pi / W) (cos theta0 - cos theta1). */
static void equirect_mean(const ibl_image *im, double out[3])
{
    double acc[3] = {0, 0, 0}, wsum = 0;
    for (int y = 0; y < im->height; y++) {
        double t0 = IBL_PI * y / im->height, t1 = IBL_PI * (y + 1) / im->height;
        double w = 2.0 * IBL_PI / im->width * (cos(t0) - cos(t1));
        const float *p = ibl_image_texel(im, 0, y);
        double row[3] = {0, 0, 0};
        for (int x = 0; x < im->width; x++, p += 4)
            for (int c = 0; c < 3; c++) row[c] += p[c];
        for (int c = 0; c < 3; c++) acc[c] += w * row[c];
        wsum += w * im->width;
    }
    for (int c = 0; c < 3; c++) out[c] = acc[c] / wsum;
}

static void json_string(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\') printf("\\%c", ch);
        else if (ch < 0x20) printf("\\u%04x", ch);
        else putchar(ch);
    }
    putchar('"');
}

int cli_cmd_info(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "info", usage, {0}, {0}, 0};
    cli_input_options in = {0};
    int json = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg) || cli_input_option(&a, arg, &in)) continue;
        if (cli_is(&a, arg, "--json", NULL)) json = 1;
        else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count != 1) cli_usage_error(&a, "needs exactly one file");
    const char *path = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    ibl_read_desc rd = {1, 0}; /* report infinities instead of refusing */
    ibl_texture tex;
    ibl_file_info info;
    ibl_status st = ibl_read_texture(ctx, path, &rd, &tex, &info);
    if (st != IBL_OK) {
        cli_error("%s", ibl_context_message(ctx));
        ibl_context_destroy(ctx);
        return CLI_EXIT_BAD_INPUT;
    }
    /* per-channel statistics over level 0 (all faces and slices) */
    size_t texels = (size_t)tex.width * tex.height * (tex.kind == IBL_TEXTURE_3D ? tex.depth : 1) *
                    (size_t)ibl_texture_faces(&tex);
    const float *p = ibl_texture_level(&tex, 0, 0);
    double mn[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, mx[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY}, mean[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < texels; i++)
        for (int c = 0; c < 4; c++) {
            double v = p[i * 4 + c];
            if (v < mn[c]) mn[c] = v;
            if (v > mx[c]) mx[c] = v;
            mean[c] += v;
        }
    for (int c = 0; c < 4; c++) mean[c] /= (double)texels;

    ibl_layout layout = IBL_LAYOUT_AUTO;
    double radiance[3] = {NAN, NAN, NAN};
    if (tex.kind == IBL_TEXTURE_CUBE) {
        ibl_cubemap view;
        ibl_cubemap_from_texture(&tex, &view);
        double m[4];
        ibl_cubemap_mean(&view, 0, m);
        memcpy(radiance, m, sizeof radiance);
        layout = IBL_LAYOUT_CUBE;
    } else if (tex.kind == IBL_TEXTURE_2D) {
        layout = in.layout ? in.layout : ibl_layout_detect(tex.width, tex.height);
        ibl_image im = {tex.width, tex.height, ibl_texture_level(&tex, 0, 0)};
        if (layout == IBL_LAYOUT_EQUIRECT) {
            equirect_mean(&im, radiance);
        } else if (layout != IBL_LAYOUT_AUTO) {
            ibl_to_cube_desc d;
            memset(&d, 0, sizeof d);
            d.layout = layout;
            ibl_cubemap cube;
            if (ibl_image_to_cubemap(ctx, &im, &d, &cube) == IBL_OK) {
                double m[4];
                ibl_cubemap_mean(&cube, 0, m);
                memcpy(radiance, m, sizeof radiance);
                ibl_cubemap_free(ctx, &cube);
            }
        }
    }
    const char *kind = tex.kind == IBL_TEXTURE_CUBE ? "cube" : tex.kind == IBL_TEXTURE_3D ? "3d" : "2d";
    const char *layout_name = layout == IBL_LAYOUT_AUTO ? "unknown" : ibl_layout_name(layout);
    /* Rec.709 luminance of the mean radiance */
    double luminance = 0.2126 * radiance[0] + 0.7152 * radiance[1] + 0.0722 * radiance[2];
    if (json) {
        printf("{\"file\": ");
        json_string(path);
        printf(", \"type\": \"%s\", \"kind\": \"%s\", \"width\": %d, \"height\": %d, \"depth\": %d, "
               "\"levels\": %d, \"format\": \"%s\", \"layout\": \"%s\",\n",
               ibl_file_type_name(info.type), kind, tex.width, tex.height, tex.depth, tex.levels,
               ibl_format_name(info.format), layout_name);
        printf(" \"min\": [%.9g, %.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g, %.9g], "
               "\"mean\": [%.9g, %.9g, %.9g, %.9g],\n",
               mn[0], mn[1], mn[2], mn[3], mx[0], mx[1], mx[2], mx[3], mean[0], mean[1], mean[2], mean[3]);
        if (isnan(radiance[0])) printf(" \"mean_radiance\": null, \"mean_luminance\": null,\n");
        else printf(" \"mean_radiance\": [%.9g, %.9g, %.9g], \"mean_luminance\": %.9g,\n",
                    radiance[0], radiance[1], radiance[2], luminance);
        printf(" \"nan_texels\": %llu, \"inf_texels\": %llu, \"negative_texels\": %llu,\n",
               (unsigned long long)info.pixels.nan_count, (unsigned long long)info.pixels.inf_count,
               (unsigned long long)info.pixels.negative_count);
        printf(" \"metadata\": {");
        for (int i = 0; i < tex.metadata_count; i++) {
            printf(i ? ", " : "");
            json_string(tex.metadata[i].key);
            printf(": ");
            json_string(tex.metadata[i].value);
        }
        printf("}}\n");
    } else {
        printf("file:            %s\n", path);
        printf("container:       %s\n", ibl_file_type_name(info.type));
        printf("kind:            %s\n", kind);
        if (tex.kind == IBL_TEXTURE_3D) printf("size:            %dx%dx%d\n", tex.width, tex.height, tex.depth);
        else printf("size:            %dx%d%s\n", tex.width, tex.height, tex.kind == IBL_TEXTURE_CUBE ? " per face" : "");
        printf("layout:          %s\n", layout_name);
        printf("pixel format:    %s\n", ibl_format_name(info.format));
        printf("mip levels:      %d\n", tex.levels);
        printf("min (RGBA):      %.6g %.6g %.6g %.6g\n", mn[0], mn[1], mn[2], mn[3]);
        printf("max (RGBA):      %.6g %.6g %.6g %.6g\n", mx[0], mx[1], mx[2], mx[3]);
        printf("mean (RGBA):     %.6g %.6g %.6g %.6g   (per texel)\n", mean[0], mean[1], mean[2], mean[3]);
        if (isnan(radiance[0])) printf("mean radiance:   n/a (layout unknown; use --layout)\n");
        else printf("mean radiance:   %.6g %.6g %.6g   (solid-angle weighted; luminance %.6g)\n",
                    radiance[0], radiance[1], radiance[2], luminance);
        printf("NaN texels:      %llu (read as 0)\n", (unsigned long long)info.pixels.nan_count);
        printf("infinite texels: %llu%s\n", (unsigned long long)info.pixels.inf_count,
               info.pixels.inf_count ? " (other commands refuse them without --clamp)" : "");
        printf("negative texels: %llu (read as 0)\n", (unsigned long long)info.pixels.negative_count);
        for (int i = 0; i < tex.metadata_count; i++)
            printf("metadata:        %s = %s\n", tex.metadata[i].key, tex.metadata[i].value);
    }
    ibl_texture_free(ctx, &tex);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
