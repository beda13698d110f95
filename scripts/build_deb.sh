#!/usr/bin/env bash
# Builds the Debian package from a configured and built tree (default: build/release) and checks
# it: the binaries, /etc/furuta/rig.toml as a conffile, the units, the dependencies, and the command
# key that postinst makes (not shipped; root:furuta 0640 once made, inside a scratch root).
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
# No secret in the package: each machine makes its own command key (docs/security.md).
if grep -q 'command.key' <<<"$contents"; then
  echo "build_deb: $deb ships a command key" >&2
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
systemd-sysusers --root="$root" furuta.conf >/dev/null 2>&1 ||
  { echo "build_deb: systemd-sysusers rejected the package's furuta.conf" >&2; exit 1; }
"$root/usr/sbin/furutad" --config "$root/etc/furuta/rig.toml" --command-key "$root/etc/furuta/command.key" \
  --create-command-key || { echo "build_deb: the packaged furutad made no command key" >&2; exit 1; }
key="$root/etc/furuta/command.key"
[ "$(stat -c %a "$key")" = 640 ] ||
  { echo "build_deb: the command key has mode $(stat -c %a "$key"), not 640" >&2; exit 1; }
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
echo "  Depends: $(dpkg-deb -f "$deb" Depends)"
