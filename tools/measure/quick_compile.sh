#!/usr/bin/env bash
# What watch's preview process buys (src/watch/preview.rs, issue 40): the
# shade pipeline's driver compile with lavapipe's default settings against
# the preview process's (GALLIVM_PERF=nopt LP_NATIVE_VECTOR_WIDTH=128), and
# the frame's render time and image under each. Renders SCENE cold (Mesa's
# shader cache disabled, as shade_compile_split.sh does) with each setting
# in turn, A B A B …, prints the median and range of the shade compile of
# FILE and of the GPU render time, and compares the two images with
# `penumbra diff` (the preview must be the loop's image). Compare only within
# one run.
#
#   tools/measure/quick_compile.sh [PENUMBRA] [ROUNDS] [SCENE] [FILE] [WIDTH]
#
# Run from the repository root.
set -euo pipefail

penumbra=${1:-target/release/penumbra}
rounds=${2:-7}
scene=${3:-scenes/showcase.json}
file=${4:-phong.wgsl}
width=${5:-640}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "# quick_compile: $scene at width $width, shade pipeline of $file, $rounds rounds; $penumbra at $(git rev-parse --short HEAD)"
echo "CPU:$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-) (family $(grep -m1 'cpu family' /proc/cpuinfo | cut -d: -f2 | tr -d ' '), model $(grep -m1 '^model\s' /proc/cpuinfo | cut -d: -f2 | tr -d ' ')); flags: $(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -E '^(sse4_2|avx|avx2|fma|bmi2|avx512f)$' | tr '\n' ' ')"
echo "driver: lavapipe, Mesa $(dpkg-query -W -f '${Version}' mesa-vulkan-drivers 2>/dev/null || echo unknown); load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"

# One cold render under the environment "$@"; prints "COMPILE_MS RENDER_MS".
run() {
    local out=$1
    shift
    env "$@" MESA_SHADER_CACHE_DISABLE=true PENUMBRA_PIPELINE_CACHE=0 "$penumbra" render "$scene" --width "$width" -o "$out" 2>&1 |
        awk -v f="/$file" '
            { for (i = 1; i < NF; i++) {
                if ($i == "shade" && index($(i + 1), f) > 0) { c = $(i + 2); if ($(i + 3) ~ /^s/) c *= 1000 }
                if ($i == "GPU" && $(i + 1) == "render") r = $(i + 2)
            } }
            END { if (c == "" || r == "") exit 1; print c, r }'
}

declare -A compile render
for _ in $(seq "$rounds"); do
    read -r c r < <(run "$work/default.png" X=1) || { echo "quick_compile: no shade compile of $file reported" >&2; exit 1; }
    compile[default]="${compile[default]:-} $c"; render[default]="${render[default]:-} $r"
    read -r c r < <(run "$work/quick.png" GALLIVM_PERF=nopt LP_NATIVE_VECTOR_WIDTH=128) || exit 1
    compile[quick]="${compile[quick]:-} $c"; render[quick]="${render[quick]:-} $r"
done

stats() { tr ' ' '\n' | grep . | sort -g | awk '{ v[NR] = $1 } END { m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2; printf "%.1f [%.1f-%.1f] ms", m, v[1], v[NR] }'; }
echo
echo "| setting | shade compile of $file | GPU render (frame) |"
echo "|---|---|---|"
echo "| lavapipe's default | $(echo "${compile[default]}" | stats) | $(echo "${render[default]}" | stats) |"
echo "| GALLIVM_PERF=nopt LP_NATIVE_VECTOR_WIDTH=128 | $(echo "${compile[quick]}" | stats) | $(echo "${render[quick]}" | stats) |"
echo
echo "images (penumbra diff default quick):"
"$penumbra" diff "$work/default.png" "$work/quick.png"
