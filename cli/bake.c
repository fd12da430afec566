/* ibl bake: everything a renderer needs from one environment, in one pass over the input. */
#include "input.h"
#include "ibl/brdf.h"
#include "ibl/irradiance.h"
#include "ibl/sh.h"
#include "ibl/sky.h"
#include "ibl/specular.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char usage[] =
    "usage: ibl bake [IN] -o DIR [options]\n"
    "\n"
    "Bakes an environment into DIR: the prefiltered specular chain (specular.ktx2 and .dds),\n"
    "the irradiance map (irradiance.ktx2 and .dds), the SH in every normalisation (sh.json),\n"
    "the BRDF tables (brdf_lut.ktx2, brdf_extra.ktx2, and ambient_brdf.ktx2 for the Phong\n"
    "family), a preview (preview.png) and manifest.json, which lists every file with its format,\n"
    "layout, conventions, level mapping and the exact parameters used. Without IN the built-in\n"
    "clear sky is baked.\n"
    "\n"
    "  -o, --output DIR       output folder (created if missing)\n"
    "  --preset P             gltf (default), filament, unreal, unity, or the seed's\n"
    "                         configurations dynamic-box16, dynamic-gauss32, dynamic-phong16,\n"
    "                         dynamic-phong32, static-phong32, static-phong64\n"
    "  --filter K             ggx, phong, blinn, box, gauss (overrides the preset)\n"
    "  --size N               specular face edge (default: the preset's)\n"
    "  --levels L             specular levels (default: down to 1x1)\n"
    "  --mapping M            level <-> roughness/shininess mapping (see 'ibl prefilter --help')\n"
    "  --edge-fixup E         none, overlap, overlap2, bent, warp\n"
    "  --mirror               specular level 0 is the unfiltered source\n"
    "  --irradiance-size N    irradiance face edge (default 16)\n"
    "  --sh-bands N           1..5 (default 3)\n"
    "  --window W             SH window: none (default), auto, or a Hanning width\n"
    "  --lut-size N           split-sum table edge (default 128)\n"
    "  --format F             pixel format of the cubemaps (default rgba16f)\n"
    "  --layout L, --yaw DEG, --mirror-input, --z-up: how to read IN (see 'ibl convert --help')\n"
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

typedef struct bake_file {
    char name[64];
    char kind[32];    /* "specular", "irradiance", ... */
    char format[32];
    char layout[96];
} bake_file;

typedef struct bake_state {
    ibl_context *ctx;
    const cli_common *common;
    const char *dir;
    bake_file files[16];
    int file_count;
    double stage_ms[8];
    const char *stage_name[8];
    int stage_count;
} bake_state;

static void join(char *out, size_t cap, const char *dir, const char *name)
{
    snprintf(out, cap, "%s/%s", dir, name);
}

static void add_file(bake_state *b, const char *name, const char *kind, const char *format,
                     const char *layout)
{
    bake_file *f = &b->files[b->file_count++];
    snprintf(f->name, sizeof f->name, "%s", name);
    snprintf(f->kind, sizeof f->kind, "%s", kind);
    snprintf(f->format, sizeof f->format, "%s", format);
    snprintf(f->layout, sizeof f->layout, "%s", layout);
}

static void stage_done(bake_state *b, const char *name, double t0)
{
    b->stage_name[b->stage_count] = name;
    b->stage_ms[b->stage_count++] = (cli_seconds() - t0) * 1000.0;
}

static ibl_status write_texture_both(bake_state *b, const char *stem, ibl_texture *tex,
                                     ibl_format format, const char *kind, const char *layout)
{
    const char *ext[2] = {"ktx2", "dds"};
    for (int i = 0; i < 2; i++) {
        char name[64], path[4096];
        snprintf(name, sizeof name, "%s.%s", stem, ext[i]);
        join(path, sizeof path, b->dir, name);
        ibl_write_desc wd;
        memset(&wd, 0, sizeof wd);
        wd.format = format;
        ibl_status st = ibl_write_texture(b->ctx, path, tex, &wd);
        if (st != IBL_OK) return st;
        add_file(b, name, kind, ibl_format_name(format ? format : IBL_FORMAT_RGBA16F), layout);
    }
    return IBL_OK;
}

/* Writes a flat table (an ibl_image) as a one-level 2D KTX2 texture with a description. */
static ibl_status write_table_ktx2(bake_state *b, const char *name, const ibl_image *image,
                                   ibl_format format, const char *description, const char *kind,
                                   const char *layout)
{
    ibl_texture tex;
    memset(&tex, 0, sizeof tex);
    tex.kind = IBL_TEXTURE_2D;
    tex.width = image->width;
    tex.height = image->height;
    tex.depth = 1;
    tex.levels = 1;
    tex.data = image->pixels;
    ibl_status st = ibl_texture_set_metadata(b->ctx, &tex, "ibl.brdf", description);
    char path[4096];
    join(path, sizeof path, b->dir, name);
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    wd.format = format;
    if (st == IBL_OK) st = ibl_write_texture(b->ctx, path, &tex, &wd);
    ibl_texture_free(b->ctx, &tex); /* the metadata; the pixels stay with the image */
    if (st == IBL_OK) add_file(b, name, kind, ibl_format_name(format), layout);
    return st;
}

/* Writes text built in a memory stream to DIR/name atomically, then frees it. */
static ibl_status write_text_file(bake_state *b, const char *name, char *text, size_t len)
{
    char path[4096];
    join(path, sizeof path, b->dir, name);
    ibl_status st = ibl_write_file_atomic(b->ctx, path, text, len);
    free(text);
    return st;
}

static void json_escape(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
        else if (c < 0x20) fprintf(f, "\\u%04x", c);
        else fputc(c, f);
    }
    fputc('"', f);
}

static int make_dir(const char *dir)
{
    if (mkdir(dir, 0777) == 0 || errno == EEXIST) {
        struct stat st;
        if (stat(dir, &st) == 0 && S_ISDIR(st.st_mode)) return 1;
    }
    return 0;
}

int cli_cmd_bake(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "bake", usage, {0}, {0}, 0};
    cli_input_options in = {0};
    const char *dir = NULL;
    const char *preset = "gltf";
    ibl_specular_desc sd;
    memset(&sd, 0, sizeof sd);
    int have_filter = 0, have_size = 0, have_levels = 0, have_mapping = 0, have_fixup = 0, mirror = 0;
    ibl_specular_filter filter = IBL_FILTER_GGX;
    int size = 0, levels = 0;
    ibl_specular_mapping mapping = IBL_MAPPING_DEFAULT;
    ibl_edge_fixup fixup = IBL_EDGE_FIXUP_NONE;
    int irradiance_size = 16, sh_bands = 3, lut_size = 128;
    ibl_sh_window window = IBL_SH_WINDOW_NONE;
    double window_width = 0;
    ibl_format format = IBL_FORMAT_RGBA16F;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--mirror-input", NULL)) {
            in.orientation.mirror = 1;
            continue;
        }
        if (strcmp(arg, "--mirror") != 0 && cli_input_option(&a, arg, &in)) continue;
        if (cli_is(&a, arg, "--output", "-o")) dir = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--preset", NULL)) preset = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--filter", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_specular_filter_from_name(v, &filter)) cli_usage_error(&a, "unknown filter '%s'", v);
            have_filter = 1;
        } else if (cli_is(&a, arg, "--size", NULL)) {
            size = cli_int(&a, arg, 1, 4096);
            have_size = 1;
        } else if (cli_is(&a, arg, "--levels", NULL)) {
            levels = cli_int(&a, arg, 1, IBL_MAX_LEVELS);
            have_levels = 1;
        } else if (cli_is(&a, arg, "--mapping", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_specular_mapping_from_name(v, &mapping)) cli_usage_error(&a, "unknown mapping '%s'", v);
            have_mapping = 1;
        } else if (cli_is(&a, arg, "--edge-fixup", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_edge_fixup_from_name(v, &fixup)) cli_usage_error(&a, "unknown edge fixup '%s'", v);
            have_fixup = 1;
        } else if (cli_is(&a, arg, "--mirror", NULL)) mirror = 1;
        else if (cli_is(&a, arg, "--irradiance-size", NULL)) irradiance_size = cli_int(&a, arg, 1, 64);
        else if (cli_is(&a, arg, "--sh-bands", NULL)) sh_bands = cli_int(&a, arg, 1, IBL_SH_MAX_BANDS);
        else if (cli_is(&a, arg, "--lut-size", NULL)) lut_size = cli_int(&a, arg, 2, 4096);
        else if (cli_is(&a, arg, "--window", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "none") == 0) window = IBL_SH_WINDOW_NONE;
            else if (strcmp(v, "auto") == 0) window = IBL_SH_WINDOW_AUTO;
            else {
                char *end;
                window_width = strtod(v, &end);
                if (*end || !(window_width > 0)) cli_usage_error(&a, "--window wants none, auto or a width");
                window = IBL_SH_WINDOW_HANNING;
            }
        } else if (cli_is(&a, arg, "--format", NULL)) {
            const char *v = cli_value(&a, arg);
            int ok = 0;
            format = ibl_format_from_name(v, &ok);
            if (!ok) cli_usage_error(&a, "unknown pixel format '%s'", v);
        } else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count > 1) cli_usage_error(&a, "takes at most one input file");
    if (!dir) cli_usage_error(&a, "needs an output folder: -o DIR");
    if (!ibl_specular_preset(preset, &sd)) cli_usage_error(&a, "unknown preset '%s'", preset);
    if (have_filter) sd.filter = filter;
    if (have_size) sd.size = size;
    if (have_levels) sd.levels = levels;
    if (have_mapping) sd.mapping = mapping;
    if (have_fixup) sd.edge_fixup = fixup;
    if (mirror) sd.mirror = 1;
    const char *input = a.positional_count ? a.positional[0] : NULL;

    ibl_context *ctx = cli_context(&a.common);
    bake_state b;
    memset(&b, 0, sizeof b);
    b.ctx = ctx;
    b.common = &a.common;
    b.dir = dir;
    double t_all = cli_seconds(), t0 = t_all;
    int rc = CLI_EXIT_OK;
    ibl_status st = IBL_OK;
    ibl_cubemap src = {0}, spec = {0}, irr = {0};
    ibl_image lut = {0}, extra = {0};
    ibl_texture amb = {0};
    ibl_sky_desc sky;
    memset(&sky, 0, sizeof sky);

    if (!make_dir(dir)) {
        cli_error("%s: cannot create the output folder: %s", dir, strerror(errno));
        ibl_context_destroy(ctx);
        return CLI_EXIT_BAD_INPUT;
    }
    /* 1. the environment, read once, as a cube at a working resolution */
    if (!in.size) in.size = sd.size > 0 ? (sd.size < 128 ? 128 : sd.size) : 256;
    if (input) {
        rc = cli_read_cubemap(ctx, &a.common, input, &in, &src, NULL);
        if (rc != CLI_EXIT_OK) goto done;
    } else {
        ibl_image image;
        sky.width = 4 * in.size;
        st = ibl_sky_render(ctx, &sky, &image);
        if (st == IBL_OK) {
            ibl_to_cube_desc cd;
            memset(&cd, 0, sizeof cd);
            cd.layout = IBL_LAYOUT_EQUIRECT;
            cd.size = in.size;
            st = ibl_image_to_cubemap(ctx, &image, &cd, &src);
            ibl_image_free(ctx, &image);
        }
        if (st != IBL_OK) goto fail;
    }
    stage_done(&b, "read", t0);

    /* 2. specular chain */
    t0 = cli_seconds();
    ibl_specular_info info;
    st = ibl_specular_prefilter(ctx, &src, &sd, &spec, &info);
    if (st != IBL_OK) goto fail;
    {
        ibl_texture tex = ibl_texture_from_cubemap(&spec);
        st = ibl_specular_set_metadata(ctx, &info, &tex);
        if (st == IBL_OK) st = write_texture_both(&b, "specular", &tex, format, "specular", "cube");
        ibl_texture_free(ctx, &tex);
        if (st != IBL_OK) goto fail;
    }
    stage_done(&b, "specular", t0);

    /* 3. irradiance map and SH */
    t0 = cli_seconds();
    ibl_irradiance_desc id;
    memset(&id, 0, sizeof id);
    id.size = irradiance_size;
    st = ibl_irradiance_cubemap(ctx, &src, &id, &irr);
    if (st != IBL_OK) goto fail;
    {
        ibl_texture tex = ibl_texture_from_cubemap(&irr);
        ibl_texture_set_metadata(ctx, &tex, "ibl.irradiance", "irradiance / pi (multiply by albedo)");
        st = write_texture_both(&b, "irradiance", &tex, format, "irradiance", "cube, E/pi");
        ibl_texture_free(ctx, &tex);
        if (st != IBL_OK) goto fail;
    }
    ibl_sh radiance;
    ibl_sh_window_report rep;
    st = ibl_sh_project_cubemap(ctx, &src, 0, sh_bands, &radiance);
    if (st == IBL_OK) st = ibl_sh_apply_window(&radiance, window, window_width, &rep);
    if (st != IBL_OK) goto fail;
    {
        char *text = NULL;
        size_t len = 0;
        FILE *mem = open_memstream(&text, &len);
        if (!mem) {
            st = IBL_ERR_OUT_OF_MEMORY;
            goto fail;
        }
        cli_sh_write_json(mem, input ? input : "built-in sky", "cube", sh_bands, window, &rep, &radiance);
        fclose(mem);
        st = write_text_file(&b, "sh.json", text, len);
        if (st != IBL_OK) goto fail;
        add_file(&b, "sh.json", "sh", "json", "real SH, see keys basis and axes");
    }
    stage_done(&b, "diffuse", t0);

    /* 4. BRDF tables */
    t0 = cli_seconds();
    {
        ibl_brdf_lut_desc ld;
        memset(&ld, 0, sizeof ld);
        ld.size = lut_size;
        st = ibl_brdf_lut(ctx, &ld, &lut);
        if (st == IBL_OK)
            st = write_table_ktx2(&b, "brdf_lut.ktx2", &lut, IBL_FORMAT_RG16F,
                                  "split-sum GGX, height-correlated Smith: R = A, G = B, specular = "
                                  "F0*A + F90*B; x = n.v, y = roughness, row 0 = roughness 0",
                                  "brdf_splitsum", "2d: x = n.v, y = roughness (texel centres)");
        if (st != IBL_OK) goto fail;
        ld.channels[0] = IBL_BRDF_ALBEDO;
        ld.channels[1] = IBL_BRDF_ALBEDO_AVG;
        ld.channels[2] = IBL_BRDF_SHEEN;
        ld.channels[3] = IBL_BRDF_SHEEN_AVG;
        st = ibl_brdf_lut(ctx, &ld, &extra);
        if (st == IBL_OK)
            st = write_table_ktx2(&b, "brdf_extra.ktx2", &extra, IBL_FORMAT_RGBA16F,
                                  "R = E (GGX directional albedo), G = E_avg, B = Charlie sheen "
                                  "albedo, A = its average; x = n.v, y = roughness",
                                  "brdf_multiscatter_sheen", "2d: x = n.v, y = roughness");
        if (st != IBL_OK) goto fail;
        if (info.filter != IBL_FILTER_GGX) {
            ibl_ambient_brdf_desc ad;
            memset(&ad, 0, sizeof ad);
            /* the material's Blinn exponent runs to blinn_factor x the Phong range (seed fit) */
            float to_blinn = info.filter == IBL_FILTER_BLINN ? 1.0f : (info.blinn_factor > 0 ? info.blinn_factor : 4.2f);
            ad.shininess_min = info.shininess_min * to_blinn;
            ad.shininess_max = info.shininess_max * to_blinn;
            st = ibl_ambient_brdf_volume(ctx, &ad, &amb);
            if (st != IBL_OK) goto fail;
            char path[4096];
            join(path, sizeof path, dir, "ambient_brdf.ktx2");
            ibl_write_desc wd;
            memset(&wd, 0, sizeof wd);
            wd.format = IBL_FORMAT_RG16F;
            st = ibl_write_texture(ctx, path, &amb, &wd);
            if (st != IBL_OK) goto fail;
            add_file(&b, "ambient_brdf.ktx2", "ambient_brdf", "rg16f", "3d: u = n.v, v = shininess (log), w = F0");
        }
    }
    stage_done(&b, "brdf", t0);

    /* 5. preview: the environment as a cross */
    t0 = cli_seconds();
    {
        ibl_from_cube_desc fd;
        memset(&fd, 0, sizeof fd);
        fd.layout = IBL_LAYOUT_EQUIRECT;
        fd.width = 1024;
        ibl_image image;
        st = ibl_cubemap_to_image(ctx, &src, &fd, &image);
        if (st != IBL_OK) goto fail;
        ibl_write_desc wd;
        memset(&wd, 0, sizeof wd);
        wd.exposure_ev = cli_auto_exposure(&image);
        char path[4096];
        join(path, sizeof path, dir, "environment.png");
        st = ibl_write_image(ctx, path, &image, &wd);
        ibl_image_free(ctx, &image);
        if (st != IBL_OK) goto fail;
        add_file(&b, "environment.png", "preview", "rgba8 srgb", "equirect, filmic tone map");
    }
    stage_done(&b, "preview", t0);

    /* 6. the manifest: everything needed to use and to reproduce the bake */
    {
        char *spec_json = NULL;
        st = ibl_specular_manifest_json(ctx, &info, &spec_json);
        if (st != IBL_OK) goto fail;
        char *text = NULL;
        size_t len = 0;
        FILE *m = open_memstream(&text, &len);
        if (!m) {
            ibl_free(ctx, spec_json);
            st = IBL_ERR_OUT_OF_MEMORY;
            goto fail;
        }
        fprintf(m, "{\n  \"generator\": \"ibl %s\",\n  \"input\": ", IBL_VERSION_STRING);
        json_escape(m, input ? input : "built-in sky");
        fprintf(m, ",\n  \"conventions\": {\"frame\": \"right-handed, +Y up\", \"cube_faces\": "
                   "\"+X -X +Y -Y +Z -Z, OpenGL/Vulkan/KTX2 orientation (docs/CONVENTIONS.md)\", "
                   "\"radiance\": \"linear Rec.709\", \"irradiance_map\": \"E/pi\"},\n");
        fprintf(m, "  \"parameters\": {\"preset\": ");
        json_escape(m, preset);
        fprintf(m, ", \"filter\": \"%s\", \"size\": %d, \"levels\": %d, \"mapping\": \"%s\", "
                   "\"edge_fixup\": \"%s\", \"mirror\": %s, \"working_size\": %d, "
                   "\"irradiance_size\": %d, \"sh_bands\": %d, \"sh_window\": \"%s\", "
                   "\"sh_window_width\": %.9g, \"lut_size\": %d, \"format\": \"%s\"",
                ibl_specular_filter_name(info.filter), info.size, info.levels,
                ibl_specular_mapping_name(info.mapping), ibl_edge_fixup_name(sd.edge_fixup),
                info.mirror ? "true" : "false", src.size, irradiance_size, sh_bands,
                window == IBL_SH_WINDOW_AUTO ? "auto" : window == IBL_SH_WINDOW_HANNING ? "hanning" : "none",
                window_width, lut_size, ibl_format_name(format));
        if (in.layout) fprintf(m, ", \"layout\": \"%s\"", ibl_layout_name(in.layout));
        fprintf(m, ", \"yaw\": %.9g, \"mirror_input\": %s, \"z_up\": %s",
                in.orientation.yaw_degrees, in.orientation.mirror ? "true" : "false",
                in.orientation.z_up ? "true" : "false");
        if (!input) {
            ibl_sky_model model;
            if (ibl_sky_model_init(ctx, &sky, &model) == IBL_OK)
                fprintf(m, ", \"sky\": {\"sun_elevation_deg\": %.9g, \"sun_azimuth_deg\": %.9g, "
                           "\"turbidity\": %.9g, \"ground_albedo\": %.9g, \"width\": %d}",
                        model.desc.sun_elevation_deg, model.desc.sun_azimuth_deg,
                        model.desc.turbidity, model.desc.ground_albedo, model.desc.width);
        }
        fprintf(m, "},\n  \"specular\": ");
        /* the prefilter's own manifest block, indented one level */
        size_t spec_len = strlen(spec_json);
        while (spec_len && spec_json[spec_len - 1] == '\n') spec_len--;
        for (size_t i = 0; i < spec_len; i++) {
            fputc(spec_json[i], m);
            if (spec_json[i] == '\n') fputs("  ", m);
        }
        fprintf(m, ",\n  \"files\": [\n");
        for (int i = 0; i < b.file_count; i++) {
            fprintf(m, "    {\"file\": ");
            json_escape(m, b.files[i].name);
            fprintf(m, ", \"kind\": \"%s\", \"format\": \"%s\", \"layout\": ", b.files[i].kind, b.files[i].format);
            json_escape(m, b.files[i].layout);
            fprintf(m, "}%s\n", i + 1 < b.file_count ? "," : "");
        }
        fprintf(m, "  ]\n}\n");
        fclose(m);
        ibl_free(ctx, spec_json);
        st = write_text_file(&b, "manifest.json", text, len);
        if (st != IBL_OK) goto fail;
    }

    if (!a.common.quiet) {
        fprintf(stderr, "baked %s into %s/ in %.0f ms:\n", input ? input : "the built-in sky", dir,
                (cli_seconds() - t_all) * 1000.0);
        for (int i = 0; i < b.stage_count; i++)
            fprintf(stderr, "  %-10s %8.1f ms\n", b.stage_name[i], b.stage_ms[i]);
        fprintf(stderr, "  specular: %s, %d levels of %d..1, mapping %s\n",
                ibl_specular_filter_name(info.filter), info.levels, info.size,
                ibl_specular_mapping_name(info.mapping));
        for (int i = 0; i < b.file_count; i++) fprintf(stderr, "  %s/%s\n", dir, b.files[i].name);
        fprintf(stderr, "  %s/manifest.json\n", dir);
    }
    goto done;
fail:
    cli_error("%s", ibl_context_message(ctx));
    rc = cli_exit_code(st) == CLI_EXIT_USAGE ? CLI_EXIT_BAD_INPUT : cli_exit_code(st);
done:
    ibl_cubemap_free(ctx, &src);
    ibl_cubemap_free(ctx, &spec);
    ibl_cubemap_free(ctx, &irr);
    ibl_image_free(ctx, &lut);
    ibl_image_free(ctx, &extra);
    ibl_texture_free(ctx, &amb);
    ibl_context_destroy(ctx);
    return rc;
}
