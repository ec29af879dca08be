#!/usr/bin/env bash
# Run in the image's build stage: lays out DEST as the whole root file system of the runtime
# image, which starts FROM scratch. That is `pintag`, bash (the health check and the start
# command), every shared library the two load (their ldd closure, the dynamic loader included),
# the fonts the label renderer asks fontconfig for, and a passwd entry for the pintag user.
# Installing the runtime packages instead would bring what those packages depend on but pintag
# never loads, and Debian's base system besides: the old image was 1.13 GB.
#
#   collect-runtime.sh PINTAG_BINARY DEST
set -euo pipefail
binary="$1" dest="$2"
uid=10001

mkdir -p "$dest"/usr/{bin,lib,lib64,local/bin} "$dest"/{etc,tmp,srv/pintag}
chmod 1777 "$dest/tmp"
# Debian's merged /usr: the loader is asked for /lib64/..., libraries are found under /lib/... .
for link in bin lib lib64 sbin; do ln -sfn "usr/$link" "$dest/$link"; done
install -m 0755 "$binary" "$dest/usr/local/bin/pintag"
install -m 0755 /usr/bin/bash "$dest/usr/bin/bash"

# Each library lands under its canonical directory with the name the program asks for.
copy_closure() {
  local program="$1" missing
  missing="$(ldd "$program" | grep 'not found' || true)"
  [[ -z "$missing" ]] || { echo "collect-runtime: $program: unresolved: $missing" >&2; exit 1; }
  ldd "$program" | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}' |
    while read -r library; do
      local directory
      directory="$(readlink -f "$(dirname "$library")")"
      mkdir -p "$dest$directory"
      [[ -e "$dest$directory/$(basename "$library")" ]] ||
        cp -L "$library" "$dest$directory/$(basename "$library")"
    done
}
copy_closure "$binary"
copy_closure /usr/bin/bash
echo "collect-runtime: $(find "$dest/usr/lib" "$dest/usr/lib64" -name '*.so*' | wc -l) shared libraries"

# Pango finds the label faces through fontconfig: its configuration, DejaVu, and of
# fonts-noto-core (42 MB) only the faces codec/src/label/label_font.cpp names (3 MB).
for path in /etc/fonts /usr/share/fontconfig /usr/share/fonts/truetype/dejavu; do
  [[ -e "$path" ]] || continue
  mkdir -p "$dest$(dirname "$path")"
  cp -a "$path" "$dest$path"
done
noto=/usr/share/fonts/truetype/noto
mkdir -p "$dest$noto"
for face in Sans{Devanagari,Bengali,Gurmukhi,Gujarati,Oriya,Tamil,Telugu,Kannada,Malayalam,OlChiki,MeeteiMayek} NaskhArabic; do
  for weight in Regular Bold; do
    cp "$noto/Noto$face-$weight.ttf" "$dest$noto/"
  done
done

printf 'root:x:0:0:root:/root:/usr/sbin/nologin\npintag:x:%d:%d:PinTag:/var/lib/pintag:/usr/sbin/nologin\n' \
  "$uid" "$uid" >"$dest/etc/passwd"
printf 'root:x:0:\npintag:x:%d:\n' "$uid" >"$dest/etc/group"
du -sh "$dest"
