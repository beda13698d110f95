#!/usr/bin/env bash
# Makes the arm64 sysroot the cross build reads its libraries from (docs/arm64.md): Debian 12's
# arm64 packages of every library furuta uses, with their dependencies, unpacked into
# build/arm64-sysroot/root. Not installed into the host through multiarch: liblcm-dev, liblcm-bin and
# glog/gflags (under Ceres) are not Multi-Arch: same, so apt would remove the host's own to install
# them. Idempotent: nothing is downloaded or unpacked again while the package set is the same.
# Needs root or sudo once, to add the arm64 architecture to apt's lists.
# Usage: scripts/arm64_sysroot.sh [SYSROOT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$(realpath -m "${1:-build/arm64-sysroot}")"

packages=(
  libc6-dev
  liblcm-dev libglib2.0-dev libsodium-dev libusb-1.0-0-dev libhidapi-dev
  libeigen3-dev libboost-dev libliquid-dev libglpk-dev libmpfr-dev libgmp-dev libtbb-dev libceres-dev
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libsystemd-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
else
  as_root=(sudo)
fi
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "arm64_sysroot: adding the arm64 architecture to apt"
  "${as_root[@]}" dpkg --add-architecture arm64
  "${as_root[@]}" apt-get update -q
elif ! apt-cache show --no-all-versions liblcm-dev:arm64 >/dev/null 2>&1; then
  "${as_root[@]}" apt-get update -q
fi

# The package set: the closure apt computes for an empty arm64 system (its own status file), with
# the downloads in the build tree (as root, not apt's sandbox user, who may not write there). Its
# names and versions are the stamp that says whether the root is up to date.
mkdir -p "$dir/apt/archives/partial" "$dir/apt/cache"
: >"$dir/apt/status"
apt_options=(
  -o "Dir::State::status=$dir/apt/status" -o "Dir::Cache=$dir/apt/cache"
  -o "Dir::Cache::archives=$dir/apt/archives" -o "APT::Architecture=arm64"
  -o "APT::Architectures::=arm64" -o "Debug::NoLocking=1" -o "APT::Sandbox::User=root"
)
wanted=$(apt-get "${apt_options[@]}" --no-install-recommends -s install "${packages[@]}" |
  awk '$1 == "Inst" { print $2, $3 }' | tr -d '()[]' | sort)
if [ -z "$wanted" ]; then
  echo "arm64_sysroot: apt found no packages to unpack" >&2
  exit 1
fi
if [ -f "$dir/root/.furuta-packages" ] && [ "$(cat "$dir/root/.furuta-packages")" = "$wanted" ]; then
  echo "arm64_sysroot: $dir/root is up to date ($(wc -l <<<"$wanted") packages)"
  exit 0
fi

echo "arm64_sysroot: downloading $(wc -l <<<"$wanted") arm64 packages"
apt-get "${apt_options[@]}" --no-install-recommends --download-only -y -q install "${packages[@]}" \
  >"$dir/apt/download.log"

# Bookworm's packages put some libraries under /lib, which is /usr/lib on a merged-/usr system:
# unpack through the same links.
rm -rf "$dir/root"
mkdir -p "$dir/root/usr/lib" "$dir/root/usr/bin" "$dir/root/usr/sbin" "$dir/root/DEBIAN"
for d in lib bin sbin; do ln -s "usr/$d" "$dir/root/$d"; done
control=$(mktemp -d)
trap 'rm -rf "$control"' EXIT
while read -r name version; do
  deb=("$dir/apt/archives/${name%%:*}_${version//:/%3a}_"*.deb)
  dpkg-deb --fsys-tarfile "${deb[0]}" | tar -x --keep-directory-symlink -C "$dir/root"
  # dpkg-shlibdeps finds the libraries' dependency information under the root's DEBIAN/ (a library
  # no installed package owns is looked up in the package tree it was found in).
  rm -rf "$control"/*
  dpkg-deb -e "${deb[0]}" "$control"
  for f in shlibs symbols; do
    [ -f "$control/$f" ] && cat "$control/$f" >>"$dir/root/DEBIAN/$f"
  done
done <<<"$wanted"

# Links that point at / on the target point into the root instead.
while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$dir/root$target")" "$link"
done < <(find "$dir/root" -type l -lname '/*' -print0)
# What maintainer scripts would do and unpacking does not: BLAS and LAPACK are chosen through
# update-alternatives (ATLAS is the one the closure brings).
lib="$dir/root/usr/lib/aarch64-linux-gnu"
for so in libblas.so libblas.so.3 liblapack.so liblapack.so.3; do
  [ -e "$lib/$so" ] || ln -s "atlas/$so" "$lib/$so"
done
# Ceres' exported target names BLAS and LAPACK by absolute paths of the target system.
sed -i -E 's#([";])/usr/lib/aarch64-linux-gnu/#\1${CMAKE_SYSROOT}/usr/lib/aarch64-linux-gnu/#g' \
  "$lib/cmake/Ceres/CeresTargets.cmake"

printf '%s\n' "$wanted" >"$dir/root/.furuta-packages"
echo "arm64_sysroot: $dir/root made from $(wc -l <<<"$wanted") packages ($(du -sh "$dir/root" | cut -f1))"
