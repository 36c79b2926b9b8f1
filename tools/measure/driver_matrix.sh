#!/usr/bin/env bash
# The driver matrix: the render phase of the bunny benchmark scene (1024x1024) and the showcase
# (960x540) on every lavapipe at hand — the installed one and Debian's main-suite one unpacked
# by tools/mesa_tree.sh — in one run, rounds interleaved (driver A, driver B, A, B, ...) so
# that a busy second core hits both alike. Each figure is one `penumbra render` process (the
# one-shot CLI render) and its summary line's "GPU render" time; a warm-up render per driver
# and scene first fills the driver's shader cache, so compiles are not counted.
#
#   tools/measure/driver_matrix.sh [ROUNDS] [-- EXTRA RENDER ARGS]    (default 5 rounds)
#
# Prints one Markdown table row per driver and scene: median [min-max] ms and Mrays/s.
set -euo pipefail
cd "$(dirname "$0")/../.."

rounds=5
if [ $# -gt 0 ] && [ "$1" != -- ]; then rounds=$1; shift; fi
[ "${1:-}" = -- ] && shift
extra=("$@")

cargo build --release --quiet --bin penumbra
bin="${CARGO_TARGET_DIR:-target}/release/penumbra"
old_icd=$(tools/mesa_tree.sh --icd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

drivers=(installed "$(basename "$(dirname "$old_icd")")")
scenes=("scenes/bunny_scene.glb" "scenes/showcase.json")

run() { # DRIVER SCENE: prints the summary line
  local env=()
  if [ "$1" != installed ]; then env=(VK_DRIVER_FILES="$old_icd" VK_ICD_FILENAMES="$old_icd"); fi
  env "${env[@]}" "$bin" render "$2" -o "$out/o.png" "${extra[@]}" | grep ' Mrays/s'
}
driver_info() {
  local env=()
  if [ "$1" != installed ]; then env=(VK_DRIVER_FILES="$old_icd" VK_ICD_FILENAMES="$old_icd"); fi
  env "${env[@]}" "$bin" devices | grep -i llvmpipe | head -n1 | sed -E 's/.*driver //'
}

for d in "${drivers[@]}"; do
  for s in "${scenes[@]}"; do run "$d" "$s" >/dev/null; done
done
for ((r = 0; r < rounds; r++)); do
  for s in "${scenes[@]}"; do
    for d in "${drivers[@]}"; do
      line=$(run "$d" "$s")
      ms=$(sed -nE 's/.*GPU render ([0-9.]+) ms.*/\1/p' <<<"$line")
      mrays=$(sed -nE 's/.*\| ([0-9.]+) Mrays\/s.*/\1/p' <<<"$line")
      echo "$ms $mrays" >>"$out/$d-$(basename "$s")"
    done
  done
done

med() { # COLUMN FILE: median [min-max]
  sort -n -k"$1" "$2" | awk -v c="$1" '{ v[NR] = $c } END {
    m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
    printf "%.1f [%.1f–%.1f]", m, v[1], v[NR] }'
}
echo "| driver | scene | render phase, ms (median [min–max] of $rounds) | Mrays/s |"
echo "|---|---|---|---|"
for s in "${scenes[@]}"; do
  for d in "${drivers[@]}"; do
    f="$out/$d-$(basename "$s")"
    echo "| $(driver_info "$d") | $(basename "$s") | $(med 1 "$f") | $(med 2 "$f") |"
  done
done
