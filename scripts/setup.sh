#!/usr/bin/env bash
# Installs the Debian packages of the named lists that are not installed yet:
#   scripts/setup.sh [serve] [test]      (no name: serve)
# serve  scripts/debian-packages-serve.txt: building and running `pintag serve`
# test   scripts/debian-packages-test.txt: the tests and benchmarks, on top of serve
# A package counts as installed when it is, or when an installed package provides it (e.g. a
# nodejs build that ships npm). Idempotent: when everything is present it changes nothing and
# asks for no privileges.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
(($# > 0)) || set -- serve

lists=()
for name in "$@"; do
  list="$here/debian-packages-$name.txt"
  [[ -f "$list" ]] || { echo "setup: no package list '$name' (serve, test)" >&2; exit 2; }
  lists+=("$list")
done

# Installed packages and what they provide, one name a line.
present="$(dpkg-query -W -f='${db:Status-Status} ${Package} ${Provides}\n' 2>/dev/null |
  awk '$1 == "installed" { for (i = 2; i <= NF; i++) { sub(/,$/, "", $i); if ($i !~ /^[(]|[)]$/) print $i } }')"

missing=()
while read -r line; do
  package="${line%%#*}"
  package="${package//[[:space:]]/}"
  [[ -z "$package" ]] && continue
  grep -qxF "$package" <<<"$present" || missing+=("$package")
done < <(cat "${lists[@]}")

if ((${#missing[@]} == 0)); then
  echo "setup: every package is installed (lists: $*)"
  exit 0
fi

sudo=()
if ((EUID != 0)); then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
echo "setup: installing ${missing[*]}"
"${sudo[@]}" apt-get update -qq
# Through env: sudo's env_reset drops DEBIAN_FRONTEND, and debconf then asks its questions.
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"

# nginx's package enables and starts its own service (port 80 on every address) where systemd
# runs; the tests only run the binary with their own configuration, on loopback. A service this
# script installed is stopped and disabled again; one that was there before is left as it was.
if [[ " ${missing[*]} " == *" nginx-light "* ]] && [[ -d /run/systemd/system ]]; then
  echo "setup: stopping and disabling the nginx service the package started (the tests run nginx themselves)"
  "${sudo[@]}" systemctl disable --now nginx.service >/dev/null 2>&1 || true
fi
