# Sourced by the docker scripts: picks a docker client that can talk to the running daemon and
# starts the daemon when none runs.
#
# The client in /usr/local/bin may be newer than Debian's docker.io daemon; Debian's own client
# (/usr/bin/docker) always matches it, so it is tried first. Sets DOCKER (an array) and, for
# docker-compose, DOCKER_HOST-independent defaults only.

DockerPickClient() {
  local candidate
  for candidate in /usr/bin/docker "$(command -v docker 2>/dev/null || true)"; do
    [[ -x "$candidate" ]] || continue
    if "$candidate" version --format '{{.Server.Version}}' >/dev/null 2>&1; then
      DOCKER=("$candidate")
      return 0
    fi
  done
  return 1
}

# Starts dockerd (as root, log in /tmp/pintag-dockerd.log) when no daemon answers, and waits up
# to 60 s for it.
DockerEnsureDaemon() {
  DockerPickClient && return 0
  if ! pgrep -x dockerd >/dev/null; then
    ((EUID == 0)) || { echo "docker: no daemon runs and starting one needs root" >&2; return 1; }
    command -v dockerd >/dev/null || { echo "docker: dockerd is not installed (docker.io)" >&2; return 1; }
    echo "docker: starting dockerd (log /tmp/pintag-dockerd.log)"
    nohup dockerd >/tmp/pintag-dockerd.log 2>&1 &
  fi
  local i
  for ((i = 0; i < 60; ++i)); do
    DockerPickClient && return 0
    sleep 1
  done
  echo "docker: the daemon did not answer within 60 s; see /tmp/pintag-dockerd.log" >&2
  return 1
}
