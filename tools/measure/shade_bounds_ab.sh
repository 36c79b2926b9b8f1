#!/usr/bin/env bash
# What naga's bounds checks in the shade stage cost (issue 36): renders a
# scene with two `penumbra` binaries in turn, A B A B …, and prints each
# round's "GPU render" time (the frame's device time, from the summary
# line), both medians, and the median of the per-round ratios B/A with its
# range. Pairs, not two separate runs, because a shared 2-core machine's
# load comes and goes (docs/bench.md).
#
#   tools/measure/shade_bounds_ab.sh A_BINARY B_BINARY [ROUNDS] [SCENE] [SPP]
#
# Example (A: the commit before the checks, B: with them):
#   git stash; cargo build --release --bin penumbra; cp target/release/penumbra /tmp/penumbra-a
#   git stash pop; cargo build --release --bin penumbra
#   tools/measure/shade_bounds_ab.sh /tmp/penumbra-a target/release/penumbra 7 scenes/shaders.json 8
set -euo pipefail

a=${1:?usage: tools/measure/shade_bounds_ab.sh A_BINARY B_BINARY [ROUNDS] [SCENE] [SPP]}
b=${2:?usage: tools/measure/shade_bounds_ab.sh A_BINARY B_BINARY [ROUNDS] [SCENE] [SPP]}
rounds=${3:-7}
scene=${4:-scenes/shaders.json}
spp=${5:-8}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# The frame's device time in ms from one render's summary line.
gpu_ms() {
    "$1" render "$scene" --spp "$spp" -o "$out/frame.png" 2>&1 |
        sed -n 's/.*GPU render \([0-9.]*\) \(m\?s\).*/\1 \2/p' |
        awk '{ print ($2 == "s") ? $1 * 1000 : $1 }'
}

grep -m1 'model name' /proc/cpuinfo
grep -m1 -E '^(cpu family|model)\s' /proc/cpuinfo | tr '\n' ' '; grep -m1 '^model\s' /proc/cpuinfo
echo "flags: $(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -E '^(avx|avx2|avx512f|fma)$' | tr '\n' ' ')"
echo "scene $scene, $spp spp, $rounds rounds; warm-up of each first"
gpu_ms "$a" >/dev/null
gpu_ms "$b" >/dev/null
as=() bs=() ratios=()
for i in $(seq "$rounds"); do
    ta=$(gpu_ms "$a")
    tb=$(gpu_ms "$b")
    as+=("$ta") bs+=("$tb")
    ratios+=("$(awk -v a="$ta" -v b="$tb" 'BEGIN { printf "%.4f", b / a }')")
    echo "round $i: A $ta ms, B $tb ms, B/A ${ratios[-1]}"
done
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
range() { printf '%s\n' "$@" | sort -g | awk 'NR == 1 { lo = $1 } { hi = $1 } END { print lo " to " hi }'; }
echo "median A $(median "${as[@]}") ms, median B $(median "${bs[@]}") ms"
echo "B/A median $(median "${ratios[@]}"), range $(range "${ratios[@]}")"
