#!/bin/sh
# make fuzz, step 2: builds the libraries behind the decoders (zlib, libdeflate, libpng,
# libjpeg-turbo, Imath, OpenEXR) from the Debian source packages that
# `scripts/install-deps.sh --fuzz` fetched into build-fuzz/deps/src, with clang and the
# fuzzer's instrumentation (-fsanitize=fuzzer-no-link,address,undefined), as static libraries
# in build-fuzz/deps/prefix. The fuzz build links them instead of Debian's shared libraries,
# so libFuzzer sees their edges and ASan sees every access they make. Each library is built
# once per source version (a stamp in the prefix); nothing is downloaded here.
set -eu
ROOT=$(pwd)
DEPS=$ROOT/build-fuzz/deps
SRC=$DEPS/src
WORK=$DEPS/build
PREFIX=$DEPS/prefix
JOBS=${JOBS:-2}
SAN="-fsanitize=fuzzer-no-link,address,undefined"
CFLAGS="-O2 -g -fno-omit-frame-pointer -fPIC $SAN"
export CC=clang CXX=clang++
mkdir -p "$WORK" "$PREFIX/lib" "$PREFIX/include" "$PREFIX/stamps"

# The unpacked source folder of a source package (the version install-deps.sh fetched).
source_dir() {
  d=$(find "$SRC/$1" -mindepth 2 -maxdepth 2 -type d -name "$1-*" 2>/dev/null | sort | tail -1)
  [ -n "$d" ] || { echo "fuzz/build-deps.sh: no source of $1 in $SRC (run scripts/install-deps.sh --fuzz)" >&2; exit 1; }
  echo "$d"
}

# build NAME SOURCE_PACKAGE: runs "build_NAME SOURCE_DIR" unless that source was built
# before with the same flags; logs to WORK/NAME.log.
build() {
  name=$1
  dir=$(source_dir "$2")
  stamp="$PREFIX/stamps/$name"
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$dir $CFLAGS" ]; then return 0; fi
  echo "building instrumented $name from $(basename "$dir") (log: build-fuzz/deps/build/$name.log)" >&2
  rm -rf "${WORK:?}/$name"
  if ! "build_$name" "$dir" >"$WORK/$name.log" 2>&1; then
    tail -30 "$WORK/$name.log" >&2
    echo "fuzz/build-deps.sh: building $name failed" >&2
    exit 1
  fi
  echo "$dir $CFLAGS" >"$stamp"
}

build_zlib() {
  cp -a "$1" "$WORK/zlib"
  cd "$WORK/zlib"
  CFLAGS="$CFLAGS" ./configure --static --prefix="$PREFIX"
  make -j"$JOBS" libz.a
  make install
  cd "$ROOT"
}

build_libdeflate() {
  cp -a "$1" "$WORK/libdeflate"
  cd "$WORK/libdeflate"
  make -j"$JOBS" libdeflate.a CC="$CC" CFLAGS="$CFLAGS" DISABLE_SHARED=1
  install -m 644 libdeflate.a "$PREFIX/lib/"
  install -m 644 libdeflate.h "$PREFIX/include/"
  cd "$ROOT"
}

build_libpng() {
  mkdir -p "$WORK/libpng"
  cd "$WORK/libpng"
  "$1/configure" --prefix="$PREFIX" --disable-shared --enable-static \
    CFLAGS="$CFLAGS" CPPFLAGS="-I$PREFIX/include" LDFLAGS="-L$PREFIX/lib $SAN"
  make -j"$JOBS" libpng16.la
  make install-libLTLIBRARIES install-pkgincludeHEADERS install-nodist_pkgincludeHEADERS
  cd "$ROOT"
}

# CMake projects: static, no tests or tools, and never a download (FetchContent disconnected;
# the dependencies are given explicitly so that nothing falls back to fetching its own).
cmake_static() {
  src=$1
  bin=$2
  shift 2
  cmake -S "$src" -B "$bin" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_INSTALL_PREFIX="$PREFIX" \
    -DCMAKE_INSTALL_LIBDIR=lib -DBUILD_SHARED_LIBS=OFF -DBUILD_TESTING=OFF \
    -DCMAKE_C_FLAGS="$CFLAGS" -DCMAKE_CXX_FLAGS="$CFLAGS" -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
    -DFETCHCONTENT_FULLY_DISCONNECTED=ON -DCMAKE_PREFIX_PATH="$PREFIX" "$@"
  cmake --build "$bin" -j "$JOBS"
  cmake --install "$bin"
}

# libjpeg-turbo without its SIMD code: that is assembly (it would need nasm), which neither
# the coverage counters nor ASan see into, and the C code it replaces gives the same pixels.
# The libjpeg API only (no TurboJPEG), no shared objects. Its GNUInstallDirs takes a relative
# library folder from the command line as relative to the current folder: it is given whole.
build_libjpeg() {
  cmake_static "$1" "$WORK/libjpeg" -DCMAKE_INSTALL_LIBDIR="$PREFIX/lib" -DENABLE_SHARED=OFF \
    -DENABLE_STATIC=ON -DWITH_SIMD=OFF -DWITH_TURBOJPEG=OFF -DWITH_JAVA=OFF
}

build_imath() {
  cmake_static "$1" "$WORK/imath" -DPYTHON=OFF -DDOCS=OFF
}

build_openexr() {
  cmake_static "$1" "$WORK/openexr" -DImath_DIR="$PREFIX/lib/cmake/Imath" \
    -DZLIB_LIBRARY="$PREFIX/lib/libz.a" -DZLIB_INCLUDE_DIR="$PREFIX/include" \
    -DOPENEXR_BUILD_TOOLS=OFF -DOPENEXR_INSTALL_TOOLS=OFF -DOPENEXR_INSTALL_EXAMPLES=OFF \
    -DOPENEXR_INSTALL_PKG_CONFIG=OFF -DDOCS=OFF
  # the configuration must have taken the libraries above, not fetched its own
  if grep -q "installing from\|compiling internal\|not found, compiling" "$WORK/openexr.log"; then
    echo "OpenEXR wanted to fetch a dependency" >&2
    return 1
  fi
}

build zlib zlib
build libdeflate libdeflate
build libpng libpng1.6
build libjpeg libjpeg-turbo
build imath imath
build openexr openexr
