#!/usr/bin/env bash
# Builds the Debian package from a configured and built tree (default: build/release) and checks
# it: the architecture of the package and of its binaries, /etc/furuta/rig.toml as a conffile, the
# units, the dependencies, and the command key that postinst makes (not shipped; root:furuta 0640
# once made, inside a scratch root). A cross-built tree (preset arm64, docs/arm64.md) gives the
# target's package: dpkg-shlibdeps reads the target's libraries from the sysroot, and the packaged
# furutad runs under qemu-user.
# Usage: scripts/build_deb.sh [BUILD_DIR [OUTPUT_DIR]]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
out="${2:-$build/packages}"
mkdir -p "$out"
cached() { sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt"; }
arch=$(sed -n 's/^set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
arch="${arch:-$(dpkg --print-architecture)}"
run_target=()
if [ "$arch" != "$(dpkg --print-architecture)" ]; then
  sysroot=$(cached FURUTA_ARM64_SYSROOT)
  run_target=("$(cached FURUTA_QEMU_AARCH64)" -L "$sysroot")
  # dpkg-shlibdeps looks for the libraries of the package's architecture, not the host's.
  export DEB_HOST_ARCH="$arch"
fi
rm -f "$out"/*.deb
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$out" >/dev/null
deb=$(ls -t "$out"/*.deb | head -n 1)
contents=$(dpkg-deb -c "$deb")
[ "$(dpkg-deb -f "$deb" Architecture)" = "$arch" ] ||
  { echo "build_deb: $deb is for $(dpkg-deb -f "$deb" Architecture), not $arch" >&2; exit 1; }
for f in ./usr/bin/furuta ./usr/sbin/furutad ./etc/furuta/rig.toml \
  ./usr/lib/systemd/system/furuta-identify.path ./usr/lib/systemd/system/furuta-identify@.service \
  ./usr/lib/systemd/system/furutad.service ./usr/lib/udev/rules.d/70-furuta-phidgets.rules \
  ./usr/lib/sysusers.d/furuta.conf ./usr/lib/tmpfiles.d/furuta.conf; do
  grep -q " $f\$" <<<"$contents" || { echo "build_deb: $f is not in $deb" >&2; exit 1; }
done
# The units need systemd; the libraries' packages come from dpkg-shlibdeps, the same on every
# architecture.
depends=$(dpkg-deb -f "$deb" Depends)
depends_names=$(sed 's/, /\n/g' <<<"$depends" | sed 's/ .*//')
for p in systemd libc6 libstdc++6 libglib2.0-0 liblcm1 libhidapi-hidraw0 libusb-1.0-0 libliquid1 \
  libsodium23 libsystemd0 libtbb12 libtomlplusplus3; do
  grep -qxF "$p" <<<"$depends_names" ||
    { echo "build_deb: $deb does not depend on $p (Depends: $depends)" >&2; exit 1; }
done
# No secret in the package: each machine makes its own keys (docs/security.md).
if grep -qE '(command|daemon)\.(key|pub)' <<<"$contents"; then
  echo "build_deb: $deb ships a key" >&2
  exit 1
fi
# What postinst does on the target, inside a root: the service user, the key furutad makes, the
# tmpfiles entries. The key must be root:furuta, mode 0640, and postinst must make it.
control=$(mktemp -d)
root=$(mktemp -d)
trap 'rm -rf "$control" "$root"' EXIT
dpkg-deb -e "$deb" "$control"
grep -q '^ *\/usr\/sbin\/furutad --config /etc/furuta/rig.toml --create-command-key' "$control/postinst" ||
  { echo "build_deb: postinst does not make the command key" >&2; exit 1; }
dpkg-deb -x "$deb" "$root"
machine=$([ "$arch" = arm64 ] && echo "ARM aarch64" || echo "x86-64")
for f in "$root/usr/bin/furuta" "$root/usr/sbin/furutad"; do
  file -b "$f" | grep -q "$machine" ||
    { echo "build_deb: ${f#"$root"} is not an $arch executable: $(file -b "$f")" >&2; exit 1; }
done
systemd-sysusers --root="$root" furuta.conf >/dev/null 2>&1 ||
  { echo "build_deb: systemd-sysusers rejected the package's furuta.conf" >&2; exit 1; }
"${run_target[@]}" "$root/usr/sbin/furutad" --config "$root/etc/furuta/rig.toml" --command-key "$root/etc/furuta/command.key" \
  --daemon-key "$root/etc/furuta/daemon.key" --command-state "$root/var/lib/furuta/command-replay.state" \
  --create-command-key || { echo "build_deb: the packaged furutad made no command key" >&2; exit 1; }
key="$root/etc/furuta/command.key"
for secret in "$key" "$root/etc/furuta/daemon.key"; do
  [ "$(stat -c %a "$secret")" = 640 ] ||
    { echo "build_deb: ${secret#"$root"} has mode $(stat -c %a "$secret"), not 640" >&2; exit 1; }
done
[ "$(stat -c %a "$root/etc/furuta/daemon.pub")" = 644 ] ||
  { echo "build_deb: the packaged furutad wrote no daemon.pub of mode 644" >&2; exit 1; }
if [ "$(id -u)" -eq 0 ]; then
  systemd-tmpfiles --root="$root" --create furuta.conf ||
    { echo "build_deb: systemd-tmpfiles rejected the package's furuta.conf" >&2; exit 1; }
  gid=$(awk -F: '$1 == "furuta" { print $3 }' "$root/etc/group")
  [ "$(stat -c %u:%g "$key")" = "0:$gid" ] ||
    { echo "build_deb: the command key is $(stat -c %u:%g "$key"), not root:furuta (0:$gid)" >&2; exit 1; }
fi
dpkg-deb -I "$deb" conffiles | grep -qx '/etc/furuta/rig.toml' ||
  { echo "build_deb: rig.toml is not a conffile" >&2; exit 1; }
echo "$deb"
echo "  Depends: $depends"
