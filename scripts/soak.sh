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

work="$(mktemp -d)"
server=""
cleanup() {
  [[ -n "$server" ]] && kill "$server" 2>/dev/null && wait "$server" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

# A 1080p photo: the committed photo of 110001's tag on a plain background.
oiiotool "$root/docker/load/tag-110001.jpg" \
  --pattern constant:color=0.55,0.52,0.47 1920x1080 3 --paste +440+20 -o "$work/photo.jpg"
export PINTAG_PHOTO="$work/photo.jpg"

# One worker thread per connection: cpp-httplib holds a worker for each kept-alive connection.
"$exe" serve --db "$work/soak.db" --port 0 --threads "$connections" --log-format json \
  >"$work/out.txt" 2>"$work/server.log" &
server=$!
for _ in $(seq 1 600); do
  grep -q "Stop with Ctrl-C." "$work/out.txt" 2>/dev/null && break
  kill -0 "$server" 2>/dev/null || { cat "$work/server.log" >&2; exit 1; }
  sleep 0.1
done
port="$(grep -o 'serving http://127.0.0.1:[0-9]*' "$work/out.txt" | grep -o '[0-9]*$')"
[[ -n "$port" ]] || { echo "soak.sh: the server did not start" >&2; cat "$work/out.txt" >&2; exit 1; }
token() { "$exe" token create --role "$1" --db "$work/soak.db" 2>/dev/null | tail -1; }
export PINTAG_COUNTER PINTAG_SCANNER
PINTAG_COUNTER="$(token counter)"
PINTAG_SCANNER="$(token scanner)"
rss() { awk '/^VmRSS:/ {print $2}' "/proc/$server/status"; }

run() {  # seconds
  wrk -t "$connections" -c "$connections" -d "${1}s" --timeout 30s \
    -s "$root/scripts/soak.lua" "http://127.0.0.1:$port" | grep '^soak-'
}
check() {  # a soak-result line
  local line="$1" name
  for name in wrong http_errors socket_errors timeouts; do
    if ! grep -q " $name=0 " <<<"$line "; then
      echo "soak.sh: FAILED: $name is not 0" >&2
      return 1
    fi
  done
}

# Resident memory is sampled every 0.5 s in both phases and their peaks are compared: one 1080p
# detection or 300 dpi label holds tens of MB for a moment, so two single samples differ by ±8 %
# on a healthy server; a leak raises the peak of the measured phase over the warm-up's.
sample_rss() {  # file: appends a sample every 0.5 s until killed
  while sleep 0.5; do printf '%s\n' "$(rss)"; done >>"$1" 2>/dev/null
}
peak() { sort -n "$1" | tail -1; }

# phase NAME SECONDS LABEL: wrk for SECONDS while sampling memory into $work/rss-NAME.txt; sets
# phase_result (the soak-result line) and phase_peak (KiB).
phase() {
  echo "soak.sh: $3 ${2}s at $connections connections"
  sample_rss "$work/rss-$1.txt" &
  local sampler=$!
  phase_result="$(run "$2")"
  kill "$sampler" 2>/dev/null || true
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
awk -v g="$growth" 'BEGIN {exit !(g < 10)}' ||
  { echo "soak.sh: FAILED: resident memory grew $growth % (limit 10 %)" >&2; exit 1; }
kill -0 "$server" || { echo "soak.sh: FAILED: the server died" >&2; exit 1; }
echo "soak.sh: passed"
