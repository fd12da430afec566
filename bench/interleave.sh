#!/bin/bash
# bench/interleave.sh ROUNDS LABEL "COMMAND" [LABEL "COMMAND" ...]: runs the commands one after
# the other, ROUNDS times over, and prints each one's median wall time (with quartiles and the
# fastest): on a shared host, whose speed drifts over seconds, commands compared this way see
# the same drift, where hyperfine runs each command's rounds in a row. The commands are run
# by this shell itself (fork and exec, output thrown away): on this project's 2-core VM, a
# process started through Python's subprocess and sh -c often had its second CPU join ~10 ms
# late, which alone took bench_pool_ceiling's one thread over two from 1.91x to 1.77x.
set -eu
ROUNDS=$1
shift
labels=()
commands=()
while [ $# -ge 2 ]; do
  labels+=("$1")
  commands+=("$2")
  shift 2
done
times=$(mktemp)
trap 'rm -f "$times"' EXIT
for ((round = 0; round < ROUNDS; round++)); do
  for k in "${!commands[@]}"; do
    start=$EPOCHREALTIME
    eval "${commands[$k]}" >/dev/null 2>&1
    end=$EPOCHREALTIME
    echo "$k $start $end" >>"$times"
  done
done
for k in "${!labels[@]}"; do
  awk -v k="$k" '$1 == k { print ($3 - $2) * 1000 }' "$times" | sort -g |
    awk -v l="${labels[$k]}" '{ v[NR] = $1 }
      END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
            printf "%-12s median %8.1f ms   quartiles %8.1f %8.1f   fastest %8.1f\n", l, m,
                   v[int((NR + 3) / 4)], v[int((3 * NR + 3) / 4)], v[1] }'
done
