#!/usr/bin/env bash
# Installs every Debian 12 package furuta needs to build, test and run.
# Idempotent: installs only what is missing, and runs `apt-get update` at most once.
# Works as root or through sudo.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git clang-format
  # messaging
  liblcm-dev liblcm-bin libglib2.0-dev
  # the daemon's signed answers (Ed25519)
  libsodium-dev
  # USB
  libusb-1.0-0-dev libhidapi-dev
  # numerics
  libeigen3-dev libboost-dev libliquid-dev libmpfr-dev libgmp-dev libtbb-dev
  # output-error refinement: nonlinear least squares with automatic differentiation
  libceres-dev
  # configuration, CLI, service
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libsystemd-dev systemd
  # tests: network namespaces for LCM over UDP multicast
  iproute2
  # tests: the HTML report is opened in headless Chromium (tests/report)
  chromium
  # packaging: cpack -G DEB, dpkg-shlibdeps for the package's dependencies (scripts/build_deb.sh)
  dpkg-dev file
  # fuzzing (scripts/fuzz.sh): clang, and libFuzzer with the sanitizer runtimes (only recommended by
  # clang-14, so named here as recommends are not installed)
  clang libclang-rt-14-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the arm64 build (scripts/test_arm64.sh): cross compilers, and qemu-user for its tests; its
  # libraries are arm64 packages unpacked into a sysroot (scripts/arm64_sysroot.sh)
  crossbuild-essential-arm64 qemu-user-static
  # linear programming: set inversion over windows (identification), the LP bound of the
  # seven-unknown problem (bench/sivia_lp_hull)
  libglpk-dev
)

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "setup: need root or sudo to install packages" >&2
  exit 1
fi

# Installed for this machine's architecture (or for all): an arm64 package of the same name is not
# the host's.
native=$(dpkg --print-architecture)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status} ${Architecture}\n' "$p" 2>/dev/null |
    grep -qE "^install ok installed ($native|all)$"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${#missing[@]} package(s): ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -q
"${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
