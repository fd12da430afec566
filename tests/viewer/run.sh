#!/bin/sh
# CTest's driver of the browser tests of `ibl view` (tests/viewer/viewer_test.mjs): checks
# that what they need is installed, then runs them. Usage: run.sh IBL WORKDIR
set -eu
here=$(cd "$(dirname "$0")" && pwd)
missing=""
[ -x "${IBL_CHROMIUM:-/usr/bin/chromium}" ] || missing="$missing chromium (Debian package)"
command -v node >/dev/null 2>&1 || missing="$missing nodejs (Debian package)"
[ -f "$here/node_modules/playwright-core/package.json" ] ||
  missing="$missing playwright-core (npm, tests/viewer/package-lock.json)"
if [ -n "$missing" ]; then
  echo "viewer test: missing:$missing; run scripts/install-deps.sh (it installs them)" >&2
  exit 1
fi
exec node "$here/viewer_test.mjs" "$1" "$2"
