#!/bin/sh
# bench/large.sh BUILD [OTHER_IBL]: the prefilter at film sizes (docs/PERFORMANCE.md "Specular
# prefilter at large sizes"). Makes the inputs (make_large_inputs.sh, in $LARGE_DIR, default
# /tmp/ibl-large), then, whole commands under hyperfine: the 512 chain from 2048x1024, the 512
# and 1024 chains from 4096x2048 on 2 threads and on 1, the Phong-family chains next to GGX at
# 1024, the 2048 chain from 8192x4096, and the peak RSS of each (GNU time). LARGE_16K=1 adds
# the 512 chain from a 16384x8192 EXR (1.3 GB; its plan is built at 2048, not at the 4096 cube
# it is read as: ibl_specular_source_size). With OTHER_IBL (another build's ibl, e.g. the
# previous commit's in a git worktree) every timing runs both binaries side by side in one
# hyperfine call.
# INPUT_ACCURACY=1 adds docs/SPECULAR.md "Accuracy against the input": the GGX chains at 512
# and 1024 (rgba32f) against the exact integral over their input (bench_input_accuracy, levels
# 1-3; minutes of CPU at 1024).
set -eu
BUILD=${1:-build}
OTHER=${2:-}
DIR=${LARGE_DIR:-/tmp/ibl-large}
EDGES="512 1024 2048"
[ "${LARGE_16K:-0}" = 1 ] && EDGES="$EDGES 4096"
sh "$(dirname "$0")/make_large_inputs.sh" "$BUILD" "$DIR" $EDGES
IBL=$BUILD/ibl
O=$DIR/out.ktx2
cases="city2048.exr|512|
city4096.exr|512|
city4096.exr|1024|
city4096.exr|1024|-j 1
city4096.exr|1024|--filter phong --levels 6
city4096.exr|1024|--filter blinn --levels 6
city4096.exr|1024|--filter box
city4096.exr|1024|--filter gauss
city8192.exr|2048|"
[ "${LARGE_16K:-0}" = 1 ] && cases="$cases
city16384.exr|512|"
echo "$cases" | while IFS='|' read -r in size extra; do
  cmd="prefilter -q $DIR/$in -o $O --size $size $extra"
  if [ -n "$OTHER" ]; then
    hyperfine -N -w 1 -r 5 "$IBL $cmd" "$OTHER $cmd"
  else
    hyperfine -N -w 1 -r 5 "$IBL $cmd"
  fi
  /usr/bin/time -f "peak RSS %M KB: $cmd" "$IBL" $cmd
done
if [ "${INPUT_ACCURACY:-0}" = 1 ]; then
  for pair in city2048.exr:512 city4096.exr:1024; do
    in=${pair%%:*} size=${pair##*:}
    "$IBL" prefilter -q "$DIR/$in" -o "$DIR/acc$size.ktx2" --size "$size" --format rgba32f
    "$BUILD/bench/bench_input_accuracy" "$DIR/$in" "$DIR/acc$size.ktx2" --samples 100 --max-level 3
  done
fi
