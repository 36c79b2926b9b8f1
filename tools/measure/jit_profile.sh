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
#   - the kernel's calls through a pointer (lavapipe's image functions: a texel load or store
#     each), its gathers (vpgather*) and its broadcasts (vpbroadcast*: among them a
#     storage-buffer load at a subgroup-uniform address, loaded once and broadcast);
#   - the share of samples in the kernel and inside the per-lane loops, by the storage-buffer
#     slot of the lavapipe context they read;
#   - per mapping of generated code (a stage's kernel, sometimes several in one mapping;
#     lavapipe's image functions), hottest first: its share of the samples and its integer
#     divisions (`div`), with the share of its samples from its first division to its last,
#     where lavapipe computes the invocation ids;
#   - the instruction sets of all the generated code (every anonymous executable mapping, each
#     stage's pipeline among them): EVEX-encoded instructions (AVX-512's encoding), those on
#     512-bit zmm registers, on the opmask registers k1-k7 and on registers 16-31. All four are
#     zero for AVX2 code, so a run under GALLIUM_OVERRIDE_CPU_CAPS=avx on an AVX-512 CPU shows
#     whether the cap holds (the environment passes through to the render).
#
#   tools/measure/jit_profile.sh [installed|OLD] [RENDER ARGS...]
#
# OLD: the tree of tools/mesa_tree.sh; RENDER ARGS go to both renders (e.g. `--traversal packet`).
#
# Needs perf (linux-perf), gdb and objdump (binutils); run it on an otherwise quiet machine.
set -euo pipefail
cd "$(dirname "$0")/../.."
driver=${1:-installed}
extra=("${@:2}")
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
[ -z "${JIT_PROFILE_KEEP:-}" ] || echo "jit_profile.sh: keeping $work" >&2
trap 'kill "$pid" 2>/dev/null || true; [ -n "${JIT_PROFILE_KEEP:-}" ] || rm -rf "$work"' EXIT
# A warm-up render fills the shader cache; the profiled one renders passes for long enough (it
# is killed once sampled and dumped).
# Both at 256 bits, lavapipe's default, which auto would raise to 512 for 64 passes on a CPU
# with AVX-512; an LP_NATIVE_VECTOR_WIDTH in the environment still wins.
env "${env[@]}" "$bin" render scenes/bunny_scene.glb --vector-width 256 --spp 2 "${extra[@]}" -o "$work/o.png" >/dev/null
env "${env[@]}" "$bin" render scenes/bunny_scene.glb --vector-width 256 --spp 1024 "${extra[@]}" -o "$work/o.png" >"$work/render.log" &
pid=$!
sleep 4
perf record -q -e cpu-clock -p "$pid" -o "$work/perf.data" -- sleep 4 >/dev/null 2>&1
gdb -p "$pid" -batch -ex 'info proc mappings' >"$work/maps" 2>/dev/null
# Anonymous executable mappings (no file name): lavapipe's generated code, largest first.
python3 -c '
import sys
maps = []
for f in (l.split() for l in open(sys.argv[1])):
    if len(f) == 5 and f[4] == "r-xp" and f[0].startswith("0x"):
        maps.append((int(f[1], 16) - int(f[0], 16), f[0], f[1]))
for _, a, b in sorted(maps, reverse=True):
    print(a, b)' "$work/maps" >"$work/jit_maps"
read -r start end <"$work/jit_maps"
dumps=()
while read -r a b; do dumps+=(-ex "dump memory $work/jit-$a.bin $a $b"); done <"$work/jit_maps"
gdb -p "$pid" -batch "${dumps[@]}" >/dev/null 2>&1
kill "$pid" 2>/dev/null || true
while read -r a b; do
  objdump -D -b binary -m i386:x86-64 --adjust-vma="$a" "$work/jit-$a.bin" >"$work/jit-$a.s"
done <"$work/jit_maps"
cp "$work/jit-$start.s" "$work/jit.s"
perf script -i "$work/perf.data" -F ip,dso 2>/dev/null >"$work/samples"
echo "driver: $(env "${env[@]}" "$bin" devices | grep -i llvmpipe | head -n1 | sed -E 's/.*driver //')"
python3 - "$work" "$start" "$end" <<'EOF'
import collections, re, sys
work, start, end = sys.argv[1], int(sys.argv[2], 16), int(sys.argv[3], 16)
def listing(path):
    """(address, instruction) of each line of an objdump listing."""
    out = []
    for line in open(path):
        m = re.match(r"\s*([0-9a-f]+):\s+(?:[0-9a-f]{2} )+\s*(\S.*)", line)
        if m:
            out.append((int(m.group(1), 16), m.group(2)))
    return out
rows = listing(f"{work}/jit.s")
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
print(f"calls through a pointer (texel loads and stores): {len(re.findall(r'call +[*]', text))}; "
      f"gathers (vpgather*): {text.count('vpgather')}; broadcasts (vpbroadcast*): {text.count('vpbroadcast')}")
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

# Each mapping's samples and integer divisions.
maps = [l.split() for l in open(f"{work}/jit_maps")]
all_ips = collections.Counter(int(s[0], 16) for s in samples)
hot = []
for a, b in maps:
    lo, hi = int(a, 16), int(b, 16)
    n = sum(v for k, v in all_ips.items() if lo <= k < hi)
    hot.append((n, a, hi - lo))
print("mappings of generated code by samples (share of all; integer divisions; share of its samples in them):")
for n, a, size in sorted(hot, reverse=True)[:4]:
    code = listing(f"{work}/jit-{a}.s")
    divs = [i for i, (_, t) in enumerate(code) if re.match(r"div\s", t)]
    at_divs = 0
    if divs:
        first, last = code[divs[0]][0], code[min(divs[-1] + 1, len(code) - 1)][0]
        at_divs = sum(v for k, v in all_ips.items() if first <= k <= last)
    print(f"  {size} bytes: {100 * n / max(total, 1):.1f}%; {len(divs)} divisions, "
          f"{100 * at_divs / max(n, 1):.1f}%")

# Instruction sets, over every mapping. In 64-bit mode a 0x62 byte that opens an instruction
# (after an optional 0x67 address-size prefix, the only legacy prefix EVEX allows) is the
# EVEX prefix: VEX-encoded AVX2 code never starts with it.
n = evex = zmm = kmask = high = 0
for a, _ in maps:
    for line in open(f"{work}/jit-{a}.s"):
        m = re.match(r"\s*[0-9a-f]+:\s+((?:[0-9a-f]{2} )+)\s*(\S.*)", line)
        if not m:
            continue
        code, t = m.group(1).split(), m.group(2)
        n += 1
        if code[0] == "62" or (code[0] == "67" and len(code) > 1 and code[1] == "62"):
            evex += 1
        zmm += "%zmm" in t
        kmask += bool(re.search(r"%k[1-7]\b", t))
        high += bool(re.search(r"%[xyz]mm(1[6-9]|2[0-9]|3[01])\b", t))
print(f"generated code: {len(maps)} mappings, {n} instructions; AVX-512: {evex} EVEX-encoded, "
      f"{zmm} on zmm registers, {kmask} on opmask registers, {high} on registers 16-31")
EOF
