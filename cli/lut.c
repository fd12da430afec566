/* ibl lut: BRDF lookup tables (split-sum GGX, multiple-scattering, sheen, tri-Ace
 * AmbientBRDF) to KTX2 / KTX / DDS / PNG / EXR / HDR / PFM, a C header or a text table. */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char usage[] =
    "usage: ibl lut -o FILE [options]\n"
    "\n"
    "Writes a BRDF lookup table. Texel (i, j) holds the value at the texel centre\n"
    "((i + 0.5) / N, (j + 0.5) / N); row 0 (top) is roughness ~ 0 (or the smallest shininess).\n"
    "\n"
    "  -o, --output FILE        .ktx2 .ktx .dds (texture), .png (16-bit) .exr .hdr .pfm (image),\n"
    "                           .h (C header) or any other name (text table: x y values)\n"
    "  --kind K                 splitsum (default): RG = (A, B), specular = F0*A + F90*B,\n"
    "                             GGX with height-correlated Smith visibility\n"
    "                           splitsum-separable: the same with Schlick-GGX k = alpha/2 (UE4)\n"
    "                           multiscatter: RG = (E, E_avg), directional albedo and its average\n"
    "                           sheen: RG = (E, E_avg) of the Charlie sheen lobe\n"
    "                           sheen-khr: RG = (E, E_avg) of KHR_materials_sheen's BRDF (Charlie\n"
    "                             visibility of Conty Estevez & Kulla 2017, alpha = y)\n"
    "                           ambient-brdf: tri-Ace AmbientBRDF volume, U = n.v, V = shininess,\n"
    "                             W = F0; R = specular albedo, G = exact diffuse factor 1 - F0\n"
    "  --size N                 texels per axis (default 128; ambient-brdf: n.v and shininess, 32)\n"
    "  --channels LIST          split-sum kinds: up to 4 of a,b,e,eavg,sheen,sheenavg,\n"
    "                           sheenkhr,sheenkhravg,0,1\n"
    "  --shininess-range A:B    ambient-brdf shininess range (default 1:2000)\n"
    "  --shininess-spacing S    log (default) or linear\n"
    "  --f0-steps K             ambient-brdf F0 slices (default 16)\n"
    "  --compact                ambient-brdf: the 2D form RG = (X, Y), AmbientBRDF = F0*X + Y\n"
    "  --normalization N        ambient-brdf: triace (tri-Ace 2010's linear fit 0.0397436 s +\n"
    "                           0.0856832, default) or exact\n"
    "  --format F               rg16f (default for 2 channels in .ktx2/.ktx/.dds), rg32f,\n"
    "                           rgba16f, rgba32f; PNG: rgba16 (default); EXR: rgb32f (default),\n"
    "                           rgb16f, rgba16f, rgba32f\n"
    "  --symbol NAME            array name in a C header (default ibl_brdf_lut)\n"
    "  --order N                quadrature size (default 24; raise to check)\n"
    "\n"
    "Flat images (.png .exr .hdr .pfm) of the 3D ambient-brdf volume stack the F0 slices\n"
    "top to bottom. See docs/BRDF.md for the maths and the shader code.\n";

typedef enum lut_kind {
    KIND_SPLITSUM, KIND_SEPARABLE, KIND_MULTISCATTER, KIND_SHEEN, KIND_SHEEN_KHR, KIND_AMBIENT
} lut_kind;

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

static int parse_channels(const char *list, ibl_brdf_channel out[4])
{
    static const struct {
        const char *name;
        ibl_brdf_channel ch;
    } names[] = {{"a", IBL_BRDF_SCALE},       {"b", IBL_BRDF_BIAS},
                 {"e", IBL_BRDF_ALBEDO},      {"eavg", IBL_BRDF_ALBEDO_AVG},
                 {"sheen", IBL_BRDF_SHEEN},   {"sheenavg", IBL_BRDF_SHEEN_AVG},
                 {"sheenkhr", IBL_BRDF_SHEEN_KHR}, {"sheenkhravg", IBL_BRDF_SHEEN_KHR_AVG},
                 {"0", IBL_BRDF_ZERO},        {"1", IBL_BRDF_ONE}};
    char buf[128];
    if (strlen(list) >= sizeof buf) return 0;
    strcpy(buf, list);
    int n = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        if (n == 4) return 0;
        size_t k = 0;
        while (k < sizeof names / sizeof names[0] && strcmp(names[k].name, tok) != 0) k++;
        if (k == sizeof names / sizeof names[0]) return 0;
        out[n++] = names[k].ch;
    }
    return n;
}

/* Largest value written, to warn when a [0, 1] format clips. */
static float max_value(const float *px, size_t texels, int channels)
{
    float m = 0;
    for (size_t i = 0; i < texels; i++)
        for (int c = 0; c < channels; c++)
            if (px[i * 4 + c] > m) m = px[i * 4 + c];
    return m;
}

typedef struct lut_options {
    const char *out, *symbol, *channels;
    lut_kind kind;
    int size, compact;
    ibl_ambient_brdf_desc ambient;
    ibl_write_desc wd;
    int text; /* a C header or text table */
} lut_options;

static lut_kind kind_from_name(cli_args *a, const char *k)
{
    static const struct {
        const char *name;
        lut_kind kind;
    } kinds[] = {{"splitsum", KIND_SPLITSUM},         {"splitsum-separable", KIND_SEPARABLE},
                 {"multiscatter", KIND_MULTISCATTER}, {"sheen", KIND_SHEEN}, {"sheen-khr", KIND_SHEEN_KHR},
                 {"ambient-brdf", KIND_AMBIENT}};
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        if (strcmp(k, kinds[i].name) == 0) return kinds[i].kind;
    cli_usage_error(a, "unknown --kind '%s' (splitsum, splitsum-separable, multiscatter, sheen, "
                       "sheen-khr, ambient-brdf)", k);
}

/* The AmbientBRDF options; returns 1 if arg was one of them. */
static int ambient_option(cli_args *a, const char *arg, lut_options *o)
{
    ibl_ambient_brdf_desc *d = &o->ambient;
    if (cli_is(a, arg, "--f0-steps", NULL)) {
        d->size_f0 = cli_int(a, arg, 1, 1024);
    } else if (cli_is(a, arg, "--shininess-range", NULL)) {
        const char *v = cli_value(a, arg);
        char *end = NULL;
        d->shininess_min = strtod(v, &end);
        const char *b = end && *end == ':' ? end + 1 : NULL;
        if (b) d->shininess_max = strtod(b, &end);
        if (!b || !*b || *end || !(d->shininess_min > 0) || !(d->shininess_max > d->shininess_min) ||
            !(d->shininess_max <= 1e6))
            cli_usage_error(a, "--shininess-range wants A:B with 0 < A < B <= 1e6, not '%s'", v);
    } else if (cli_is(a, arg, "--shininess-spacing", NULL)) {
        const char *v = cli_value(a, arg);
        if (strcmp(v, "log") == 0) d->spacing = IBL_SHININESS_LOG;
        else if (strcmp(v, "linear") == 0) d->spacing = IBL_SHININESS_LINEAR;
        else cli_usage_error(a, "--shininess-spacing wants log or linear, not '%s'", v);
    } else if (cli_is(a, arg, "--normalization", NULL)) {
        const char *v = cli_value(a, arg);
        if (strcmp(v, "triace") == 0) d->normalization = IBL_BLINN_TRIACE_FIT;
        else if (strcmp(v, "exact") == 0) d->normalization = IBL_BLINN_EXACT;
        else cli_usage_error(a, "--normalization wants triace or exact, not '%s'", v);
    } else if (cli_flag(a, arg, "--compact", NULL)) {
        o->compact = 1;
    } else {
        return 0;
    }
    return 1;
}

static void parse(cli_args *a, lut_options *o)
{
    const char *arg, *format = NULL;
    int ambient = 0;
    while ((arg = cli_next(a)) != NULL) {
        if (cli_common_option(a, arg)) continue;
        if (ambient_option(a, arg, o)) ambient = 1;
        else if (cli_is(a, arg, "--output", "-o")) o->out = cli_value(a, arg);
        else if (cli_is(a, arg, "--kind", NULL)) o->kind = kind_from_name(a, cli_value(a, arg));
        else if (cli_is(a, arg, "--size", NULL)) o->size = cli_int(a, arg, 1, 4096);
        else if (cli_is(a, arg, "--channels", NULL)) o->channels = cli_value(a, arg);
        else if (cli_is(a, arg, "--format", NULL)) format = cli_value(a, arg);
        else if (cli_is(a, arg, "--symbol", NULL)) o->symbol = cli_value(a, arg);
        else if (cli_is(a, arg, "--order", NULL)) o->ambient.order = cli_int(a, arg, 4, 192);
        else cli_positional_or_unknown(a, arg);
    }
    if (a->positional_count) cli_usage_error(a, "unexpected argument '%s'", a->positional[0]);
    if (!o->out) cli_usage_error(a, "missing -o FILE");
    if (ambient && o->kind != KIND_AMBIENT)
        cli_usage_error(a, "--shininess-*, --f0-steps, --compact and --normalization need "
                           "--kind ambient-brdf");
    if (o->channels && o->kind == KIND_AMBIENT)
        cli_usage_error(a, "--channels applies to the split-sum kinds only");
    ibl_file_type type = ibl_file_type_from_path(o->out);
    o->text = type == IBL_FILE_UNKNOWN;
    if (format && !ibl_format_from_name(format, &o->wd.format))
        cli_usage_error(a, "unknown --format '%s'", format);
    if (format && o->text) cli_usage_error(a, "--format does not apply to C headers and text tables");
    if (!o->text && !ibl_file_type_writes_format(type, o->wd.format))
        cli_usage_error(a, "%s cannot store %s pixels", o->out, ibl_format_name(o->wd.format));
    if (o->symbol && !ends_with(o->out, ".h")) cli_usage_error(a, "--symbol applies to .h outputs only");
    if (o->wd.format == IBL_FORMAT_DEFAULT && type == IBL_FILE_PNG) o->wd.format = IBL_FORMAT_RGBA16_UNORM;
}

/* The AmbientBRDF volume (or its compact 2D form) into tex / img, with its description. */
static ibl_status compute_ambient(ibl_context *ctx, lut_options *o, ibl_texture *tex,
                                  ibl_image *img, char *comment, size_t cap)
{
    ibl_ambient_brdf_desc *d = &o->ambient;
    d->size_nv = d->size_shininess = o->size;
    snprintf(comment, cap,
             "tri-Ace 2010 AmbientBRDF, %s normalisation, shininess %g..%g %s spacing.\n%s",
             d->normalization == IBL_BLINN_EXACT ? "exact" : "triace",
             d->shininess_min > 0 ? d->shininess_min : 1.0,
             d->shininess_max > 0 ? d->shininess_max : 2000.0,
             d->spacing == IBL_SHININESS_LINEAR ? "linear" : "log",
             o->compact ? "x = n.v, y = shininess row; channels X, Y: AmbientBRDF = F0 * X + Y"
                        : "x = n.v, y = shininess row, z = F0 slice; channels: specular, diffuse "
                          "factor (1 - F0)");
    return o->compact ? ibl_ambient_brdf_table(ctx, d, img) : ibl_ambient_brdf_volume(ctx, d, tex);
}

/* A split-sum-family table into img; *channels receives its channel count. */
static ibl_status compute_splitsum(ibl_context *ctx, const cli_args *a, const lut_options *o,
                                   ibl_image *img, int *channels, char *comment, size_t cap)
{
    ibl_brdf_lut_desc d = {.size = o->size, .order = o->ambient.order};
    d.visibility = o->kind == KIND_SEPARABLE ? IBL_VISIBILITY_SEPARABLE : IBL_VISIBILITY_HEIGHT_CORRELATED;
    const char *what = o->kind == KIND_SEPARABLE
                           ? "split-sum GGX (Karis 2013), Schlick-GGX k = alpha/2; channels A, B: "
                             "specular = F0 * A + F90 * B"
                           : "split-sum GGX (Karis 2013), height-correlated Smith; channels A, B: "
                             "specular = F0 * A + F90 * B";
    if (o->kind == KIND_MULTISCATTER) {
        d.channels[0] = IBL_BRDF_ALBEDO;
        d.channels[1] = IBL_BRDF_ALBEDO_AVG;
        what = "GGX (height-correlated) directional albedo E and its average E_avg (Kulla-Conty "
               "multiple-scattering compensation)";
    } else if (o->kind == KIND_SHEEN) {
        d.channels[0] = IBL_BRDF_SHEEN;
        d.channels[1] = IBL_BRDF_SHEEN_AVG;
        what = "Charlie sheen (Estevez-Kulla 2017, Neubelt-Pettineo visibility) directional albedo "
               "E and its average";
    } else if (o->kind == KIND_SHEEN_KHR) {
        d.channels[0] = IBL_BRDF_SHEEN_KHR;
        d.channels[1] = IBL_BRDF_SHEEN_KHR_AVG;
        what = "KHR_materials_sheen: Charlie distribution and Charlie visibility (Conty Estevez & "
               "Kulla 2017), directional albedo E and its average; y = sheenRoughness = alpha";
    }
    if (o->channels) {
        memset(d.channels, 0, sizeof d.channels);
        if (!parse_channels(o->channels, d.channels))
            cli_usage_error(a, "--channels wants up to 4 of a,b,e,eavg,sheen,sheenavg,sheenkhr,"
                               "sheenkhravg,0,1, not '%s'",
                            o->channels);
        what = "custom channels (see --channels)";
    }
    snprintf(comment, cap, "%s.\nx = n.v, y = %s; row 0 is r ~ 0.", what,
             o->kind == KIND_SHEEN_KHR && !o->channels ? "sheenRoughness r (alpha = r)"
                                                      : "perceptual roughness r (alpha = r^2)");
    *channels = ibl_brdf_lut_channel_count(&d);
    return ibl_brdf_lut(ctx, &d, img);
}

/* The table as a text/C header, a container, or a flat image (3D volumes stack their slices). */
static ibl_status write_table(ibl_context *ctx, const cli_common *c, lut_options *o,
                              ibl_texture *tex, int channels, const char *comment)
{
    ibl_file_type type = ibl_file_type_from_path(o->out);
    if (o->text) return ibl_write_table(ctx, o->out, tex, channels, o->symbol ? o->symbol : "ibl_brdf_lut", comment);
    if (ibl_file_type_is_container(type)) {
        if (o->wd.format == IBL_FORMAT_DEFAULT) o->wd.format = channels <= 2 ? IBL_FORMAT_RG16F : IBL_FORMAT_RGBA16F;
        tex->format = o->wd.format;
        ibl_status st = ibl_texture_set_metadata(ctx, tex, "ibl.lut", comment);
        return st == IBL_OK ? ibl_write_texture(ctx, o->out, tex, &o->wd) : st;
    }
    size_t texels = (size_t)tex->width * tex->height * tex->depth;
    if (type == IBL_FILE_PNG && max_value(tex->data, texels, channels) > 1.0f)
        cli_info(c, "ibl: warning: %s: values above 1 are clipped by PNG\n", o->out);
    ibl_image flat = {tex->width, tex->height * tex->depth, tex->data};
    return ibl_write_image(ctx, o->out, &flat, &o->wd);
}

int cli_cmd_lut(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "lut", usage, {0}, {0}, 0};
    lut_options o;
    memset(&o, 0, sizeof o);
    parse(&a, &o);
    ibl_context *ctx = cli_context(&a.common);
    ibl_texture tex;
    ibl_image img;
    memset(&tex, 0, sizeof tex);
    memset(&img, 0, sizeof img);
    int channels = 2;
    char comment[512];
    double t0 = cli_seconds();
    ibl_status st = o.kind == KIND_AMBIENT
                        ? compute_ambient(ctx, &o, &tex, &img, comment, sizeof comment)
                        : compute_splitsum(ctx, &a, &o, &img, &channels, comment, sizeof comment);
    if (st == IBL_OK && !tex.data) /* one texture view over a 2D result */
        tex = (ibl_texture){.kind = IBL_TEXTURE_2D, .width = img.width, .height = img.height,
                            .depth = 1, .levels = 1, .data = img.pixels};
    if (st == IBL_OK) st = write_table(ctx, &a.common, &o, &tex, channels, comment);
    if (st == IBL_OK && tex.depth > 1)
        cli_info(&a.common, "%s: %dx%dx%d, %d channels, %.2f s\n", o.out, tex.width, tex.height,
                 tex.depth, channels, cli_seconds() - t0);
    else if (st == IBL_OK)
        cli_info(&a.common, "%s: %dx%d, %d channel%s, %.2f s\n", o.out, tex.width, tex.height,
                 channels, channels > 1 ? "s" : "", cli_seconds() - t0);
    else
        cli_report_failure(ctx, o.out, st);
    /* tex is either the volume (owns its texels) or a view of img; both may own metadata */
    if (img.pixels) tex.owns_data = 0;
    ibl_texture_free(ctx, &tex);
    ibl_image_free(ctx, &img);
    ibl_context_destroy(ctx);
    return cli_exit_code(st);
}
