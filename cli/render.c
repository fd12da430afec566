/* ibl render: the preview of a probe on spheres or a mesh, its Monte Carlo reference, and
 * labelled side-by-side comparisons. A thin client of bake.h and render.h. */
#include "input.h"
#include "render_probes.h"

#include "ibl/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char usage[] =
    "usage: ibl render INPUT -o OUT [options]\n"
    "       ibl render SCENE --probes DIR -o OUT [options]   (options: ibl render --probes DIR --help)\n"
    "\n"
    "Draws the environment and a grid of spheres (GGX roughness 0..1 for a metal and a\n"
    "dielectric row, and a row of Blinn-Phong shininess values) lit by the baked probe, with a\n"
    "small CPU ray tracer. OUT .png/.jpg is tone-mapped (filmic), .exr/.hdr/.pfm is linear.\n"
    "\n"
    "INPUT is a bake folder (what `ibl bake` writes) or its manifest.json, an environment in\n"
    "any layout or a cube texture (.ktx2/.dds; baked in memory first, see docs/SHADING.md), or\n"
    "'sky' for the built-in procedural sky.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE     output image (required)\n"
    "  --scene balls|FILE    the sphere grid (default) or a Wavefront OBJ mesh; its vertex\n"
    "                        colours' red is the AO, otherwise AO is ray-cast\n"
    "  --exposure EV         exposure for tone-mapped outputs (default: automatic, the\n"
    "                        image's mean luminance maps to middle grey)\n"
    "  --width W             image width (default 1024); --height H (default W/2)\n"
    "  --specular-size N     face size of the in-memory prefiltered chain (default 128)\n"
    "  --chain FILE          use this prefiltered chain (a cube .ktx2/.dds; one ibl wrote\n"
    "                        describes its levels, any other is taken as level k at\n"
    "                        roughness k/(levels-1)) instead of prefiltering INPUT, which\n"
    "                        stays the background, mirror and SH source; with --lut FILE\n"
    "                        (split-sum table) and --ambient FILE (AmbientBRDF volume, as\n"
    "                        `ibl lut` writes them; --ambient-range A:B, default 1:2000)\n"
    "  --atlas               read the chain from the bake's 2D mip atlas (a bake made with\n"
    "                        --out-layout atlas), bilinear in each level then linear, as\n"
    "                        shaders/ibl_atlas.glsl does on an 8-slot GLES device (no mirror)\n"
    "  --so FORMULA          specular occlusion: none ao triace triace-shininess triace-fast\n"
    "                        frostbite cone (default none)\n"
    "  --mix MODE            ambient composition: multiply lerp-albedo lerp-ao ao-lerp-ao\n"
    "                        lerp-ao2 entire (default multiply)\n"
    "  --energy MODE         GGX multiple scattering: none fdez-aguera turquin (default none)\n"
    "  --horizon             horizon occlusion of reflections\n"
    "  --mirror-direction    look up rough reflections along R, not the lobe's dominant\n"
    "                        direction (shows the split sum's error at high roughness)\n"
    "  --sphere-ao MIN       synthetic AO on the spheres from MIN (bottom) to 1 (top)\n"
    "  --environment FILE    the unfiltered environment for the background and the\n"
    "                        reference (default: INPUT's; a bake folder's is its chain's\n"
    "                        level 0): give a bake its source to measure it\n"
    "  --reference           Monte Carlo reference of the same scene (no split sum)\n"
    "  --samples N           reference iterations per pixel, 3 directions each (default 256)\n"
    "  --supersample N       N x N rays per pixel for the runtime shading (default 1; the\n"
    "                        reference spreads its samples over each pixel anyway)\n"
    "  --report              also render the reference and print the error per sphere\n"
    "                        (the runtime image then uses at least 4 x 4 rays per pixel)\n"
    "  --light SPEC          a punctual light (KHR_lights_punctual units; repeat for more, up\n"
    "                        to 16; unshadowed, not drawn), ':'-separated fields, an empty\n"
    "                        field keeps its default:\n"
    "                          dir:DX,DY,DZ[:R,G,B[:LUX[:SIZE]]]\n"
    "                          point:X,Y,Z[:R,G,B[:CANDELA[:RADIUS[:RANGE]]]]\n"
    "                          spot:X,Y,Z:DX,DY,DZ[:R,G,B[:CANDELA[:RADIUS[:RANGE[:IN,OUT]]]]]\n"
    "                        D is the direction the light travels; colour default 1,1,1,\n"
    "                        intensity 1; SIZE is the tangent of a directional light's\n"
    "                        angular radius (the sun: 0.0047), RADIUS a sphere's (default 0:\n"
    "                        a delta light); RANGE default 0: none; IN,OUT the spot's cone\n"
    "                        half-angles in degrees (default 0,45). The scene is centred at\n"
    "                        the origin, +Y up, the camera at (0,0,12), spheres of radius\n"
    "                        0.48. e.g. --light point:-3,4,4::60:0.5:30\n"
    "  --light-size MODEL    what a light's size does at run time: widen (default: tri-Ace's\n"
    "                        shininess hack for Blinn-Phong, Karis's sphere-light alpha for\n"
    "                        GGX) or ignore (a delta light); the reference always integrates\n"
    "                        the sphere\n"
    "  --compare A B         two variants side by side, labelled; each is a comma-separated\n"
    "                        list of so=, mix=, energy=, bp-diffuse=ambient-brdf|f0, samples=,\n"
    "                        sphere-ao=, light-size=, horizon, mirror-direction, nearest-level,\n"
    "                        reference, skin=off|on, applied over the other options, e.g.\n"
    "                        --compare so=none so=triace-fast,sphere-ao=0.2\n"
    "                        --compare '' reference,samples=512\n"
    "                        --compare skin=off skin=on\n"
    "skin (docs/SKIN.md; --scene is then a glTF or OBJ mesh with texture coordinates):\n"
    "  --scattered BASE      the scattered normal maps BASE_r, _g, _b (what `ibl sss -o BASE`\n"
    "                        wrote), each colour channel lit along its own normal\n"
    "  --normal FILE         the unscattered normal map (specular, and skin=off)\n"
    "  --transmittance FILE  the grey transmittance map (`ibl sss --transmittance`)\n"
    "  --range MM            the thickness its 0 stands for (default 8)\n"
    "  --albedo R,G,B        the skin's diffuse albedo (default 0.8,0.55,0.45)\n"
    CLI_INPUT_HELP
    "  -q, -j N, --clamp, --max-memory MiB: see 'ibl --help'\n";

typedef struct variant {
    ibl_render_desc desc;
    char label[96];
} variant;

/* One "key[=value]" override; returns 0 if unknown or malformed. */
static int apply_setting(ibl_render_desc *d, const char *key, const char *value)
{
    if (strcmp(key, "so") == 0) return value && ibl_so_formula_from_name(value, &d->shade.so);
    if (strcmp(key, "mix") == 0) return value && ibl_ambient_mix_from_name(value, &d->shade.mix);
    if (strcmp(key, "energy") == 0) return value && ibl_energy_compensation_from_name(value, &d->shade.energy);
    if (strcmp(key, "light-size") == 0)
        return value && ibl_light_size_model_from_name(value, &d->shade.light_size);
    if (strcmp(key, "horizon") == 0) return d->shade.horizon_occlusion = 1;
    if (strcmp(key, "nearest-level") == 0) return d->shade.nearest_level = 1;
    if (strcmp(key, "mirror-direction") == 0) return d->shade.mirror_direction = 1;
    if (strcmp(key, "reference") == 0) return d->reference = 1;
    if (strcmp(key, "skin") == 0) {
        if (!value || (strcmp(value, "off") != 0 && strcmp(value, "on") != 0)) return 0;
        d->skin_off = strcmp(value, "off") == 0;
        return 1;
    }
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

enum { MAX_LIGHTS = 16 };

/* Parses "x,y,z" (count numbers) into out; 0 if malformed. */
static int parse_numbers(const char *text, float *out, int count)
{
    const char *p = text;
    for (int i = 0; i < count; i++) {
        char *end;
        double x = strtod(p, &end);
        if (end == p || !(x > -1e30 && x < 1e30)) return 0;
        out[i] = (float)x;
        if (i + 1 < count && *end != ',') return 0;
        p = end + (i + 1 < count);
        if (i + 1 == count && *end) return 0;
    }
    return 1;
}

/* One --light SPEC (the help text gives the grammar). */
static void parse_light(cli_args *a, const char *spec, ibl_light *light)
{
    char buf[256], *field[9] = {0};
    snprintf(buf, sizeof buf, "%s", spec);
    int n = 0;
    for (char *p = buf; n < 9; n++) {
        field[n] = p;
        char *colon = strchr(p, ':');
        if (!colon) {
            n++;
            break;
        }
        *colon = 0;
        p = colon + 1;
    }
    memset(light, 0, sizeof *light);
    int spot = strcmp(field[0], "spot") == 0, at = 1;
    if (strcmp(field[0], "dir") == 0 || strcmp(field[0], "directional") == 0)
        light->type = IBL_LIGHT_DIRECTIONAL;
    else if (strcmp(field[0], "point") == 0)
        light->type = IBL_LIGHT_POINT;
    else if (spot)
        light->type = IBL_LIGHT_SPOT;
    else
        cli_usage_error(a, "--light '%s': the type is dir, point or spot", spec);
    float v[3];
    int fields = light->type == IBL_LIGHT_DIRECTIONAL ? 5 : (spot ? 8 : 6);
    if (n > fields || n < (spot ? 3 : 2)) cli_usage_error(a, "--light '%s': %d fields", spec, n);
    if (!parse_numbers(field[at++], v, 3)) cli_usage_error(a, "--light '%s': bad vector", spec);
    ibl_vec3 vec = {v[0], v[1], v[2]};
    if (light->type == IBL_LIGHT_DIRECTIONAL) light->direction = vec;
    else light->position = vec;
    if (spot) {
        if (!parse_numbers(field[at++], v, 3)) cli_usage_error(a, "--light '%s': bad direction", spec);
        light->direction = (ibl_vec3){v[0], v[1], v[2]};
    }
    float *scalars[3] = {&light->intensity, &light->size, &light->range};
    for (int k = at; k < n; k++) {
        if (!field[k][0]) continue; /* empty: the default */
        int ok, which = k - at;     /* 0 colour, 1 intensity, 2 size, 3 range, 4 cone */
        if (which == 0) ok = parse_numbers(field[k], light->color, 3);
        else if (which <= 3) ok = parse_numbers(field[k], scalars[which - 1], 1);
        else {
            ok = parse_numbers(field[k], v, 2);
            light->inner_cone = v[0] * 0.017453293f;
            light->outer_cone = v[1] * 0.017453293f;
        }
        if (!ok) cli_usage_error(a, "--light '%s': bad field '%s'", spec, field[k]);
    }
    /* light.h reads intensity 0 as glTF's default 1: ask for a positive one */
    if (n > at + 1 && field[at + 1][0] && !(light->intensity > 0.0f))
        cli_usage_error(a, "--light '%s': the intensity must be > 0", spec);
    ibl_context *check;
    if (ibl_context_create(&(ibl_context_desc){.threads = 1}, &check) != IBL_OK)
        cli_usage_error(a, "out of memory");
    if (ibl_light_validate(check, light, 0) != IBL_OK) {
        char msg[256];
        snprintf(msg, sizeof msg, "%s", ibl_context_message(check));
        ibl_context_destroy(check);
        cli_usage_error(a, "--light '%s': %s", spec, msg);
    }
    ibl_context_destroy(check);
}

/* What the command line asked for besides the variants. */
typedef struct render_options {
    const char *output, *scene, *environment, *cmp[2];
    const char *scattered, *normal, *transmittance;
    ibl_render_skin skin;
    ibl_light lights[MAX_LIGHTS];
    double exposure;
    int exposure_given, specular_size, report, atlas;
    cli_input_options input;
    ibl_bake_parts parts;
    ibl_render_desc base;
} render_options;

static void parse_ambient_range(cli_args *a, const char *arg, ibl_bake_parts *parts)
{
    const char *v = cli_value(a, arg);
    char *end = NULL;
    double lo = strtod(v, &end), hi = end && *end == ':' ? strtod(end + 1, &end) : -1;
    if (!end || *end || !(lo > 0 && hi > lo))
        cli_usage_error(a, "--ambient-range wants A:B with 0 < A < B, not '%s'", v);
    parts->ambient_shininess_min = (float)lo;
    parts->ambient_shininess_max = (float)hi;
}

/* The options of the shading itself (also the keys of --compare). */
static int shading_option(cli_args *a, const char *arg, ibl_render_desc *d)
{
    static const char *const keys[] = {"--so", "--mix", "--energy", NULL};
    for (int i = 0; keys[i]; i++)
        if (cli_is(a, arg, keys[i], NULL)) {
            const char *v = cli_value(a, arg);
            if (!apply_setting(d, keys[i] + 2, v)) cli_usage_error(a, "unknown %s '%s'", keys[i], v);
            return 1;
        }
    if (cli_is(a, arg, "--horizon", NULL)) d->shade.horizon_occlusion = 1;
    else if (cli_is(a, arg, "--mirror-direction", NULL)) d->shade.mirror_direction = 1;
    else if (cli_is(a, arg, "--sphere-ao", NULL)) d->sphere_ao_min = (float)cli_double(a, arg, 0, 1);
    else if (cli_is(a, arg, "--supersample", NULL)) d->supersample = cli_int(a, arg, 1, 16);
    else if (cli_is(a, arg, "--samples", NULL)) d->reference_samples = cli_int(a, arg, 1, 1 << 20);
    else if (cli_is(a, arg, "--reference", NULL)) d->reference = 1;
    else return 0;
    return 1;
}

static void parse(cli_args *a, render_options *o)
{
    const char *arg;
    while ((arg = cli_next(a))) {
        if (cli_common_option(a, arg) || cli_input_option(a, arg, &o->input) ||
            shading_option(a, arg, &o->base))
            continue;
        if (cli_is(a, arg, "--output", "-o")) o->output = cli_value(a, arg);
        else if (cli_is(a, arg, "--scene", NULL)) o->scene = cli_value(a, arg);
        else if (cli_is(a, arg, "--environment", NULL)) o->environment = cli_value(a, arg);
        else if (cli_is(a, arg, "--exposure", NULL)) {
            o->exposure = cli_double(a, arg, -40, 40);
            o->exposure_given = 1;
        } else if (cli_is(a, arg, "--width", NULL)) o->base.width = cli_int(a, arg, 8, 16384);
        else if (cli_is(a, arg, "--height", NULL)) o->base.height = cli_int(a, arg, 4, 16384);
        else if (cli_is(a, arg, "--specular-size", NULL)) o->specular_size = cli_int(a, arg, 4, 1024);
        else if (cli_is(a, arg, "--report", NULL)) o->report = 1;
        else if (cli_is(a, arg, "--atlas", NULL)) o->atlas = 1;
        else if (cli_is(a, arg, "--light", NULL)) {
            if (o->base.light_count == MAX_LIGHTS) cli_usage_error(a, "at most %d lights", MAX_LIGHTS);
            parse_light(a, cli_value(a, arg), &o->lights[o->base.light_count++]);
        } else if (cli_is(a, arg, "--light-size", NULL)) {
            const char *v = cli_value(a, arg);
            if (!ibl_light_size_model_from_name(v, &o->base.shade.light_size))
                cli_usage_error(a, "unknown --light-size '%s'", v);
        }
        else if (cli_is(a, arg, "--scattered", NULL)) o->scattered = cli_value(a, arg);
        else if (cli_is(a, arg, "--normal", NULL)) o->normal = cli_value(a, arg);
        else if (cli_is(a, arg, "--transmittance", NULL)) o->transmittance = cli_value(a, arg);
        else if (cli_is(a, arg, "--range", NULL)) o->skin.thickness_range_mm = (float)cli_double(a, arg, 1e-3, 1e6);
        else if (cli_is(a, arg, "--albedo", NULL)) {
            const char *v = cli_value(a, arg);
            if (!parse_numbers(v, o->skin.albedo, 3) || !(o->skin.albedo[0] >= 0 && o->skin.albedo[1] >= 0 &&
                                                          o->skin.albedo[2] >= 0))
                cli_usage_error(a, "--albedo wants R,G,B >= 0, not '%s'", v);
        }
        else if (cli_is(a, arg, "--chain", NULL)) o->parts.specular = cli_value(a, arg);
        else if (cli_is(a, arg, "--lut", NULL)) o->parts.splitsum = cli_value(a, arg);
        else if (cli_is(a, arg, "--ambient", NULL)) o->parts.ambient_brdf = cli_value(a, arg);
        else if (cli_is(a, arg, "--ambient-range", NULL)) parse_ambient_range(a, arg, &o->parts);
        else if (cli_is(a, arg, "--compare", NULL)) {
            o->cmp[0] = cli_value(a, arg);
            if (a->index >= a->argc) cli_usage_error(a, "--compare needs two variants");
            o->cmp[1] = a->argv[a->index++];
        } else {
            cli_positional_or_unknown(a, arg);
        }
    }
    o->base.lights = o->lights;
    if (a->positional_count != 1) cli_usage_error(a, "needs one INPUT");
    if (!o->output) cli_usage_error(a, "needs -o OUT");
    cli_check_output(a, o->output);
    if ((o->parts.splitsum || o->parts.ambient_brdf) && !o->parts.specular)
        cli_usage_error(a, "--lut and --ambient go with --chain");
    if ((o->normal || o->transmittance) && !o->scattered)
        cli_usage_error(a, "--normal and --transmittance go with --scattered");
    if (o->scattered && (!o->normal || !o->scene || strcmp(o->scene, "balls") == 0))
        cli_usage_error(a, "--scattered needs --normal and --scene MESH");
}

static int is_bake(const char *path)
{
    struct stat st;
    size_t n = strlen(path);
    return (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) ||
           (n >= 5 && strcmp(path + n - 5, ".json") == 0);
}

/* The environment INPUT names: the built-in sky or a file in any layout. */
static int read_environment(ibl_context *ctx, const cli_args *a, const render_options *o,
                            const char *input, ibl_cubemap *env)
{
    cli_input_options in = o->input; /* a copy: the read records the input's detail in it */
    if (strcmp(input, "sky") != 0) return cli_read_cubemap(ctx, &a->common, input, &in, env, NULL);
    return cli_read_sky(ctx, NULL, &o->input, env);
}

/* The bake the probe views: a folder, or made here from an environment (with a chain given
 * by --chain, or prefiltered in memory). */
static int make_bake(ibl_context *ctx, const cli_args *a, const render_options *o,
                     ibl_bake_data *bake)
{
    const char *input = a->positional[0];
    ibl_read_desc rd = {.clamp_infinite = a->common.clamp};
    ibl_status st;
    if (is_bake(input)) {
        st = ibl_bake_load(ctx, input, &rd, bake);
        if (st != IBL_OK) cli_report_failure(ctx, input, st);
        return st == IBL_OK ? CLI_EXIT_OK : CLI_EXIT_BAD_INPUT;
    }
    ibl_cubemap env = {0};
    int rc = read_environment(ctx, a, o, input, &env);
    if (rc != CLI_EXIT_OK) return rc;
    if (o->parts.specular) {
        st = ibl_bake_load_parts(ctx, &o->parts, &rd, bake);
        if (st == IBL_OK) bake->environment = env; /* the background and mirror */
        else ibl_cubemap_free(ctx, &env);
    } else {
        ibl_bake_desc d;
        ibl_render_bake_desc(&env, o->specular_size, &d);
        st = ibl_bake_compute(ctx, &env, &d, bake);
        ibl_cubemap_free(ctx, &env);
    }
    if (st != IBL_OK) cli_report_failure(ctx, o->parts.specular ? o->parts.specular : input, st);
    return st == IBL_OK ? CLI_EXIT_OK : CLI_EXIT_BAD_INPUT;
}

/* Renders the variants (and the report), tone-maps and writes OUT. */
static ibl_status render_and_write(ibl_context *ctx, const cli_args *a, const render_options *o,
                                   const ibl_probe *probe, const ibl_mesh *mesh)
{
    variant v[2];
    int count = o->cmp[0] ? 2 : 1;
    for (int i = 0; i < count; i++) {
        v[i].desc = o->base;
        v[i].desc.mesh = mesh;
        snprintf(v[i].label, sizeof v[i].label, "%s", o->cmp[i] && o->cmp[i][0] ? o->cmp[i] : "default");
        if (o->cmp[i]) apply_spec((cli_args *)a, &v[i].desc, o->cmp[i]);
    }
    if (o->report && v[0].desc.supersample < 4 && !v[0].desc.reference) v[0].desc.supersample = 4;
    ibl_image images[2] = {{0}}, out = {0};
    int *ids = NULL;
    ibl_status st = IBL_OK;
    if (o->report) {
        int w = o->base.width ? o->base.width : 1024;
        int h = o->base.height ? o->base.height : (o->base.width ? (w + 1) / 2 : 512);
        ids = malloc(sizeof(int) * (size_t)w * h);
        if (!ids) st = IBL_ERR_OUT_OF_MEMORY;
    }
    for (int i = 0; i < count && st == IBL_OK; i++) {
        double s0 = cli_seconds();
        st = ibl_render(ctx, probe, &v[i].desc, &images[i], i == 0 ? ids : NULL);
        if (st == IBL_OK)
            cli_info(&a->common, "rendered %dx%d%s in %.3f s\n", images[i].width, images[i].height,
                     v[i].desc.reference ? " (reference)" : "", cli_seconds() - s0);
    }
    if (st == IBL_OK && o->report) {
        ibl_render_desc rd = v[0].desc;
        rd.reference = !rd.reference;
        if (!rd.reference && rd.supersample < 4) rd.supersample = 4;
        ibl_image other;
        st = ibl_render(ctx, probe, &rd, &other, NULL);
        if (st == IBL_OK) {
            report_errors(rd.reference ? &images[0] : &other, rd.reference ? &other : &images[0],
                          ids, rd.mesh != NULL);
            ibl_image_free(ctx, &other);
        }
    }
    if (st == IBL_OK) {
        int display = cli_is_display_format(o->output);
        /* one exposure for every image of a comparison, from the first */
        float exposure = o->exposure_given ? (float)o->exposure : ibl_image_auto_exposure(&images[0]);
        for (int i = 0; i < count && display; i++) ibl_render_tonemap(&images[i], exposure);
        ibl_write_desc wd = {.tonemap = display ? IBL_TONEMAP_NONE : IBL_TONEMAP_DEFAULT};
        if (count == 2)
            st = ibl_render_side_by_side(ctx, &images[0], v[0].label, &images[1], v[1].label, &out);
        if (st == IBL_OK) st = ibl_write_image(ctx, o->output, count == 2 ? &out : &images[0], &wd);
        if (st == IBL_OK) cli_info(&a->common, "wrote %s\n", o->output);
    }
    free(ids);
    ibl_image_free(ctx, &out);
    for (int i = 0; i < 2; i++) ibl_image_free(ctx, &images[i]);
    return st;
}

/* The skin's mesh and maps (--scattered): five images, freed by the caller. */
typedef struct skin_data {
    ibl_scene *mesh;
    ibl_image maps[5]; /* normal, scattered r g b, transmittance */
} skin_data;

static ibl_status load_skin(ibl_context *ctx, render_options *o, skin_data *sd)
{
    const char *failed = o->scene;
    ibl_status st = ibl_scene_load(ctx, o->scene, &sd->mesh);
    char paths[5][4096];
    snprintf(paths[0], sizeof paths[0], "%s", o->normal);
    const char *dot = strrchr(o->scattered, '.'), *slash = strrchr(o->scattered, '/');
    if (!dot || (slash && dot < slash)) dot = o->scattered + strlen(o->scattered);
    for (int c = 0; c < 3; c++)
        snprintf(paths[1 + c], sizeof paths[1 + c], "%.*s_%c%s", (int)(dot - o->scattered),
                 o->scattered, "rgb"[c], dot);
    snprintf(paths[4], sizeof paths[4], "%s", o->transmittance ? o->transmittance : "");
    for (int i = 0; i < 5 && st == IBL_OK; i++) {
        if (!paths[i][0]) continue;
        failed = paths[i];
        st = ibl_read_image(ctx, paths[i], &(ibl_read_desc){.as_data = 1}, &sd->maps[i], NULL);
    }
    if (st != IBL_OK) {
        cli_report_failure(ctx, failed, st);
        return st;
    }
    o->skin.mesh = sd->mesh;
    o->skin.normal = &sd->maps[0];
    for (int c = 0; c < 3; c++) o->skin.scattered[c] = &sd->maps[1 + c];
    o->skin.transmittance = o->transmittance ? &sd->maps[4] : NULL;
    o->base.skin = &o->skin;
    return IBL_OK;
}

int cli_cmd_render(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (strcmp(argv[i], "--probes") == 0 || strncmp(argv[i], "--probes=", 9) == 0)
            return cli_render_probes(argc, argv);
    cli_args a = {argc, argv, 0, "render", usage, {0}, {0}, 0};
    render_options o;
    memset(&o, 0, sizeof o);
    parse(&a, &o);
    ibl_context *ctx = cli_context(&a.common);
    ibl_bake_data bake = {0};
    ibl_probe probe;
    ibl_mesh mesh = {0};
    ibl_cubemap environment = {0};
    double t0 = cli_seconds();
    int rc = make_bake(ctx, &a, &o, &bake);
    if (rc == CLI_EXIT_OK && o.environment) {
        rc = read_environment(ctx, &a, &o, o.environment, &environment);
        o.base.environment = &environment;
    }
    ibl_status st = IBL_OK;
    skin_data sd;
    memset(&sd, 0, sizeof sd);
    if (rc == CLI_EXIT_OK && o.scattered && load_skin(ctx, &o, &sd) != IBL_OK) rc = CLI_EXIT_BAD_INPUT;
    if (rc == CLI_EXIT_OK) {
        st = ibl_bake_probe(ctx, &bake, &probe);
        if (st == IBL_OK && o.atlas && !probe.atlas) {
            cli_error("%s: holds no mip atlas (bake it with --out-layout atlas)", a.positional[0]);
            rc = CLI_EXIT_BAD_INPUT;
        } else if (st == IBL_OK && o.atlas) {
            probe.use_atlas = 1;
            st = ibl_probe_validate(ctx, &probe);
        }
        if (rc == CLI_EXIT_OK && st == IBL_OK && o.scene && strcmp(o.scene, "balls") != 0 && !o.scattered)
            st = ibl_mesh_load_obj(ctx, o.scene, 0, &mesh);
        if (rc == CLI_EXIT_OK && st == IBL_OK)
            cli_info(&a.common, "probe ready in %.2f s\n", cli_seconds() - t0);
        if (rc == CLI_EXIT_OK && st == IBL_OK) st = render_and_write(ctx, &a, &o, &probe, mesh.positions ? &mesh : NULL);
        if (st != IBL_OK) cli_report_failure(ctx, a.positional[0], st), rc = CLI_EXIT_BAD_INPUT;
    }
    ibl_mesh_free(ctx, &mesh);
    ibl_scene_destroy(sd.mesh);
    for (int i = 0; i < 5; i++) ibl_image_free(ctx, &sd.maps[i]);
    ibl_cubemap_free(ctx, &environment);
    ibl_bake_free(ctx, &bake);
    ibl_context_destroy(ctx);
    return rc;
}
