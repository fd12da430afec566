#!/bin/sh
# make fuzz: builds the decoding libraries from Debian's sources with the fuzzer's
# instrumentation (fuzz/build-deps.sh; scripts/install-deps.sh --fuzz fetched the sources),
# the libFuzzer targets with clang (ASan+UBSan) against them, and runs each target on a
# working copy of its starting corpus. New crashes are kept in fuzz/crashes/NAME so that
# `make test` replays them forever after.
#   FUZZ_SECONDS  seconds per target (default 60)
#   FUZZ_RUNS     stop a target after this many executions instead (whichever comes first)
#   FUZZ_TARGETS  names to run (default: every target), e.g. "jpeg exr"
# Each run's whole log is build-fuzz/logs/NAME.log; one summary line per target is printed.
set -eu
SECONDS_PER_TARGET=${FUZZ_SECONDS:-60}
RUNS=${FUZZ_RUNS:--1}
ROOT=$(pwd)
DEPS=$ROOT/build-fuzz/deps/prefix
BUDGET_MB=1024 # fuzz/fuzz_common.h's FUZZ_BUDGET: no single malloc may exceed it

sh fuzz/build-deps.sh
PKG_CONFIG_PATH=$DEPS/lib/pkgconfig cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DIBL_BUILD_FUZZ=ON -DIBL_BUILD_TESTS=OFF \
  -DIBL_BUILD_BENCH=OFF -DIBL_FUZZ_DEPS="$DEPS" -DOpenEXR_DIR="$DEPS/lib/cmake/OpenEXR" \
  -DImath_DIR="$DEPS/lib/cmake/Imath" -DZLIB_LIBRARY="$DEPS/lib/libz.a" \
  -DZLIB_INCLUDE_DIR="$DEPS/include" -DCMAKE_EXE_LINKER_FLAGS="-L$DEPS/lib" \
  -DCMAKE_C_FLAGS="-fsanitize=fuzzer-no-link,address,undefined" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined" >/dev/null
cmake --build build-fuzz -j 2 --target fuzz_all -- --no-print-directory >/dev/null

# The instrumented libraries must be the ones linked: no Debian copy may be loaded.
for t in build-fuzz/fuzz/fuzz_*; do
  if ldd "$t" | grep -E "lib(png16|jpeg|z|deflate)\.so|lib(OpenEXR|Imath|Iex|IlmThread)[-.]" >&2; then
    echo "fuzz/run.sh: $t loads uninstrumented decoding libraries" >&2
    exit 1
  fi
done

mkdir -p build-fuzz/logs
for t in build-fuzz/fuzz/fuzz_*; do
  name=${t##*/fuzz_}
  if [ -n "${FUZZ_TARGETS:-}" ] && ! echo " $FUZZ_TARGETS " | grep -q " $name "; then continue; fi
  work=fuzz/corpus-work/$name
  log=build-fuzz/logs/$name.log
  mkdir -p "$work" "fuzz/crashes/$name"
  cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
  before=$(ls "fuzz/crashes/$name" | wc -l)
  start=$(date +%s)
  # UBSan stops at its first report (as in make test; fuzz/ubsan.supp lists the few inside
  # Debian's libraries that are not ibl's); a single allocation above the
  # budget is a crash (-malloc_limit_mb): the library must refuse such sizes itself.
  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1:suppressions="$ROOT/fuzz/ubsan.supp" "$t" -max_total_time="$SECONDS_PER_TARGET" \
    -runs="$RUNS" -rss_limit_mb=3072 -malloc_limit_mb=$BUDGET_MB -timeout=60 -max_len=262144 \
    -artifact_prefix="fuzz/crashes/$name/" -print_final_stats=1 "$work" >"$log" 2>&1 || true
  end=$(date +%s)
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
  cov=$(grep -oE "cov: [0-9]+" "$log" | tail -1 | cut -d' ' -f2)
  crashes=$(($(ls "fuzz/crashes/$name" | wc -l) - before))
  echo "fuzz_$name: $((end - start)) s, ${execs:-?} executions, ${cov:-?} edges, peak RSS ${rss:-?} MB, $crashes new crashes"
  grep -E "^(==[0-9]+==ERROR|SUMMARY|.*runtime error)" "$log" | head -5 || true
done
