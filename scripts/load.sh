#!/usr/bin/env bash
# Load figures for docs/PERFORMANCE.md: starts `pintag serve` on loopback with a scratch database,
# then drives it with wrk (keep-alive, scripts/load/request.lua checks every answer's status) for a
# bounded time per route; fails when any answer had another status or a socket error:
#   livez      GET /livez
#   lookup     GET /api/v1/pincodes/110001
#   detect     POST /api/v1/detect, a mixed set of 1080p phone JPEG scenes in rotation (tags from
#              14 to 160 px at every tilt, and tagless frames)
#   label-pdf  GET /api/v1/labels/110001.pdf
#   label-png  GET /api/v1/labels/110001.png (300 dpi)
#   tag-png    GET /api/v1/tags/110001.png?px=512
# Each prints requests/s and mean, p90, p99 and max latency. Never asserts a time.
#
#   scripts/load.sh [route ...]     default: all of the above
#   PINTAG_LOAD_SECONDS=N           seconds per route (default 10)
#   PINTAG_LOAD_CONNECTIONS=N       wrk connections (default 4; wrk uses 2 threads, 1 for 1 connection)
#   PINTAG_LOAD_SERVER_THREADS=N    pintag serve --threads (default 4)
#   PINTAG_LOAD_FRAMES=DIR          the JPEG scenes (default build/load-frames-2, made on first use
#                                   by the benchmark's scene generator, pintag_bench --save-frames;
#                                   "-2": the quick sweep's own frames since 2026-12-07, so a
#                                   build tree's cache of the earlier ones is not taken for them)
#   PINTAG_BUILD_DIR                build tree (default build/; needs pintag, and pintag_bench to
#                                   make the frames: PINTAG_TESTS=ON scripts/build.sh)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${PINTAG_BUILD_DIR:-$root/build}"
seconds="${PINTAG_LOAD_SECONDS:-10}"
connections="${PINTAG_LOAD_CONNECTIONS:-4}"
server_threads="${PINTAG_LOAD_SERVER_THREADS:-4}"
wrk_threads=$((connections < 2 ? connections : 2))  # wrk needs a connection per thread
frames="${PINTAG_LOAD_FRAMES:-$build/load-frames-2}"
pintag="$build/server/pintag"
routes=("$@")
known_routes=(livez lookup detect label-pdf label-png tag-png)
[[ ${#routes[@]} -gt 0 ]] || routes=("${known_routes[@]}")
# Every name checked before anything runs: a typo at the end came after minutes of the others.
for route in "${routes[@]}"; do
  [[ " ${known_routes[*]} " == *" $route "* ]] ||
    { echo "load.sh: unknown route '$route' (${known_routes[*]})" >&2; exit 2; }
done

command -v wrk >/dev/null || { echo "load.sh: wrk is missing (Debian package wrk)" >&2; exit 1; }
[[ -x "$pintag" ]] || { echo "load.sh: no $pintag; run scripts/build.sh pintag" >&2; exit 1; }

make_frames() {
  # The quick sweep's frames: one per size x tilt bin (49) and 6 tagless, rendered as PNG, then
  # saved as 4:2:0 JPEG at quality 90 as a phone would. Made beside the cache and moved into
  # place whole: a run stopped halfway left a part of the set that later runs took for all of it.
  local bench="$build/bench/pintag_bench"
  [[ -x "$bench" ]] || { echo "load.sh: no $bench to render the scenes" >&2; exit 1; }
  local partial="$frames.partial"
  rm -rf "$partial"
  mkdir -p "$partial/png"
  echo "load.sh: rendering the scenes into $frames (once)" >&2
  "$bench" --quick --detectors pintag --one-thread-only --quiet --save-frames "$partial/png" \
    --out "$partial/bench" >/dev/null
  for f in "$partial/png"/*.png; do
    iconvert --quality 90 "$f" "$partial/$(basename "${f%.png}").jpg"
  done
  rm -rf "$partial/png" "$partial/bench"
  rm -rf "$frames"
  mv "$partial" "$frames"
}
if [[ " ${routes[*]} " == *" detect "* ]] && ! compgen -G "$frames/*.jpg" >/dev/null; then
  make_frames
fi

# shellcheck source=scripts/lib.sh
source "$root/scripts/lib.sh"
scratch="$(mktemp -d)"
cleanup() {
  stop_scratch_server
  rm -rf "$scratch"
}
trap cleanup EXIT

db="$scratch/scratch.db"
start_scratch_server "$pintag" "$scratch" "$scratch/serve.log" --threads "$server_threads"
port="$server_port"
counter="$("$pintag" token create --role counter --label load --db "$db" 2>/dev/null | tail -1)"
scanner="$("$pintag" token create --role scanner --label load --db "$db" 2>/dev/null | tail -1)"
ls "$frames"/*.jpg >"$scratch/frames.txt" 2>/dev/null || true

echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores," \
  "load average $(cut -d' ' -f1-3 /proc/loadavg) before the run;" \
  "wrk -t$wrk_threads -c$connections, ${seconds}s a route, keep-alive; pintag serve --threads $server_threads"
server_cpu_ticks() {  # user + system clock ticks the server has used so far
  awk '{print $14 + $15}' "/proc/$server_pid/stat"
}
failures=0
run() {  # name method path token bodies
  local before after line requests
  before="$(server_cpu_ticks)"
  line="$(PINTAG_NAME="$1" PINTAG_METHOD="$2" PINTAG_PATH="$3" PINTAG_TOKEN="$4" \
    PINTAG_BODIES="$5" wrk -t"$wrk_threads" -c"$connections" -d"${seconds}s" --timeout 10s \
    -s "$root/scripts/load/request.lua" "http://127.0.0.1:$port" | grep '^pintag-load')"
  after="$(server_cpu_ticks)"
  requests="$(sed -n 's/.* requests=\([0-9]*\) .*/\1/p' <<<"$line" | head -1)"
  # The server's own CPU per request: on a machine shared with other work, what 2 idle cores
  # would sustain is about 2000 / this (wrk's own CPU aside).
  echo "$line" | sed "1s/\$/ server_cpu_ms_per_request=$(awk -v t=$((after - before)) \
    -v hz="$(getconf CLK_TCK)" -v n="${requests:-0}" \
    'BEGIN { if (n > 0) printf "%.3f", t * 1000 / hz / n; else print "n/a" }')/"
  if ! grep -q ' wrong=0 errors=0$' <<<"$(head -1 <<<"$line")"; then failures=$((failures + 1)); fi
}
for route in "${routes[@]}"; do
  case "$route" in
    livez) run livez GET /livez "" "" ;;
    lookup) run lookup GET /api/v1/pincodes/110001 "" "" ;;
    detect)
      echo "# detect: $(wc -l <"$scratch/frames.txt") JPEG scenes from $frames"
      run detect POST /api/v1/detect "$scanner" "$scratch/frames.txt" ;;
    label-pdf) run label-pdf GET /api/v1/labels/110001.pdf "$counter" "" ;;
    label-png) run label-png GET "/api/v1/labels/110001.png?dpi=300" "$counter" "" ;;
    tag-png) run tag-png GET "/api/v1/tags/110001.png?px=512" "$counter" "" ;;
  esac
done
# Figures from a run with wrong answers or socket errors are not figures of a working server.
if ((failures > 0)); then
  echo "load.sh: FAILED: $failures of ${#routes[@]} routes had wrong answers or errors" >&2
  exit 1
fi
