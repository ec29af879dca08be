#!/usr/bin/env bash
# Quick start, step 1: install what is missing, build, and run the main job.
# For now the main job renders a sample tag; with the HTTP server it will start the server.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
build="${PINTAG_BUILD_DIR:-$root/build}"
mkdir -p "$root/out"
"$build/server/pintag" render --key 11684 --size-mm 50 --dpi 300 -o "$root/out/sample-tag.png"
"$build/server/pintag" render --key 11684 --size-mm 50 -o "$root/out/sample-tag.svg"
echo "Sample tag (key 11684): $root/out/sample-tag.png and .svg"
