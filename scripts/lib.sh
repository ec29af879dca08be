# Shared by the scripts that run a scratch `pintag serve` or a sanitizer build; sourced, not run.
#   sanitizer_env [ASAN_OPTIONS extras]   exports ASan, LSan and UBSan options
#   start_scratch_server EXE DIR LOG [serve options…]
#                                         starts EXE serve on 127.0.0.1, a free port, database
#                                         DIR/scratch.db; sets server_pid and server_port
#   stop_scratch_server                   stops it (idempotent; never fails)

# The suppressions path is quoted inside the option string: the sanitizers split their options
# at spaces, so a checkout under "My Projects" stopped every sanitized binary before main.
sanitizer_env() {
  local root
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1${1:+:$1}"
  # Leaks in libraries we do not own (fontconfig's caches, …) are listed in lsan.supp.
  export LSAN_OPTIONS="suppressions='$root/tests/sanitize/lsan.supp':print_suppressions=0"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
}

# The serve settings a user may have exported for scripts/start.sh (docs/API.md, "Running it"):
# a scratch server takes none of them, so that PINTAG_BIND=0.0.0.0 or PINTAG_READ_ONLY=1 in the
# shell neither exposes it nor changes what it answers. scripts/test.sh runs the suite without
# them for the same reason (the test servers are started by the tests). Every variable
# `pintag serve --help` names is here (ServeHelp.NamesTheEnvironmentVariableOfEveryOption).
scratch_server_env=(-u PINTAG_BIND -u PINTAG_PORT -u PINTAG_DB -u PINTAG_READ_ONLY -u PINTAG_PRIMARY
  -u PINTAG_FOLLOW -u PINTAG_FOLLOW_INTERVAL_MS -u PINTAG_FOLLOW_TOKEN -u PINTAG_FOLLOW_TOKEN_FILE
  -u PINTAG_SCAN_LOG -u PINTAG_SNAPSHOT -u PINTAG_WEB -u PINTAG_TRUSTED_PROXY -u PINTAG_THREADS
  -u PINTAG_LOG_FORMAT -u PINTAG_MAX_BATCH -u PINTAG_MAX_BODY_MB -u PINTAG_MAX_PIXELS
  -u PINTAG_MAX_PIXELS_IN_FLIGHT -u PINTAG_MAX_TAG_PX -u PINTAG_READ_TIMEOUT -u PINTAG_WRITE_TIMEOUT
  -u PINTAG_DRAIN_TIMEOUT -u PINTAG_MIN_BODY_RATE -u PINTAG_ADMIN_TOKEN_OUT)

server_pid=""
server_port=""
start_scratch_server() {  # exe dir log [serve options…]
  local exe="$1" dir="$2" log="$3"
  shift 3
  env "${scratch_server_env[@]}" "$exe" serve --db "$dir/scratch.db" --port 0 --bind 127.0.0.1 \
    "$@" >"$log" 2>&1 &
  server_pid=$!
  local _
  for _ in $(seq 1 600); do
    if grep -q "Stop with Ctrl-C." "$log" 2>/dev/null; then
      server_port="$(sed -n 's|.*serving http://127\.0\.0\.1:\([0-9]*\)/.*|\1|p' "$log" | head -1)"
      break
    fi
    kill -0 "$server_pid" 2>/dev/null || break
    sleep 0.1
  done
  if [[ -z "$server_port" ]]; then
    echo "the scratch server did not start; its output:" >&2
    cat "$log" >&2
    return 1
  fi
}

# Never fails: it runs in EXIT traps under set -e, where a failing command would skip the rest
# of the cleanup and turn a passing run's status into the server's own exit status.
stop_scratch_server() {
  if [[ -n "$server_pid" ]]; then
    kill "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
    server_pid=""
  fi
}
