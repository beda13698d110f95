#!/usr/bin/env bash
# furutad on the simulated rig, killed with SIGKILL at seeded random moments (TRIALS times), then
# out of disk (RLIMIT_FSIZE; a small tmpfs), then with its logs directory removed and made
# read-only mid-session. furuta_crash_trials drives each and checks the logs with our reader and
# with lcm-logplayer after recovery (tests/daemon/crash_trials.cpp says what is checked).
#
# Runs in a user + network + mount namespace of its own (unshare -rnm: no privilege needed): only
# loopback, multicast routed to it, a private tmpfs. Exit 77 (skipped) where that is not permitted.
#
# usage: crash_trials_test.sh FURUTAD CRASH_TRIALS RIG_TOML [TRIALS [SEED [SCENARIOS]]]
#   SCENARIOS: space-separated subset of "kill fsize small-fs dir-removed dir-readonly" (default all)
set -u

FURUTAD=$1
DRIVER=$2
RIG_TOML=$3
TRIALS=${4:-200}
SEED=${5:-$(date +%s)}
SCENARIOS=${6:-"kill fsize small-fs dir-removed dir-readonly"}
# Short enough that a trial loses little, long enough that syncing is not every cycle.
FLUSH_MS=${FURUTA_CRASH_FLUSH_MS:-50}

if [ -z "${FURUTA_CRASH_TEST_IN_NS:-}" ]; then
  . "$(dirname "$0")/namespace_or_skip.sh"
  namespace_or_skip -rnm unshare ip mount lcm-logplayer
  FURUTA_CRASH_TEST_IN_NS=1 exec unshare -rnm bash "$0" "$FURUTAD" "$DRIVER" "$RIG_TOML" \
    "$TRIALS" "$SEED" "$SCENARIOS"
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/furuta-crash.XXXXXX")
cleanup() {
  # The tmpfs goes with the namespace; its mount point must be empty of mounts to be removed.
  umount "$TMP/small-fs/logs" 2>/dev/null
  chmod -R u+w "$TMP" 2>/dev/null
  rm -rf "$TMP"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  exit 1
}

. "$(dirname "$0")/loopback_multicast.sh"

CONFIG="$TMP/rig.toml"
# The simulated rig moves in wall time, like the real one: where the machine starves furutad (the
# sanitizer builds in CI), a loop stall leaves the last duty applied. The disk sessions must run
# for seconds before the disk fills; with the bang-bang flipping at 86 deg a stall of about 0.1 s
# there carried the arm past its 150 deg limit, and the session ended on that instead. Flipping at
# 20 deg (with the trials' duty of 0.15) leaves room for stalls of about half a second.
sed -e "s|^lcm_url = .*|lcm_url = \"$URL\"|" \
    -e "s|^flush_interval_ms = .*|flush_interval_ms = $FLUSH_MS|" \
    -e "s|^rest_check_s = .*|rest_check_s = 0.0|" \
    -e "s|^arm_switch_deg = [0-9.]*|arm_switch_deg = 20|" "$RIG_TOML" > "$CONFIG"
grep -q "^flush_interval_ms = $FLUSH_MS$" "$CONFIG" || fail "could not set flush_interval_ms"
grep -q "^rest_check_s = 0.0$" "$CONFIG" || fail "could not set rest_check_s"
grep -q "^arm_switch_deg = 20 " "$CONFIG" || fail "could not set arm_switch_deg"

echo "seed $SEED, flush_interval_ms $FLUSH_MS, $TRIALS kill trials, LCM $URL"
status=0
for scenario in $SCENARIOS; do
  work="$TMP/$scenario"
  mkdir -p "$work/logs"
  if [ "$scenario" = small-fs ]; then
    # Room for the first session's start and a few seconds of samples, not for much more.
    mount -t tmpfs -o size=256k,mode=0755 tmpfs "$work/logs" || fail "cannot mount a tmpfs"
  fi
  echo "--- $scenario"
  if ! "$DRIVER" --furutad "$FURUTAD" --config "$CONFIG" --work "$work" --lcm-url "$URL" \
      --scenario "$scenario" --trials "$TRIALS" --seed "$SEED" --flush-ms "$FLUSH_MS"; then
    status=1
    echo "--- furutad output ($scenario, last 40 lines):"
    tail -n 40 "$work/furutad.out"
  fi
done
[ "$status" -eq 0 ] && echo "PASS"
exit $status
