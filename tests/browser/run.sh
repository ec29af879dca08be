#!/usr/bin/env bash
# ctest entry for the browser tests: installs playwright-core from package-lock.json when it is
# missing or another version than the lock's, then runs every *.test.js with node's test runner,
# one file at a time.
# PINTAG_BIN (the pintag binary) and PINTAG_SCREENSHOT_DIR come from tests/browser/CMakeLists.txt.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
command -v node >/dev/null || { echo "browser tests: node not found (scripts/setup.sh test installs nodejs)" >&2; exit 1; }
version_of() {  # the "version" field of a package.json, or of package-lock.json's entry
  node -e 'const [file, key] = process.argv.slice(1); try { const j = require(file);
    console.log(key ? j.packages[key].version : j.version); } catch { console.log(""); }' "$@"
}
wanted="$(version_of ./package-lock.json node_modules/playwright-core)"
if [[ "$(version_of ./node_modules/playwright-core/package.json)" != "$wanted" ]]; then
  npm ci --no-audit --no-fund
fi
exec node --test --test-concurrency=1
