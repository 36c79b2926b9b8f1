#!/usr/bin/env bash
# Where lavapipe's generated kernel spends its time: renders the bunny benchmark scene for a
# few seconds, samples the process with `perf record -e cpu-clock` (software clock: virtual
# machines often have no hardware counters), dumps the JIT-compiled kernel (the largest
# anonymous executable mapping) from the running process with gdb, disassembles it with
# objdump and prints what distinguishes one driver's code from another's:
#
#   - code size, stack frame size and distinct stack slots (spills);
#   - per-lane loops: `cmp $0x8` closing a loop over the 8 lanes of a 256-bit vector, the
#     shape gallivm gives a load or store at a per-lane address when it emits it as a loop;
#   - `and $0x7` lane masks: a vector lane chosen by a loop counter, which LLVM lowers to
#     storing the whole vector to the stack, writing one lane and reloading it;
#   - the share of samples in the kernel and inside the per-lane loops, by the storage-buffer
#     slot of the lavapipe context they read.
#
#   tools/jit_profile.sh [installed|OLD]     OLD: the tree of tools/mesa_tree.sh
#
# Needs perf (linux-perf), gdb and objdump (binutils); run it on an otherwise quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
driver=${1:-installed}
for t in perf gdb objdump python3; do
  command -v "$t" >/dev/null || { echo "jit_profile.sh: needs $t" >&2; exit 1; }
done
cargo build --release --quiet --bin penumbra
bin="${CARGO_TARGET_DIR:-target}/release/penumbra"
env=()
if [ "$driver" != installed ]; then
  icd=$(tools/mesa_tree.sh --icd 2>/dev/null)
  env=(VK_DRIVER_FILES="$icd" VK_ICD_FILENAMES="$icd")
fi
work=$(mktemp -d)
trap 'kill "$pid" 2>/dev/null || true; rm -rf "$work"' EXIT
# A warm-up render fills the shader cache; the profiled one renders passes for long enough.
env "${env[@]}" "$bin" render scenes/bunny_scene.glb --spp 2 -o "$work/o.png" >/dev/null
env "${env[@]}" "$bin" render scenes/bunny_scene.glb --spp 64 -o "$work/o.png" >"$work/render.log" &
pid=$!
sleep 4
perf record -q -e cpu-clock -p "$pid" -o "$work/perf.data" -- sleep 4 >/dev/null 2>&1
gdb -p "$pid" -batch -ex 'info proc mappings' >"$work/maps" 2>/dev/null
read -r start end < <(python3 -c '
import sys
best = (0, "", "")
for f in (l.split() for l in open(sys.argv[1])):
    if len(f) == 5 and f[4] == "r-xp" and f[0].startswith("0x"):
        best = max(best, (int(f[1], 16) - int(f[0], 16), f[0], f[1]))
print(best[1], best[2])' "$work/maps")
gdb -p "$pid" -batch -ex "dump memory $work/jit.bin $start $end" >/dev/null 2>&1
kill "$pid" 2>/dev/null || true
objdump -D -b binary -m i386:x86-64 --adjust-vma="$start" "$work/jit.bin" >"$work/jit.s"
perf script -i "$work/perf.data" -F ip,dso 2>/dev/null >"$work/samples"
echo "driver: $(env "${env[@]}" "$bin" devices | grep -i llvmpipe | head -n1 | sed -E 's/.*driver //')"
python3 - "$work" "$start" "$end" <<'EOF'
import collections, re, sys
work, start, end = sys.argv[1], int(sys.argv[2], 16), int(sys.argv[3], 16)
rows = []
for line in open(f"{work}/jit.s"):
    m = re.match(r"\s*([0-9a-f]+):\s+(?:[0-9a-f]{2} )+\s*(\S.*)", line)
    if m:
        rows.append((int(m.group(1), 16), m.group(2)))
samples = [l.split() for l in open(f"{work}/samples") if l.strip()]
total = len(samples)
ips = collections.Counter(int(s[0], 16) for s in samples if start <= int(s[0], 16) < end)
in_jit = sum(ips.values())
text = "\n".join(t for _, t in rows)
slots = {int(x, 16) for x in re.findall(r"\b(0x[0-9a-f]+)\(%rsp", text)}
loops = []
for i, (a, t) in enumerate(rows[:-1]):
    nxt = rows[i + 1][1]
    if t.startswith("cmp    $0x8,") and nxt.startswith("jae"):
        target = int(nxt.split()[-1], 16)
        if target > a:
            loops.append((rows[i - 1][0], target))
print(f"kernel code: {end - start} bytes, {len(rows)} instructions")
print(f"stack: frame up to {max(slots, default=0)} bytes, {len(slots)} distinct slots")
print(f"per-lane loops: {len(loops)}; loop-indexed lanes (and $0x7): {text.count('and    $0x7,')}")
print(f"samples: {total}, in the kernel: {100 * in_jit / max(total, 1):.1f}%")
by_slot = collections.Counter()
for lo, hi in loops:
    n = sum(v for k, v in ips.items() if lo <= k < hi)
    body = " ".join(t for a, t in rows if lo <= a < hi)
    regs = sorted(set(re.findall(r"(0x[0-9a-f]+)\(%r1[45]\)", body)))
    by_slot[",".join(regs) or "-"] += n
inside = sum(by_slot.values())
print(f"samples inside per-lane loops: {100 * inside / max(in_jit, 1):.1f}% of the kernel's")
for k, v in by_slot.most_common(8):
    print(f"  context offsets {k}: {100 * v / max(in_jit, 1):.1f}%")
EOF
