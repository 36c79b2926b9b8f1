#!/usr/bin/env bash
# Whether two commits render every scene of scenes/ to the same pixels: a
# refactoring must keep every image bit for bit (issue 37). Builds `penumbra`
# (dev profile) at both commits in scratch worktrees, renders each scene at 1
# and 4 samples per pixel to OpenEXR (linear f32, no rounding) with each, and
# compares the pairs with `penumbra diff`: the check passes only when every
# pair has max_abs_error 0. (The EXR bytes themselves may differ: the writer
# compresses blocks in parallel.)
#
#   tools/measure/same_images.sh BASE_COMMIT [NEW_COMMIT]    (NEW_COMMIT: HEAD)
#
# SAME_IMAGES_TARGET names the target directory the builds share (default
# target/same_images; a copy of a built target directory saves the
# dependencies' build).
set -euo pipefail

root=$(git rev-parse --show-toplevel)
base=${1:?usage: tools/measure/same_images.sh BASE_COMMIT [NEW_COMMIT]}
new=${2:-HEAD}
scratch=$root/target/same_images
target=${SAME_IMAGES_TARGET:-$scratch/target}
mkdir -p "$scratch"

build() { # commit -> path of its penumbra binary
    local sha dir
    sha=$(git -C "$root" rev-parse --verify "$1^{commit}")
    dir=$scratch/$sha
    [ -d "$dir" ] || git -C "$root" worktree add --detach "$dir" "$sha" >&2
    if [ ! -x "$scratch/penumbra-$sha" ]; then
        # Cargo names the build of a path package by its path relative to the
        # workspace root, the same in every worktree: make the files newer
        # than another commit's build.
        find "$dir" -path "$dir/.git" -prune -o -type f -exec touch {} +
        (cd "$dir" && CARGO_TARGET_DIR=$target cargo build -q --bin penumbra >&2)
        cp "$target/debug/penumbra" "$scratch/penumbra-$sha"
    fi
    echo "$scratch/penumbra-$sha"
}

a=$(build "$base")
b=$(build "$new")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
status=0
for scene in "$root"/scenes/*.json "$root"/scenes/*.glb; do
    name=$(basename "$scene")
    for spp in 1 4; do
        "$a" render "$scene" -o "$out/a.exr" --spp "$spp" >/dev/null
        "$b" render "$scene" -o "$out/b.exr" --spp "$spp" >/dev/null
        err=$("$b" diff "$out/a.exr" "$out/b.exr" | sed -n 's/^max_abs_error: //p')
        if [ "$err" = 0 ]; then
            echo "same: $name at $spp spp"
        else
            echo "DIFFERENT: $name at $spp spp (max_abs_error $err)"
            status=1
        fi
    done
done
exit $status
