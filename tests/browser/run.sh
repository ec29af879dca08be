#!/usr/bin/env bash
# ctest entry for the browser tests: installs playwright-core from package-lock.json when it is
# missing, then runs every *.test.js with node's test runner, one file at a time.
# PINTAG_BIN (the pintag binary) and PINTAG_SCREENSHOT_DIR come from tests/browser/CMakeLists.txt.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
command -v node >/dev/null || { echo "browser tests: node not found (scripts/setup.sh test installs nodejs)" >&2; exit 1; }
if [[ ! -f node_modules/playwright-core/package.json ]]; then
  npm ci --no-audit --no-fund
fi
exec node --test --test-concurrency=1
