#!/usr/bin/env bash
# `furuta start` run by a user outside group furuta (issue 21): the key is there, mode 0640, but
# this user may not read it. The CLI must say so plainly and exit 77 without sending anything;
# `furuta status` by the same user still gets as far as asking (exit 2: no daemon here).
# Needs root to switch to user nobody (setpriv); exit 77 (skipped) otherwise.
# usage: start_without_key_test.sh FURUTA RIG_TOML
set -u
FURUTA=$1
RIG_TOML=$2
if [ "$(id -u)" -ne 0 ] || ! command -v setpriv >/dev/null; then
  echo "skipped: needs root and setpriv to run the CLI as another user"
  exit 77
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/furuta-nokey.XXXXXX")
trap 'rm -rf "$dir"' EXIT
chmod 0755 "$dir"
printf '%064d\n' 0 > "$dir/command.key"
chown root:root "$dir/command.key"
chmod 0640 "$dir/command.key"
cp "$RIG_TOML" "$dir/rig.toml"
chmod 0644 "$dir/rig.toml"
as_nobody() { setpriv --reuid=65534 --regid=65534 --clear-groups "$FURUTA" "$@"; }

out=$(as_nobody start --config "$dir/rig.toml" --command-key "$dir/command.key" \
  --lcm-url "memq://" --timeout 0.2 2>&1)
code=$?
[ "$code" -eq 77 ] || { echo "FAIL: furuta start as nobody exited $code (want 77): $out"; exit 1; }
grep -q "^furuta start: not in group furuta: cannot start sessions; stop/estop/status still work" \
  <<< "$out" || { echo "FAIL: the message does not say why: $out"; exit 1; }
grep -q "Permission denied" <<< "$out" || { echo "FAIL: the reason is missing: $out"; exit 1; }

out=$(as_nobody status --config "$dir/rig.toml" --lcm-url "memq://" --timeout 0.2 2>&1)
code=$?
[ "$code" -eq 2 ] || { echo "FAIL: furuta status as nobody exited $code (want 2): $out"; exit 1; }
grep -q "no answer from furutad" <<< "$out" || { echo "FAIL: status: $out"; exit 1; }
echo "start without the key: exit 77, \"not in group furuta\"; status still asks"
