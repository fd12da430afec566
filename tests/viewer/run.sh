#!/bin/sh
# CTest's driver of the browser tests (tests/viewer/*.mjs; default viewer_test.mjs, the tests
# of `ibl view`): checks that what they need is installed, then runs one. Usage:
#   run.sh IBL WORKDIR [SCRIPT]
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
exec node "$here/${3:-viewer_test.mjs}" "$1" "$2"
