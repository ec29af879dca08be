#!/usr/bin/env bash
# Quick start, step 2: install what the tests need that is missing, build everything (tests and
# benchmarks required: a missing package stops the configure, naming it), and run every test.
# Fails when any test fails, none is found, or any is skipped (a skip means something is missing).
#   scripts/test.sh              the suite (CI runs this)
#   scripts/test.sh --sanitize   the same suite built with ASan and UBSan in build-sanitize/
#                                (docs/RELIABILITY.md: slower, so not part of CI)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ "${1:-}" == "--sanitize" ]]; then
  export PINTAG_SANITIZE=ON
  export PINTAG_BUILD_DIR="${PINTAG_BUILD_DIR:-$root/build-sanitize}"
  # Leaks in libraries we do not own (fontconfig's caches, …) are listed in lsan.supp.
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
  export LSAN_OPTIONS="suppressions=$root/tests/sanitize/lsan.supp:print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
fi
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
