#!/usr/bin/env bash
# The scaled-out deployment proven in Docker on this machine, end to end (docs/SCALING.md):
# builds the images, brings up docker/compose.yaml (one primary, three read-only replicas, nginx;
# host networking, everything on 127.0.0.1), drives mixed traffic through nginx with wrk while one
# replica is killed and started again, checks every answer, adds a pincode on the primary and
# checks every replica serves it within 10 s, measures /api/v1/detect through nginx with 1 and 3
# replicas, and tears everything down. Too slow for every CI run (the first image build compiles
# pintag: 15-25 minutes on 2 cores); run it by hand as root:
#
#   scripts/test-docker.sh            # PINTAG_LOAD_SECONDS=30 PINTAG_BENCH_SECONDS=20 to change
#
# Exit status 0 only when every check held. The last lines are a summary for docs/SCALING.md.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$root/scripts/docker-lib.sh"
load_seconds="${PINTAG_LOAD_SECONDS:-30}"
bench_seconds="${PINTAG_BENCH_SECONDS:-20}"
project="pintagtest$$"
work="$(mktemp -d /tmp/pintag-docker-test.XXXXXX)"
failures=0
summary=()

say() { echo "test-docker: $*"; }
check() {  # check DESCRIPTION COMMAND...: records a pass or a failure
  local what="$1"
  shift
  if "$@"; then say "ok: $what"; summary+=("ok: $what"); else
    say "FAILED: $what"; summary+=("FAILED: $what"); failures=$((failures + 1)); fi
}
# Below Linux's ephemeral range (32768 and up), so no outgoing connection holds one; each port is
# handed out once per run, since the one picked before may not be listened on yet.
given_ports=" "
free_port() {  # free_port VAR: sets VAR to a loopback port nothing listens on (not in a $(…):
  local port      # the ports given are remembered in this shell)
  while true; do
    port=$((20000 + RANDOM % 12000))
    [[ "$given_ports" == *" $port "* ]] && continue
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      given_ports+="$port "
      printf -v "$1" '%s' "$port"
      return
    fi
  done
}
http_status() { curl -s -o /dev/null -w '%{http_code}' --max-time 10 "$@" || true; }
wait_ready() {  # wait_ready PORT SECONDS
  local i
  for ((i = 0; i < $2 * 5; ++i)); do
    [[ "$(http_status "http://127.0.0.1:$1/readyz")" == 200 ]] && return 0
    sleep 0.2
  done
  return 1
}

DockerEnsureDaemon
command -v docker-compose >/dev/null || { say "docker-compose is not installed"; exit 1; }
command -v wrk >/dev/null || { say "wrk is not installed"; exit 1; }
compose=(docker-compose -f "$root/docker/compose.yaml" -p "$project")
export DOCKER_HOST="${DOCKER_HOST:-unix:///var/run/docker.sock}"

cleanup() {
  say "tearing down"
  "${compose[@]}" down -v --remove-orphans >/dev/null 2>&1 || true
  [[ -n "${single_nginx:-}" ]] && "${DOCKER[@]}" rm -f "$single_nginx" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

say "base image"
"$root/scripts/docker-base.sh"
say "building pintag:latest (BuildKit, ccache in a cache mount)"
start=$SECONDS
DOCKER_BUILDKIT=1 "${DOCKER[@]}" build --network host -f "$root/docker/Dockerfile" \
  -t pintag:latest "$root" >"$work/build-pintag.log" 2>&1 ||
  { tail -40 "$work/build-pintag.log"; exit 1; }
say "built pintag:latest in $((SECONDS - start)) s"
"${DOCKER[@]}" build --network host -f "$root/docker/nginx/Dockerfile" -t pintag-nginx:latest \
  "$root" >"$work/build-nginx.log" 2>&1 || { tail -40 "$work/build-nginx.log"; exit 1; }
pintag_size="$("${DOCKER[@]}" image inspect -f '{{.Size}}' pintag:latest)"
nginx_size="$("${DOCKER[@]}" image inspect -f '{{.Size}}' pintag-nginx:latest)"
say "image sizes: pintag $((pintag_size / 1000000)) MB, pintag-nginx $((nginx_size / 1000000)) MB"
summary+=("images: pintag:latest $((pintag_size / 1000000)) MB, pintag-nginx:latest $((nginx_size / 1000000)) MB")
check "pintag image is at most 400 MB" test "$pintag_size" -le 400000000

for port_name in PINTAG_NGINX_PORT PINTAG_PRIMARY_PORT PINTAG_REPLICA1_PORT PINTAG_REPLICA2_PORT \
  PINTAG_REPLICA3_PORT; do
  free_port "$port_name"
  export "${port_name?}"
done
front="http://127.0.0.1:$PINTAG_NGINX_PORT"
replica_ports=("$PINTAG_REPLICA1_PORT" "$PINTAG_REPLICA2_PORT" "$PINTAG_REPLICA3_PORT")
say "ports: nginx $PINTAG_NGINX_PORT, primary $PINTAG_PRIMARY_PORT, replicas ${replica_ports[*]}"

say "starting everything as docker/compose.yaml says: up -d, then the replica token"
"${compose[@]}" up -d >/dev/null 2>&1
wait_ready "$PINTAG_PRIMARY_PORT" 120 || { "${compose[@]}" logs primary; exit 1; }
token() { "${compose[@]}" exec -T primary pintag token create --role "$1" --label test-docker \
  --db /var/lib/pintag/pintag.db "${@:2}" 2>/dev/null | tr -d '\r\n'; }
# The first admin token, from the file the primary wrote it to; then the other roles' tokens.
# (The image holds pintag and bash only: the file is read by bash.)
admin="$("${compose[@]}" exec -T primary bash -c 'echo "$(</var/lib/pintag/first-admin.token)"' |
  tr -d '\r\n')"
counter="$(token counter)" scanner="$(token scanner)"
token replica --out /var/lib/pintag-follow/replica.token
# The replicas, started before the token was there, start again until they find it.
for port in "${replica_ports[@]}"; do
  wait_ready "$port" 120 || { "${compose[@]}" logs; exit 1; }
done
wait_ready "$PINTAG_NGINX_PORT" 60 || { "${compose[@]}" logs nginx; exit 1; }
ids_before="$("${compose[@]}" ps -q | sort)"
# Another operator's shell, with none of this script's variables but the ports: nothing is
# recreated, and the replicas keep serving.
env -u PINTAG_REPLICA_TOKEN "${compose[@]}" up -d >/dev/null 2>&1
check "a second up -d from another shell recreates nothing" \
  test "$("${compose[@]}" ps -q | sort)" = "$ids_before"
check "the replicas still serve after it" bash -c \
  "for p in ${replica_ports[*]}; do [[ \$(curl -s -o /dev/null -w '%{http_code}' http://127.0.0.1:\$p/readyz) == 200 ]] || exit 1; done"
check "the replica token is in no container's environment" bash -c \
  "! ${DOCKER[*]} inspect $("${compose[@]}" ps -q | tr '\n' ' ') | grep -q 'pt_[0-9]'"
check "the first admin token is in the primary's volume, and works" test \
  "$(curl -s -o /dev/null -w '%{http_code}' -H "Authorization: Bearer $admin" \
    "http://127.0.0.1:$PINTAG_PRIMARY_PORT/api/v1/tokens")" = 200
check "no secret is in any container's log" bash -c \
  "! ${compose[*]} logs 2>&1 | grep -q 'pt_[0-9]*_'"
healthy() {  # healthy SERVICE: Docker's HEALTHCHECK says so within 60 s
  local i
  for ((i = 0; i < 60; ++i)); do
    [[ "$("${DOCKER[@]}" inspect -f '{{.State.Health.Status}}' \
      "$("${compose[@]}" ps -q "$1")" 2>/dev/null)" == healthy ]] && return 0
    sleep 1
  done
  return 1
}
check "the image's HEALTHCHECK reports the primary healthy" healthy primary
check "the image's HEALTHCHECK reports replica-1 healthy" healthy replica-1
check "a replica refuses a write with 403 naming the primary" bash -c \
  "curl -s -X POST -H 'Content-Type: application/json' -d '{}' \
     http://127.0.0.1:$PINTAG_REPLICA1_PORT/api/v1/pincodes | grep -q 'Read-Only Replica.*127.0.0.1:$PINTAG_PRIMARY_PORT\|127.0.0.1:$PINTAG_PRIMARY_PORT.*Read-Only Replica'"

export PINTAG_COUNTER="$counter" PINTAG_SCANNER="$scanner"
export PINTAG_PHOTO="$root/docker/load/tag-110001.jpg"
say "mixed load through nginx for $load_seconds s; replica-2 is killed and started again"
wrk -t4 -c4 -d"${load_seconds}s" --timeout 30s -s "$root/docker/load/mixed.lua" "$front" \
  >"$work/wrk-mixed.log" 2>&1 &
wrk_pid=$!
sleep $((load_seconds / 3))
"${DOCKER[@]}" kill "$("${compose[@]}" ps -q replica-2)" >/dev/null
say "killed replica-2"
sleep $((load_seconds / 3))
"${compose[@]}" up -d replica-2 >/dev/null 2>&1
say "started replica-2 again"
wait "$wrk_pid" || true
cat "$work/wrk-mixed.log"
result="$(grep '^pintag-load ' "$work/wrk-mixed.log" | head -1)"
summary+=("mixed load, ${load_seconds} s, 4 connections, replica-2 killed at $((load_seconds / 3)) s and restarted at $((2 * load_seconds / 3)) s: ${result#pintag-load }")
field() { sed -n "s/.* $1=\([0-9.]*\).*/\1/p" <<<"$result"; }
check "load completed requests" test "$(field completed)" -gt 0
check "0 wrong answers" test "$(field wrong)" = 0
check "0 socket errors" test "$(field socket_errors)" = 0
check "0 timeouts" test "$(field timeouts)" = 0
check "replica-2 is ready again" wait_ready "$PINTAG_REPLICA2_PORT" 60

# A server that dies (its init killed from the host, as a crash would end it) is started again by
# the restart policy; one stopped by hand stops at once (an init passes SIGTERM on).
"${DOCKER[@]}" inspect -f '{{.State.Pid}}' "$("${compose[@]}" ps -q replica-3)" | xargs kill -9
sleep 1
check "replica-3 starts again by itself after its process was killed" bash -c \
  "for i in \$(seq 60); do [[ \$(${DOCKER[*]} inspect -f '{{.RestartCount}}' $("${compose[@]}" ps -q replica-3)) -ge 1 ]] && break; sleep 1; done;
   [[ \$(${DOCKER[*]} inspect -f '{{.RestartCount}}' $("${compose[@]}" ps -q replica-3)) -ge 1 ]]"
check "replica-3 is ready again" wait_ready "$PINTAG_REPLICA3_PORT" 60
stop_start=$(date +%s%3N)
"${DOCKER[@]}" stop "$("${compose[@]}" ps -q replica-1)" >/dev/null
stop_ms=$(($(date +%s%3N) - stop_start))
summary+=("docker stop of a replica took ${stop_ms} ms")
check "docker stop of a replica takes under 5 s (SIGTERM reached pintag)" test "$stop_ms" -lt 5000
check "the stopped replica exited 0" test \
  "$("${DOCKER[@]}" inspect -f '{{.State.ExitCode}}' "$("${compose[@]}" ps -q replica-1)")" = 0
"${compose[@]}" up -d replica-1 >/dev/null 2>&1
check "replica-1 is ready again" wait_ready "$PINTAG_REPLICA1_PORT" 60
check "nginx's HEALTHCHECK reports it healthy" healthy nginx
# nginx sends the pages to the replicas: each must serve them (they had no --web until 2026-12-08).
check "the counter, scanner and registry pages answer 200 through nginx" bash -c \
  "for page in counter.html scanner.html registry.html; do [[ \$(curl -s -o /dev/null -w '%{http_code}' $front/\$page) == 200 ]] || exit 1; done"
check "nginx answers its own 413 as problem+json" bash -c \
  "head -c 26214401 /dev/zero | curl -s -D - -o /dev/null -H 'Content-Type: image/jpeg' \
     --data-binary @- $front/api/v1/detect | grep -qi '^content-type: application/problem+json'"
check "nginx's access log is in docker logs, with the request id" bash -c \
  "curl -s -o /dev/null -H 'X-Request-Id: test-docker-log-1' $front/livez; sleep 2;
   ${compose[*]} logs nginx 2>&1 | grep -q 'id=test-docker-log-1'"
check "the server nginx sent it to logs the client nginx named, with nginx as the proxy" bash -c \
  "${compose[*]} logs primary replica-1 replica-2 replica-3 2>&1 | grep 'id=test-docker-log-1' |
     grep -q 'client=127.0.0.1 .* proxy=127.0.0.1'"

say "adding pincode 999555 on the primary through nginx"
added="$(curl -s -o /dev/null -w '%{http_code}' -X POST "$front/api/v1/pincodes" \
  -H "Authorization: Bearer $admin" -H 'Content-Type: application/json' \
  -d '{"pincode": "999555", "offices": [{"name": "Docker Nagar", "district": "Testpur",
       "state": "Test State", "circle": "Test", "region": "T", "division": "TD"}]}')"
check "the write through nginx reached the primary (201)" test "$added" = 201
start_ms=$(date +%s%3N)
all_ms=""
for port in "${replica_ports[@]}"; do
  until [[ "$(http_status "http://127.0.0.1:$port/api/v1/pincodes/999555")" == 200 ]]; do
    (($(date +%s%3N) - start_ms > 10000)) && break
    sleep 0.1
  done
  all_ms=$(($(date +%s%3N) - start_ms))
done
summary+=("pincode added on the primary served by all three replicas after ${all_ms} ms")
check "all replicas serve the new pincode within 10 s" bash -c \
  "for p in ${replica_ports[*]}; do [[ \$(curl -s -o /dev/null -w '%{http_code}' http://127.0.0.1:\$p/api/v1/pincodes/999555) == 200 ]] || exit 1; done; [[ $all_ms -le 10000 ]]"

bench() {  # bench LABEL URL: /api/v1/detect only
  PINTAG_ONLY_KIND=4 wrk -t4 -c4 -d"${bench_seconds}s" --timeout 30s \
    -s "$root/docker/load/mixed.lua" "$2" >"$work/wrk-$1.log" 2>&1 || true
  local line
  line="$(grep '^pintag-load ' "$work/wrk-$1.log" | head -1)"
  say "detect through nginx, $1: ${line#pintag-load }"
  summary+=("/api/v1/detect through nginx, $1, $(nproc) cores, 4 connections, ${bench_seconds} s: ${line#pintag-load }")
  # A rate that counts wrong answers or dropped connections is not a rate of detections.
  check "detect benchmark, $1: 0 wrong answers, socket errors and timeouts" \
    grep -q ' wrong=0 socket_errors=0 timeouts=0 ' <<<"$line"
}
bench "3 replicas" "$front"
free_port single_port
single_nginx="$("${DOCKER[@]}" run -d --network host -e PINTAG_LISTEN="127.0.0.1:$single_port" \
  -e PINTAG_PRIMARY="127.0.0.1:$PINTAG_PRIMARY_PORT" \
  -e PINTAG_REPLICAS="127.0.0.1:$PINTAG_REPLICA1_PORT" pintag-nginx:latest)"
wait_ready "$single_port" 30
bench "1 replica" "http://127.0.0.1:$single_port"

echo
echo "test-docker summary ($(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores):"
printf '  %s\n' "${summary[@]}"
((failures == 0)) || { echo "test-docker: $failures check(s) failed"; exit 1; }
echo "test-docker: every check held"
