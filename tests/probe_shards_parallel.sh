#!/bin/sh
# The sample scene's probe set baked as N shards through GNU parallel, merged, and compared
# byte for byte with a single-process bake (docs/PROBES.md "Scale-out"). Small captures keep
# it to a few seconds. Usage: probe_shards_parallel.sh IBL REPO_ROOT WORKDIR [N]
set -eu
IBL=$1 ROOT=$2 WORK=$3 N=${4:-3}
command -v parallel >/dev/null || { echo "GNU parallel is missing (scripts/install-deps.sh)" >&2; exit 1; }
SET="$ROOT/examples/rooms/probes.json"
rm -rf "$WORK"; mkdir -p "$WORK"
"$IBL" capture -q "$ROOT/examples/rooms/scene.gltf" --probes "$SET" -o "$WORK/captures" \
    --size 16 --samples 2 --bounces 1
"$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/single"
seq 1 "$N" | parallel --halt now,fail=1 -j "$N" \
    "$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/sharded" --shard {}/"$N"
"$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/sharded" --merge
diff -r "$WORK/single" "$WORK/sharded"
echo "probe bake: $N shards through GNU parallel + merge = single process, byte for byte"
rm -rf "$WORK"
