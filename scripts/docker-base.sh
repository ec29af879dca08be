#!/usr/bin/env bash
# Builds the local Debian 12 base image the Dockerfiles start FROM, when it is missing. No image
# registry is reachable from the machines this project runs on, so the base is made here:
# debootstrap --variant=minbase bookworm from Debian's mirror, then `docker import`.
#
#   PINTAG_BASE_IMAGE   image name (default pintag-base:bookworm)
#   PINTAG_DEBIAN_MIRROR  (default http://deb.debian.org/debian)
#   --force             rebuild even when the image exists
set -euo pipefail
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/docker-lib.sh"

image="${PINTAG_BASE_IMAGE:-pintag-base:bookworm}"
mirror="${PINTAG_DEBIAN_MIRROR:-http://deb.debian.org/debian}"
force=0
[[ "${1:-}" == "--force" ]] && force=1

DockerEnsureDaemon
if ((force == 0)) && "${DOCKER[@]}" image inspect "$image" >/dev/null 2>&1; then
  echo "docker-base: $image exists"
  exit 0
fi
command -v debootstrap >/dev/null || { echo "docker-base: debootstrap is not installed" >&2; exit 1; }
((EUID == 0)) || { echo "docker-base: debootstrap needs root" >&2; exit 1; }

rootfs="$(mktemp -d /var/tmp/pintag-rootfs.XXXXXX)"
trap 'rm -rf "$rootfs"' EXIT
echo "docker-base: debootstrap --variant=minbase bookworm into $rootfs (about a minute)"
debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$rootfs.log" 2>&1 ||
  { tail -20 "$rootfs.log" >&2; rm -f "$rootfs.log"; exit 1; }
rm -f "$rootfs.log"
# Slim it the way Debian's own container images are: no apt lists, caches, docs or man pages.
rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*.bin "$rootfs"/var/cache/apt/archives/*.deb
rm -rf "$rootfs"/usr/share/doc/* "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/*
echo "deb $mirror bookworm main" >"$rootfs/etc/apt/sources.list"
echo "deb $mirror bookworm-updates main" >>"$rootfs/etc/apt/sources.list"
echo "deb ${mirror%/debian}/debian-security bookworm-security main" >>"$rootfs/etc/apt/sources.list"
tar --numeric-owner -C "$rootfs" -c . | "${DOCKER[@]}" import \
  --change 'CMD ["/bin/bash"]' --change 'ENV LANG=C.UTF-8' - "$image"
echo "docker-base: built $image ($("${DOCKER[@]}" image inspect -f '{{.Size}}' "$image") bytes)"
