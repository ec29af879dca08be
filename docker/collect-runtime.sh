#!/usr/bin/env bash
# Run in the image's build stage: copies what `pintag` needs at run time into a root tree DEST,
# which the runtime stage copies whole. That is the binary, every shared library it loads (the
# ldd closure) that the base image does not already hold, and the fonts the label renderer asks
# fontconfig for. Installing the runtime packages instead would drag in what those libraries'
# packages depend on but pintag never loads (GDAL, video codecs, ...): about 900 MB.
#
#   collect-runtime.sh BINARY DEST BASE_FILE_LIST
# BASE_FILE_LIST: every path the base image's packages installed (dpkg -L), listed before the
# build dependencies were added.
set -euo pipefail
binary="$1" dest="$2" base_files="$3"

mkdir -p "$dest/usr/local/bin"
install -m 0755 "$binary" "$dest/usr/local/bin/pintag"

in_base() { grep -qxF "$1" "$base_files"; }

missing="$(ldd "$binary" | grep 'not found' || true)"
[[ -z "$missing" ]] || { echo "collect-runtime: unresolved libraries:\n$missing" >&2; exit 1; }
count=0
while read -r library; do
  [[ -n "$library" ]] || continue
  real="$(readlink -f "$library")"
  # Debian's merged /usr: ldd may say /lib/..., dpkg lists /usr/lib/... or the other way round.
  if in_base "$library" || in_base "$real" || in_base "${library#/usr}" || in_base "/usr$library"; then
    continue
  fi
  mkdir -p "$dest$(dirname "$library")"
  cp -L "$library" "$dest$library"
  count=$((count + 1))
done < <(ldd "$binary" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u)
echo "collect-runtime: $count shared libraries beyond the base image"

# cairo's toy text API finds "DejaVu Sans" through fontconfig: its configuration and the fonts.
for path in /etc/fonts /usr/share/fontconfig /usr/share/fonts/truetype/dejavu; do
  [[ -e "$path" ]] || continue
  mkdir -p "$dest$(dirname "$path")"
  cp -a "$path" "$dest$path"
done
du -sh "$dest"
