#!/usr/bin/env bash
# The stages against the megakernel with the same BVH builder: makes a scratch commit of the
# megakernel (7031ecb, the commit before the stages) whose src/bvh.rs is B's, then times it
# against B with tools/measure/ab_commits.sh. Since 9403186 the builder gives a ground quad beside a
# mesh a side of its own, which speeds up the megakernel as much as the stages; this separates
# what the stages cost from what the tree gains (docs/stages.md). The builder's file is the
# same at 7031ecb as at 9403186's parent but for a comment, so B's file compiles there.
#
#   tools/measure/ab_same_tree.sh B_COMMIT [ROUNDS] [SCENE]
#
# The scratch commit is a detached commit in target/ab_commits (no branch points at it).
set -euo pipefail

root=$(git rev-parse --show-toplevel)
b=${1:?usage: tools/measure/ab_same_tree.sh B_COMMIT [ROUNDS] [SCENE]}
megakernel=7031ecb
scratch=${AB_SCRATCH:-$root/target/ab_commits}
sha=$(git -C "$root" rev-parse --verify "$b^{commit}")
dir=$scratch/megakernel-tree-$sha
if [ ! -d "$dir" ]; then
    mkdir -p "$scratch"
    git -C "$root" worktree add --detach "$dir" "$megakernel" >&2
    git -C "$root" show "$sha:src/bvh.rs" >"$dir/src/bvh.rs"
    git -C "$dir" -c user.name=ab_same_tree -c user.email=ab_same_tree@localhost \
        commit -q -am "scratch: $megakernel with the BVH builder of $sha (measurement only)"
fi
a=$(git -C "$dir" rev-parse HEAD)
echo "A: $megakernel with src/bvh.rs of $sha ($a)" >&2
exec "$root/tools/measure/ab_commits.sh" "$a" "$sha" "${2:-11}" "${3:-scenes/bunny_scene.glb}"
