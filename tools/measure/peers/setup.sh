#!/usr/bin/env bash
# What the benchmark's peers (tools/measure/peers/peers.py) need, for `tools/setup.sh --bench`:
# python3-venv and a libLLVM shared library from Debian (Dr.Jit's LLVM back end loads it
# through DRJIT_LIBLLVM_PATH; peers.py finds the newest /usr/lib/*/libLLVM*.so* itself), and
# a virtual environment target/bench-venv with the exact versions of
# tools/measure/peers/requirements.txt (Mitsuba 3, Dr.Jit, embreex, numpy). Never installs into the
# system Python. Idempotent: a second run changes nothing.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
venv="$root/target/bench-venv"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup.sh --bench: run as root or install sudo" >&2; exit 1; }
  SUDO="sudo"
fi

# The newest libllvmNN the configured suites offer (Debian 12: libllvm19 in the main suite).
llvm=""
for v in 20 19 18 17 16 15; do
  if [ -n "$(apt-cache policy "libllvm$v" 2>/dev/null | awk '/Candidate:/ && $2 != "(none)"')" ]; then
    llvm="libllvm$v"; break
  fi
done
if [ -z "$llvm" ]; then
  $SUDO apt-get update -qq
  for v in 20 19 18 17 16 15; do
    if [ -n "$(apt-cache policy "libllvm$v" 2>/dev/null | awk '/Candidate:/ && $2 != "(none)"')" ]; then
      llvm="libllvm$v"; break
    fi
  done
fi
[ -n "$llvm" ] || { echo "setup.sh --bench: no libllvm package found (Mitsuba's LLVM variant needs one)" >&2; exit 1; }
missing=()
for p in python3-venv "$llvm"; do
  dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null | grep -q '^ii' || missing+=("$p")
done
command -v cc >/dev/null || missing+=(gcc) # compiles tools/measure/peers/embree_frame.c
if [ "${#missing[@]}" -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Debian's Python (python3-venv belongs to it), not whatever python3 comes first on PATH.
[ -x "$venv/bin/python" ] || /usr/bin/python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$here/requirements.txt"
echo "setup.sh --bench: peers in $venv: $("$venv/bin/python" "$here/peers.py" versions)"
