#!/usr/bin/env bash
# The checks docs/gpu.md reports, for a machine with a Vulkan GPU: the render test binaries
# with the Khronos validation layer on, one-shot renders with their phases, per-stage times,
# the staged renderer against the megakernel (7031ecb), the pipeline cache on disk (one-shot
# renders without and with it), and the benchmark without lavapipe's knobs and the peers. Everything it prints and writes goes to OUT.
#
#   cargo build --release --workspace --all-targets && cargo test --release --no-run
#   tools/measure/ab_commits.sh --build 7031ecb        # the megakernel's `ab` (prints its path)
#   tools/gpu_check.sh OUT
#
# BIN (default target/release) holds penumbra, ab, stage_times and bench, and BIN/deps the
# test binaries gpu-* and vulkan_staging-* (the newest of each); AB_MEGA is the megakernel's
# `ab` (default: tools/measure/ab_commits.sh --build 7031ecb) and MEGA_SHADERS its shader tree
# (default: the scratch worktree beside it). A machine without cargo (a lent GPU machine)
# takes binaries built elsewhere this way. The validation layer must be installed (Debian's
# vulkan-validationlayers; VK_LAYER_PATH may point at an unpacked copy).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: tools/gpu_check.sh OUT}
mkdir -p "$out"
exec > >(tee "$out/gpu_check.log") 2>&1
bin=${BIN:-target/release}
newest() { ls -t "$bin"/deps/"$1"-* 2>/dev/null | grep -v '\.d$' | head -1; }
mega=${AB_MEGA:-$(tools/measure/ab_commits.sh --build 7031ecb)}
mega_shaders=${MEGA_SHADERS:-target/ab_commits/$(git rev-parse 7031ecb)/shaders}
t0=$(date +%s)
step() { echo "[$(($(date +%s) - t0)) s] $*"; }

command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
grep -m1 'model name' /proc/cpuinfo
"$bin/penumbra" devices

step "render tests, validation on"
(
    export PENUMBRA_VALIDATION=1
    timeout 300 "$(newest gpu)" --test-threads 8 >"$out/gpu_tests.log" 2>&1
    echo "gpu tests: exit $?"
    grep -E '^test result|FAILED|panicked|VUID' "$out/gpu_tests.log" | head -40
    timeout 120 "$(newest vulkan_staging)" 2>&1 | grep -E 'test result|panicked'
)

step "one-shot renders of the bunny scene (phases)"
for _ in 1 2 3; do
    "$bin/penumbra" render scenes/bunny_scene.glb -o "$out/bunny.png" 2>&1 | tail -1
done

step "stage times"
for s in scenes/bunny_scene.glb scenes/showcase.json scenes/area_lights.json; do
    "$bin/stage_times" "$s" 9 2>&1 | grep -E '^  |at [0-9]+x'
done

step "megakernel (7031ecb) against the stages: wall ms per frame, median of 5 pairs, 3 rounds"
for s in scenes/bunny_scene.glb scenes/showcase.json scenes/area_lights.json; do
    for r in 1 2 3; do
        a=$("$mega" "$s" --a "$mega_shaders" --b "$mega_shaders" --pairs 5 2>/dev/null | awk '/^A: [0-9]/ { print $2 }')
        b=$("$bin/ab" "$s" --a shaders --b shaders --pairs 5 2>/dev/null | awk '/^A: [0-9]/ { print $2 }')
        echo "$s round $r: megakernel $a ms, stages $b ms"
    done
done

step "pipeline cache on disk: one-shot renders, pipeline creation without, then with, penumbra's VkPipelineCache"
# The NVIDIA driver's own shader disk cache is off in these three runs, so that the second
# shows what penumbra's cache file (src/vulkan/pipeline_cache.rs) saves by itself; the first
# writes the file into a fresh cache directory, the third has it turned off.
pc=$(mktemp -d)
for run in "cold, writes the file" "warm, reads it" "turned off (PENUMBRA_PIPELINE_CACHE=0)"; do
    off=1; case $run in turned*) off=0 ;; esac
    line=$(XDG_CACHE_HOME=$pc __GL_SHADER_DISK_CACHE=0 PENUMBRA_PIPELINE_CACHE=$off \
        "$bin/penumbra" render scenes/bunny_scene.glb -o "$out/bunny_pc.png" 2>&1 | tail -1)
    echo "$run: $(echo "$line" | grep -oE 'pipeline creation [0-9.]+ ms'), $(echo "$line" | grep -oE 'driver compile [0-9.]+ ms' | head -1)"
done
ls -l "$pc/penumbra" | grep pipelines- || echo "no pipeline cache file written"
rm -rf "$pc"

step "benchmark"
"$bin/bench" --no-knobs --no-peers --out "$out/bench"
step end
