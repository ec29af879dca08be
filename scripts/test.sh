#!/usr/bin/env bash
# Quick start, step 2: install what the tests need that is missing, build everything (tests and
# benchmarks required: a missing package stops the configure, naming it), and run every test.
# Fails when any test fails, none is found, or any is skipped (a skip means something is missing).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/setup.sh" serve test
PINTAG_TESTS=ON "$root/scripts/build.sh"
build="${PINTAG_BUILD_DIR:-$root/build}"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" --timeout 1800 \
  --no-tests=error | tee "$log" || status=$?
if grep -q -- '\*\*\*Skipped' "$log"; then
  echo "test.sh: these tests were skipped, which means something they need is missing:" >&2
  grep -- '\*\*\*Skipped' "$log" >&2
  exit 1
fi
exit "$status"
