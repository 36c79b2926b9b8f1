#!/bin/bash
# A 16384x16384 render in 32 tiles and its merge to PNG and EXR, with the
# merge's time and peak memory (docs/farm.md, "A 16384² merge"). Needs about
# 7 GB of free disk in a temporary folder and a few minutes on 2 cores.
#
#   tools/measure/farm_poster.sh [SCENE [TILES]]   default scenes/showcase.json 32
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${PENUMBRA:-$root/target/release/penumbra}
scene=$root/${1:-scenes/showcase.json}
tiles=${2:-32}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
t0=$(date +%s.%N)
for ((i = 0; i < tiles; i++)); do
  "$bin" render "$scene" --width 16384 --height 16384 --tile "$i/$tiles" -o "p$i.exr" >/dev/null
done
t1=$(date +%s.%N)
echo "render $tiles tiles, one after another: $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s"
echo "parts: $(du -ch p*.exr | tail -n1 | cut -f1)"
/usr/bin/time -f "merge to PNG: %e s, peak RSS %M KiB" "$bin" merge p*.exr -o poster.png >/dev/null
/usr/bin/time -f "merge to EXR: %e s, peak RSS %M KiB" "$bin" merge p*.exr -o poster.exr >/dev/null
ls -l poster.png poster.exr | awk '{ print $NF ": " $5 " bytes" }'
