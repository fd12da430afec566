/* ibl render SCENE --probes DIR: a glTF scene through a camera, lit by its probe bake
 * (ibl_probe_render), with comparisons that switch one feature off and a path-traced
 * reference (ibl_trace_view) measured per region. A thin client of probes.h. */
#include "render_probes.h"

#include "input.h"
#include "ibl/probes.h"
#include "ibl/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl render SCENE --probes DIR -o OUT [options]\n"
    "\n"
    "Renders SCENE (glTF 2.0) from a camera with every visible surface lit by the probe bake\n"
    "DIR (`ibl bake --probes`): tiled culling of the influence volumes with the view's depth,\n"
    "per-pixel influence weights, parallax correction, the alpha-aware priority blend with\n"
    "the global probe last, split-sum GGX specular and SH diffuse (docs/PROBES.md). Emitters\n"
    "show their own radiance. OUT .png/.jpg is tone-mapped (filmic), .exr/.hdr/.pfm linear.\n"
    "\n"
    "options:\n"
    "  --probes DIR          the probe bake folder (required)\n"
    "  -o, --output FILE     output image (required)\n"
    "  --set SET             the probe-set file: its \"view\" is the default camera and its\n"
    "                        global environment lights the reference (without it: the\n"
    "                        camera at the scene's centre looking along -Z, and the global\n"
    "                        probe's sharpest level)\n"
    "  --camera X,Y,Z        camera position; --target X,Y,Z the point it looks at;\n"
    "  --fov DEGREES         vertical field of view (default 60)\n"
    "  --width W             image width (default 640); --height H (default W * 9 / 16)\n"
    "  --exposure EV         exposure of tone-mapped outputs (default: automatic, from the\n"
    "                        probe-lit image; every half of a comparison uses the same)\n"
    "  --compare FEATURE     parallax, blend or alpha: the render with the feature (left)\n"
    "                        and without it (right), labelled\n"
    "  --reference           path-trace the same view (ibl_trace_view) and write the\n"
    "                        probe-lit render and the reference side by side; prints the\n"
    "                        error per region (a pixel's region: the probe with the largest\n"
    "                        specular share at its surface, or 'global')\n"
    "  --reference-output F  also write the reference alone to F\n"
    "  --samples N           reference paths per pixel (default 256)\n"
    "  --bounces N           reference reflections per path (default 3: the captures'\n"
    "                        default 2 plus the reflection at the visible surface)\n"
    "  --seed N              the reference's random seed (default 0)\n"
    "  -q, -j N, --max-memory MiB: see 'ibl --help'\n";

typedef struct probe_render_options {
    const char *scene, *probes, *set, *output, *reference_output, *compare;
    ibl_camera cam;
    int camera_given, target_given, fov_given, reference;
    ibl_vec3 target;
    double exposure;
    int exposure_given;
    ibl_trace_desc trace;
} probe_render_options;

static ibl_vec3 vec3_value(cli_args *a, const char *arg)
{
    const char *v = cli_value(a, arg);
    double x[3];
    char *end = (char *)v;
    for (int i = 0; i < 3; i++) {
        const char *start = end + (i > 0);
        x[i] = strtod(start, &end);
        if (end == start || !isfinite(x[i]) || fabs(x[i]) > 1e6 || *end != (i < 2 ? ',' : '\0'))
            cli_usage_error(a, "%s wants X,Y,Z, not '%s'", arg, v);
    }
    return (ibl_vec3){(float)x[0], (float)x[1], (float)x[2]};
}

static void parse(cli_args *a, probe_render_options *o)
{
    const char *arg;
    while ((arg = cli_next(a))) {
        if (cli_common_option(a, arg)) continue;
        if (cli_is(a, arg, "--output", "-o")) o->output = cli_value(a, arg);
        else if (cli_is(a, arg, "--probes", NULL)) o->probes = cli_value(a, arg);
        else if (cli_is(a, arg, "--set", NULL)) o->set = cli_value(a, arg);
        else if (cli_is(a, arg, "--camera", NULL)) o->cam.position = vec3_value(a, arg), o->camera_given = 1;
        else if (cli_is(a, arg, "--target", NULL)) o->target = vec3_value(a, arg), o->target_given = 1;
        else if (cli_is(a, arg, "--fov", NULL)) {
            o->cam.fov_y_degrees = (float)cli_double(a, arg, 1, 170);
            o->fov_given = 1;
        } else if (cli_is(a, arg, "--width", NULL)) o->cam.width = cli_int(a, arg, 8, 16384);
        else if (cli_is(a, arg, "--height", NULL)) o->cam.height = cli_int(a, arg, 4, 16384);
        else if (cli_is(a, arg, "--exposure", NULL)) {
            o->exposure = cli_double(a, arg, -40, 40);
            o->exposure_given = 1;
        } else if (cli_is(a, arg, "--compare", NULL)) {
            o->compare = cli_value(a, arg);
            if (strcmp(o->compare, "parallax") && strcmp(o->compare, "blend") && strcmp(o->compare, "alpha"))
                cli_usage_error(a, "--compare wants parallax, blend or alpha, not '%s'", o->compare);
        } else if (cli_flag(a, arg, "--reference", NULL)) o->reference = 1;
        else if (cli_is(a, arg, "--reference-output", NULL)) o->reference_output = cli_value(a, arg);
        else if (cli_is(a, arg, "--samples", NULL)) o->trace.samples = cli_int(a, arg, 1, 1 << 20);
        else if (cli_is(a, arg, "--bounces", NULL)) {
            o->trace.bounces = cli_int(a, arg, 0, 64);
            if (o->trace.bounces == 0) o->trace.bounces = IBL_CAPTURE_NO_BOUNCE;
        } else if (cli_is(a, arg, "--seed", NULL)) o->trace.seed = (uint32_t)cli_double(a, arg, 0, 4294967295.0);
        else cli_positional_or_unknown(a, arg);
    }
    if (a->positional_count != 1) cli_usage_error(a, "needs one SCENE");
    if (!o->output) cli_usage_error(a, "needs -o OUT");
    if (o->compare && o->reference) cli_usage_error(a, "--compare and --reference are separate renders");
    if (o->reference_output && !o->reference) cli_usage_error(a, "--reference-output goes with --reference");
    o->scene = a->positional[0];
    cli_check_output(a, o->output);
    if (o->reference_output) cli_check_output(a, o->reference_output);
    if (!o->cam.width) o->cam.width = 640;
    if (!o->cam.height) o->cam.height = o->cam.width * 9 / 16 > 4 ? o->cam.width * 9 / 16 : 4;
    if (!o->trace.samples) o->trace.samples = 256;
    if (!o->trace.bounces) o->trace.bounces = 3;
}

/* The camera: the flags over the set's view over the scene's centre looking along -Z. */
static int make_camera(cli_args *a, probe_render_options *o, const ibl_probe_set *set,
                       const ibl_scene *scene)
{
    ibl_scene_info info;
    ibl_scene_get_info(scene, &info);
    ibl_vec3 pos = {0.5f * (info.bounds_min[0] + info.bounds_max[0]),
                    0.5f * (info.bounds_min[1] + info.bounds_max[1]),
                    0.5f * (info.bounds_min[2] + info.bounds_max[2])};
    ibl_vec3 target = {pos.x, pos.y, pos.z - 1.0f};
    float fov = 60.0f;
    if (set && set->has_view) pos = set->view.position, target = set->view.target, fov = set->view.fov_y_degrees;
    if (o->camera_given) pos = o->cam.position;
    if (o->target_given) target = o->target;
    if (o->fov_given) fov = o->cam.fov_y_degrees;
    ibl_vec3 f = {target.x - pos.x, target.y - pos.y, target.z - pos.z};
    float len = sqrtf(f.x * f.x + f.y * f.y + f.z * f.z);
    if (!(len > 0.0f)) cli_usage_error(a, "the camera's target must differ from its position");
    /* +Y up unless the camera looks straight up or down */
    ibl_vec3 up = fabsf(f.y) > 0.999f * len ? (ibl_vec3){0, 0, -1} : (ibl_vec3){0, 1, 0};
    o->cam.position = pos;
    o->cam.forward = f;
    o->cam.up = up;
    o->cam.fov_y_degrees = fov;
    return CLI_EXIT_OK;
}

typedef struct region_sum {
    double render, reference, abs_error;
    long pixels;
} region_sum;

static double mean_rgb(const float *p)
{
    return (p[0] + p[1] + p[2]) / 3.0;
}

/* Per region: the mean of the probe-lit image and of the reference, the error of the mean
 * and the mean absolute per-pixel error relative to the reference's mean. */
static void report_regions(const ibl_probe_bake_data *bake, const ibl_image *render,
                           const ibl_image *reference, const int *regions)
{
    int n = bake->count + 1; /* slot count: global */
    region_sum *sum = calloc((size_t)n + 1, sizeof *sum);
    if (!sum) return;
    size_t pixels = (size_t)render->width * render->height;
    for (size_t i = 0; i < pixels; i++) {
        if (regions[i] == IBL_REGION_BACKGROUND) continue;
        int k = regions[i] >= 0 ? regions[i] : n - 1;
        double a = mean_rgb(render->pixels + 4 * i), b = mean_rgb(reference->pixels + 4 * i);
        sum[k].render += a;
        sum[k].reference += b;
        sum[k].abs_error += fabs(a - b);
        sum[k].pixels++;
        sum[n].render += a, sum[n].reference += b, sum[n].abs_error += fabs(a - b), sum[n].pixels++;
    }
    printf("%-16s %8s %11s %11s %10s %10s\n", "region", "pixels", "probes", "reference",
           "mean err", "pixel err");
    for (int k = 0; k <= n; k++) {
        if (!sum[k].pixels) continue;
        const char *name = k < bake->count ? bake->records[k].name : k == n - 1 ? "global" : "all surfaces";
        double ra = sum[k].render / sum[k].pixels, rb = sum[k].reference / sum[k].pixels;
        printf("%-16s %8ld %11.4g %11.4g %+9.1f%% %9.1f%%\n", name, sum[k].pixels, ra, rb,
               rb > 0 ? 100.0 * (ra - rb) / rb : 0.0,
               rb > 0 ? 100.0 * sum[k].abs_error / sum[k].pixels / rb : 0.0);
    }
    free(sum);
}

static ibl_status write_display(ibl_context *ctx, const char *path, ibl_image *image,
                                float exposure)
{
    int display = cli_is_display_format(path);
    if (display) ibl_render_tonemap(image, exposure);
    ibl_write_desc wd = {.tonemap = display ? IBL_TONEMAP_NONE : IBL_TONEMAP_DEFAULT};
    return ibl_write_image(ctx, path, image, &wd);
}

/* The reference's environment: the set's (what the captures saw), or the global probe's
 * sharpest level. */
static ibl_status reference_environment(ibl_context *ctx, const ibl_probe_set *set,
                                        const ibl_probe_bake_data *bake, ibl_cubemap *env)
{
    if (set) return ibl_probe_set_environment(ctx, set, env);
    const ibl_cubemap *g = &bake->global.specular;
    ibl_status st = ibl_cubemap_alloc(ctx, g->size, 1, env);
    if (st == IBL_OK) memcpy(env->data, g->data, sizeof(float) * 4 * 6 * (size_t)g->size * g->size);
    return st;
}

/* Renders what the options ask for and writes OUT (and the reference). */
static ibl_status render_all(ibl_context *ctx, cli_args *a, const probe_render_options *o,
                             const ibl_scene *scene, const ibl_probe_set *set,
                             const ibl_probe_bake_data *bake)
{
    ibl_image img[2] = {{0}}, joined = {0};
    ibl_cubemap env = {0};
    size_t pixels = (size_t)o->cam.width * o->cam.height;
    int *regions = o->reference ? malloc(sizeof(int) * pixels) : NULL;
    ibl_probe_render_desc d;
    memset(&d, 0, sizeof d);
    double t0 = cli_seconds();
    ibl_status st = o->reference && !regions ? IBL_ERR_OUT_OF_MEMORY : IBL_OK;
    if (st == IBL_OK) st = ibl_probe_render(ctx, scene, bake, &o->cam, &d, &img[0], regions);
    if (st == IBL_OK)
        cli_info(&a->common, "probe-lit %dx%d in %.2f s\n", o->cam.width, o->cam.height, cli_seconds() - t0);
    const char *labels[2] = {"probes", "path traced"};
    char with[64] = "", without[64] = "";
    if (st == IBL_OK && o->compare) {
        d.blend.no_parallax = strcmp(o->compare, "parallax") == 0;
        d.blend.no_blend = strcmp(o->compare, "blend") == 0;
        d.blend.no_alpha = strcmp(o->compare, "alpha") == 0;
        snprintf(with, sizeof with, "with %s", o->compare);
        snprintf(without, sizeof without, "without %s", o->compare);
        labels[0] = with, labels[1] = without;
        st = ibl_probe_render(ctx, scene, bake, &o->cam, &d, &img[1], NULL);
    }
    if (st == IBL_OK && o->reference) {
        st = reference_environment(ctx, set, bake, &env);
        t0 = cli_seconds();
        if (st == IBL_OK) st = ibl_trace_view(ctx, scene, &env, &o->cam, &o->trace, &img[1]);
        if (st == IBL_OK) {
            cli_info(&a->common, "reference: %d paths per pixel, %d bounces, %.1f s\n", o->trace.samples,
                     o->trace.bounces < 0 ? 0 : o->trace.bounces, cli_seconds() - t0);
            report_regions(bake, &img[0], &img[1], regions);
        }
    }
    float exposure = st == IBL_OK && !o->exposure_given ? ibl_image_auto_exposure(&img[0]) : (float)o->exposure;
    if (st == IBL_OK && o->reference_output) {
        ibl_image copy;
        st = ibl_image_alloc(ctx, img[1].width, img[1].height, &copy);
        if (st == IBL_OK) {
            memcpy(copy.pixels, img[1].pixels, sizeof(float) * 4 * pixels);
            st = write_display(ctx, o->reference_output, &copy, exposure);
            ibl_image_free(ctx, &copy);
        }
        if (st == IBL_OK) cli_info(&a->common, "wrote %s\n", o->reference_output);
    }
    int two = o->compare || o->reference;
    if (st == IBL_OK && two && cli_is_display_format(o->output)) {
        for (int i = 0; i < 2; i++) ibl_render_tonemap(&img[i], exposure);
        exposure = 0.0f;
    }
    if (st == IBL_OK && two) st = ibl_render_side_by_side(ctx, &img[0], labels[0], &img[1], labels[1], &joined);
    if (st == IBL_OK) {
        if (two && cli_is_display_format(o->output)) {
            ibl_write_desc wd = {.tonemap = IBL_TONEMAP_NONE};
            st = ibl_write_image(ctx, o->output, &joined, &wd);
        } else {
            st = write_display(ctx, o->output, two ? &joined : &img[0], exposure);
        }
    }
    if (st == IBL_OK) cli_info(&a->common, "wrote %s\n", o->output);
    free(regions);
    ibl_cubemap_free(ctx, &env);
    ibl_image_free(ctx, &joined);
    for (int i = 0; i < 2; i++) ibl_image_free(ctx, &img[i]);
    return st;
}

int cli_render_probes(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "render", usage, {0}, {0}, 0};
    probe_render_options o;
    memset(&o, 0, sizeof o);
    parse(&a, &o);
    ibl_context *ctx = cli_context(&a.common);
    ibl_probe_set set;
    memset(&set, 0, sizeof set);
    ibl_scene *scene = NULL;
    ibl_probe_bake_data bake;
    memset(&bake, 0, sizeof bake);
    const char *failed = o.set;
    ibl_status st = o.set ? ibl_probe_set_load(ctx, o.set, &set) : IBL_OK;
    if (st == IBL_OK) failed = o.scene, st = ibl_scene_load_gltf(ctx, o.scene, &scene);
    if (st == IBL_OK) failed = o.probes, st = ibl_probe_bake_load(ctx, o.probes, &bake);
    int rc = CLI_EXIT_OK;
    if (st == IBL_OK) {
        make_camera(&a, &o, o.set ? &set : NULL, scene);
        failed = o.output;
        st = render_all(ctx, &a, &o, scene, o.set ? &set : NULL, &bake);
    }
    if (st != IBL_OK) {
        cli_report_failure(ctx, failed, st);
        rc = cli_exit_code(st);
    }
    ibl_probe_bake_free(ctx, &bake);
    ibl_scene_destroy(scene);
    if (o.set) ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
    return rc;
}
