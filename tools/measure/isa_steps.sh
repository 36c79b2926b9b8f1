#!/usr/bin/env bash
# The kernel's tuning steps (docs/bench.md §6), each measured with AVX-512 code and with AVX2
# code on one machine in one run. lavapipe targets every instruction set the CPU reports;
# Mesa's GALLIUM_OVERRIDE_CPU_CAPS=avx caps it below AVX-512 (tools/measure/jit_profile.sh counts the
# EVEX-encoded instructions of the generated code, to check that it does), so an AVX-512
# machine gives both kinds of code.
#
#   tools/measure/isa_steps.sh [ROUNDS] [STEP...]      (default 5 rounds, every step; STEP: A..B)
#
# A step is two commits, A before the change and B after it (the table below, in §6's order).
# Where the change touched only shaders, or host code that A's shaders run under unchanged
# ("shaders"; 3079c47 only lets naga validate subgroup operations and picks devices that have
# them, and 52fe479 has no `ab`), one process of B's `ab` renders A's and B's shader trees in
# interleaved pairs; where it changed the host too ("commits"), A's and B's
# own `ab` binaries run in turn (tools/measure/ab_commits.sh --build makes them). In every round each
# step runs under both instruction sets, the order alternating from round to round. Each
# figure is the median frame of 3 pairs: the driver threads' CPU time (`ab --cpu-time`) where
# the commit's `ab` has it, wall time before that (marked "wall"). Prints one table row per
# step: each side's median, B/A under each instruction set (median [min–max] over rounds), and
# the quotient of the two ratios. Last, this checkout's kernel (its own `ab` build and shaders/)
# under both, AVX2 / AVX-512.
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
rounds=5
if [ $# -gt 0 ] && [[ "$1" =~ ^[0-9]+$ ]]; then rounds=$1; shift; fi
scene=scenes/bunny_scene.glb

# A B kind what
steps=(
  "52fe479 3079c47 shaders ray counters summed per subgroup, no workgroup barrier"
  "3079c47 1fbf176 commits closest-hit traversal while-while"
  "259268b b034ab0 shaders shadow rays nearer child first, slab test by compare and select"
  "b034ab0 a3625fc commits node records with both children's boxes quantised to 8 bits"
  "6bfe8af 5de8055 commits first light read once per SIMD group"
  "da6e098 ac8511d commits BVH records as sampled-image texels"
  "ac2360d ab7fa43 commits BVH records as storage-image texels"
  "ab7fa43 f9bee1e commits triangles as storage-image texels"
  "0f9746b 32f5909 shaders newest four stack entries in a register"
  "32f5909 c8ac603 commits records of two texels instead of three"
)
if [ $# -gt 0 ]; then
  chosen=()
  for want in "$@"; do
    for s in "${steps[@]}"; do
      read -r a b _ <<<"$s"
      if [ "$a..$b" = "$want" ]; then chosen+=("$s"); fi
    done
  done
  [ ${#chosen[@]} -gt 0 ] || { echo "isa_steps.sh: no step matches $*" >&2; exit 2; }
  steps=("${chosen[@]}")
fi

isas=(avx512 avx2)
isa_env() { if [ "$1" = avx2 ]; then echo GALLIUM_OVERRIDE_CPU_CAPS=avx; fi; }
grep -qw avx512f /proc/cpuinfo || { echo "isa_steps.sh: this CPU has no AVX-512" >&2; exit 2; }

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scratch=${AB_SCRATCH:-$root/target/ab_commits}
bin_of() { tools/measure/ab_commits.sh --build "$1"; }
shaders_of() { # COMMIT -> its shaders/, in a scratch worktree made if missing
  local dir
  dir=$scratch/$(git rev-parse --verify "$1^{commit}")
  [ -d "$dir" ] || git worktree add --detach "$dir" "$1" >/dev/null 2>&1
  echo "$dir/shaders"
}
has_cpu_time() { "$1" --help 2>&1 | grep -q -- --cpu-time; }

# ab's output lines "A: 12.3 ..." and "B: 45.6 ..." -> "12.3 45.6"
ab_pair() { awk '/^A: [0-9]/ { a = $2 } /^B: [0-9]/ { b = $2 } END { print a, b }'; }

measure() { # STEP_INDEX ISA: appends "a b" (ms of each side) to $out/STEP-ISA
  local a b kind env flag ba bb
  read -r a b kind _ <<<"${steps[$1]}"
  env=$(isa_env "$2")
  if [ "$kind" = shaders ]; then
    ba=$(bin_of "$b")
    flag=$(has_cpu_time "$ba" && echo --cpu-time || true)
    env $env "$ba" "$scene" --a "$(shaders_of "$a")" --b "$(shaders_of "$b")" --pairs 3 $flag 2>/dev/null |
      ab_pair >>"$out/$1-$2"
  else
    ba=$(bin_of "$a")
    bb=$(bin_of "$b")
    local ta tb
    flag=$(has_cpu_time "$ba" && echo --cpu-time || true)
    ta=$(env $env "$ba" "$scene" --b "$(shaders_of "$a")" --pairs 3 $flag 2>/dev/null | ab_pair | cut -d' ' -f1)
    flag=$(has_cpu_time "$bb" && echo --cpu-time || true)
    tb=$(env $env "$bb" "$scene" --b "$(shaders_of "$b")" --pairs 3 $flag 2>/dev/null | ab_pair | cut -d' ' -f1)
    echo "$ta $tb" >>"$out/$1-$2"
  fi
}

# Build everything first, so that no build runs between measurements.
for s in "${steps[@]}"; do
  read -r a b kind _ <<<"$s"
  shaders_of "$a" >/dev/null
  if [ "$kind" = commits ]; then bin_of "$a" >/dev/null; fi
  bin_of "$b" >/dev/null
done
cargo build --release --quiet -p penumbra-tools --bin ab
head_ab=${CARGO_TARGET_DIR:-target}/release/ab

for ((r = 0; r < rounds; r++)); do
  order=("${isas[@]}")
  if ((r % 2)); then order=(avx2 avx512); fi
  for i in "${!steps[@]}"; do
    for isa in "${order[@]}"; do measure "$i" "$isa"; done
  done
  for isa in "${order[@]}"; do
    env $(isa_env "$isa") "$head_ab" "$scene" --b shaders --pairs 3 --cpu-time 2>/dev/null |
      ab_pair | cut -d' ' -f1 >>"$out/head-$isa"
  done
  echo "round $((r + 1)) of $rounds done" >&2
done

stats() { # file of numbers -> "median [min–max]"
  sort -g "$1" | awk '{ v[NR] = $1 } END {
    m = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
    printf "%.3f [%.3f–%.3f]", m, v[1], v[NR] }'
}
med() { sort -g "$1" | awk '{ v[NR] = $1 } END { printf "%.1f", (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "| step (A → B) | what B changed | ms a frame A → B, AVX-512 | ms a frame A → B, AVX2 | B/A, AVX-512 | B/A, AVX2 | AVX2 ratio / AVX-512 ratio |"
echo "|---|---|---|---|---|---|---|"
for i in "${!steps[@]}"; do
  read -r a b kind what <<<"${steps[$i]}"
  unit=""
  if [ "$kind" = shaders ]; then has_cpu_time "$(bin_of "$b")" || unit=" (wall)"
  else has_cpu_time "$(bin_of "$a")" || unit=" (wall)"; fi
  cells=()
  for isa in "${isas[@]}"; do
    awk '{ print $1 }' "$out/$i-$isa" >"$out/a"
    awk '{ print $2 }' "$out/$i-$isa" >"$out/b"
    awk '{ print $2 / $1 }' "$out/$i-$isa" >"$out/ratio-$isa"
    cells+=("$(med "$out/a") → $(med "$out/b")$unit")
  done
  ra=$(sort -g "$out/ratio-avx512" | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
  rb=$(sort -g "$out/ratio-avx2" | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
  echo "| $a → $b | $what | ${cells[0]} | ${cells[1]} | $(stats "$out/ratio-avx512") | $(stats "$out/ratio-avx2") | $(awk -v a="$ra" -v b="$rb" 'BEGIN { printf "%.3f", b / a }') |"
done
paste "$out/head-avx512" "$out/head-avx2" | awk '{ print $2 / $1 }' >"$out/head-ratio"
echo
echo "HEAD ($(git rev-parse --short HEAD)), the staged kernel: $(med "$out/head-avx512") ms of worker CPU time per frame with AVX-512 code, $(med "$out/head-avx2") ms with AVX2 code; AVX2 / AVX-512 per round: $(stats "$out/head-ratio") over $rounds rounds"
