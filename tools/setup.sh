#!/usr/bin/env bash
# Installs what penumbra needs to render on a machine without a GPU driver:
# the Vulkan loader and Mesa's CPU driver lavapipe, from the newest suite the
# distribution offers (on Debian 12 that is bookworm-backports: Mesa 25 ran
# our ray-tracing kernel 1.75x faster than bookworm's Mesa 22.3).
#
#   tools/setup.sh              loader + lavapipe, only if no Vulkan driver is present
#   tools/setup.sh --tests      also what the test suite needs: the Khronos validation
#                               layer and Chromium (hot-reload page test); --ci is the same
#                               and Chromium (the `penumbra watch --serve` page test,
#                               tests/watch_browser.rs, drives it headless)
#
# The backports suite is added on the mirror the machine already uses; no
# mirror address is written here. Idempotent: a second run changes nothing.
set -euo pipefail

want_bench=0 # --bench: the benchmark's peers (tools/peers/setup.sh)
want_layers=0
for arg in "$@"; do
  case "$arg" in
    --tests|--ci) want_layers=1 ;;
    --bench) want_bench=1 ;;
    *) echo "setup.sh: unknown argument '$arg' (expected --tests)" >&2; exit 2 ;;
  esac
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup.sh: run as root or install sudo" >&2; exit 1; }
  SUDO="sudo"
fi

icd_dirs="/usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d"
have_loader() { ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1'; }
# A driver other than lavapipe (a GPU): then we install nothing for it.
have_gpu_driver() {
  for d in $icd_dirs; do
    for f in "$d"/*.json; do
      [ -e "$f" ] || continue
      case "$(basename "$f")" in lvp_icd*) ;; *) return 0 ;; esac
    done
  done
  return 1
}

. /etc/os-release
packages=()
suite_opt=()
if have_loader && have_gpu_driver; then
  echo "setup.sh: a Vulkan loader and GPU driver are present; not installing lavapipe"
else
  packages+=(libvulkan1 mesa-vulkan-drivers)
  if [ "${ID:-}" = debian ] && [ -n "${VERSION_CODENAME:-}" ]; then
    bp="${VERSION_CODENAME}-backports"
    if ! grep -rqs -- "$bp" /etc/apt/sources.list /etc/apt/sources.list.d/; then
      # Reuse the URI of the machine's configured Debian archive (deb822 or one-line format).
      uri=$(grep -hsE '^URIs:' /etc/apt/sources.list.d/*.sources | awk '{print $2}' | grep -v -- '-security' | head -n1 || true)
      if [ -z "$uri" ]; then
        uri=$(grep -hsE '^deb ' /etc/apt/sources.list /etc/apt/sources.list.d/*.list | awk '{print $2}' | grep -v -- '-security' | head -n1 || true)
      fi
      if [ -z "$uri" ]; then
        echo "setup.sh: no Debian mirror configured in /etc/apt; cannot add $bp" >&2
        exit 1
      fi
      echo "setup.sh: adding $bp from $uri"
      echo "deb $uri $bp main" | $SUDO tee /etc/apt/sources.list.d/penumbra-backports.list >/dev/null
    fi
    suite_opt=(-t "$bp")
  fi
fi
if [ "$want_layers" = 1 ]; then
  packages+=(vulkan-validationlayers)
  # Headless browser for tests/watch_browser.rs.
  packages+=(chromium)
fi

if [ "${#packages[@]}" -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  # From backports where it has the package (Mesa), else from the main suite.
  $SUDO apt-get install -y -qq --no-install-recommends "${suite_opt[@]}" "${packages[@]}"
fi

if ! command -v cargo >/dev/null; then
  echo "setup.sh: cargo not found. Install Rust (1.80 or newer) with rustup: https://rustup.rs" >&2
  exit 1
fi

for d in $icd_dirs; do
  for f in "$d"/lvp_icd*.json; do [ -e "$f" ] && echo "setup.sh: lavapipe driver: $f"; done
done
dpkg-query -W -f='setup.sh: ${Package} ${Version}\n' mesa-vulkan-drivers 2>/dev/null || true

# --bench: Mitsuba 3 and Embree for the benchmark's peer figures, in a venv under target/
# (tools/peers/setup.sh says what and why).
if [ "$want_bench" = 1 ]; then
  "$(dirname "$0")/peers/setup.sh"
fi
