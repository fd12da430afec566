#!/bin/sh
# make demo: the main job on the built-in environment, no input file needed.
set -eu
IBL=${1:-build/ibl}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$IBL" bake -o "$OUT/bake"
if "$IBL" render "$OUT/bake" -o "$OUT/preview.png" -q 2>/dev/null; then :; else
  "$IBL" render sky -o "$OUT/preview.png" -q
fi
echo
echo "demo results:"
echo "  $OUT/bake/            everything a renderer needs (manifest.json lists each file)"
echo "  $OUT/preview.png      spheres lit by the bake (GGX roughness x metalness, Blinn-Phong row)"
