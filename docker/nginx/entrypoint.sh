#!/bin/sh
# Renders the configuration from the environment and runs nginx in the foreground.
#   PINTAG_LISTEN    address:port to listen on (e.g. 127.0.0.1:8080)
#   PINTAG_PRIMARY   address:port of the primary
#   PINTAG_REPLICAS  address:port of each replica, separated by spaces or commas
set -eu
: "${PINTAG_LISTEN:?set PINTAG_LISTEN}" "${PINTAG_PRIMARY:?set PINTAG_PRIMARY}" \
  "${PINTAG_REPLICAS:?set PINTAG_REPLICAS}"
here=/opt/pintag-nginx
# shellcheck disable=SC2046  # the list is split on purpose
"$here/render-conf.sh" "$here/pintag.conf.template" "$PINTAG_NGINX_PREFIX" "$PINTAG_LISTEN" \
  "$PINTAG_PRIMARY" $(echo "$PINTAG_REPLICAS" | tr ',' ' ')
# The access log to the container's stdout (docker logs), beside the error log on stderr.
ln -sf /dev/stdout "$PINTAG_NGINX_PREFIX/logs/access.log"
exec nginx -p "$PINTAG_NGINX_PREFIX" -e stderr -c "$PINTAG_NGINX_PREFIX/nginx.conf" -g 'daemon off;'
