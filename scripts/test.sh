#!/usr/bin/env bash
# Quick start, step 2: install what the tests need that is missing, build everything (tests and
# benchmarks required: a missing package stops the configure, naming it), and run every test.
# Fails when any test fails, none is found, or any is skipped (a skip means something is missing)
# or disabled.
#   scripts/test.sh              the suite (CI runs this)
#   scripts/test.sh --sanitize   the same suite built with ASan and UBSan in build-sanitize/
#                                (docs/RELIABILITY.md: slower, so not part of CI)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/lib.sh
source "$root/scripts/lib.sh"
case "${1:-}" in
  "") ;;
  --sanitize)
    export PINTAG_SANITIZE=ON
    # Always its own tree: an exported PINTAG_BUILD_DIR would turn the normal build into ASan.
    export PINTAG_BUILD_DIR="$root/build-sanitize"
    sanitizer_env strict_string_checks=1
    ;;
  *) echo "test.sh: unknown argument '$1' (none, or --sanitize)" >&2; exit 2 ;;
esac
(($# <= 1)) || { echo "test.sh: one argument at most (--sanitize)" >&2; exit 2; }
"$root/scripts/setup.sh" serve test
PINTAG_TESTS=ON "$root/scripts/build.sh"
build="${PINTAG_BUILD_DIR:-$root/build}"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
# 600 s for a test that sets no TIMEOUT of its own (every unit test takes seconds): a few hangs
# must not use up CI's 90 minutes before ctest can say which tests hung.
# Without the serve settings a user may have exported for scripts/start.sh (scripts/lib.sh): the
# test servers inherit the environment, and PINTAG_READ_ONLY=1 failed every test that writes.
env "${scratch_server_env[@]}" \
  ctest --test-dir "$build" --output-on-failure --parallel "$(nproc)" --timeout 600 \
  --no-tests=error | tee "$log" || status=$?
if grep -q -- '\*\*\*Skipped' "$log"; then
  echo "test.sh: these tests were skipped, which means something they need is missing:" >&2
  grep -- '\*\*\*Skipped' "$log" >&2
  exit 1
fi
# A DISABLED_ test is "Not Run (Disabled)", which ctest counts as no failure.
if grep -q -- '\*\*\*Not Run\|(Disabled)' "$log"; then
  echo "test.sh: these tests did not run:" >&2
  grep -- '\*\*\*Not Run\|(Disabled)' "$log" >&2
  exit 1
fi
exit "$status"
