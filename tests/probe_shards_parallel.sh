#!/bin/sh
# The sample scene's probe set baked as N shards through GNU parallel, merged, and compared
# byte for byte with a single-process bake (docs/PROBES.md "Scale-out"). The set is the
# sample's with every cube edge cut to 8 (global probe and captures) and the global probe's
# split-sum table is 16 wide: the proof is the same bytes whatever the sizes, and the global
# probe's bake at 128 with its 128-wide tables took most of the time under ASan.
# Usage: probe_shards_parallel.sh IBL REPO_ROOT WORKDIR [N]
set -eu
IBL=$1 ROOT=$2 WORK=$3 N=${4:-3}
command -v parallel >/dev/null || { echo "GNU parallel is missing (scripts/install-deps.sh)" >&2; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
SET="$WORK/probes.json"
sed 's/"size": [0-9]*/"size": 8/' "$ROOT/examples/rooms/probes.json" > "$SET"
grep -q '"size": 8' "$SET" || { echo "the sample set has no sizes to cut" >&2; exit 1; }
"$IBL" capture -q "$ROOT/examples/rooms/scene.gltf" --probes "$SET" -o "$WORK/captures" \
    --samples 2 --bounces 1
"$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/single" --lut-size 16
seq 1 "$N" | parallel --halt now,fail=1 -j "$N" \
    "$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/sharded" --shard {}/"$N"
"$IBL" bake -q -j 1 --probes "$SET" --captures "$WORK/captures" -o "$WORK/sharded" --merge --lut-size 16
diff -r "$WORK/single" "$WORK/sharded"
echo "probe bake: $N shards through GNU parallel + merge = single process, byte for byte"
rm -rf "$WORK"
