/* ibl bake --probes SET: the probe-array bake (docs/PROBES.md "The probe bake"), a thin client
 * of ibl_probe_bake: captures from a folder or captured in the same run (--scene), shards and
 * the merge. */
#include "bake_probes.h"
#include "ibl/probes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cli_shard_value(cli_args *a, const char *arg, int *shard, int *shards)
{
    const char *v = cli_value(a, arg);
    char *end;
    long i = strtol(v, &end, 10), n = 0;
    if (*end == '/') n = strtol(end + 1, &end, 10);
    if (*end || n < 1 || n > 100000 || i < 1 || i > n)
        cli_usage_error(a, "--shard wants I/N with 1 <= I <= N, not '%s'", v);
    *shard = (int)i;
    *shards = (int)n;
}

/* Captures every probe in memory (--scene). */
static ibl_status capture_all(ibl_context *ctx, const char *scene_path, const ibl_probe_set *set,
                              const ibl_cubemap *env, ibl_cubemap *cubes)
{
    ibl_scene *scene = NULL;
    ibl_status st = ibl_scene_load_gltf(ctx, scene_path, &scene);
    for (int i = 0; i < set->probe_count && st == IBL_OK; i++)
        st = ibl_capture_probe(ctx, scene, env, &set->probes[i], i, NULL, &cubes[i]);
    ibl_scene_destroy(scene);
    return st;
}

int cli_bake_probes(cli_args *a, const cli_probe_bake_options *o)
{
    if (!o->captures == !o->scene) cli_usage_error(a, "--probes needs --captures DIR or --scene SCENE");
    if (o->shards && o->merge) cli_usage_error(a, "--shard and --merge do not go together");
    if (o->scene && (o->shards || o->merge))
        cli_usage_error(a, "--scene captures every probe in the run: use --captures with --shard/--merge");
    ibl_context *ctx = cli_context(&a->common);
    double t0 = cli_seconds();
    ibl_probe_set set;
    ibl_cubemap env = {0}, *cubes = NULL;
    ibl_status st = ibl_probe_set_load(ctx, o->probes, &set);
    int loaded = st == IBL_OK;
    if (st == IBL_OK && !o->shards) st = ibl_probe_set_environment(ctx, &set, &env);
    if (st == IBL_OK && o->scene) {
        cubes = calloc((size_t)set.probe_count, sizeof *cubes);
        st = cubes ? capture_all(ctx, o->scene, &set, &env, cubes) : IBL_ERR_OUT_OF_MEMORY;
    }
    ibl_probe_bake_report rep;
    memset(&rep, 0, sizeof rep);
    if (st == IBL_OK) {
        ibl_probe_bake_desc d;
        memset(&d, 0, sizeof d);
        d.captures = o->captures;
        d.cubes = cubes;
        d.shard = o->shard;
        d.shards = o->shards;
        d.merge = o->merge;
        d.format = o->format;
        d.lut_size = o->lut_size;
        st = ibl_probe_bake(ctx, &set, o->shards ? NULL : &env, &d, o->dir, &rep);
    }
    int rc = CLI_EXIT_OK;
    if (st != IBL_OK) {
        cli_report_failure(ctx, o->dir, st);
        rc = cli_exit_code(st);
    } else if (o->shards) {
        cli_info(&a->common, "shard %d/%d of %s: %d probes filtered, %d already in %s (%.1f s)\n",
                 o->shard, o->shards, o->probes, rep.computed, rep.reused, o->dir, cli_seconds() - t0);
    } else {
        cli_info(&a->common, "baked %d probes into %s: %d filtered, %d reused (%.1f s)\n",
                 set.probe_count, o->dir, rep.computed, rep.reused, cli_seconds() - t0);
    }
    for (int i = 0; cubes && i < set.probe_count; i++) ibl_cubemap_free(ctx, &cubes[i]);
    free(cubes);
    ibl_cubemap_free(ctx, &env);
    if (loaded) ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
    return rc;
}
