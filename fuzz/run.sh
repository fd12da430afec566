#!/bin/sh
# make fuzz: builds the libFuzzer targets with clang (ASan+UBSan) and runs each for
# FUZZ_SECONDS (default 60) on a working copy of its seed corpus. New crashes are kept in
# fuzz/crashes/NAME so that `make test` replays them forever after.
set -eu
SECONDS_PER_TARGET=${FUZZ_SECONDS:-60}
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DIBL_BUILD_FUZZ=ON -DIBL_BUILD_TESTS=OFF -DIBL_BUILD_BENCH=OFF \
  -DCMAKE_C_FLAGS="-fsanitize=fuzzer-no-link,address,undefined" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined" >/dev/null
cmake --build build-fuzz -j 2 -- --no-print-directory >/dev/null
for t in build-fuzz/fuzz/fuzz_*; do
  name=${t##*/fuzz_}
  work=fuzz/corpus-work/$name
  mkdir -p "$work" "fuzz/crashes/$name"
  cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
  echo "== fuzz_$name for ${SECONDS_PER_TARGET}s"
  "$t" -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=2048 -max_len=262144 \
    -artifact_prefix="fuzz/crashes/$name/" -print_final_stats=1 "$work" 2>&1 |
    grep -E "^(#[0-9]+.*(DONE|pulse)|stat::number_of_executed_units|stat::peak_rss|.*ERROR)" | tail -4 || true
done
