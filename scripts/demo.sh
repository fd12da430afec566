#!/bin/sh
# make demo: the main job on the built-in environment, no input file needed. The preview is
# rendered from the bake itself: if ibl cannot read what it wrote, the demo fails.
set -eu
IBL=${1:-build/ibl}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$IBL" bake -o "$OUT/bake"
"$IBL" render "$OUT/bake" -o "$OUT/preview.png" -q
"$IBL" view "$OUT/bake" -o "$OUT/viewer.html" -q
echo
echo "demo results:"
echo "  $OUT/bake/            everything a renderer needs (manifest.json lists each file)"
echo "  $OUT/preview.png      spheres lit by the bake (GGX roughness x metalness, Blinn-Phong row)"
echo "  $OUT/viewer.html      the bake in a browser (WebGL2, one self-contained file; docs/VIEWER.md)"
