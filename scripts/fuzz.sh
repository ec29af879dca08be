#!/usr/bin/env bash
# libFuzzer targets (fuzz/), built with Debian's clang-14 (-fsanitize=fuzzer,address,undefined)
# into build-fuzz/ (override with PINTAG_FUZZ_BUILD_DIR).
#   scripts/fuzz.sh [target …]          run each target for PINTAG_FUZZ_SECONDS (default 1800) on
#                                       a corpus in build-fuzz/corpus/<target>, grown from the
#                                       seeds in fuzz/corpus/<target>; crashes are written to
#                                       build-fuzz/crashes/<target>/ (keep one in
#                                       fuzz/regressions/<target>/ once fixed)
#                                       PINTAG_FUZZ_JOBS=N (default 1) fuzzes with N worker
#                                       processes (libFuzzer -fork=N, one per core): one run,
#                                       its executions the workers' sum
#                                       PINTAG_FUZZ_RUNS=N also stops it after N executions
#                                       (all workers together), whichever limit comes first;
#                                       Ctrl-C stops it too, and is recorded as stopped by hand
#   scripts/fuzz.sh --smoke [target …]  the bounded run of the test suite: every seed and every
#                                       regression input once, then a run from a fixed seed of
#                                       PINTAG_FUZZ_SMOKE_RUNS (default 500) executions in all,
#                                       the seeds' and regression inputs' included; it fails on
#                                       any slow-unit file (an input over 10 s) as on a crash
# Both first replay each seed and regression input alone, and the seeds listed in
# fuzz/expect-success.txt with PINTAG_FUZZ_EXPECT_SUCCESS set: each of those must succeed (a 2xx,
# a clean import), so a seed that no longer reaches its handler fails the run.
# Targets: image_detect http_request http_connection json_body csv_import parsers (default: all).
# Each run's executions are appended to build-fuzz/fuzz-runs.txt (docs/RELIABILITY.md records them).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# "-dirty" when tracked files differ from the commit (the build has them too).
commit="$(git -C "$root" describe --always --dirty --abbrev=12 2>/dev/null || echo "unknown commit")"
build="${PINTAG_FUZZ_BUILD_DIR:-$root/build-fuzz}"
smoke=0
if [[ "${1:-}" == "--smoke" ]]; then
  smoke=1
  shift
fi
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(image_detect http_request http_connection json_body csv_import parsers)

for tool in clang++-14; do
  command -v "$tool" >/dev/null ||
    { echo "fuzz.sh: $tool is missing (Debian clang-14 and libclang-rt-14-dev)" >&2; exit 1; }
done
if [[ ! -f "$build/build.ninja" ]]; then
  options=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14
           -DPINTAG_FUZZ=ON -DPINTAG_TESTS=OFF)
  command -v ccache >/dev/null && options+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S "$root" -B "$build" "${options[@]}" >/dev/null
fi
build_targets=()
for target in "${targets[@]}"; do build_targets+=(--target "fuzz_$target"); done
cmake --build "$build" --parallel "$(nproc)" "${build_targets[@]}"

# shellcheck source=scripts/lib.sh
source "$root/scripts/lib.sh"
sanitizer_env
status=0
for target in "${targets[@]}"; do
  exe="$build/fuzz/fuzz_$target"
  seeds="$root/fuzz/corpus/$target"
  regressions="$root/fuzz/regressions/$target"
  crashes="$build/crashes/$target"
  mkdir -p "$crashes"
  log="$build/fuzz-$target.log"
  [[ $smoke == 1 ]] && log="$build/fuzz-$target-smoke.log"
  inputs=()
  [[ -d "$regressions" ]] && inputs+=("$regressions"/*)
  [[ -d "$seeds" ]] && inputs+=("$seeds"/*)
  # libFuzzer's default timeout is 1200 s; a kept input is a small one. Artifacts (a slow unit
  # too) go beside the crashes, not into the working directory.
  limits=(-timeout=30 -rss_limit_mb=2048 -artifact_prefix="$crashes/")
  # Every kept input once, as plain files (a regression must stay fixed).
  if [[ ${#inputs[@]} -gt 0 ]] && ! "$exe" "${limits[@]}" -runs=1 "${inputs[@]}" >"$log" 2>&1; then
    echo "fuzz.sh: $target fails on a kept input:" >&2
    tail -40 "$log" >&2
    status=1
    continue
  fi
  # The seeds meant to succeed must still reach their handlers and succeed there: fuzzing a
  # refusal at validation would leave the handler behind it untested while everything passes.
  expected=()
  while read -r listed _; do
    [[ "$listed" == "$target"/* ]] || continue
    [[ -f "$root/fuzz/corpus/$listed" ]] ||
      { echo "fuzz.sh: fuzz/expect-success.txt names a missing seed $listed" >&2; exit 2; }
    expected+=("$root/fuzz/corpus/$listed")
  done < <(grep -v '^#' "$root/fuzz/expect-success.txt")
  if [[ ${#expected[@]} -gt 0 ]] &&
    ! PINTAG_FUZZ_EXPECT_SUCCESS=1 "$exe" "${limits[@]}" -runs=1 "${expected[@]}" >>"$log" 2>&1; then
    echo "fuzz.sh: $target: a seed of fuzz/expect-success.txt did not succeed:" >&2
    tail -40 "$log" >&2
    status=1
    continue
  fi
  corpus="$build/corpus/$target"
  mkdir -p "$corpus"
  if [[ $smoke == 1 ]]; then
    corpus="$(mktemp -d)"
    args=(-runs="${PINTAG_FUZZ_SMOKE_RUNS:-500}" -seed=1 -max_len=65536 -timeout=30
          -rss_limit_mb=2048)
  else
    args=(-max_total_time="${PINTAG_FUZZ_SECONDS:-1800}" -max_len=1048576 -timeout=30
          -rss_limit_mb=2048)
    if [[ -n "${PINTAG_FUZZ_RUNS:-}" ]]; then
      [[ "$PINTAG_FUZZ_RUNS" =~ ^[0-9]+$ ]] ||
        { echo "fuzz.sh: PINTAG_FUZZ_RUNS must be a number" >&2; exit 2; }
      args+=(-runs="$PINTAG_FUZZ_RUNS")
    fi
    jobs="${PINTAG_FUZZ_JOBS:-1}"
    [[ "$jobs" =~ ^[0-9]+$ ]] || { echo "fuzz.sh: PINTAG_FUZZ_JOBS must be a number" >&2; exit 2; }
    # Fork mode would otherwise skip over timeouts and out-of-memory inputs; stop on them as one
    # process does.
    if [[ "$jobs" -gt 1 ]]; then args+=(-fork="$jobs" -ignore_timeouts=0 -ignore_ooms=0); fi
  fi
  # New inputs go to the first folder only; the seeds and regressions are read, never written.
  dirs=("$corpus")
  [[ -d "$seeds" ]] && dirs+=("$seeds")
  [[ -d "$regressions" ]] && dirs+=("$regressions")
  artifacts_before="$(find "$crashes" -type f | wc -l)"
  started=$SECONDS
  outcome=0
  "$exe" "${args[@]}" -artifact_prefix="$crashes/" -print_final_stats=1 "${dirs[@]}" \
    >>"$log" 2>&1 || outcome=$?
  artifacts_after="$(find "$crashes" -type f | wc -l)"
  how="no failure"
  # Stopped with Ctrl-C (or SIGINT to the fuzzer): not a failure when it left no input behind.
  if ((outcome != 0)) && ((artifacts_after == artifacts_before)) &&
    tail -40 "$log" | grep -q 'libFuzzer: run interrupted'; then
    outcome=0
    how="stopped by hand, no failure"
  fi
  # libFuzzer exits 0 after writing a slow-unit file; in the bounded run, on seeds and a few
  # hundred mutations, an input that slow is a finding.
  if ((outcome == 0 && smoke == 1 && artifacts_after > artifacts_before)); then
    echo "fuzz.sh: $target: an input took over 10 s (a slow-unit file in $crashes/)" >&2
    outcome=1
  fi
  if ((outcome == 0)); then
    workers=""
    if [[ $smoke == 0 && "${jobs:-1}" -gt 1 ]]; then
      # With -fork each worker prints its own final stats; the parent's last "#N: cov: …" line
      # counts every worker's executions.
      runs="$(grep -o '^#[0-9]*: cov' "$log" | tail -1 | tr -dc '0-9' || true)"
      workers=" ($jobs workers)"
    else
      runs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)"
    fi
    echo "fuzz.sh: $target: ${runs:-?} executions, $how"
    # The tree it was built from: a figure quoted later must say which code it covers.
    echo "$(date -u +%FT%TZ) $target $( [[ $smoke == 1 ]] && echo smoke || echo long ) ${runs:-?}$workers, $how, $((SECONDS - started)) s, built from $commit" \
      >>"$build/fuzz-runs.txt"
  else
    echo "fuzz.sh: $target FAILED; the input is in $crashes/:" >&2
    tail -60 "$log" >&2
    status=1
  fi
  [[ $smoke == 1 ]] && rm -rf "$corpus"
done
exit "$status"
