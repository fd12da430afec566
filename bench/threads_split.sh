#!/bin/sh
# bench/threads_split.sh BUILD [IN] [SIZE]: why two threads gain what they gain on this host,
# stage by stage, for the prefilter's calls in one process (bench_stages --task-times: the
# loops run on the library's pool through bench/timed_pool.c, which times every task). Runs bench_stages at 1 and 2
# threads in turn, RUNS rounds (default 15), and prints per stage the medians of the wall
# time and of the time inside tasks. From the totals:
#   outside  the one-thread wall time spent outside any loop (reading the file, OpenEXR's
#            setup, the calling thread's stretches between loops, the writes and fsync):
#            on two threads it still runs on one;
#   growth   the tasks' time on two threads over one: what running both threads at once
#            costs each (the memory bus, the host's scheduling of two virtual CPUs);
#   bound    outside + two-thread task time / 2: the two-thread wall time with perfect
#            sharing, and so the most the one-thread time over it can be on this host.
# Defaults: tests/data/city.exr and 256 (the 256 GGX chain of `ibl prefilter`). Whole
# commands add start-up, the manifest and exit on one thread (bench/threads.sh times those).
# SIDE=1 makes the first stages as the command does for a small input (bench_stages
# --side-by-side: the read and the conversion beside the plan, one stage).
set -eu
BUILD=${1:-build}
IN=${2:-$(dirname "$0")/../tests/data/city.exr}
SIZE=${3:-256}
RUNS=${RUNS:-15}
MODE=
[ "${SIDE:-0}" = 1 ] && MODE=--side-by-side
B=$BUILD/bench/bench_stages
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
i=0
while [ "$i" -lt "$RUNS" ]; do
  for j in 1 2; do
    # the stage name is the first 22 columns; then wall, CPU, user, sys, faults, RSS, tasks
    "$B" --task-times $MODE "$IN" "$SIZE" "$j" "$TMP/out.ktx2" |
      awk -v j="$j" 'NR > 2 { name = substr($0, 1, 22); sub(/ +$/, "", name); gsub(/ /, "_", name);
                              split(substr($0, 23), f, " "); print j, name, f[1], f[7] }' >>"$TMP/rows"
  done
  i=$((i + 1))
done
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
printf '%-22s %9s %9s %9s %9s %9s %7s\n' stage "1: wall" "1: tasks" "outside" "2: wall" "2: tasks" growth
awk '$1 == 1 { print $2 }' "$TMP/rows" | awk '!seen[$0]++' | while read -r stage; do
  w1=$(awk -v s="$stage" '$1 == 1 && $2 == s { print $3 }' "$TMP/rows" | median)
  t1=$(awk -v s="$stage" '$1 == 1 && $2 == s { print $4 }' "$TMP/rows" | median)
  w2=$(awk -v s="$stage" '$1 == 2 && $2 == s { print $3 }' "$TMP/rows" | median)
  t2=$(awk -v s="$stage" '$1 == 2 && $2 == s { print $4 }' "$TMP/rows" | median)
  awk -v s="$stage" -v w1="$w1" -v t1="$t1" -v w2="$w2" -v t2="$t2" 'BEGIN {
    gsub(/_/, " ", s); g = t1 > 0 ? sprintf("%.2f", t2 / t1) : "-";
    printf "%-22s %9.1f %9.1f %9.1f %9.1f %9.1f %7s\n", s, w1, t1, w1 - t1, w2, t2, g
    if (s == "total") {
      b = (w1 - t1) + t2 / 2
      printf "\noutside loops %.1f ms; tasks %.1f ms on one thread, %.1f on two (growth %.2f)\n", w1 - t1, t1, t2, t2 / t1
      printf "bound %.1f ms: one thread over two at most %.2fx; measured %.1f / %.1f ms = %.2fx\n", b, w1 / b, w1, w2, w1 / w2
    } }'
done
