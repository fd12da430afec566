/* ibl capture: path-traces the cube of every local probe of a probe set in a glTF scene. */
#include "cli.h"
#include "ibl/probes.h"
#include "input.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl capture SCENE --probes SET -o CAPTURES [options]\n"
    "\n"
    "Captures each local probe of SET (a probe-set file, docs/PROBES.md) in SCENE (glTF 2.0,\n"
    ".gltf or .glb): a cube of premultiplied radiance and coverage alpha per probe, path-traced\n"
    "with the set's global probe (the sky or an HDRI) and the scene's emissive surfaces as\n"
    "light. Far-plane probes only see geometry inside their influence volume (alpha marks it);\n"
    "infinite probes see the sky too (alpha 1). CAPTURES receives captures.json and NAME.ktx2\n"
    "per probe (RGBA32F), all or nothing. The result is identical for any -j.\n"
    "\n"
    "  --probes SET         the probe-set file (required)\n"
    "  -o, --output DIR     the captures folder (created if missing)\n"
    "  --bounces N          reflections a path may take (default 2; 0: emitters and sky only)\n"
    "  --samples N          paths per texel (default 64)\n"
    "  --size N             cube edge for every probe (default: each probe's \"size\")\n"
    "  --seed N             random seed (default 0)\n"
    "  -q, -j N, --max-memory: see 'ibl --help'\n";

int cli_cmd_capture(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "capture", usage, {0}, {0}, 0};
    ibl_capture_desc d;
    memset(&d, 0, sizeof d);
    const char *out = NULL, *probes = NULL;
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--output", "-o")) out = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--probes", NULL)) probes = cli_value(&a, arg);
        else if (cli_is(&a, arg, "--bounces", NULL)) {
            d.bounces = cli_int(&a, arg, 0, 64);
            if (d.bounces == 0) d.bounces = IBL_CAPTURE_NO_BOUNCE;
        } else if (cli_is(&a, arg, "--samples", NULL)) d.samples = cli_int(&a, arg, 1, 1 << 20);
        else if (cli_is(&a, arg, "--size", NULL)) d.size = cli_int(&a, arg, 1, 4096);
        else if (cli_is(&a, arg, "--seed", NULL)) d.seed = (uint32_t)cli_double(&a, arg, 0, 4294967295.0);
        else cli_positional_or_unknown(&a, arg);
    }
    if (a.positional_count != 1) cli_usage_error(&a, "needs one scene file");
    if (!probes) cli_usage_error(&a, "needs a probe set: --probes SET");
    if (!out) cli_usage_error(&a, "needs an output folder: -o CAPTURES");
    const char *scene_path = a.positional[0];
    cli_check_not_inside(&a, scene_path, out);
    cli_check_not_inside(&a, probes, out);

    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_probe_set set;
    ibl_scene *scene = NULL;
    ibl_cubemap env = {0};
    ibl_status st = ibl_probe_set_load(ctx, probes, &set);
    if (st == IBL_OK) st = ibl_scene_load_gltf(ctx, scene_path, &scene);
    if (st == IBL_OK) st = ibl_probe_set_environment(ctx, &set, &env);
    if (st == IBL_OK) {
        ibl_scene_info info;
        ibl_scene_get_info(scene, &info);
        cli_info(&a.common, "%s: %d triangles (%d emissive), %d materials; %d probes\n",
                 scene_path, info.triangle_count, info.emissive_triangle_count,
                 info.material_count, set.probe_count);
        st = ibl_capture_set(ctx, scene, &env, &set, &d, out);
    }
    int rc = CLI_EXIT_OK;
    if (st != IBL_OK) {
        cli_report_failure(ctx, out, st);
        rc = cli_exit_code(st);
    } else {
        cli_info(&a.common, "wrote %s (%d probes) in %.1f s\n", out, set.probe_count,
                 cli_seconds() - t0);
    }
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(scene);
    ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
    return rc;
}
