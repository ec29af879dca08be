#!/usr/bin/env bash
# Configures (until a configure has succeeded) and builds into build/ (override with
# PINTAG_BUILD_DIR):
#   scripts/build.sh                    everything the configure found packages for
#   scripts/build.sh pintag             only the named targets (scripts/start.sh builds `pintag`)
#   PINTAG_TESTS=ON scripts/build.sh    configure again first, requiring the tests and benchmarks
#                                       (scripts/test.sh; see PINTAG_TESTS in CMakeLists.txt)
#   PINTAG_SANITIZE=ON                  with ASan and UBSan (use its own PINTAG_BUILD_DIR;
#                                       scripts/test.sh --sanitize does both)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${PINTAG_BUILD_DIR:-$root/build}"
options=(-G Ninja -DCMAKE_BUILD_TYPE=Release)
command -v ccache >/dev/null && options+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# Always passed: a cached ON from one sanitized build must not stay in the tree's later builds.
options+=(-DPINTAG_SANITIZE="${PINTAG_SANITIZE:-OFF}")
if [[ -n "${PINTAG_TESTS:-}" ]]; then
  cmake -S "$root" -B "$build" "${options[@]}" -DPINTAG_TESTS="$PINTAG_TESTS"
elif [[ ! -f "$build/build.ninja" ]]; then
  cmake -S "$root" -B "$build" "${options[@]}"
fi
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build "$build" --parallel "$(nproc)" "${targets[@]}"
