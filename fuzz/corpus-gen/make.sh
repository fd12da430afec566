#!/bin/sh
# Writes the starting corpora in fuzz/corpus/NAME from scratch-built programs and standard
# Debian tools (run from the repository root after `make build`; needs what
# `scripts/install-deps.sh --fuzz` installs: python3, cjpeg, libopenexr-dev):
#   containers.c     KTX2 / KTX1 / DDS through ibl's own encoders (every format and kind)
#   blocks.c         raw BC6H and ASTC blocks for the block-reader targets (bc6h, astc)
#   exr_variants.cpp OpenEXR through OpenEXR's C++ API (every compression, tiled, multi-part...)
#   images.py        PNG, JPEG (cjpeg), Radiance HDR, PFM, legacy-FourCC DDS
# The dispatcher's corpus (any) takes a few files of each. Files are small (a few KB).
set -eu
BUILD=${BUILD:-build}
OUT=fuzz/corpus
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cc -std=c11 -O1 -Wall -Wextra -Werror -Iinclude fuzz/corpus-gen/containers.c "$BUILD/libibl.a" \
  $(pkg-config --libs OpenEXR libpng libjpeg libdeflate libzstd) -lastcenc -lstdc++ -lpthread -lm \
  -o "$TMP/containers"
cc -std=c11 -O1 -Wall -Wextra -Werror -Iinclude fuzz/corpus-gen/blocks.c "$BUILD/libibl.a" \
  $(pkg-config --libs OpenEXR libpng libjpeg libdeflate libzstd) -lastcenc -lstdc++ -lpthread -lm \
  -o "$TMP/blocks"
c++ -std=c++17 -O1 -Wall -Wextra -Werror $(pkg-config --cflags OpenEXR) fuzz/corpus-gen/exr_variants.cpp \
  $(pkg-config --libs OpenEXR) -o "$TMP/exr_variants"
mkdir -p "$OUT/ktx2" "$OUT/ktx1" "$OUT/dds" "$OUT/exr" "$OUT/any" "$OUT/bc6h" "$OUT/astc"
"$TMP/containers" "$OUT"
"$TMP/blocks" "$OUT"
"$TMP/exr_variants" "$OUT/exr"
python3 fuzz/corpus-gen/images.py "$OUT"
for f in ktx2/cube_rg11b10f.ktx2 ktx1/3d_rgb9e5.ktx dds/2d_rg32f.dds exr/comp_dwab.exr \
  exr/tiled_mipmap_piz.exr exr/window_data_around.exr exr/luma_chroma_piz.exr; do
  cp "$OUT/$f" "$OUT/any/"
done
