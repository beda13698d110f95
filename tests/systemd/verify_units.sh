#!/usr/bin/env bash
# systemd-analyze verify on the project's units, with ExecStart pointed at the freshly built
# binaries. (tests/install/install_test.sh verifies them as installed.)
set -euo pipefail
furutad="$1"
units_dir="$2"
furuta="$3"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for unit in "$units_dir"/*.service "$units_dir"/*.path; do
  sed -e "s|^ExecStart=/usr/sbin/furutad|ExecStart=$furutad|" \
    -e "s|^ExecStartPre=+/usr/sbin/furutad|ExecStartPre=+$furutad|" \
    -e "s|^ExecStart=/usr/bin/furuta |ExecStart=$furuta |" "$unit" > "$work/$(basename "$unit")"
done
# Warnings about the machine (no udev-settle unit in a container, no furuta user) are not the unit's
# fault; anything else systemd-analyze prints is.
# A template is verified as an instance (the default rig's).
for template in "$work"/*@.service; do
  [ -e "$template" ] && mv "$template" "${template%@.service}@rig.service"
done
out=$(systemd-analyze verify "$work"/*.service "$work"/*.path 2>&1 || true)
filtered=$(printf '%s\n' "$out" | grep -v -e 'systemd-udev-settle' -e "^$" \
  -e 'Failed to resolve user' -e 'Failed to resolve group' -e 'network-online.target' || true)
if [ -n "$filtered" ]; then
  printf 'systemd-analyze verify found problems:\n%s\n' "$filtered"
  exit 1
fi
echo "units verified: $(ls "$work" | tr '\n' ' ')"
