/* ibl info: what a file holds and what its pixels look like. */
#include "input.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl info FILE [--layout L] [--json]\n"
    "\n"
    "Prints the size, layout, pixel format, mip levels, min/max/mean per channel, the\n"
    "solid-angle-weighted mean radiance (what a white diffuse sphere would average), the counts\n"
    "of NaN/infinite/negative pixels and the metadata of an image or texture; for a cube-map\n"
    "array (KTX2 or DDS) the layer count and each layer's mean radiance.\n"
    "\n"
    "  --layout L   layout of a flat image (default: from the aspect ratio)\n"
    "  --json       one JSON object on stdout\n"
    "  -q, -j N, --max-memory MiB: see 'ibl --help' (infinite pixels are counted, not refused)\n";

typedef struct file_stats {
    double min[4], max[4], mean[4];
    double radiance[3]; /* solid-angle weighted; NaN when the layout is unknown */
    ibl_layout layout;
    int layers;              /* cube-map arrays: the layer count; else 0 */
    double *layer_radiance;  /* cube-map arrays: 3 per layer (malloc) */
} file_stats;

/* Per-channel statistics over level 0 (every face and slice) and the mean radiance. */
static void measure(ibl_context *ctx, const ibl_texture *tex, ibl_layout asked, file_stats *s)
{
    size_t texels = (size_t)tex->width * tex->height * (tex->kind == IBL_TEXTURE_3D ? tex->depth : 1) *
                    (size_t)ibl_texture_faces(tex);
    const float *p = ibl_texture_level(tex, 0, 0);
    for (int c = 0; c < 4; c++) s->min[c] = INFINITY, s->max[c] = -INFINITY, s->mean[c] = 0;
    for (size_t i = 0; i < texels; i++)
        for (int c = 0; c < 4; c++) {
            double v = p[i * 4 + c];
            s->min[c] = v < s->min[c] ? v : s->min[c];
            s->max[c] = v > s->max[c] ? v : s->max[c];
            s->mean[c] += v;
        }
    for (int c = 0; c < 4; c++) s->mean[c] /= (double)texels;
    s->radiance[0] = s->radiance[1] = s->radiance[2] = NAN;
    s->layout = IBL_LAYOUT_AUTO;
    double m[4];
    if (tex->kind == IBL_TEXTURE_CUBE_ARRAY) {
        /* each layer's mean radiance, and their mean */
        s->layers = tex->depth;
        s->layer_radiance = calloc((size_t)tex->depth * 3, sizeof *s->layer_radiance);
        s->layout = IBL_LAYOUT_CUBE;
        if (!s->layer_radiance) return;
        for (int c = 0; c < 3; c++) s->radiance[c] = 0.0;
        for (int i = 0; i < tex->depth; i++) {
            ibl_texture one = *tex;
            one.kind = IBL_TEXTURE_CUBE;
            one.depth = 1;
            one.levels = 1;
            one.data = ibl_texture_level(tex, 0, 6 * i);
            ibl_cubemap view;
            ibl_cubemap_from_texture(&one, &view);
            ibl_cubemap_mean(&view, 0, m);
            for (int c = 0; c < 3; c++) {
                s->layer_radiance[3 * i + c] = m[c];
                s->radiance[c] += m[c] / tex->depth;
            }
        }
    } else if (tex->kind == IBL_TEXTURE_CUBE) {
        ibl_cubemap view;
        ibl_cubemap_from_texture(tex, &view);
        ibl_cubemap_mean(&view, 0, m);
        memcpy(s->radiance, m, sizeof s->radiance);
        s->layout = IBL_LAYOUT_CUBE;
    } else if (tex->kind == IBL_TEXTURE_2D) {
        s->layout = asked ? asked : ibl_layout_detect(tex->width, tex->height);
        ibl_image im = {tex->width, tex->height, ibl_texture_level(tex, 0, 0)};
        if (s->layout != IBL_LAYOUT_AUTO && ibl_image_mean(ctx, &im, s->layout, m) == IBL_OK)
            memcpy(s->radiance, m, sizeof s->radiance);
    }
}

static const char *kind_name(const ibl_texture *tex)
{
    return tex->kind == IBL_TEXTURE_CUBE         ? "cube"
           : tex->kind == IBL_TEXTURE_CUBE_ARRAY ? "cube-array"
           : tex->kind == IBL_TEXTURE_3D         ? "3d"
                                                 : "2d";
}

static const char *layout_name(ibl_layout layout)
{
    return layout == IBL_LAYOUT_AUTO ? "unknown" : ibl_layout_name(layout);
}

/* A JSON string of bytes that may not be UTF-8 (a path): as is when valid, else with every
 * byte above 0x7F shown as '?'. */
static json_t *any_string(const char *s)
{
    json_t *v = json_string(s);
    if (v) return v;
    char *copy = strdup(s);
    if (!copy) return NULL;
    for (char *p = copy; *p; p++)
        if ((unsigned char)*p >= 0x80) *p = '?';
    v = json_string(copy);
    free(copy);
    return v;
}

static json_t *numbers(const double *v, int n)
{
    json_t *a = json_array();
    for (int i = 0; i < n; i++) json_array_append_new(a, isfinite(v[i]) ? json_real(v[i]) : json_null());
    return a;
}

static void print_json(const char *path, const ibl_texture *tex, const ibl_file_info *info,
                       const file_stats *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "file", any_string(path));
    json_object_set_new(o, "type", json_string(ibl_file_type_name(info->type)));
    json_object_set_new(o, "kind", json_string(kind_name(tex)));
    json_object_set_new(o, "width", json_integer(tex->width));
    json_object_set_new(o, "height", json_integer(tex->height));
    json_object_set_new(o, "depth", json_integer(tex->kind == IBL_TEXTURE_3D ? tex->depth : 1));
    json_object_set_new(o, "layers", json_integer(s->layers));
    json_object_set_new(o, "levels", json_integer(tex->levels));
    json_object_set_new(o, "format", json_string(ibl_format_name(info->format)));
    json_object_set_new(o, "layout", json_string(layout_name(s->layout)));
    json_object_set_new(o, "min", numbers(s->min, 4));
    json_object_set_new(o, "max", numbers(s->max, 4));
    json_object_set_new(o, "mean", numbers(s->mean, 4));
    int known = !isnan(s->radiance[0]);
    double luminance = 0.2126 * s->radiance[0] + 0.7152 * s->radiance[1] + 0.0722 * s->radiance[2];
    json_object_set_new(o, "mean_radiance", known ? numbers(s->radiance, 3) : json_null());
    json_object_set_new(o, "mean_luminance", known ? json_real(luminance) : json_null());
    if (s->layers && s->layer_radiance) {
        json_t *layers = json_array();
        for (int i = 0; i < s->layers; i++)
            json_array_append_new(layers, numbers(s->layer_radiance + 3 * i, 3));
        json_object_set_new(o, "layer_mean_radiance", layers);
    }
    json_object_set_new(o, "nan_texels", json_integer((json_int_t)info->pixels.nan_count));
    json_object_set_new(o, "inf_texels", json_integer((json_int_t)info->pixels.inf_count));
    json_object_set_new(o, "negative_texels", json_integer((json_int_t)info->pixels.negative_count));
    json_t *meta = json_object();
    for (int i = 0; i < tex->metadata_count; i++)
        json_object_set_new(meta, tex->metadata[i].key, any_string(tex->metadata[i].value));
    json_object_set_new(o, "metadata", meta);
    char *text = json_dumps(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(9));
    if (text) puts(text);
    free(text);
    json_decref(o);
}

static void print_text(const char *path, const ibl_texture *tex, const ibl_file_info *info,
                       const file_stats *s)
{
    printf("file:            %s\n", path);
    printf("container:       %s\n", ibl_file_type_name(info->type));
    printf("kind:            %s\n", kind_name(tex));
    if (tex->kind == IBL_TEXTURE_3D) printf("size:            %dx%dx%d\n", tex->width, tex->height, tex->depth);
    else printf("size:            %dx%d%s\n", tex->width, tex->height, tex->kind == IBL_TEXTURE_2D ? "" : " per face");
    if (s->layers) printf("layers:          %d cubes\n", s->layers);
    printf("layout:          %s\n", layout_name(s->layout));
    printf("pixel format:    %s\n", ibl_format_name(info->format));
    printf("mip levels:      %d\n", tex->levels);
    printf("min (RGBA):      %.6g %.6g %.6g %.6g\n", s->min[0], s->min[1], s->min[2], s->min[3]);
    printf("max (RGBA):      %.6g %.6g %.6g %.6g\n", s->max[0], s->max[1], s->max[2], s->max[3]);
    printf("mean (RGBA):     %.6g %.6g %.6g %.6g   (per texel)\n", s->mean[0], s->mean[1], s->mean[2], s->mean[3]);
    const double *r = s->radiance;
    if (isnan(r[0])) printf("mean radiance:   n/a (layout unknown; use --layout)\n");
    else printf("mean radiance:   %.6g %.6g %.6g   (solid-angle weighted; luminance %.6g)%s\n", r[0],
                r[1], r[2], 0.2126 * r[0] + 0.7152 * r[1] + 0.0722 * r[2],
                s->layers ? " (mean of the layers)" : "");
    for (int i = 0; s->layer_radiance && i < s->layers; i++)
        printf("  layer %-8d %.6g %.6g %.6g\n", i, s->layer_radiance[3 * i],
               s->layer_radiance[3 * i + 1], s->layer_radiance[3 * i + 2]);
    printf("NaN texels:      %llu (read as 0)\n", (unsigned long long)info->pixels.nan_count);
    printf("infinite texels: %llu%s\n", (unsigned long long)info->pixels.inf_count,
           info->pixels.inf_count ? " (other commands refuse them without --clamp)" : "");
    printf("negative texels: %llu (read as 0)\n", (unsigned long long)info->pixels.negative_count);
    for (int i = 0; i < tex->metadata_count; i++)
        printf("metadata:        %s = %s\n", tex->metadata[i].key, tex->metadata[i].value);
}

int cli_cmd_info(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "info", usage, {0}, {0}, 0};
    ibl_layout layout = IBL_LAYOUT_AUTO;
    int json = 0;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--layout", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_layout_from_name(v, &layout)) cli_usage_error(&a, "unknown layout '%s'", v);
        } else if (cli_flag(&a, arg, "--json", NULL)) {
            json = 1;
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "needs exactly one file");
    const char *path = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    ibl_read_desc rd = {.clamp_infinite = 1}; /* report infinities instead of refusing */
    ibl_texture tex;
    ibl_file_info info;
    ibl_status st = ibl_read_texture(ctx, path, &rd, &tex, &info);
    if (st != IBL_OK) {
        cli_report_failure(ctx, path, st);
        ibl_context_destroy(ctx);
        return CLI_EXIT_BAD_INPUT;
    }
    file_stats s = {0};
    measure(ctx, &tex, layout, &s);
    if (json) print_json(path, &tex, &info, &s);
    else print_text(path, &tex, &info, &s);
    free(s.layer_radiance);
    ibl_texture_free(ctx, &tex);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
