#!/bin/sh
# BC6H and astcenc on prefiltered 256 chains: the quality and speed tables of docs/FORMATS.md
# ("BC6H") and docs/PERFORMANCE.md ("Compressed textures").
#   sh bench/compress_tables.sh [BUILD] [HDRI folder]
# Each HDRI (and the built-in clear sky with its sun, where BC6H's endpoint quantization is
# hardest) is prefiltered to the default GGX chain (256 faces, 9 levels) as float texels,
# then bench_compress encodes it at every quality, on 2 threads.
set -eu
BUILD=${1:-build}
HDRI=${2:-tests/data}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
"$BUILD/ibl" sky -q -o "$OUT/sky.exr"
for f in "$HDRI"/city.exr "$HDRI"/forest.exr "$HDRI"/interior.exr "$HDRI"/night.exr \
         "$HDRI"/studio.exr "$HDRI"/sunset.exr "$OUT/sky.exr"; do
  n=$(basename "$f" .exr)
  "$BUILD/ibl" prefilter -q "$f" -o "$OUT/$n.ktx2" --size 256 --format rgba32f
done
cd "$OUT"
"$OLDPWD/$BUILD/bench/bench_compress" -j 2 --runs 5 --astc city.ktx2 forest.ktx2 interior.ktx2 \
  night.ktx2 studio.ktx2 sunset.ktx2 sky.ktx2
