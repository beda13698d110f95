#!/usr/bin/env bash
# furutad and the furuta CLI as separate processes talking LCM over real UDP multicast: start,
# status and stop a session, start another and send furutad SIGTERM in the middle of it. furutad
# must exit 0 and leave complete logs whose last motor command is the zero, and lcm-logplayer must
# play them.
#
# Runs in a network namespace of its own (unshare -rn: no privilege needed), with only loopback up
# and multicast routed to it, so nothing leaves the machine and parallel runs cannot hear each
# other. Exit 77 (skipped) where such a namespace is not permitted.
#
# usage: udp_multicast_test.sh FURUTAD FURUTA RIG_TOML
set -u
shopt -s nullglob

FURUTAD=$1
FURUTA=$2
RIG_TOML=$3

if [ -z "${FURUTA_UDP_TEST_IN_NETNS:-}" ]; then
  . "$(dirname "$0")/namespace_or_skip.sh"
  namespace_or_skip -rn unshare ip lcm-logplayer
  FURUTA_UDP_TEST_IN_NETNS=1 exec unshare -rn bash "$0" "$@"
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/furuta-udp.XXXXXX")
DAEMON_PID=""
cleanup() {
  if [ -n "$DAEMON_PID" ] && kill -0 "$DAEMON_PID" 2>/dev/null; then
    kill -KILL "$DAEMON_PID" 2>/dev/null
    wait "$DAEMON_PID" 2>/dev/null
  fi
  rm -rf "$TMP"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*"
  if [ -f "$TMP/furutad.log" ]; then
    echo "--- furutad output:"
    cat "$TMP/furutad.log"
  fi
  exit 1
}

. "$(dirname "$0")/loopback_multicast.sh"
PLAY_URL="udpm://$GROUP:$((PORT + 1))?ttl=0"

CONFIG="$TMP/rig.toml"
LOGS="$TMP/logs"
. "$(dirname "$0")/udp_rig_config.sh"
udp_rig_config "$RIG_TOML" "$CONFIG" "$URL" "$LOGS" "$TMP"

cli() { "$FURUTA" "$@" --config "$CONFIG" --timeout 5; }
status_line() { cli status 2>/dev/null; }
cycles_of() { sed -n 's/.*cycles \([0-9]*\),.*/\1/p'; }
# The finished log of the session labelled $1 (none while it runs or is being finished).
finished_logs() { ended=("$LOGS"/*_"$1".lcmlog); }

# Waits (up to a minute: a hang guard, not a timing check) until `status` matches a pattern
# and shows at least `min_cycles` cycles; prints that status line. Says why on stderr if not,
# and gives up at once if the finished log of the session labelled `label` appears (it ended).
wait_for_status() {
  local pattern=$1 min_cycles=${2:-0} label=${3:-} line="" cycles ended
  for _ in $(seq 1 120); do
    if [ -n "$label" ] && finished_logs "$label" && [ "${#ended[@]}" -gt 0 ]; then
      echo "session $label ended (last status: $line)" >&2
      return 1
    fi
    line=$(status_line)
    if [[ "$line" == *"$pattern"* ]]; then
      cycles=$(echo "$line" | cycles_of)
      if [ "${cycles:-0}" -ge "$min_cycles" ]; then
        echo "$line"
        return 0
      fi
    fi
    if ! kill -0 "$DAEMON_PID" 2>/dev/null; then
      echo "furutad died while waiting for '$pattern'" >&2
      return 1
    fi
    # Slower than the daemon's rate limit (5 commands a second, status requests included), so
    # the starts and stops in between are never refused for it.
    sleep 0.5
  done
  echo "status never showed '$pattern' with at least $min_cycles cycles (last: $line)" >&2
  return 1
}

check_log() {
  local log=$1 reason=$2 info samples
  info=$("$FURUTA" log info "$log") || fail "furuta log info failed on $log: $info"
  echo "$info"
  grep -q "^  end       $reason, " <<< "$info" || fail "$log does not end with $reason"
  grep -q "^  motor     last command duty 0, braking 1$" <<< "$info" \
    || fail "the last motor command in $log is not the zero"
  grep -q "sequence numbers missing" <<< "$info" && fail "$log misses samples"
  # Started by `furuta start`, signed (issue 21): the log names who.
  grep -q "^  started   by $(id -un)@.* (signed command)$" <<< "$info" \
    || fail "$log does not name the signed start's sender"
  samples=$(sed -n 's/^  samples   \([0-9]*\).*/\1/p' <<< "$info")
  [ "${samples:-0}" -gt 0 ] || fail "$log has no samples"
  # lcm-logplayer reads every event (-v lists each) and publishes it.
  lcm-logplayer -v -s 20 --lcm-url="$PLAY_URL" "$log" > "$TMP/played.txt" 2>&1 \
    || fail "lcm-logplayer failed on $log: $(cat "$TMP/played.txt")"
  played=$(grep -c " Channel RIG_SAMPLE " "$TMP/played.txt")
  [ "$played" -eq "$samples" ] || fail "lcm-logplayer played $played samples of $samples"
  grep -q " Channel RIG_COMMAND_SIGNED " "$TMP/played.txt" \
    || fail "lcm-logplayer did not play the signed start of $log"
}

# The keys, as the unit's ExecStartPre makes them: the command key, the daemon key and its public
# half, which the CLI checks every answer with.
"$FURUTAD" -c "$CONFIG" --create-command-key || fail "furutad --create-command-key failed"
[ "$(stat -c %a "$TMP/daemon.pub")" = 644 ] || fail "no daemon.pub of mode 644"

"$FURUTAD" --sim -c "$CONFIG" > "$TMP/furutad.log" 2>&1 &
DAEMON_PID=$!

line=$(wait_for_status "state idle" 80) || fail "furutad did not come up"
echo "furutad up: $line"
# Its answers are signed, and checked: no warning that they were taken unverified.
out=$(cli status 2>&1) || fail "furuta status failed: $out"
grep -q "unverified" <<< "$out" && fail "the daemon's answers were not verified: $out"

# Only those who can read the key start sessions (issue 21): an unsigned start is refused with
# its reason, a start without the key is not even sent (77), and both leave the rig idle.
bad_key="$TMP/no-such.key"
out=$(cli start --command-key "$bad_key" --profile free_decay --duration 1 --label nokey 2>&1)
code=$?
[ "$code" -eq 77 ] || fail "a start without the key exited $code (want 77): $out"
grep -q "cannot start sessions; stop/estop/status still work" <<< "$out" \
  || fail "a start without the key did not say why: $out"

# Session 1: a free decay (zero duty, so the pendulum stays still for the next one), stopped by
# `furuta stop`.
cli start --profile free_decay --amplitude 0.1 --duration 60 --label udp_stop \
  || fail "furuta start (session 1) refused"
line=$(wait_for_status "state running") || fail "session 1 did not start"
line=$(wait_for_status "_udp_stop") || fail "the status does not name session 1"
echo "session 1: $line"
cli stop || fail "furuta stop refused"
line=$(wait_for_status "state idle") || fail "session 1 did not stop"
echo "after stop: $line"

# Session 2: a bang-bang, under way for about a second, then SIGTERM to furutad. The simulated
# rig moves in wall time like the real one, so on a starved machine (the sanitizer builds in CI) a
# loop stall longer than the room the configuration leaves (above) can carry the arm past its
# limit before the signal: the safety rule then ends the session, which is right, but leaves
# nothing for the signal to stop. Such a session's log must still be complete and end on the zero
# command; then another one is started (three at most).
before=$(echo "$line" | cycles_of)
signal_label=""
for attempt in 1 2 3; do
  label="udp_signal_$attempt"
  cli start --profile bang_bang --amplitude 0.15 --duration 60 --label "$label" \
    || fail "furuta start ($label) refused"
  if wait_for_status "state running" $((before + 100)) "$label" > /dev/null 2> "$TMP/wait.txt"; then
    signal_label=$label
    break
  fi
  last=$(status_line)
  [[ "$last" == *"state fault"*"last fault: "* ]] \
    || fail "session 2 ($label) did not run: $(cat "$TMP/wait.txt")"
  echo "session 2 ($label) ended by a safety rule before the signal: $last"
  # The recorder finishes the log on its own thread, a moment after the loop ended the session.
  for _ in $(seq 1 50); do
    finished_logs "$label"
    [ "${#ended[@]}" -eq 1 ] && break
    sleep 0.2
  done
  [ "${#ended[@]}" -eq 1 ] || fail "expected one log of $label, found: $(ls -A "$LOGS")"
  faulted_reason=$(sed -n 's/.*last fault: \([a-z_]*\).*/\1/p' <<< "$last")
  check_log "${ended[0]}" "$faulted_reason"
  before=$(echo "$last" | cycles_of)
done
[ -n "$signal_label" ] || fail "three sessions in a row ended by a safety rule before the signal"
echo "session 2 under way; SIGTERM"
kill -TERM "$DAEMON_PID"
for _ in $(seq 1 300); do
  kill -0 "$DAEMON_PID" 2>/dev/null || break
  sleep 0.2
done
kill -0 "$DAEMON_PID" 2>/dev/null && fail "furutad still running a minute after SIGTERM"
wait "$DAEMON_PID"
rc=$?
DAEMON_PID=""
[ "$rc" -eq 0 ] || fail "furutad exited with $rc after SIGTERM"

# Both logs finished (none left as .part), complete, and ending with the zero command.
parts=("$LOGS"/.partial/*)
[ "${#parts[@]}" -eq 0 ] || fail "unfinished logs left: ${parts[*]}"
stop_logs=("$LOGS"/*_udp_stop.lcmlog)
signal_logs=("$LOGS"/*_"$signal_label".lcmlog)
[ "${#stop_logs[@]}" -eq 1 ] || fail "expected one log of session 1, found: $(ls -A "$LOGS")"
[ "${#signal_logs[@]}" -eq 1 ] || fail "expected one log of session 2, found: $(ls -A "$LOGS")"

check_log "${stop_logs[0]}" "stop_command"
check_log "${signal_logs[0]}" "signal"
# Session 2 drove the motor before the signal.
info=$("$FURUTA" log info "${signal_logs[0]}")
samples=$(sed -n 's/^  samples   \([0-9]*\).*/\1/p' <<< "$info")
[ "$samples" -ge 50 ] || fail "session 2 was not under way when the signal came ($samples samples)"
echo "PASS"
