#!/usr/bin/env bash
# A large glTF model's load as a user meets it (issue 39, docs/textures.md):
# `penumbra render MODEL` with an empty Mesa shader cache (cold), then twice
# with the cache that run filled (warm), each under /usr/bin/time -v. Prints
# the machine (CPU family, model and flags; the Mesa package), then per run
# the render summary line (load, upload, driver compile per pipeline,
# texture memory), the wall time and the peak resident memory. Runs are not
# repeated: compare ratios only within one run of this script.
#
#   tools/measure/model_load.sh MODEL [PENUMBRA] [-- RENDER OPTIONS]
#
# PENUMBRA is the binary (default target/debug/penumbra; say which profile
# the figures come from). RENDER OPTIONS default to `--width 320 --spp 4`.
set -euo pipefail

model=${1:?usage: tools/measure/model_load.sh MODEL [PENUMBRA] [-- RENDER OPTIONS]}
shift
penumbra=target/debug/penumbra
if [ $# -gt 0 ] && [ "$1" != "--" ]; then
    penumbra=$1
    shift
fi
[ "${1:-}" = "--" ] && shift
opts=("$@")
[ ${#opts[@]} -gt 0 ] || opts=(--width 320 --spp 4)

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)
family=$(grep -m1 'cpu family' /proc/cpuinfo | cut -d: -f2 | tr -d ' ')
cpumodel=$(grep -m1 '^model\s' /proc/cpuinfo | cut -d: -f2 | tr -d ' ')
flags=$(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -E '^(sse4_2|avx|avx2|fma|bmi2|avx512[a-z_]*)$' | tr '\n' ' ')
mesa=$(dpkg-query -W -f '${Version}' mesa-vulkan-drivers 2>/dev/null || echo unknown)
echo "# model_load: $model; $penumbra ${opts[*]}"
echo "CPU:$cpu (family $family, model $cpumodel); flags: $flags"
echo "cores: $(nproc); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "driver: lavapipe, Mesa $mesa"

for run in cold warm warm; do
    MESA_SHADER_CACHE_DIR=$scratch/cache /usr/bin/time -v "$penumbra" render "$model" \
        -o "$scratch/out.png" "${opts[@]}" >"$scratch/stdout" 2>"$scratch/stderr" || {
        cat "$scratch/stderr" >&2
        exit 1
    }
    wall=$(grep 'Elapsed (wall clock)' "$scratch/stderr" | awk '{print $NF}')
    rss=$(grep 'Maximum resident set size' "$scratch/stderr" | awk '{print $NF}')
    echo "$run: wall $wall, peak RSS $((rss / 1024)) MiB"
    grep -v '^note:' "$scratch/stdout" "$scratch/stderr" | grep 'load .* ms' | sed 's/^[^:]*://' || true
done
