#!/usr/bin/env bash
# Kernel variants on both lavapipes: builds the committed tree (HEAD) and HEAD with each patch
# given applied, then renders the bunny benchmark scene with every build on the
# installed lavapipe and on Debian's main-suite one (tools/mesa_tree.sh), interleaved round by
# round (driver, then build), after a warm-up render of each that fills the shader cache.
#
#   tools/measure/driver_variants.sh [--base COMMIT] [--cpu] [ROUNDS] PATCH...
#
# (default: HEAD, 5 rounds; "HEAD" in the table is the base commit). The two patches
# docs/drivers.md measured apply only to the kernel of b43f463 and were removed (issue 37);
# docs/drivers.md says how to get them back and measure them at that commit.
#
# Without --cpu each figure is the summary line's render phase of a 1-pass render; with --cpu
# it is the CPU time (user + system, all threads) of a whole 4-pass render process, which other
# processes on the cores disturb less than wall time. Prints, per build and driver, the median
# [min–max], the ratio of the medians to HEAD's on the same driver, and whether the image equals
# HEAD's (penumbra diff). The builds live in target/variants/.
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD

base=HEAD
if [ "${1:-}" = --base ]; then base=${2:?--base needs a commit}; shift 2; fi
cpu=0
if [ "${1:-}" = --cpu ]; then cpu=1; shift; fi
rounds=5
if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then rounds=$1; shift; fi
patches=("$@")
if [ ${#patches[@]} -eq 0 ]; then
  echo "usage: tools/measure/driver_variants.sh [--base COMMIT] [--cpu] [ROUNDS] PATCH..." >&2
  exit 2
fi

work="$root/target/variants"
mkdir -p "$work"
export CARGO_TARGET_DIR="$work/target"
build() { # NAME [PATCH]: a build of the base commit (+ PATCH) as $work/NAME.bin
  local dir="$work/src-$1"
  rm -rf "$dir" && mkdir -p "$dir"
  git archive "$base" | tar -x -C "$dir"
  if [ -n "${2:-}" ]; then patch -s -p1 -d "$dir" <"$2"; fi
  (cd "$dir" && cargo build --release --quiet --bin penumbra)
  cp "$CARGO_TARGET_DIR/release/penumbra" "$work/$1.bin"
}
names=(HEAD)
build HEAD
for p in "${patches[@]}"; do
  n=$(basename "$p" .patch)
  names+=("$n")
  build "$n" "$p"
done
old_icd=$(tools/mesa_tree.sh --icd 2>/dev/null)
drivers=(installed old)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

one() { # NAME DRIVER: prints the figure; leaves the image in $out/NAME.png
  local env=() spp=1
  if [ "$2" = old ]; then env=(VK_DRIVER_FILES="$old_icd" VK_ICD_FILENAMES="$old_icd"); fi
  if [ "$cpu" = 1 ]; then spp=4; fi
  local cmd=(env "${env[@]}" "$work/$1.bin" render scenes/bunny_scene.glb --spp "$spp" -o "$out/$1-$2.png")
  if [ "$cpu" = 1 ]; then
    local TIMEFORMAT='%U %S'
    { time "${cmd[@]}" >/dev/null; } 2>"$out/time"
    awk '{ printf "%.0f\n", ($1 + $2) * 1000 }' "$out/time"
  else
    "${cmd[@]}" | sed -nE 's/.*GPU render ([0-9.]+) ms.*/\1/p'
  fi
}
for d in "${drivers[@]}"; do for n in "${names[@]}"; do one "$n" "$d" >/dev/null; done; done
for ((r = 0; r < rounds; r++)); do
  for d in "${drivers[@]}"; do for n in "${names[@]}"; do one "$n" "$d" >>"$out/$n-$d"; done; done
done

median() { sort -n "$1" | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
range() { sort -n "$1" | awk 'NR == 1 { lo = $1 } { hi = $1 } END { print lo "–" hi }'; }
what=$([ "$cpu" = 1 ] && echo "CPU ms, 4-pass render" || echo "render phase ms, 1 pass")
echo "| build | driver | $what, median [min–max] of $rounds | / HEAD | image = HEAD's |"
echo "|---|---|---|---|---|"
for d in "${drivers[@]}"; do
  info=$(env $([ "$d" = old ] && echo VK_DRIVER_FILES="$old_icd" VK_ICD_FILENAMES="$old_icd") \
    "$work/HEAD.bin" devices | grep -i llvmpipe | head -n1 | sed -E 's/.*driver llvmpipe //')
  base=$(median "$out/HEAD-$d")
  for n in "${names[@]}"; do
    m=$(median "$out/$n-$d")
    same=$("$work/HEAD.bin" diff "$out/HEAD-$d.png" "$out/$n-$d.png" | awk '/^max_abs_error/ { print ($2 == 0) ? "yes" : "no (" $2 ")" }')
    echo "| $n | $info | $m [$(range "$out/$n-$d")] | $(awk -v a="$m" -v b="$base" 'BEGIN { printf "%.2f", a / b }') | $same |"
  done
done
