#!/bin/bash
# Measures `penumbra farm slurm` on the local cluster (tools/slurm-local.sh up
# first) for docs/farm.md: one scene in 1, 2, 4, 8 and 16 tiles, with the Mesa
# shader cache disabled and shared, against one process; then a batch of 100
# small glTF renders in 1 process and in 4 array tasks. Prints markdown tables.
#
#   tools/measure/farm_measure.sh [SCENE [SIZE]]     default scenes/bunny_scene.glb 4096
#
# Per task: wall time (the job script's own start/end stamps), and from the
# task's log the phases penumbra reports (driver compile, GPU render, write);
# start-up is wall time less load, compiles, render, readback and write.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${PENUMBRA:-$root/target/release/penumbra}
scene=${1:-scenes/bunny_scene.glb}
size=${2:-4096}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$root/scenes" "$work/"
cd "$work"
export PENUMBRA=$bin

secs() { awk -v s="$1" 'BEGIN { printf "%.2f", s }'; }
now() { date +%s.%N; }

# Mean of a phase ("driver compile 12.3 ms") over the task logs of a run.
phase() {
  grep -ho "$2 [0-9.]* ms" "$1"/logs/task-*.log | awk '{ s += $(NF-1); n++ } END { printf "%.0f", n ? s / n : 0 }'
}

t0=$(now)
MESA_SHADER_CACHE_DISABLE=true "$bin" render "$scene" --width "$size" --height "$size" -o single.png >single.log
t1=$(now)
single=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')
echo "One process, $scene at ${size}x${size}, Mesa cache disabled: $(secs "$single") s"
grep -o 'driver compile [0-9.]* ms, .*GPU render [0-9.]* ms' single.log || true
echo
echo "| Mesa cache | tiles | task wall (mean) | start-up (mean) | driver compile (mean) | GPU render (mean) | write (mean) | merge | end to end | vs one process |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for cache in disabled shared; do
  for n in 1 2 4 8 16; do
    out=t$cache$n.png
    if [[ $cache == disabled ]]; then
      env=(MESA_SHADER_CACHE_DISABLE=true)
    else
      mkdir -p "mesa-$n"
      env=(MESA_SHADER_CACHE_DIR="$work/mesa-$n")
    fi
    t0=$(now)
    env "${env[@]}" "$bin" farm slurm "$scene" -o "$out" --tiles "$n" --width "$size" --height "$size" --submit >"$out.report"
    t1=$(now)
    cmp -s single.png "$out" || { echo "$out differs from the single render" >&2; exit 1; }
    w="$out.farm"
    wall=$(awk '{ s += $2 - $1; n++ } END { print s / n }' "$w"/logs/task-*.time)
    busy=$(grep -ho '| load .*write [0-9.]* ms' "$w"/logs/task-*.log | grep -o '[0-9.]* ms' |
      awk '{ s += $1 } END { print s }')
    startup=$(awk -v w="$wall" -v b="$busy" -v n="$n" 'BEGIN { printf "%.2f", w - b / 1000 / n }')
    merge=$(awk '{ printf "%.2f", $2 - $1 }' "$w"/logs/merge.time)
    e2e=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')
    echo "| $cache | $n | $(secs "$wall") s | $startup s | $(phase "$w" 'driver compile') ms | $(phase "$w" 'GPU render') ms | $(phase "$w" 'write') ms | $merge s | $(secs "$e2e") s | $(awk -v a="$e2e" -v b="$single" 'BEGIN { printf "%.2f", a / b }')x |"
  done
done

# A batch of 100 small glTF renders (the bunny at 128x128, 100 outputs).
for i in $(seq -w 0 99); do echo "scenes/bunny_scene.glb b$i.png"; done >list.txt
mkdir -p one farm
t0=$(now)
"$bin" render --batch list.txt -o one --width 128 --height 128 >/dev/null
t1=$(now)
t2=$(now)
"$bin" farm slurm --batch list.txt --tasks 4 -o farm --width 128 --height 128 --submit >batch.report
t3=$(now)
echo
echo "| batch of 100 (128x128) | end to end |"
echo "|---|---|"
echo "| one process | $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }') s |"
echo "| farm slurm --tasks 4 | $(awk -v a="$t2" -v b="$t3" 'BEGIN { printf "%.2f", b - a }') s |"
