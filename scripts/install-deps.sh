#!/bin/sh
# Installs the Debian 12 packages ibl needs to build, test and benchmark, when missing.
# This list is the single source of truth for dependencies (README.md repeats it).
#   build:     cmake make gcc g++ pkg-config
#   libraries: libopenexr-dev (OpenEXR 3.1, every compression incl. DWAA/DWAB; brings Imath)
#              libstb-dev (stb_image / stb_image_write: PNG and JPEG reading, JPEG writing)
#              libpng-dev (PNG writing, 8-bit sRGB and 16-bit linear)
#              libdeflate-dev (EXR ZIP/ZIPS chunks: 2-3x faster whole-buffer inflate than zlib)
#              libjansson-dev (JSON: the bake manifest, sh.json, --json outputs)
#   tests:     libcmocka-dev (test framework; CTest drives it)
#   fuzzing:   clang libclang-rt-14-dev (libFuzzer, sanitizer runtimes)   [make fuzz only]
#   benchmarks: hyperfine                                              [make bench only]
set -eu
PACKAGES="cmake make gcc g++ pkg-config libopenexr-dev libstb-dev libpng-dev libdeflate-dev libjansson-dev libcmocka-dev"
case "${1:-}" in
  --fuzz) PACKAGES="$PACKAGES clang libclang-rt-14-dev" ;;
  --bench) PACKAGES="$PACKAGES hyperfine" ;;
esac
missing=""
for p in $PACKAGES; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing="$missing $p"
  fi
done
[ -z "$missing" ] && exit 0
if [ "$(id -u)" = 0 ]; then
  echo "installing:$missing" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq >/dev/null
  apt-get install -y -qq --no-install-recommends $missing >/dev/null
else
  echo "ibl needs these Debian packages; run:" >&2
  echo "  sudo apt-get install -y$missing" >&2
  exit 1
fi
