#!/usr/bin/env bash
# Where the shade pipeline's driver compile goes (issue 40: what a shading
# edit in `watch` recompiles). Exports the committed shaders four times and
# edits shaders/stages/shade.wgsl in three of the copies:
#
#   full      the shaders as committed
#   no-shade  the light loop adds intensity × diffuse instead of calling the
#             shader file's shade() (what the user's shade() costs)
#   no-ambient  the ambient sum is 0 (what the ambient loop costs)
#   floor     the stage writes a constant colour once it has its pixel: no
#             record loads, no light loop, no user code (lavapipe's cost of a
#             pipeline with the stage's bindings and image write)
#
# then renders SCENE with each (`--shaders DIR`) and an empty Mesa shader
# cache (disabled, so that two shader files whose edited stages compile to the
# same code do not share a compile), A B C D A B C D …, and prints for each variant the median and range
# of the driver compile that the summary line reports for the shade pipeline
# of FILE (default phong.wgsl). The images of the edited variants are wrong on
# purpose; only their compile times are read. Compare only within one run.
#
#   tools/measure/shade_compile_split.sh [PENUMBRA] [ROUNDS] [SCENE] [FILE]
#
# PENUMBRA defaults to target/release/penumbra (the driver's compile does not
# depend on penumbra's profile). Run from the repository root.
set -euo pipefail

penumbra=${1:-target/release/penumbra}
rounds=${2:-5}
scene=${3:-scenes/showcase.json}
file=${4:-phong.wgsl}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "# shade_compile_split: $scene, shade pipeline of $file, $rounds rounds; $penumbra at $(git rev-parse --short HEAD)"
echo "CPU:$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-) (family $(grep -m1 'cpu family' /proc/cpuinfo | cut -d: -f2 | tr -d ' '), model $(grep -m1 '^model\s' /proc/cpuinfo | cut -d: -f2 | tr -d ' ')); flags: $(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -E '^(sse4_2|avx|avx2|fma|bmi2|avx512f)$' | tr '\n' ' ')"
echo "driver: lavapipe, Mesa $(dpkg-query -W -f '${Version}' mesa-vulkan-drivers 2>/dev/null || echo unknown); load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"

variants=(full no-shade no-ambient floor)
for v in "${variants[@]}"; do
    mkdir -p "$work/$v"
    git archive HEAD shaders | tar -x -C "$work/$v"
done
# Each edit must match exactly once, so that a change to shade.wgsl stops the
# script instead of measuring an unedited copy.
python3 - "$work" <<'EOF'
import sys
work = sys.argv[1]
def edit(variant, old, new):
    p = f"{work}/{variant}/shaders/stages/shade.wgsl"
    s = open(p).read()
    if s.count(old) != 1:
        sys.exit(f"shade_compile_split: the {variant} edit no longer matches shaders/stages/shade.wgsl")
    open(p, "w").write(s.replace(old, new))
edit("no-shade", """                    if penumbra_HAS_OCCLUSION {
                        colour += scale * shade(s, l, p);
                    } else {
                        colour += shade(s, l, p);
                    }""", "                    colour += l.intensity * l.diffuse;")
edit("no-ambient", "colour = penumbra_ambient_sum(s, p);", "colour = vec3<f32>(0.0);")
p = f"{work}/floor/shaders/stages/shade.wgsl"
s = open(p).read()
start = s.find("    let local = px - push.tile_origin;")
end = s.find("    let at = px.y * push.size.x")
if start < 0 or end < start:
    sys.exit("shade_compile_split: the floor edit no longer matches shaders/stages/shade.wgsl")
open(p, "w").write(s[:start] + "    var colour = vec3<f32>(0.5);\n" + s[end:])
EOF

# The shade pipeline's driver compile of $file, in ms, from one cold render.
compile_ms() {
    MESA_SHADER_CACHE_DISABLE=true PENUMBRA_PIPELINE_CACHE=0 "$penumbra" render "$scene" --width 32 --shaders "$work/$1/shaders" -o "$work/$1.png" 2>&1 |
        grep -o "shade [^ ]*/$file [0-9.]* m\?s" | awk '{ print ($4 == "s") ? $3 * 1000 : $3 }'
}

declare -A times
for _ in $(seq "$rounds"); do
    for v in "${variants[@]}"; do
        t=$(compile_ms "$v")
        [ -n "$t" ] || { echo "shade_compile_split: no shade compile of $file reported for $v" >&2; exit 1; }
        times[$v]="${times[$v]:-} $t"
    done
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '| variant | driver compile, median [min–max] ms | of full |\n|---|---:|---:|\n'
full_median=$(tr ' ' '\n' <<<"${times[full]}" | grep . | sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }')
for v in "${variants[@]}"; do
    tr ' ' '\n' <<<"${times[$v]}" | grep . | sort -g |
        awk -v v="$v" -v full="$full_median" '{ a[NR] = $1 } END {
            m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2
            printf "| %s | %.1f [%.1f–%.1f] | %.2f |\n", v, m, a[1], a[NR], m / full }'
done
