#!/bin/sh
# bench/make_large_inputs.sh BUILD OUTDIR [EDGE...]: the large test inputs of the prefilter's
# scaling cases, made from tests/data/city.exr by `ibl convert` (nothing large is committed).
# For every cube edge E given (default 512 1024 2048: 2048x1024, 4096x2048 and 8192x4096, 23,
# 90 and 346 MB; 4096 makes the 16384x8192 one, 1.3 GB, and needs 1.5 GiB more on the way) it
# writes OUTDIR/city{4E}.exr, a 4E x 2E float RGB equirect (OpenEXR ZIP): city.exr resampled up
# to an E cube, then unfolded. --format rgb32f: the resampled cube's alpha is 1 only to within
# float rounding, which would otherwise make the writer keep a fourth channel that no real HDRI
# has. Existing files are kept.
set -eu
BUILD=${1:?usage: make_large_inputs.sh BUILD OUTDIR [EDGE...]}
OUT=${2:?usage: make_large_inputs.sh BUILD OUTDIR [EDGE...]}
shift 2
[ $# -gt 0 ] || set -- 512 1024 2048
SRC=$(dirname "$0")/../tests/data/city.exr
mkdir -p "$OUT"
for E in "$@"; do
  F="$OUT/city$((4 * E)).exr"
  [ -s "$F" ] && continue
  "$BUILD/ibl" convert -q "$SRC" -o "$OUT/cube$E.ktx2" --size "$E" --format rgba32f
  "$BUILD/ibl" convert -q "$OUT/cube$E.ktx2" -o "$F" --format rgb32f
  rm -f "$OUT/cube$E.ktx2"
  echo "$F"
done
