#!/bin/sh
# CTest's driver of the node tests of tests/viewer other than the viewer's own (run.sh):
# checks that what they need is installed, then runs one. Usage: run_node.sh SCRIPT IBL WORKDIR
#   engines_test.mjs   three.js and Babylon.js in headless chromium against ibl bake --target
#   ktx_roundtrip.mjs  every KTX2 ibl writes through ktx-parse, byte-identical
#   gltf_test.mjs      ibl bake --target gltf through Babylon.js's glTF loader in headless chromium
#   lightprobe_test.mjs  sh.json's engines.three in three.js's LightProbe in headless chromium
set -eu
here=$(cd "$(dirname "$0")" && pwd)
script=$1
shift
missing=""
command -v node >/dev/null 2>&1 || missing="$missing nodejs (Debian package)"
for m in ktx-parse three @babylonjs/core @babylonjs/loaders playwright-core; do
  [ -f "$here/node_modules/$m/package.json" ] || missing="$missing $m (npm, tests/viewer/package-lock.json)"
done
if [ "$script" != ktx_roundtrip.mjs ]; then
  [ -x "${IBL_CHROMIUM:-/usr/bin/chromium}" ] || missing="$missing chromium (Debian package)"
fi
if [ -n "$missing" ]; then
  echo "$script: missing:$missing; run scripts/install-deps.sh (it installs them)" >&2
  exit 1
fi
exec node "$here/$script" "$@"
