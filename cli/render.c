/* ibl render: the preview of a probe on spheres or a mesh, its Monte Carlo reference, and
 * labelled side-by-side comparisons. A thin client of render.h and shade.h. */
#include "cli.h"

#include "ibl/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char usage[] =
    "usage: ibl render INPUT -o OUT [options]\n"
    "\n"
    "Draws the environment and a grid of spheres (GGX roughness 0..1 for a metal and a\n"
    "dielectric row, and a row of Blinn-Phong shininess values) lit by the baked probe, with a\n"
    "small CPU ray tracer. OUT .png/.jpg is tone-mapped (filmic), .exr/.hdr/.pfm is linear.\n"
    "\n"
    "INPUT is a bake directory (what `ibl bake` writes), an environment image in any layout\n"
    "(prefiltered in memory; see docs/SHADING.md), a cube texture (.ktx2/.dds), or 'sky' for\n"
    "the built-in procedural sky.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE     output image (required)\n"
    "  --scene balls|FILE    the sphere grid (default) or a Wavefront OBJ mesh; its vertex\n"
    "                        colours' red is the AO, otherwise AO is ray-cast\n"
    "  --exposure EV         exposure for tone-mapped outputs (default: automatic, the\n"
    "                        image's mean luminance maps to middle grey)\n"
    "  --width W             image width (default 1024); --height H (default W/2)\n"
    "  --layout L            layout of INPUT (equirect, hcross, ...; default: detect)\n"
    "  --specular-size N     face size of the in-memory prefiltered chain (default 128)\n"
    "  --chain FILE          use this prefiltered chain (cube .ktx2/.dds, level k at roughness\n"
    "                        k/(levels-1)) instead of prefiltering INPUT, which stays the\n"
    "                        background, mirror and SH source; with --lut FILE (split-sum\n"
    "                        table) and --ambient FILE (AmbientBRDF volume, as `ibl lut`\n"
    "                        writes them; --ambient-range A:B, default 1:2000)\n"
    "  --so FORMULA          specular occlusion: none ao triace triace-shininess triace-fast\n"
    "                        frostbite cone (default none)\n"
    "  --mix MODE            ambient composition: multiply lerp-albedo lerp-ao ao-lerp-ao\n"
    "                        lerp-ao2 entire (default multiply)\n"
    "  --energy MODE         GGX multiple scattering: none fdez-aguera turquin (default none)\n"
    "  --horizon             horizon occlusion of reflections\n"
    "  --mirror-direction    look up rough reflections along R, not the lobe's dominant\n"
    "                        direction (shows the split sum's error at high roughness)\n"
    "  --sphere-ao MIN       synthetic AO on the spheres from MIN (bottom) to 1 (top)\n"
    "  --reference           Monte Carlo reference of the same scene (no split sum)\n"
    "  --samples N           reference iterations per pixel, 3 directions each (default 256)\n"
    "  --supersample N       N x N rays per pixel for the runtime shading (default 1; the\n"
    "                        reference spreads its samples over each pixel anyway)\n"
    "  --report              also render the reference and print the error per sphere\n"
    "                        (the runtime image then uses at least 4 x 4 rays per pixel)\n"
    "  --compare A B         two variants side by side, labelled; each is a comma-separated\n"
    "                        list of so=, mix=, energy=, bp-diffuse=ambient-brdf|f0, samples=,\n"
    "                        sphere-ao=, horizon, mirror-direction, nearest-level,\n"
    "                        reference, applied over the other options, e.g.\n"
    "                        --compare so=none so=triace-fast,sphere-ao=0.2\n"
    "                        --compare '' reference,samples=512\n";

typedef struct variant {
    ibl_render_desc desc;
    char label[96];
} variant;

static int energy_from_name(const char *s, ibl_energy_compensation *out)
{
    if (strcmp(s, "none") == 0)
        *out = IBL_ENERGY_NONE;
    else if (strcmp(s, "fdez-aguera") == 0)
        *out = IBL_ENERGY_FDEZ_AGUERA;
    else if (strcmp(s, "turquin") == 0)
        *out = IBL_ENERGY_TURQUIN;
    else
        return 0;
    return 1;
}

/* One "key[=value]" override; returns 0 if unknown or malformed. */
static int apply_setting(ibl_render_desc *d, const char *key, const char *value)
{
    if (strcmp(key, "so") == 0) return value && ibl_so_formula_from_name(value, &d->shade.so);
    if (strcmp(key, "mix") == 0) return value && ibl_ambient_mix_from_name(value, &d->shade.mix);
    if (strcmp(key, "energy") == 0) return value && energy_from_name(value, &d->shade.energy);
    if (strcmp(key, "horizon") == 0) return d->shade.horizon_occlusion = 1;
    if (strcmp(key, "nearest-level") == 0) return d->shade.nearest_level = 1;
    if (strcmp(key, "mirror-direction") == 0) return d->shade.mirror_direction = 1;
    if (strcmp(key, "reference") == 0) return d->reference = 1;
    if (strcmp(key, "bp-diffuse") == 0) {
        if (!value) return 0;
        if (strcmp(value, "ambient-brdf") == 0)
            d->shade.bp_diffuse = IBL_BP_DIFFUSE_AMBIENT_BRDF;
        else if (strcmp(value, "f0") == 0)
            d->shade.bp_diffuse = IBL_BP_DIFFUSE_F0;
        else
            return 0;
        return 1;
    }
    if (strcmp(key, "samples") == 0 || strcmp(key, "sphere-ao") == 0) {
        if (!value) return 0;
        char *end;
        double x = strtod(value, &end);
        if (*end || !(x >= 0)) return 0;
        if (key[1] == 'a')
            d->reference_samples = x > 1 << 20 ? 1 << 20 : (int)x;
        else
            d->sphere_ao_min = x > 1 ? 1.0f : (float)x;
        return 1;
    }
    return 0;
}

static void apply_spec(cli_args *a, ibl_render_desc *d, const char *spec)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", spec);
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(tok, '=');
        if (eq) *eq = 0;
        if (!apply_setting(d, tok, eq ? eq + 1 : NULL))
            cli_usage_error(a, "bad --compare setting '%s%s%s'", tok, eq ? "=" : "",
                            eq ? eq + 1 : "");
    }
}

static int is_directory(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static ibl_status load_environment(ibl_context *ctx, const cli_args *a, const char *path,
                                   ibl_layout layout, ibl_cubemap *out)
{
    ibl_status st;
    ibl_read_desc rd = {.clamp_infinite = a->common.clamp};
    ibl_image im = {0};
    if (strcmp(path, "sky") == 0) {
        st = ibl_sky_render(ctx, NULL, &im);
    } else {
        ibl_file_info info;
        ibl_texture tex;
        st = ibl_read_texture(ctx, path, &rd, &tex, &info);
        if (st != IBL_OK) return st;
        cli_report_pixels(&a->common, path, &info.pixels);
        if (tex.kind == IBL_TEXTURE_CUBE) {
            ibl_cubemap view;
            st = ibl_cubemap_from_texture(&tex, &view);
            if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, view.size, 1, out);
            if (st == IBL_OK)
                memcpy(out->data, view.data, ibl_cubemap_floats(view.size, 1) * sizeof(float));
            ibl_texture_free(ctx, &tex);
            return st;
        }
        /* a flat image: level 0 of the 2D texture, viewed as an image */
        im.width = tex.width;
        im.height = tex.height;
        im.pixels = tex.data;
        ibl_to_cube_desc cd = {.layout = layout};
        st = ibl_image_to_cubemap(ctx, &im, &cd, out);
        ibl_texture_free(ctx, &tex);
        return st;
    }
    if (st != IBL_OK) return st;
    ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT};
    st = ibl_image_to_cubemap(ctx, &im, &cd, out);
    ibl_image_free(ctx, &im);
    return st;
}

static int is_display_output(const char *path)
{
    ibl_file_type t = ibl_file_type_from_path(path);
    return t == IBL_FILE_PNG || t == IBL_FILE_JPEG;
}

/* Mean relative error of the runtime image against the reference over each sphere. */
static void report_errors(const ibl_image *fast, const ibl_image *ref, const int *ids, int mesh)
{
    ibl_render_object objs[64];
    int n = ibl_render_scene_objects(objs, 64);
    if (mesh) {
        n = 1;
        snprintf(objs[0].label, sizeof objs[0].label, "mesh");
    }
    printf("%-22s %10s %10s %8s\n", "sphere", "split-sum", "reference", "error");
    double worst = 0;
    for (int o = 0; o < n; o++) {
        double sa = 0, sb = 0;
        size_t count = 0;
        for (size_t i = 0; i < (size_t)fast->width * fast->height; i++) {
            if (ids[i] != o) continue;
            for (int c = 0; c < 3; c++) {
                sa += fast->pixels[i * 4 + c];
                sb += ref->pixels[i * 4 + c];
            }
            count++;
        }
        if (!count) continue;
        double rel = sb > 0 ? (sa - sb) / sb : 0;
        if (rel < 0 ? -rel > worst : rel > worst) worst = rel < 0 ? -rel : rel;
        printf("%-22s %10.4g %10.4g %+7.2f%%\n", objs[o].label, sa / (3.0 * count),
               sb / (3.0 * count), 100 * rel);
    }
    printf("worst |error| %.2f%%\n", 100 * worst);
}

int cli_cmd_render(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "render", usage, {0}, {0}, 0};
    const char *output = NULL, *scene = NULL, *cmp[2] = {NULL, NULL};
    double exposure = 0;
    int exposure_given = 0;
    int width = 0, height = 0, specular_size = 0, report = 0;
    ibl_layout layout = IBL_LAYOUT_AUTO;
    ibl_probe_files files = {0};
    ibl_render_desc base = {0};
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o"))
            output = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--scene", NULL))
            scene = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--exposure", NULL)) {
            exposure = cli_double(&a, arg, -40, 40);
            exposure_given = 1;
        }
        else if (cli_is(&a, arg, "--width", NULL))
            width = cli_int(&a, arg, 8, 16384);
        else if (cli_is(&a, arg, "--height", NULL))
            height = cli_int(&a, arg, 4, 16384);
        else if (cli_is(&a, arg, "--specular-size", NULL))
            specular_size = cli_int(&a, arg, 4, 1024);
        else if (cli_is(&a, arg, "--samples", NULL))
            base.reference_samples = cli_int(&a, arg, 1, 1 << 20);
        else if (cli_is(&a, arg, "--reference", NULL))
            base.reference = 1;
        else if (cli_is(&a, arg, "--report", NULL))
            report = 1;
        else if (cli_is(&a, arg, "--chain", NULL))
            files.specular = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--lut", NULL))
            files.splitsum = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--ambient", NULL))
            files.ambient_brdf = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--ambient-range", NULL)) {
            const char *v = cli_value(&a, arg);
            char *end = NULL;
            double lo = strtod(v, &end), hi = end && *end == ':' ? strtod(end + 1, &end) : -1;
            if (!end || *end || !(lo > 0 && hi > lo))
                cli_usage_error(&a, "--ambient-range wants A:B with 0 < A < B, not '%s'", v);
            files.ambient_shininess_min = (float)lo;
            files.ambient_shininess_max = (float)hi;
        } else if (cli_is(&a, arg, "--supersample", NULL))
            base.supersample = cli_int(&a, arg, 1, 16);
        else if (cli_is(&a, arg, "--horizon", NULL))
            base.shade.horizon_occlusion = 1;
        else if (cli_is(&a, arg, "--mirror-direction", NULL))
            base.shade.mirror_direction = 1;
        else if (cli_is(&a, arg, "--sphere-ao", NULL))
            base.sphere_ao_min = (float)cli_double(&a, arg, 0, 1);
        else if (cli_is(&a, arg, "--layout", NULL)) {
            const char *v = cli_value(&a, arg);
            layout = ibl_layout_from_name(v);
            if (layout == IBL_LAYOUT_AUTO && strcmp(v, "auto") != 0)
                cli_usage_error(&a, "unknown layout '%s'", v);
        } else if (cli_is(&a, arg, "--so", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_so_formula_from_name(v, &base.shade.so))
                cli_usage_error(&a, "unknown --so '%s'", v);
        } else if (cli_is(&a, arg, "--mix", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_ambient_mix_from_name(v, &base.shade.mix))
                cli_usage_error(&a, "unknown --mix '%s'", v);
        } else if (cli_is(&a, arg, "--energy", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!energy_from_name(v, &base.shade.energy))
                cli_usage_error(&a, "unknown --energy '%s'", v);
        } else if (cli_is(&a, arg, "--compare", NULL)) {
            cmp[0] = cli_value(&a, arg);
            if (a.index >= a.argc) cli_usage_error(&a, "--compare needs two variants");
            cmp[1] = a.argv[a.index++];
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "needs one INPUT");
    if (!output) cli_usage_error(&a, "needs -o OUT");
    if (ibl_file_type_from_path(output) == IBL_FILE_UNKNOWN)
        cli_usage_error(&a, "cannot tell the output format of '%s' from its extension", output);
    base.width = width;
    base.height = height;

    ibl_context *ctx = cli_context(&a.common);
    const char *input = a.positional[0];
    ibl_probe probe = {0};
    ibl_cubemap env = {0};
    ibl_mesh mesh = {0};
    ibl_image images[2] = {{0}}, out = {0};
    int *ids = NULL;
    ibl_status st;
    double t0 = cli_seconds();
    if (is_directory(input)) {
        st = ibl_probe_load(ctx, input, &probe);
    } else {
        st = load_environment(ctx, &a, input, layout, &env);
        if (st == IBL_OK && files.specular) {
            files.mirror = input;
            files.clamp_infinite = a.common.clamp;
            if (strcmp(input, "sky") == 0) files.mirror = NULL;
            st = ibl_probe_load_files(ctx, &files, &probe);
        } else if (st == IBL_OK) {
            ibl_render_probe_desc pd = {.specular_size = specular_size};
            st = ibl_render_probe_from_environment(ctx, &env, &pd, &probe);
        }
        if (st == IBL_OK) base.environment = &env;
    }
    if (st == IBL_OK && scene && strcmp(scene, "balls") != 0) {
        st = ibl_mesh_load_obj(ctx, scene, 0, &mesh);
        base.mesh = &mesh;
    }
    double t1 = cli_seconds();
    if (st == IBL_OK) cli_info(&a.common, "probe ready in %.2f s\n", t1 - t0);

    variant v[2];
    int count = cmp[0] ? 2 : 1;
    for (int i = 0; i < count; i++) {
        v[i].desc = base;
        snprintf(v[i].label, sizeof v[i].label, "%s", cmp[i] && cmp[i][0] ? cmp[i] : "default");
        if (cmp[i]) apply_spec(&a, &v[i].desc, cmp[i]);
    }
    if (report && v[0].desc.supersample < 4 && !v[0].desc.reference) v[0].desc.supersample = 4;
    if (report && st == IBL_OK) {
        int w = width ? width : 1024, h = height ? height : (width ? (w + 1) / 2 : 512);
        ids = malloc(sizeof(int) * (size_t)w * h);
        if (!ids) st = IBL_ERR_OUT_OF_MEMORY;
    }
    for (int i = 0; i < count && st == IBL_OK; i++) {
        double s0 = cli_seconds();
        st = ibl_render(ctx, &probe, &v[i].desc, &images[i], i == 0 ? ids : NULL);
        if (st == IBL_OK)
            cli_info(&a.common, "rendered %dx%d%s in %.3f s\n", images[i].width, images[i].height,
                     v[i].desc.reference ? " (reference)" : "", cli_seconds() - s0);
    }
    if (st == IBL_OK && report) {
        ibl_render_desc rd = v[0].desc;
        rd.reference = !rd.reference;
        if (!rd.reference && rd.supersample < 4) rd.supersample = 4;
        ibl_image other;
        st = ibl_render(ctx, &probe, &rd, &other, NULL);
        if (st == IBL_OK) {
            report_errors(rd.reference ? &images[0] : &other, rd.reference ? &other : &images[0],
                          ids, rd.mesh != NULL);
            ibl_image_free(ctx, &other);
        }
    }
    if (st == IBL_OK) {
        int display = is_display_output(output);
        /* one exposure for every image of a comparison, from the first */
        if (display && !exposure_given) exposure = cli_auto_exposure(&images[0]);
        for (int i = 0; i < count && display; i++) ibl_render_tonemap(&images[i], (float)exposure);
        ibl_write_desc wd = {0};
        if (display) wd.tonemap = IBL_TONEMAP_NONE;
        if (count == 2) {
            st = ibl_render_side_by_side(ctx, &images[0], v[0].label, &images[1], v[1].label, &out);
            if (st == IBL_OK) st = ibl_write_image(ctx, output, &out, &wd);
        } else {
            st = ibl_write_image(ctx, output, &images[0], &wd);
        }
        if (st == IBL_OK) cli_info(&a.common, "wrote %s\n", output);
    }
    if (st != IBL_OK) cli_error("%s", ibl_context_message(ctx));
    free(ids);
    ibl_image_free(ctx, &out);
    for (int i = 0; i < 2; i++) ibl_image_free(ctx, &images[i]);
    ibl_mesh_free(ctx, &mesh);
    ibl_probe_free(ctx, &probe);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
    return cli_exit_code(st);
}
