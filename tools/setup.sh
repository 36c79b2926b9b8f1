#!/usr/bin/env bash
# Installs what penumbra needs to render on a machine without a GPU: the Vulkan loader and
# Mesa's CPU driver lavapipe, from the newest suite the distribution offers (on Debian 12 that
# is bookworm-backports: Mesa 25 ran our ray-tracing kernel about 3x faster than bookworm's
# Mesa 22.3 on one machine, docs/drivers.md).
#
#   tools/setup.sh              loader + lavapipe unless the loader reports a GPU
#   tools/setup.sh --tests      also what the test suite needs: the Khronos validation
#                               layer, Chromium (the `penumbra watch --serve` page test,
#                               tests/cli/watch_browser.rs, drives it headless) and Debian's
#                               main-suite lavapipe unpacked into target/ (tools/mesa_tree.sh)
#                               for the render tests against the older driver; --ci is the same
#   tools/setup.sh --dry-run    say what was found and what would be done; change nothing
#
# The decision is by the devices the Vulkan loader reports (`vulkaninfo --summary`; when
# vulkan-tools is not installed, its package is unpacked into a temporary directory for the
# probe), not by ICD files: Debian's mesa-vulkan-drivers ships Intel and Radeon ICD files
# that find no device on a machine without those GPUs.
#   - no loader, or a loader with no device:  install the loader and lavapipe
#   - only CPU devices (lavapipe):             upgrade lavapipe to the newest suite
#   - any other device (a GPU):                touch nothing for Vulkan
#
# Test hook: PENUMBRA_SETUP_DEVICES_FILE=FILE takes FILE as the output of
# `vulkaninfo --summary` (the value `no-loader` stands for a machine without the loader) and
# PENUMBRA_SETUP_MESA_VERSION as the installed mesa-vulkan-drivers version (`none`: not
# installed); either implies --dry-run (tests/cli/setup_script.rs).
#
# The backports suite is added on the mirror the machine already uses; no
# mirror address is written here. Idempotent: a second run changes nothing.
set -euo pipefail

want_bench=0 # --bench: the benchmark's peers (tools/measure/peers/setup.sh)
want_layers=0
dry_run=0
for arg in "$@"; do
  case "$arg" in
    --tests|--ci) want_layers=1 ;;
    --bench) want_bench=1 ;;
    --dry-run) dry_run=1 ;;
    *) echo "setup.sh: unknown argument '$arg' (expected --tests, --bench or --dry-run)" >&2; exit 2 ;;
  esac
done
fake_devices="${PENUMBRA_SETUP_DEVICES_FILE:-}"
fake_mesa="${PENUMBRA_SETUP_MESA_VERSION:-}"
if [ -n "$fake_devices" ] || [ -n "$fake_mesa" ]; then dry_run=1; fi

SUDO=""
if [ "$dry_run" = 0 ] && [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup.sh: run as root or install sudo" >&2; exit 1; }
  SUDO="sudo"
fi

# --- What the Vulkan loader reports -------------------------------------------------------
have_loader() {
  if [ -n "$fake_devices" ]; then [ "$fake_devices" != no-loader ]; return; fi
  ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1'
}
probe_dir=""
cleanup_probe() { [ -z "$probe_dir" ] || rm -rf "$probe_dir"; }
trap cleanup_probe EXIT
# Sets $summary to `vulkaninfo --summary`, from vulkan-tools if installed, else from its
# package unpacked into a temporary directory (nothing installed). Empty: no device found.
vi=""
read_devices() {
  if [ -n "$fake_devices" ]; then summary=$(cat -- "$fake_devices"); return; fi
  [ -n "$vi" ] || vi=$(command -v vulkaninfo || true)
  if [ -z "$vi" ]; then
    probe_dir=$(mktemp -d)
    if ! (cd "$probe_dir" && apt-get download -qq vulkan-tools >/dev/null 2>&1); then
      $SUDO apt-get update -qq
      (cd "$probe_dir" && apt-get download -qq vulkan-tools >/dev/null 2>&1) || {
        echo "setup.sh: cannot fetch vulkan-tools to list the Vulkan devices; install it and rerun" >&2
        exit 1
      }
    fi
    dpkg -x "$probe_dir"/vulkan-tools_*.deb "$probe_dir/root"
    vi="$probe_dir/root/usr/bin/vulkaninfo"
  fi
  # Fails (no output) when the loader finds no driver with a device.
  summary=$("$vi" --summary 2>/dev/null || true)
}
# One line per device: TYPE|NAME|DRIVER INFO, TYPE as vulkaninfo says it without its prefix
# (CPU, INTEGRATED_GPU, DISCRETE_GPU, VIRTUAL_GPU, OTHER).
parse_devices() {
  awk -F'= *' '
    function flush() { if (type != "") print type "|" name "|" info; type = ""; name = ""; info = "" }
    /^GPU[0-9]+:/ { flush() }
    /^[ \t]*deviceType[ \t]*=/ { type = $2; sub(/^PHYSICAL_DEVICE_TYPE_/, "", type) }
    /^[ \t]*deviceName[ \t]*=/ { name = $2 }
    /^[ \t]*driverInfo[ \t]*=/ { info = $2 }
    END { flush() }'
}
installed_mesa() {
  if [ -n "$fake_mesa" ]; then [ "$fake_mesa" = none ] || echo "$fake_mesa"; return; fi
  if [ -n "$fake_devices" ]; then return; fi
  # (dpkg-query fails for a package it has never seen: not installed.)
  { dpkg-query -W -f='${db:Status-Abbrev} ${Version}\n' mesa-vulkan-drivers 2>/dev/null || true; } \
    | awk '$1 ~ /^ii/ { print $2 }'
}

. /etc/os-release
mesa=$(installed_mesa)
mesa_said="mesa-vulkan-drivers ${mesa:-not installed}"
action=install
if ! have_loader; then
  echo "setup.sh: found: no Vulkan loader (libvulkan.so.1); $mesa_said"
else
  read_devices
  devices=$(parse_devices <<<"$summary")
  if [ -z "$devices" ]; then
    echo "setup.sh: found: a Vulkan loader that reports no device; $mesa_said"
  else
    while IFS='|' read -r type name info; do
      echo "setup.sh: found: $type device: $name${info:+ ($info)}"
    done <<<"$devices"
    if grep -qv '^CPU|' <<<"$devices"; then
      action=keep
    else
      action=upgrade
      echo "setup.sh: found: CPU devices only; $mesa_said"
    fi
  fi
fi

packages=()
suite_opt=()
bp=""
if [ "$action" = keep ]; then
  echo "setup.sh: decision: keep: a GPU is present; not installing or upgrading anything for Vulkan"
else
  packages+=(libvulkan1 mesa-vulkan-drivers)
  if [ "${ID:-}" = debian ] && [ -n "${VERSION_CODENAME:-}" ]; then
    bp="${VERSION_CODENAME}-backports"
    suite_opt=(-t "$bp")
  fi
  if [ "$action" = upgrade ]; then
    echo "setup.sh: decision: upgrade: lavapipe to the newest in ${bp:-the configured suites}"
  else
    echo "setup.sh: decision: install: the Vulkan loader and lavapipe from ${bp:-the configured suites}"
  fi
fi
if [ "$want_layers" = 1 ]; then
  packages+=(vulkan-validationlayers)
  # Headless browser for tests/cli/watch_browser.rs.
  packages+=(chromium)
fi

if [ "$dry_run" = 1 ]; then
  echo "setup.sh: dry run: would install: ${packages[*]:-nothing}${bp:+ (-t $bp)}"
  if [ "$want_layers" = 1 ]; then echo "setup.sh: dry run: would unpack Debian's main-suite lavapipe into target/ (tools/mesa_tree.sh)"; fi
  if [ "$want_layers" = 1 ]; then echo "setup.sh: dry run: would install for the Slurm tests (unless present): slurmctld slurmd slurm-client munge"; fi
  exit 0
fi

if [ -n "$bp" ] && ! grep -rqs -- "$bp" /etc/apt/sources.list /etc/apt/sources.list.d/; then
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

if [ "${#packages[@]}" -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  # From backports where it has the package (Mesa), else from the main suite. With -t the
  # newest version there is installed even over an older one already present.
  $SUDO apt-get install -y -qq --no-install-recommends "${suite_opt[@]}" "${packages[@]}"
fi

if [ "$want_layers" = 1 ]; then
  tools_dir="$(dirname "$0")"
  "$tools_dir/mesa_tree.sh"
fi

# --tests: a single-host Slurm cluster for the farm tests (tests/cli/farm_slurm.rs starts it with
# tools/slurm-local.sh), from the main suite (Debian 12: Slurm 22.05, the version the
# set-up in tools/slurm-local.sh was found to work with).
slurm_packages=(slurmctld slurmd slurm-client munge)
if [ "$want_layers" = 1 ]; then
  missing=()
  for p in "${slurm_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  if [ "${#missing[@]}" -gt 0 ]; then
    echo "setup.sh: installing for the Slurm tests: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
  else
    echo "setup.sh: Slurm test packages present: ${slurm_packages[*]}"
  fi
fi

if [ "$action" != keep ]; then
  now=$(installed_mesa)
  if [ "$now" = "$mesa" ]; then
    echo "setup.sh: done: mesa-vulkan-drivers ${now:-not installed} (already the newest; nothing changed)"
  else
    echo "setup.sh: done: mesa-vulkan-drivers ${mesa:-not installed} -> ${now:-not installed}"
  fi
  read_devices
  parse_devices <<<"$summary" | while IFS='|' read -r type name info; do
    echo "setup.sh: now: $type device: $name${info:+ ($info)}"
  done
fi

if ! command -v cargo >/dev/null; then
  echo "setup.sh: cargo not found. Install Rust (1.80 or newer) with rustup: https://rustup.rs" >&2
  exit 1
fi

# --bench: Mitsuba 3 and Embree for the benchmark's peer figures, in a venv under target/
# (tools/measure/peers/setup.sh says what and why).
if [ "$want_bench" = 1 ]; then
  "$(dirname "$0")/measure/peers/setup.sh"
fi
