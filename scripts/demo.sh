#!/bin/sh
# make demo: the main job on the built-in environment, no input file needed.
set -eu
IBL=${1:-build/ibl}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$IBL" sky -q -o "$OUT/sky.exr"
"$IBL" convert -q "$OUT/sky.exr" -o "$OUT/sky_cube.ktx2" --size 256 --mips
"$IBL" convert -q "$OUT/sky.exr" -o "$OUT/sky_cross.png" --out-layout hcross --size 128
"$IBL" info "$OUT/sky_cube.ktx2"
echo
echo "demo results in $OUT/:"
echo "  sky.exr         the built-in clear sky (equirectangular, linear)"
echo "  sky_cube.ktx2   the same as a 256-face cubemap with its mip chain (RGBA16F)"
echo "  sky_cross.png   a tone-mapped preview (horizontal cross)"
