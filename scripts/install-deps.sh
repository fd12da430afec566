#!/bin/sh
# Installs the Debian 12 packages ibl needs to build, test and benchmark, when missing.
# This list is the single source of truth for dependencies (README.md repeats it).
#   build:     cmake make gcc g++ pkg-config
#   libraries: libopenexr-dev (OpenEXR 3.1, every compression incl. DWAA/DWAB; brings Imath)
#              libpng-dev (PNG reading; writing 8-bit sRGB and 16-bit linear)
#              libjpeg-dev (libjpeg-turbo: JPEG reading and writing)
#              libdeflate-dev (EXR ZIP/ZIPS chunks: 2-3x faster whole-buffer inflate than zlib)
#              libjansson-dev (JSON: the bake manifest, sh.json, --json outputs, probe sets)
#              libassimp-dev (glTF 2.0 scenes for probe capture, through its C API; loaded
#                when a scene is read, src/scene/libraries.h)
#              libembree-dev (Intel Embree 3: ray casting in those scenes; loaded likewise)
#              libzstd-dev (Zstandard: KTX2 supercompression, written with --zstd, read always)
#              libastcenc-dev (ARM's astcenc 4.2: ASTC HDR encoding and decoding)
#   tests:     libcmocka-dev (test framework; CTest drives it), parallel (GNU parallel: the
#              probe bake's shard/merge test and docs/PROBES.md's scale-out recipes)
#   shaders:   libegl-dev (EGL headers, libglvnd's loader), libgl-dev (GL/glcorearb.h),
#              libegl-mesa0 (Mesa's EGL: the surfaceless platform), libgl1-mesa-dri (llvmpipe,
#              OpenGL 4.5 core in software), glslang-tools (glslangValidator: every GLSL
#              dialect and HLSL); tests/test_shaders.c and examples/ run them headless
#   viewer:    chromium (the headless browser of the `ibl view` tests, software WebGL2),
#              nodejs and npm (npm only when no npm is on PATH: a nodejs that bundles it
#              conflicts with Debian's); then `npm ci` in tests/viewer installs the exact
#              versions of its package-lock.json from the npm registry (no browser
#              download: the tests drive /usr/bin/chromium): playwright-core; three and
#              @babylonjs/core (the engines `ibl bake --target` is tested in, served
#              locally); ktx-parse (the KTX2 round trip of every file ibl writes);
#              filament (Filament's WebAssembly build, which `ibl bake --target filament`
#              is rendered in; @babylonjs/core's DDSTools also reads ibl's DDS files);
#              @babylonjs/loaders (Babylon's glTF loader and its EXT_lights_image_based,
#              which loads `ibl bake --target gltf`)
#              python3-openimageio (OpenImageIO's Python module: an independent reader of
#              ibl's BC6H DDS files, tests/viewer/dds_oiio_test.py)
#   godot:     godot3 (Godot 3.2.3: tests/godot renders `ibl bake --target godot` in it), xvfb
#              and xauth (xvfb-run: the X server Godot needs, without a display)
#   fuzzing:   clang libclang-rt-14-dev (libFuzzer, sanitizer runtimes), dpkg-dev (apt-get
#              source unpacks with dpkg-source), zlib1g-dev libimath-dev (their versions name
#              the sources to fetch), python3 libjpeg-turbo-progs (cjpeg) for
#              fuzz/corpus-gen/make.sh, which writes the starting corpora    [make fuzz only]
#              and the SOURCE packages below, fetched with `apt-get source` into
#              build-fuzz/deps/src so that fuzz/build-deps.sh can build them instrumented
#   benchmarks: hyperfine                                              [make bench only]
#
# `--fuzz` may add a deb-src entry mirroring the machine's deb entries (same URIs, suites,
# components and keyring) in /etc/apt/sources.list.d/ibl-deb-src.sources. Nothing else is
# ever downloaded: every byte comes through apt from the machine's configured Debian archive.
set -eu
PACKAGES="cmake make gcc g++ pkg-config libopenexr-dev libpng-dev libjpeg-dev libdeflate-dev libjansson-dev libassimp-dev libembree-dev libzstd-dev libastcenc-dev libcmocka-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri glslang-tools parallel chromium nodejs python3-openimageio godot3 xvfb xauth"
command -v npm >/dev/null 2>&1 || PACKAGES="$PACKAGES npm"
# Source package:binary package whose installed version is fetched (headers and instrumented
# libraries then match exactly). Built in this order by fuzz/build-deps.sh.
FUZZ_SOURCES="zlib:zlib1g-dev libdeflate:libdeflate-dev libpng1.6:libpng-dev libjpeg-turbo:libjpeg62-turbo-dev imath:libimath-dev openexr:libopenexr-dev"
FUZZ_SRC_DIR=${FUZZ_SRC_DIR:-build-fuzz/deps/src}
case "$FUZZ_SRC_DIR" in /*) ;; *) FUZZ_SRC_DIR="$(pwd)/$FUZZ_SRC_DIR" ;; esac
mode=${1:-}
case "$mode" in
  --fuzz) PACKAGES="$PACKAGES zlib1g-dev libimath-dev clang libclang-rt-14-dev dpkg-dev python3 libjpeg-turbo-progs" ;;
  --bench) PACKAGES="$PACKAGES hyperfine" ;;
esac
is_root() { [ "$(id -u)" = 0 ]; }

missing=""
for p in $PACKAGES; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing="$missing $p"
  fi
done
if [ -n "$missing" ]; then
  if is_root; then
    echo "installing:$missing" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends $missing >/dev/null
  else
    echo "ibl needs these Debian packages; run:" >&2
    echo "  sudo apt-get install -y$missing" >&2
    exit 1
  fi
fi
# the browser tests' npm packages, from the lock file (again whenever it changes)
viewer_dir="$(cd "$(dirname "$0")/.." && pwd)/tests/viewer"
if [ -f "$viewer_dir/package-lock.json" ] &&
   ! cmp -s "$viewer_dir/package-lock.json" "$viewer_dir/node_modules/.ibl-lock" 2>/dev/null; then
  echo "installing the viewer tests' npm packages (npm ci in tests/viewer)" >&2
  (cd "$viewer_dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) ||
    { echo "npm ci failed in $viewer_dir" >&2; exit 1; }
  cp "$viewer_dir/package-lock.json" "$viewer_dir/node_modules/.ibl-lock"
fi
[ "$mode" = --fuzz ] || exit 0

# ---- fuzz mode: the sources of the libraries the decoders run, for instrumented builds ----
# A source package is fetched once; its folder is named after the version the binary
# package has, so an upgrade of the system library fetches (and builds) the new one.
need=""
for entry in $FUZZ_SOURCES; do
  src=${entry%%:*}
  bin=${entry#*:}
  ver=$(dpkg-query -W -f='${source:Version}' "$bin")
  [ -f "$FUZZ_SRC_DIR/$src/$(echo "$ver" | tr : _)/.fetched" ] || need="$need $src=$ver"
done
[ -z "$need" ] && exit 0

# deb-src lines for the deb lines the machine already has (deb822 or one-line format)
has_deb_src() {
  grep -qsE '^[[:space:]]*deb-src[[:space:]]' /etc/apt/sources.list /etc/apt/sources.list.d/*.list ||
    grep -qsE '^Types:.*deb-src' /etc/apt/sources.list.d/*.sources
}
if ! has_deb_src; then
  if ! is_root; then
    echo "make fuzz builds Debian's sources of its decoding libraries; as root, add deb-src" >&2
    echo "entries matching your deb entries and rerun, or run: sudo sh $0 --fuzz" >&2
    exit 1
  fi
  out=/etc/apt/sources.list.d/ibl-deb-src.sources
  echo "adding deb-src entries for the configured Debian archive: $out" >&2
  {
    for f in /etc/apt/sources.list.d/*.sources; do
      [ -f "$f" ] && [ "$f" != "$out" ] || continue
      # each deb822 stanza with Types: deb, as the same stanza with Types: deb-src
      awk 'BEGIN { RS = ""; ORS = "\n\n" }
           /(^|\n)Types:[ \t]*deb([ \t]|\n|$)/ { sub(/Types:[ \t]*deb/, "Types: deb-src"); print }' "$f"
    done
    if [ -f /etc/apt/sources.list ]; then
      sed -n 's/^[[:space:]]*deb[[:space:]]\+\(\[[^]]*\][[:space:]]\+\)\?\([^[:space:]]\+\)[[:space:]]\+\([^[:space:]]\+\)[[:space:]]\+\(.*\)$/Types: deb-src\nURIs: \2\nSuites: \3\nComponents: \4\n/p' \
        /etc/apt/sources.list
    fi
  } >"$out.tmp"
  mv "$out.tmp" "$out"
  apt-get update -qq >/dev/null
fi
for spec in $need; do
  src=${spec%%=*}
  ver=${spec#*=}
  dir="$FUZZ_SRC_DIR/$src/$(echo "$ver" | tr : _)"
  rm -rf "$dir"
  mkdir -p "$dir"
  echo "fetching Debian source $src $ver" >&2
  # the installed version first; the archive may have moved on since (and a mirror may
  # lack one suite's sources): then every version it lists, newest first
  ok=""
  for v in "$ver" $(apt-cache showsrc "$src" | sed -n 's/^Version: //p' | sort -rV); do
    if (cd "$dir" && apt-get source -qq "$src=$v" >/dev/null 2>>"$dir.log"); then
      ok=$v
      break
    fi
    rm -rf "$dir" && mkdir -p "$dir"
  done
  [ -n "$ok" ] || { cat "$dir.log" >&2; echo "cannot fetch the Debian source of $src" >&2; exit 1; }
  [ "$ok" = "$ver" ] || echo "  $src $ver is not in the archive's sources: fetched $ok" >&2
  touch "$dir/.fetched"
done
