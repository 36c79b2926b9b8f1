#!/usr/bin/env bash
# A/B timing of two commits whose host code differs (tools/measure/ab.rs compares
# shader trees under one binary; a change to the GPU data layout needs two
# binaries). Builds `ab` at both commits in scratch worktrees, then runs them
# in turn, A B A B …, each with its own commit's shaders, each process
# rendering the scene (3 pairs of frames,
# --cpu-time: the driver threads' CPU time per frame, which other processes
# sharing the cores do not inflate), and prints each round's medians, the
# median of the per-round ratios B/A and its range.
#
#   tools/measure/ab_commits.sh A_COMMIT B_COMMIT [ROUNDS] [SCENE]
#   tools/measure/ab_commits.sh --build COMMIT     builds only; prints the path of COMMIT's ab binary
#                                          (its shaders are in the worktree beside it:
#                                          tools/measure/isa_steps.sh uses both)
#
# Example: tools/measure/ab_commits.sh HEAD~1 HEAD 7 scenes/bunny_scene.glb
set -euo pipefail

root=$(git rev-parse --show-toplevel)
scratch=${AB_SCRATCH:-$root/target/ab_commits}
mkdir -p "$scratch"

build() { # commit -> path of its ab binary
    local sha dir
    sha=$(git -C "$root" rev-parse --verify "$1^{commit}")
    dir=$scratch/$sha
    if [ ! -d "$dir" ]; then
        git -C "$root" worktree add --detach "$dir" "$sha" >&2
    fi
    # One target directory for all scratch builds (dependencies build once);
    # each commit's binary is copied out of it.
    # Commits since the tools became the workspace member penumbra-tools
    # (tools/Cargo.toml; tools/measure/Cargo.toml since issue 37) build `ab`
    # as its binary; older ones as the root package's example.
    if [ ! -x "$scratch/ab-$sha" ]; then
        # A commit from before the workspace (no [workspace] table) would
        # otherwise count as a member of this checkout's workspace, above it.
        grep -q '^\[workspace\]' "$dir/Cargo.toml" || printf '\n[workspace]\n' >>"$dir/Cargo.toml"
        # Cargo names a path package's build by its path relative to the
        # workspace root, the same in every scratch worktree, and rebuilds it
        # only for sources newer than that build: a worktree made before
        # another commit's build would pass for built. Make its files newer.
        find "$dir" -path "$dir/.git" -prune -o -type f -exec touch {} +
        if [ -f "$dir/tools/measure/Cargo.toml" ] || [ -f "$dir/tools/Cargo.toml" ]; then
            (cd "$dir" && CARGO_TARGET_DIR=$scratch/target cargo build -q --release -p penumbra-tools --bin ab >&2)
            cp "$scratch/target/release/ab" "$scratch/ab-$sha"
        else
            (cd "$dir" && CARGO_TARGET_DIR=$scratch/target cargo build -q --release --example ab >&2)
            cp "$scratch/target/release/examples/ab" "$scratch/ab-$sha"
        fi
    fi
    echo "$scratch/ab-$sha"
}

if [ "${1:-}" = --build ]; then
    build "${2:?usage: tools/measure/ab_commits.sh --build COMMIT}"
    exit 0
fi
a=${1:?usage: tools/measure/ab_commits.sh A_COMMIT B_COMMIT [ROUNDS] [SCENE]}
b=${2:?usage: tools/measure/ab_commits.sh A_COMMIT B_COMMIT [ROUNDS] [SCENE]}
rounds=${3:-7}
scene=${4:-scenes/bunny_scene.glb}

run() { # binary, shader tree -> median worker-CPU ms per frame of one process
    (cd "$root" && "$1" "$scene" --b "$2" --pairs 3 --cpu-time 2>/dev/null) |
        awk '/^A: [0-9]/ { print $2 }'
}

bin_a=$(build "$a")
bin_b=$(build "$b")
# Each binary renders with its own commit's shaders (the kernel and the host
# layout it reads must match).
shaders_a=$scratch/$(git -C "$root" rev-parse --verify "$a^{commit}")/shaders
shaders_b=$scratch/$(git -C "$root" rev-parse --verify "$b^{commit}")/shaders
for ((i = 1; i <= rounds; i++)); do
    ta=$(run "$bin_a" "$shaders_a")
    tb=$(run "$bin_b" "$shaders_b")
    echo "round $i: A $ta ms, B $tb ms, B/A $(awk -v a="$ta" -v b="$tb" 'BEGIN { printf "%.3f", b / a }')"
done | tee /dev/stderr | awk '
    { split($0, f, "B/A "); r[NR] = f[2] + 0; split($0, g, " "); ta[NR] = g[4] + 0; tb[NR] = g[7] + 0 }
    END {
        n = NR
        for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) {
            if (r[j] < r[i]) { t = r[i]; r[i] = r[j]; r[j] = t }
            if (ta[j] < ta[i]) { t = ta[i]; ta[i] = ta[j]; ta[j] = t }
            if (tb[j] < tb[i]) { t = tb[i]; tb[i] = tb[j]; tb[j] = t }
        }
        m = (n % 2) ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2
        ma = (n % 2) ? ta[(n + 1) / 2] : (ta[n / 2] + ta[n / 2 + 1]) / 2
        mb = (n % 2) ? tb[(n + 1) / 2] : (tb[n / 2] + tb[n / 2 + 1]) / 2
        printf "A: %.1f ms, B: %.1f ms of worker CPU time per frame (medians)\n", ma, mb
        printf "B/A: %.3f [%.3f-%.3f] over %d rounds\n", m, r[1], r[n], n
    }'
