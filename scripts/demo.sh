#!/bin/sh
# make demo: the main job on the built-in environment. Grows with the project.
set -eu
IBL=${1:-build/ibl}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$IBL" --version
echo "demo: results in $OUT"
