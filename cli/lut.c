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
    "                           ambient-brdf: tri-Ace AmbientBRDF volume, U = n.v, V = shininess,\n"
    "                             W = F0; R = specular albedo, G = exact diffuse factor 1 - F0\n"
    "  --size N                 texels per axis (default 128; ambient-brdf: n.v and shininess, 32)\n"
    "  --channels LIST          split-sum kinds: up to 4 of a,b,e,eavg,sheen,sheenavg,0,1\n"
    "  --shininess-range A:B    ambient-brdf shininess range (default 1:2000)\n"
    "  --shininess-spacing S    log (default) or linear\n"
    "  --f0-steps K             ambient-brdf F0 slices (default 16)\n"
    "  --compact                ambient-brdf: the 2D form RG = (X, Y), AmbientBRDF = F0*X + Y\n"
    "  --normalization N        ambient-brdf: triace (the linear fit 0.0397436 s + 0.0856832, default) or exact\n"
    "  --format F               rg16f (default for 2 channels in .ktx2/.ktx/.dds), rg32f,\n"
    "                           rgba16f, rgba32f; PNG: rgba16 (default); EXR: rgb32f (default),\n"
    "                           rgb16f, rgba16f, rgba32f\n"
    "  --symbol NAME            array name in a C header (default ibl_brdf_lut)\n"
    "  --order N                quadrature points per piece (default 24; raise to check)\n"
    "\n"
    "Flat images (.png .exr .hdr .pfm) of the 3D ambient-brdf volume stack the F0 slices\n"
    "top to bottom. See docs/BRDF.md for the maths and the shader code.\n";

typedef enum lut_kind { KIND_SPLITSUM, KIND_SEPARABLE, KIND_MULTISCATTER, KIND_SHEEN, KIND_AMBIENT } lut_kind;

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

int cli_cmd_lut(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "lut", usage, {0}, {0}, 0};
    const char *out = NULL, *format_name = NULL, *symbol = NULL, *channels_arg = NULL;
    lut_kind kind = KIND_SPLITSUM;
    int size = 0, f0_steps = 0, compact = 0, order = 0;
    double smin = 0, smax = 0;
    ibl_shininess_spacing spacing = IBL_SHININESS_LOG;
    ibl_blinn_normalization norm = IBL_BLINN_TRIACE_FIT;
    int saw_ambient_option = 0;
    const char *arg;
    while ((arg = cli_next(&a)) != NULL) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o")) {
            out = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--kind", NULL)) {
            const char *k = cli_value(&a, arg);
            if (strcmp(k, "splitsum") == 0) kind = KIND_SPLITSUM;
            else if (strcmp(k, "splitsum-separable") == 0) kind = KIND_SEPARABLE;
            else if (strcmp(k, "multiscatter") == 0) kind = KIND_MULTISCATTER;
            else if (strcmp(k, "sheen") == 0) kind = KIND_SHEEN;
            else if (strcmp(k, "ambient-brdf") == 0) kind = KIND_AMBIENT;
            else
                cli_usage_error(&a, "unknown --kind '%s' (splitsum, splitsum-separable, "
                                    "multiscatter, sheen, ambient-brdf)", k);
        } else if (cli_is(&a, arg, "--size", NULL)) {
            size = cli_int(&a, arg, 1, 4096);
        } else if (cli_is(&a, arg, "--f0-steps", NULL)) {
            f0_steps = cli_int(&a, arg, 1, 1024);
            saw_ambient_option = 1;
        } else if (cli_is(&a, arg, "--shininess-range", NULL)) {
            const char *v = cli_value(&a, arg);
            char *end = NULL;
            smin = strtod(v, &end);
            if (!end || *end != ':') cli_usage_error(&a, "--shininess-range wants A:B, not '%s'", v);
            const char *b = end + 1;
            smax = strtod(b, &end);
            if (!*b || *end || !(smin > 0) || !(smax > smin) || !(smax <= 1e6))
                cli_usage_error(&a, "--shininess-range wants 0 < A < B <= 1e6, not '%s'", v);
            saw_ambient_option = 1;
        } else if (cli_is(&a, arg, "--shininess-spacing", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "log") == 0) spacing = IBL_SHININESS_LOG;
            else if (strcmp(v, "linear") == 0) spacing = IBL_SHININESS_LINEAR;
            else cli_usage_error(&a, "--shininess-spacing wants log or linear, not '%s'", v);
            saw_ambient_option = 1;
        } else if (cli_is(&a, arg, "--normalization", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "triace") == 0) norm = IBL_BLINN_TRIACE_FIT;
            else if (strcmp(v, "exact") == 0) norm = IBL_BLINN_EXACT;
            else cli_usage_error(&a, "--normalization wants seed or exact, not '%s'", v);
            saw_ambient_option = 1;
        } else if (cli_is(&a, arg, "--compact", NULL)) {
            compact = 1;
            saw_ambient_option = 1;
        } else if (cli_is(&a, arg, "--channels", NULL)) {
            channels_arg = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--format", NULL)) {
            format_name = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--symbol", NULL)) {
            symbol = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--order", NULL)) {
            order = cli_int(&a, arg, 4, 192);
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count) cli_usage_error(&a, "unexpected argument '%s'", a.positional[0]);
    if (!out) cli_usage_error(&a, "missing -o FILE");
    if (saw_ambient_option && kind != KIND_AMBIENT)
        cli_usage_error(&a, "--shininess-*, --f0-steps, --compact and --normalization need "
                            "--kind ambient-brdf");
    if (channels_arg && kind == KIND_AMBIENT)
        cli_usage_error(&a, "--channels applies to the split-sum kinds only");

    ibl_file_type type = ibl_file_type_from_path(out);
    int text = type == IBL_FILE_UNKNOWN;
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    if (format_name) {
        int ok = 0;
        ok = ibl_format_from_name(format_name, &wd.format);
        if (!ok) cli_usage_error(&a, "unknown --format '%s'", format_name);
        if (text) cli_usage_error(&a, "--format does not apply to C headers and text tables");
    }
    if (symbol && !ends_with(out, ".h")) cli_usage_error(&a, "--symbol applies to .h outputs only");

    ibl_context *ctx = cli_context(&a.common);
    ibl_status st = IBL_OK;
    ibl_texture tex;
    memset(&tex, 0, sizeof tex);
    int nch = 2;
    ibl_image img;
    memset(&img, 0, sizeof img);
    char comment[512];
    double t0 = cli_seconds();

    if (kind == KIND_AMBIENT) {
        ibl_ambient_brdf_desc d;
        memset(&d, 0, sizeof d);
        d.size_nv = d.size_shininess = size;
        d.size_f0 = f0_steps;
        d.shininess_min = smin;
        d.shininess_max = smax;
        d.spacing = spacing;
        d.normalization = norm;
        d.order = order;
        snprintf(comment, sizeof comment,
                 "tri-Ace AmbientBRDF (seed 000), %s normalisation, shininess %g..%g %s spacing.\n"
                 "%s",
                 norm == IBL_BLINN_EXACT ? "exact" : "triace", smin > 0 ? smin : 1.0,
                 smax > 0 ? smax : 2000.0, spacing == IBL_SHININESS_LINEAR ? "linear" : "log",
                 compact ? "x = n.v, y = shininess row; channels X, Y: AmbientBRDF = F0 * X + Y"
                         : "x = n.v, y = shininess row, z = F0 slice; channels: specular, "
                           "diffuse factor (1 - F0)");
        if (compact) {
            st = ibl_ambient_brdf_table(ctx, &d, &img);
        } else {
            st = ibl_ambient_brdf_volume(ctx, &d, &tex);
        }
    } else {
        ibl_brdf_lut_desc d;
        memset(&d, 0, sizeof d);
        d.size = size;
        d.order = order;
        d.visibility = kind == KIND_SEPARABLE ? IBL_VISIBILITY_SEPARABLE
                                              : IBL_VISIBILITY_HEIGHT_CORRELATED;
        const char *what = "split-sum GGX (Karis 2013), height-correlated Smith; channels A, B: "
                           "specular = F0 * A + F90 * B";
        if (kind == KIND_SEPARABLE)
            what = "split-sum GGX (Karis 2013), Schlick-GGX k = alpha/2; channels A, B: "
                   "specular = F0 * A + F90 * B";
        if (kind == KIND_MULTISCATTER) {
            d.channels[0] = IBL_BRDF_ALBEDO;
            d.channels[1] = IBL_BRDF_ALBEDO_AVG;
            what = "GGX (height-correlated) directional albedo E and its average E_avg "
                   "(Kulla-Conty multiple-scattering compensation)";
        } else if (kind == KIND_SHEEN) {
            d.channels[0] = IBL_BRDF_SHEEN;
            d.channels[1] = IBL_BRDF_SHEEN_AVG;
            what = "Charlie sheen (Estevez-Kulla 2017, Neubelt-Pettineo visibility) directional "
                   "albedo E and its average";
        }
        if (channels_arg) {
            memset(d.channels, 0, sizeof d.channels);
            if (!parse_channels(channels_arg, d.channels))
                cli_usage_error(&a, "--channels wants up to 4 of a,b,e,eavg,sheen,sheenavg,0,1, "
                                    "not '%s'", channels_arg);
            what = "custom channels (see --channels)";
        }
        snprintf(comment, sizeof comment, "%s.\nx = n.v, y = perceptual roughness r (alpha = r^2); "
                 "row 0 is r ~ 0.", what);
        nch = ibl_brdf_lut_channel_count(&d);
        st = ibl_brdf_lut(ctx, &d, &img);
    }
    if (st != IBL_OK) goto fail;

    /* One texture view over whatever was computed (2D image or 3D volume). */
    if (!tex.data) {
        tex.kind = IBL_TEXTURE_2D;
        tex.width = img.width;
        tex.height = img.height;
        tex.depth = 1;
        tex.levels = 1;
        tex.data = img.pixels;
    }
    size_t texels = (size_t)tex.width * tex.height * tex.depth;
    if (text) {
        st = ibl_write_table(ctx, out, &tex, nch, symbol ? symbol : "ibl_brdf_lut", comment);
    } else if (ibl_file_type_is_container(type)) {
        if (wd.format == IBL_FORMAT_DEFAULT) wd.format = nch <= 2 ? IBL_FORMAT_RG16F : IBL_FORMAT_RGBA16F;
        tex.format = wd.format;
        st = ibl_texture_set_metadata(ctx, &tex, "ibl.lut", comment);
        if (st == IBL_OK) st = ibl_write_texture(ctx, out, &tex, &wd);
    } else {
        if (type == IBL_FILE_PNG && wd.format == IBL_FORMAT_DEFAULT) wd.format = IBL_FORMAT_RGBA16_UNORM;
        if (type == IBL_FILE_PNG && max_value(tex.data, texels, nch) > 1.0f)
            cli_info(&a.common, "ibl: warning: %s: values above 1 are clipped by PNG\n", out);
        /* a 3D volume as slices stacked top to bottom */
        ibl_image flat = {tex.width, tex.height * tex.depth, tex.data};
        st = ibl_write_image(ctx, out, &flat, &wd);
    }
    if (st != IBL_OK) goto fail;
    if (tex.depth > 1)
        cli_info(&a.common, "%s: %dx%dx%d, %d channels, %.2f s\n", out, tex.width, tex.height,
                 tex.depth, nch, cli_seconds() - t0);
    else
        cli_info(&a.common, "%s: %dx%d, %d channel%s, %.2f s\n", out, tex.width, tex.height, nch,
                 nch > 1 ? "s" : "", cli_seconds() - t0);

fail:
    if (st != IBL_OK) cli_error("%s", ibl_context_message(ctx));
    /* tex is either the volume (owns its texels) or a view of img; both may own metadata */
    if (img.pixels) {
        tex.owns_data = 0;
        ibl_texture_free(ctx, &tex);
        ibl_image_free(ctx, &img);
    } else {
        ibl_texture_free(ctx, &tex);
    }
    ibl_context_destroy(ctx);
    return cli_exit_code(st);
}
