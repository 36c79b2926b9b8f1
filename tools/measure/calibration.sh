#!/usr/bin/env bash
# The calibration's figures on this machine (docs/drivers.md, "Calibration"): the machine
# (CPU vendor, family, model, name and its vector instruction sets from /proc/cpuinfo; the
# driver from `penumbra devices`), then RUNS runs of `penumbra calibrate`, each into a fresh
# cache directory (so each measures: 3 interleaved rounds of every candidate, 8 warm frames
# each, the probes in their own processes), with each candidate's median and range, the
# choice, and the run's wall time. Mesa's shader cache stays where it is (warmed by a first,
# unreported run), so the wall time is that of a calibration after the driver has compiled
# the kernel once at each setting.
#
#   tools/measure/calibration.sh [RUNS]         (default 3; PENUMBRA=path/to/penumbra,
#                                                default target/release, else target/debug)
set -euo pipefail
cd "$(dirname "$0")/../.."
runs=${1:-3}
tgt=${CARGO_TARGET_DIR:-target}
bin=${PENUMBRA:-}
if [ -z "$bin" ]; then
  if [ -x "$tgt/release/penumbra" ]; then bin=$tgt/release/penumbra; else bin=$tgt/debug/penumbra; fi
fi
[ -x "$bin" ] || { echo "error: $bin: no penumbra binary (cargo build first)" >&2; exit 1; }
unset LP_NATIVE_VECTOR_WIDTH GALLIUM_OVERRIDE_CPU_CAPS PENUMBRA_CALIBRATION_FAKE
field() { grep -m1 "^$1[[:space:]]*:" /proc/cpuinfo | sed 's/^[^:]*:[[:space:]]*//'; }
vectors=$(field flags | tr ' ' '\n' | grep -E '^(avx|avx2|avx512.*|amx.*)$' | tr '\n' ' ')
echo "CPU: $(field vendor_id) family $(field 'cpu family') model $(field model) ($(field 'model name')), $(nproc) cores; vector sets: $vectors"
echo "Driver: $("$bin" devices | grep -m1 -i llvmpipe || "$bin" devices | head -1)"
echo "Kernel: $(uname -r); binary: $bin"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
mesa=${MESA_SHADER_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}}
XDG_CACHE_HOME=$scratch/warm MESA_SHADER_CACHE_DIR=$mesa "$bin" calibrate > /dev/null
for r in $(seq "$runs"); do
  echo
  echo "Run $r:"
  t0=$(date +%s.%N)
  XDG_CACHE_HOME=$scratch/run$r MESA_SHADER_CACHE_DIR=$mesa "$bin" calibrate | grep -v '^remembered in'
  t1=$(date +%s.%N)
  echo "wall time: $(echo "$t1 - $t0" | bc) s"
done
