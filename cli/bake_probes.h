/* ibl bake --probes: the probe-array bake's part of the bake command (cli/bake_probes.c). */
#ifndef IBL_CLI_BAKE_PROBES_H
#define IBL_CLI_BAKE_PROBES_H

#include "cli.h"

typedef struct cli_probe_bake_options {
    const char *dir, *probes, *captures, *scene;
    int shard, shards, merge;
    int lut_size; /* --lut-size: the global probe's split-sum table */
    ibl_format format;
} cli_probe_bake_options;

#define CLI_PROBE_BAKE_HELP                                                                   \
    "\n"                                                                                      \
    "Probe sets (docs/PROBES.md): ibl bake --probes SET (--captures CAPTURES | --scene SCENE)\n" \
    "-o DIR bakes the global probe and every local probe's capture into DIR: probes.ktx2\n"   \
    "(one cube-map array, blend order), probes.bin (std430 records) and probes.json.\n"     \
    "  --probes SET           the probe-set file\n"                                         \
    "  --captures DIR         what 'ibl capture' wrote for SET\n"                           \
    "  --scene SCENE          capture SET in SCENE (glTF) in this run instead\n"            \
    "  --shard I/N            only filter share I of N of the probes (parts in DIR)\n"      \
    "  --merge                assemble DIR from the parts the shards wrote\n"            \
    "  (--lut-size and --format apply: the global probe's table, the local chains' storage)\n"

void cli_shard_value(cli_args *a, const char *arg, int *shard, int *shards);
int cli_bake_probes(cli_args *a, const cli_probe_bake_options *o);

#endif
