#!/usr/bin/env bash
# `cmake --install` into a DESTDIR with prefix /usr, as a package would: every file where Debian
# expects it, the installed units through `systemd-analyze verify` against the installed binaries
# (--root, with the host's own units copied in for the targets they order against), and the
# sysusers/tmpfiles entries applied inside that root.
set -euo pipefail
build="$1"
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
fail() { echo "install test: $*" >&2; exit 1; }

DESTDIR="$root" cmake --install "$build" --prefix /usr >/dev/null

units=usr/lib/systemd/system
for f in usr/bin/furuta usr/sbin/furutad; do
  [ -x "$root/$f" ] || fail "$f is not installed as an executable"
done
for f in etc/furuta/rig.toml "$units/furutad.service" "$units/furuta-identify@.service" \
  "$units/furuta-identify.path" usr/lib/udev/rules.d/70-furuta-phidgets.rules \
  usr/lib/sysusers.d/furuta.conf usr/lib/tmpfiles.d/furuta.conf usr/share/doc/furuta/README.md; do
  [ -f "$root/$f" ] || fail "$f is missing"
done
# The installed configuration is the default the commands fall back to, never the source tree's
# it was built from.
for command in "furuta process-logs" "furuta run" "furuta status"; do
  help=$("$root/usr/bin/${command%% *}" ${command#* } --help)
  printf '%s' "$help" | grep -q '/etc/furuta/rig.toml' ||
    fail "$command --help does not default to /etc/furuta/rig.toml"
  ! printf '%s' "$help" | grep -q '=[^ ]*config/rig.toml' ||
    fail "$command --help defaults to the source tree's config/rig.toml"
done
help=$("$root/usr/sbin/furutad" --help)
printf '%s' "$help" | grep -q '/etc/furuta/rig.toml' ||
  fail "furutad --help does not default to /etc/furuta/rig.toml"
grep -q '^\[automation\]' "$root/etc/furuta/rig.toml" || fail "rig.toml has no [automation]"

# Every ExecStart names an installed binary, and the path unit starts an installed service.
grep -h '^ExecStart=' "$root/$units"/furuta*.service | while read -r line; do
  binary=${line#ExecStart=}
  binary=${binary%% *}
  [ -x "$root$binary" ] || fail "$line: $binary is not installed"
done
target=$(sed -n 's/^Unit=//p' "$root/$units/furuta-identify.path")
template=$(printf '%s' "$target" | sed 's/@[^.]*\./@./')
[ -f "$root/$units/$template" ] || fail "furuta-identify.path starts $target, which is not installed"
instance=$(printf '%s' "$target" | sed -n 's/.*@\([^.]*\)\..*/\1/p')
[ -z "$instance" ] || [ -f "$root/etc/furuta/$instance.toml" ] ||
  fail "furuta-identify.path starts $target, but /etc/furuta/$instance.toml is not installed"

cp -rn /usr/lib/systemd/system/. "$root/$units/"
# systemd-analyze warns (exit 0) on unknown keys and bad values: any output is a problem, except
# what the container lacks (the furuta user before sysusers has run in a real root).
out=$(systemd-analyze verify --root="$root" furutad.service furuta-identify@rig.service \
  furuta-identify.path 2>&1) || fail "systemd-analyze verify failed:
$out"
filtered=$(printf '%s\n' "$out" | grep -v -e '^$' -e 'Failed to resolve user' \
  -e 'Failed to resolve group' || true)
[ -z "$filtered" ] || fail "systemd-analyze verify found problems:
$filtered"

# The service user and the state directories, created inside the root as on a real install
# (chown needs root: elsewhere only the user entries are checked).
systemd-sysusers --root="$root" furuta.conf >/dev/null 2>&1 || fail "systemd-sysusers rejected furuta.conf"
grep -q '^furuta:' "$root/etc/passwd" || fail "sysusers created no furuta user"
if [ "$(id -u)" -eq 0 ]; then
  systemd-tmpfiles --root="$root" --create furuta.conf || fail "systemd-tmpfiles rejected furuta.conf"
  uid=$(awk -F: '$1 == "furuta" { print $3 }' "$root/etc/passwd")
  for d in logs logs/done logs/failed identifications; do
    [ -d "$root/var/lib/furuta/$d" ] || fail "tmpfiles created no /var/lib/furuta/$d"
    [ "$(stat -c %u "$root/var/lib/furuta/$d")" = "$uid" ] ||
      fail "/var/lib/furuta/$d is not owned by the furuta user ($uid)"
  done
fi

# The command key (issue 21, docs/security.md): made by the install, 64 hex digits, mode 0640,
# owner root, group furuta (the tmpfiles `z` line, applied inside the root, when not made by root
# where the group already existed); a second install keeps it.
key="$root/etc/furuta/command.key"
[ -f "$key" ] || fail "cmake --install made no /etc/furuta/command.key"
grep -qxE '[0-9a-f]{64}' "$key" || fail "/etc/furuta/command.key is not 64 hex digits"
[ "$(stat -c %a "$key")" = 640 ] || fail "/etc/furuta/command.key has mode $(stat -c %a "$key"), not 640"
if [ "$(id -u)" -eq 0 ]; then
  gid=$(awk -F: '$1 == "furuta" { print $3 }' "$root/etc/group")
  [ "$(stat -c %u:%g "$key")" = "0:$gid" ] ||
    fail "/etc/furuta/command.key is owned by $(stat -c %u:%g "$key"), not root:furuta (0:$gid)"
fi
# The daemon key the same way (its public half is written by furutad --create-command-key).
daemon_key="$root/etc/furuta/daemon.key"
grep -qxE '[0-9a-f]{64}' "$daemon_key" || fail "cmake --install made no daemon key of 64 hex digits"
[ "$(stat -c %a "$daemon_key")" = 640 ] || fail "/etc/furuta/daemon.key has mode $(stat -c %a "$daemon_key"), not 640"
before=$(cat "$key")
DESTDIR="$root" cmake --install "$1" --prefix /usr >/dev/null
[ "$(cat "$key")" = "$before" ] || fail "a second cmake --install replaced the command key"
# The unit makes it on first start when missing, as root.
grep -q '^ExecStartPre=+/usr/sbin/furutad .*--create-command-key' "$root/$units/furutad.service" ||
  fail "furutad.service does not make the command key before it starts"
echo "install test: files in place, units verified (systemd-analyze verify --root), user, directories and command key created"
