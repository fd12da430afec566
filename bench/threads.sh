#!/bin/sh
# bench/threads.sh BUILD [OTHER_IBL]: how the whole `ibl prefilter` command scales from one
# thread to two, start-up and file writing included: the 256 chain of tests/data/city.exr
# (1024x512) and the 512 chain of a 2048x1024 input (make_large_inputs.sh, in $LARGE_DIR,
# default /tmp/ibl-large), each at -j 1 and -j 2 under hyperfine -N (15 runs after 2 warm-ups;
# RUNS overrides). With OTHER_IBL (another build's ibl, e.g. the previous commit's in a git
# worktree) each hyperfine call runs both binaries side by side. The ratio to read is the
# -j 1 mean over the -j 2 mean; on a shared host also compare user+sys, which others' load
# changes less than the wall clock. Then the same commands in turn (bench/interleave.sh, RUNS
# rounds, medians): hyperfine's series of two-thread runs can sit in a slower state of this
# host for seconds (docs/PERFORMANCE.md "At large sizes"), which interleaved runs share out.
# Last, bench_pool_ceiling at 1 and 2 threads: what a perfectly parallel process of the same
# shape gains on this host.
set -eu
BUILD=${1:-build}
OTHER=${2:-}
DIR=${LARGE_DIR:-/tmp/ibl-large}
RUNS=${RUNS:-15}
sh "$(dirname "$0")/make_large_inputs.sh" "$BUILD" "$DIR" 512
IBL=$BUILD/ibl
O=$DIR/threads.ktx2
for c in "$(dirname "$0")/../tests/data/city.exr|256" "$DIR/city2048.exr|512"; do
  in=${c%%|*} size=${c##*|}
  cmd="prefilter -q $in -o $O --size $size"
  if [ -n "$OTHER" ]; then
    hyperfine -N -w 2 -r "$RUNS" "$IBL $cmd -j 1" "$IBL $cmd -j 2" "$OTHER $cmd -j 1" "$OTHER $cmd -j 2"
  else
    hyperfine -N -w 2 -r "$RUNS" "$IBL $cmd -j 1" "$IBL $cmd -j 2"
  fi
  bash "$(dirname "$0")/interleave.sh" "$RUNS" "$size -j 1" "$IBL $cmd -j 1" "$size -j 2" "$IBL $cmd -j 2"
done
# The host's own ceiling for a process of the 256 command's shape (bench_pool_ceiling.c: as
# many parallel-fors through the same pool, arithmetic only, no serial code): the ratio the
# command's can be read against.
C=$BUILD/bench/bench_pool_ceiling
if [ -x "$C" ]; then
  hyperfine -N -w 2 -r "$RUNS" "$C 1" "$C 2"
  bash "$(dirname "$0")/interleave.sh" "$RUNS" "ceiling 1" "$C 1" "ceiling 2" "$C 2"
fi
