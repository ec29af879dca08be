#!/bin/sh
# Renders pintag.conf.template into an nginx prefix directory and makes the directories the
# configuration names there.
#   render-conf.sh TEMPLATE PREFIX LISTEN PRIMARY REPLICA...
# LISTEN, PRIMARY and each REPLICA are address:port, e.g. 127.0.0.1:8080. Writes PREFIX/nginx.conf.
set -eu
[ "$#" -ge 4 ] || { echo "usage: $0 TEMPLATE PREFIX LISTEN PRIMARY REPLICA..." >&2; exit 2; }
template="$1" prefix="$2" listen="$3" primary="$4"
shift 4
check() {
  case "$1" in
    *[!0-9A-Za-z.:_\[\]-]* | '') echo "render-conf: '$1' is not address:port" >&2; exit 2 ;;
  esac
}
check "$listen"
check "$primary"
servers=""
for replica in "$@"; do
  check "$replica"
  servers="$servers    server $replica max_fails=1 fail_timeout=2s;\\
"
done
mkdir -p "$prefix/logs" "$prefix/tmp"
sed -e "s|@LISTEN@|$listen|" -e "s|@PRIMARY@|$primary|" -e "s|^@REPLICA_SERVERS@\$|$servers|" \
  "$template" >"$prefix/nginx.conf"
