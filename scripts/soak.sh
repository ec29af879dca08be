#!/usr/bin/env bash
# Soak: one `pintag serve` on loopback under wrk's mixed traffic (scripts/soak.lua: lookups,
# searches, routes, label PDFs and PNGs, detections of a 1080p JPEG), every answer checked.
#   scripts/soak.sh                       60 s at 64 connections after a 30 s warm-up
#   SOAK_SECONDS=8 SOAK_WARMUP_SECONDS=16 SOAK_CONNECTIONS=8 scripts/soak.sh   (the test suite's)
# Passes when no answer was wrong or missing (0 errors, 0 socket errors, 0 timeouts) and the
# server's peak resident memory in the measured phase is less than 10 % above its warm-up peak.
# Prints one `soak-result` line with mean, p50, p90, p99 and max latency (docs/RELIABILITY.md
# records them).
# Needs the `pintag` build (PINTAG_EXE, default build/server/pintag), wrk and oiiotool.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
exe="${PINTAG_EXE:-$root/build/server/pintag}"
seconds="${SOAK_SECONDS:-60}"
warmup="${SOAK_WARMUP_SECONDS:-30}"
connections="${SOAK_CONNECTIONS:-64}"
for tool in wrk oiiotool; do
  command -v "$tool" >/dev/null || { echo "soak.sh: $tool is missing" >&2; exit 1; }
done
[[ -x "$exe" ]] || { echo "soak.sh: no $exe (scripts/build.sh builds it)" >&2; exit 1; }

# shellcheck source=scripts/lib.sh
source "$root/scripts/lib.sh"
work="$(mktemp -d)"
sampler=""
cleanup() {
  [[ -n "$sampler" ]] && { kill "$sampler" 2>/dev/null || true; }
  stop_scratch_server
  rm -rf "$work"
}
trap cleanup EXIT
# The server's own log, shown whenever the soak fails: a crash or a refusal says why there.
failed() {
  echo "soak.sh: FAILED: $1; the server's log ends:" >&2
  tail -n 40 "$work/server.log" >&2
  exit 1
}

# A 1080p photo: the committed photo of 110001's tag on a plain background.
oiiotool "$root/docker/load/tag-110001.jpg" \
  --pattern constant:color=0.55,0.52,0.47 1920x1080 3 --paste +440+20 -o "$work/photo.jpg"
export PINTAG_PHOTO="$work/photo.jpg"

# One worker thread per connection: cpp-httplib holds a worker for each kept-alive connection.
start_scratch_server "$exe" "$work" "$work/server.log" --threads "$connections" --log-format json
port="$server_port"
token() { "$exe" token create --role "$1" --db "$work/scratch.db" 2>/dev/null | tail -1; }
export PINTAG_COUNTER PINTAG_SCANNER
PINTAG_COUNTER="$(token counter)"
PINTAG_SCANNER="$(token scanner)"
rss() {
  kill -0 "$server_pid" 2>/dev/null || failed "the server died"
  awk '/^VmRSS:/ {print $2}' "/proc/$server_pid/status"
}

run() {  # seconds
  wrk -t "$connections" -c "$connections" -d "${1}s" --timeout 30s \
    -s "$root/scripts/soak.lua" "http://127.0.0.1:$port" | grep '^soak-'
}
check() {  # a soak-result line
  local line="$1" name
  [[ "$line" == soak-result* ]] || failed "wrk gave no soak-result line"
  for name in wrong http_errors socket_errors timeouts; do
    grep -q " $name=0 " <<<"$line " || failed "$name is not 0"
  done
}

# Resident memory is sampled every 0.5 s in both phases and their peaks are compared: one 1080p
# detection or 300 dpi label holds tens of MB for a moment, so two single samples differ by ±8 %
# on a healthy server; a leak raises the peak of the measured phase over the warm-up's.
sample_rss() {  # file: appends a sample every 0.5 s until killed or the server is gone
  while sleep 0.5 && kill -0 "$server_pid" 2>/dev/null; do
    awk '/^VmRSS:/ {print $2}' "/proc/$server_pid/status"
  done >>"$1" 2>/dev/null
}
peak() { sort -n "$1" | tail -1; }

# phase NAME SECONDS LABEL: wrk for SECONDS while sampling memory into $work/rss-NAME.txt; sets
# phase_result (the soak-result line) and phase_peak (KiB).
phase() {
  echo "soak.sh: $3 ${2}s at $connections connections"
  sample_rss "$work/rss-$1.txt" &
  sampler=$!
  phase_result="$(run "$2" || true)"
  kill "$sampler" 2>/dev/null || true
  sampler=""
  echo "$phase_result"
  rss >>"$work/rss-$1.txt"
  phase_peak="$(peak "$work/rss-$1.txt")"
}

phase warm "$warmup" warm-up
check "$phase_result"
rss_warm="$phase_peak"
phase run "$seconds" measured
result="$phase_result"
rss_end="$phase_peak"
echo "soak-memory-series-kib $(awk 'NR % 10 == 0' "$work/rss-run.txt" | tr '\n' ' ')"
growth="$(awk -v a="$rss_warm" -v b="$rss_end" 'BEGIN {printf "%.1f", (b - a) * 100 / a}')"
echo "soak-memory peak_warmup_kib=$rss_warm peak_run_kib=$rss_end growth_percent=$growth"
check "$result"
awk -v g="$growth" 'BEGIN {exit !(g < 10)}' || failed "resident memory grew $growth % (limit 10 %)"
kill -0 "$server_pid" 2>/dev/null || failed "the server died"
echo "soak.sh: passed"
