#!/usr/bin/env bash
# Quick start, step 1: install the packages serving needs that are missing, build the `pintag`
# command alone (no tests, no benchmarks), then start the PinTag server in the foreground
# (Ctrl-C stops it). The first start creates and seeds the database and prints one admin token;
# later starts say how to make one.
#
#   PINTAG_DB=FILE      database (default: out/pintag.db)
#   PINTAG_PORT=N       port (default 8080)
#   PINTAG_BIND=ADDR    address (default 127.0.0.1; 0.0.0.0 for every interface)
#   PINTAG_BUILD_DIR    build tree (default build/)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/setup.sh" serve
"$root/scripts/build.sh" pintag
build="${PINTAG_BUILD_DIR:-$root/build}"
db="${PINTAG_DB:-$root/out/pintag.db}"
mkdir -p "$(dirname "$db")"
args=(serve --db "$db" --port "${PINTAG_PORT:-8080}" --bind "${PINTAG_BIND:-127.0.0.1}")
[[ -d "$root/web" ]] && args+=(--web "$root/web")
echo "Starting the server (database $db; first start seeds it, ~2 s)."
echo "Another admin token at any time: $build/server/pintag token create --role admin --db $db"
exec "$build/server/pintag" "${args[@]}"
