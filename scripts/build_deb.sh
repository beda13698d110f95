#!/usr/bin/env bash
# Builds the Debian package from a configured and built tree (default: build/release) and checks
# it: the binaries, /etc/furuta/rig.toml as a conffile, the units, and the dependencies.
# Usage: scripts/build_deb.sh [BUILD_DIR [OUTPUT_DIR]]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
out="${2:-$build/packages}"
mkdir -p "$out"
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$out" >/dev/null
deb=$(ls -t "$out"/*.deb | head -n 1)
contents=$(dpkg-deb -c "$deb")
for f in ./usr/bin/furuta ./usr/sbin/furutad ./etc/furuta/rig.toml \
  ./usr/lib/systemd/system/furuta-identify.path ./usr/lib/systemd/system/furuta-identify@.service \
  ./usr/lib/systemd/system/furutad.service ./usr/lib/udev/rules.d/70-furuta-phidgets.rules \
  ./usr/lib/sysusers.d/furuta.conf ./usr/lib/tmpfiles.d/furuta.conf; do
  grep -q " $f\$" <<<"$contents" || { echo "build_deb: $f is not in $deb" >&2; exit 1; }
done
dpkg-deb -f "$deb" Depends | grep -q 'systemd' || { echo "build_deb: no Depends" >&2; exit 1; }
dpkg-deb -I "$deb" conffiles | grep -qx '/etc/furuta/rig.toml' ||
  { echo "build_deb: rig.toml is not a conffile" >&2; exit 1; }
echo "$deb"
echo "  Depends: $(dpkg-deb -f "$deb" Depends)"
