#!/usr/bin/env bash
# Unpacks the distribution's main-suite lavapipe (on Debian 12: Mesa 22.3, the one a machine
# has before tools/setup.sh upgrades it) into target/mesa-MAJOR.MINOR/ next to the installed
# one, so that tests and benchmarks can run against both drivers on one machine. Nothing is
# installed into the system: the package is fetched with `apt-get download` and unpacked
# with `dpkg -x`, and an ICD file pointing at the unpacked libvulkan_lvp.so is written beside
# it. Point a process at it with
#
#   VK_DRIVER_FILES=$(tools/mesa_tree.sh --icd) VK_ICD_FILENAMES=$(tools/mesa_tree.sh --icd) CMD
#
# (VK_DRIVER_FILES for loaders from 1.3.234 on, VK_ICD_FILENAMES for older ones.)
#
#   tools/mesa_tree.sh          fetch and unpack (once; a second run changes nothing)
#   tools/mesa_tree.sh --icd    print the ICD file's path (fetching first if needed)
#
# Its runtime dependencies (LLVM 15, libdrm, ...) are the installed ones: on Debian 12 the
# main-suite and the backports Mesa both link LLVM 15, so no second copy of them is needed.
set -euo pipefail
cd "$(dirname "$0")/.."

print_icd=0
for arg in "$@"; do
  case "$arg" in
    --icd) print_icd=1 ;;
    *) echo "mesa_tree.sh: unknown argument '$arg' (expected --icd)" >&2; exit 2 ;;
  esac
done
say() { [ "$print_icd" = 1 ] && echo "mesa_tree.sh: $*" >&2 || echo "mesa_tree.sh: $*"; }

. /etc/os-release
suite="${VERSION_CODENAME:?mesa_tree.sh: /etc/os-release names no VERSION_CODENAME}"
# The version the main suite (not -updates, -security or -backports) offers.
version=$(apt-cache madison mesa-vulkan-drivers 2>/dev/null \
  | awk -F'|' -v s=" $suite/main " 'index($3, s) { gsub(/ /, "", $2); print $2; exit }')
if [ -z "$version" ]; then
  echo "mesa_tree.sh: apt knows no mesa-vulkan-drivers in $suite/main (run apt-get update)" >&2
  exit 1
fi
short=$(echo "$version" | sed -E 's/^([0-9]+:)?([0-9]+\.[0-9]+).*/\2/')
dir="target/mesa-$short"
icd="$PWD/$dir/lvp_icd.json"
lib="$PWD/$dir/root/usr/lib/$(uname -m)-linux-gnu/libvulkan_lvp.so"

if [ -f "$icd" ] && [ -f "$lib" ] && [ "$(cat "$dir/version" 2>/dev/null)" = "$version" ]; then
  say "lavapipe $version already unpacked in $dir"
else
  say "unpacking lavapipe $version ($suite/main) into $dir"
  rm -rf "$dir/root" "$dir/deb"
  mkdir -p "$dir/deb"
  # apt's sandbox user may not write here; the download itself is the same.
  (cd "$dir/deb" && apt-get download -qq "mesa-vulkan-drivers=$version" 2>&1 \
    | grep -v 'Download is performed unsandboxed' >&2 || true)
  deb=$(ls "$dir"/deb/mesa-vulkan-drivers_*.deb 2>/dev/null | head -n1)
  [ -n "$deb" ] || { echo "mesa_tree.sh: apt-get download mesa-vulkan-drivers=$version failed" >&2; exit 1; }
  dpkg -x "$deb" "$dir/root"
  [ -f "$lib" ] || { echo "mesa_tree.sh: $deb holds no $lib" >&2; exit 1; }
  if ldd "$lib" | grep -q 'not found'; then
    echo "mesa_tree.sh: $lib misses libraries:" >&2
    ldd "$lib" | grep 'not found' >&2
    exit 1
  fi
  api=$(sed -nE 's/.*"api_version": *"([^"]+)".*/\1/p' "$dir"/root/usr/share/vulkan/icd.d/lvp_icd*.json | head -n1)
  cat >"$icd" <<EOF
{
    "ICD": {
        "api_version": "${api:-1.1.0}",
        "library_path": "$lib"
    },
    "file_format_version": "1.0.0"
}
EOF
  echo "$version" >"$dir/version"
  say "ICD file: $icd"
fi
if [ "$print_icd" = 1 ]; then echo "$icd"; fi
