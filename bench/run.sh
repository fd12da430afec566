#!/bin/sh
# make bench: runs every benchmark program in the build folder on the shared test data and
# the whole-command timings with hyperfine. Results go to stdout; copy the figures you quote
# into docs/PERFORMANCE.md together with this command.
set -eu
BUILD=${1:-build}
DATA=${IBL_TESTDATA:-../shared/testdata}
[ -d "$DATA" ] || DATA=tests/data
for b in "$BUILD"/bench/bench_*; do
  [ -x "$b" ] || continue
  echo "== $b"
  "$b" "$DATA"
done
if [ -x bench/commands.sh ]; then sh bench/commands.sh "$BUILD" "$DATA"; fi
