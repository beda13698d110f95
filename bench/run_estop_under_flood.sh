#!/usr/bin/env bash
# `furuta estop` under a flood of wrongly signed starts (bench/estop_under_flood.cpp): furutad --sim
# in a private network namespace (unshare -rn: no privilege needed; loopback up, multicast routed
# to it, a group and port of this run's own, ttl=0), so the flood never leaves this run. A figure,
# not a test: docs/measurements/estop-under-flood.md. Exit 77 where the namespace is not permitted.
#
# usage: bench/run_estop_under_flood.sh [BUILD_DIR] [TRIES] [RATE]   (build/ci, 20, 100000)
# Writes the benchmark's JSON to $FURUTA_BENCH_OUT/estop_under_flood.json (out/bench);
# FURUTA_FLOOD_ARGS adds options of estop_under_flood (e.g. "--flood-threads 2 --sign-each").
set -u

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/ci}
TRIES=${2:-20}
RATE=${3:-100000}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
FURUTAD="$BUILD/daemon/furutad"
FURUTA="$BUILD/app/furuta"
BENCH="$BUILD/bench/estop_under_flood"
OUT=${FURUTA_BENCH_OUT:-$ROOT/out/bench}

for exe in "$FURUTAD" "$FURUTA" "$BENCH"; do
  if [ ! -x "$exe" ]; then
    echo "missing $exe: cmake --build $BUILD --target estop_under_flood furutad furuta" >&2
    exit 2
  fi
done

if [ -z "${FURUTA_FLOOD_BENCH_IN_NETNS:-}" ]; then
  . "$ROOT/tests/daemon/namespace_or_skip.sh"
  namespace_or_skip -rn unshare ip
  mkdir -p "$OUT"
  # As root, a network namespace alone (no user namespace), so furutad can take the unit's
  # Nice=-10 below; otherwise both, and furutad runs at the flood's own priority.
  ns=-rn
  [ "$(id -u)" -eq 0 ] && unshare -n true 2>/dev/null && ns=-n
  FURUTA_FLOOD_BENCH_IN_NETNS=1 exec unshare $ns bash "$0" "$BUILD" "$TRIES" "$RATE"
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/furuta-flood.XXXXXX")
DAEMON_PID=""
cleanup() {
  if [ -n "$DAEMON_PID" ] && kill -0 "$DAEMON_PID" 2>/dev/null; then
    kill -TERM "$DAEMON_PID" 2>/dev/null
    for _ in $(seq 1 100); do
      kill -0 "$DAEMON_PID" 2>/dev/null || break
      sleep 0.1
    done
    kill -KILL "$DAEMON_PID" 2>/dev/null
    wait "$DAEMON_PID" 2>/dev/null
  fi
  rm -rf "$TMP"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  if [ -f "$TMP/furutad.log" ]; then
    echo "--- furutad output:" >&2
    cat "$TMP/furutad.log" >&2
  fi
  exit 2
}

. "$ROOT/tests/daemon/loopback_multicast.sh"

CONFIG="$TMP/rig.toml"
LOGS="$TMP/logs"
KEY="$TMP/command.key"
# As tests/daemon/udp_multicast_test.sh configures it (a session started right after an e-stop
# runs at once), every key and state file in the temporary directory.
. "$ROOT/tests/daemon/udp_rig_config.sh"
udp_rig_config "$ROOT/config/rig.toml" "$CONFIG" "$URL" "$LOGS" "$TMP"

# The keys first, as the unit's ExecStartPre makes them; the benchmark signs its starts with the
# command key.
"$FURUTAD" --config "$CONFIG" --create-command-key > "$TMP/keys.log" 2>&1 \
  || fail "furutad --create-command-key: $(cat "$TMP/keys.log")"
# The priority furutad.service gives it (Nice=-10: above other users' processes, the flood's
# among them), where this run may; said either way.
NICE=(nice -n "${FURUTA_DAEMON_NICE:--10}")
if ! nice -n "${FURUTA_DAEMON_NICE:--10}" true 2>/dev/null || [ "$(nice -n "${FURUTA_DAEMON_NICE:--10}" nice)" != "${FURUTA_DAEMON_NICE:--10}" ]; then
  NICE=()
fi
echo "furutad's nice value: $(${NICE[@]+"${NICE[@]}"} nice)"
${NICE[@]+"${NICE[@]}"} "$FURUTAD" --sim --config "$CONFIG" > "$TMP/furutad.log" 2>&1 &
DAEMON_PID=$!

up=""
for _ in $(seq 1 60); do
  if "$FURUTA" status --config "$CONFIG" --timeout 1 > "$TMP/status.txt" 2>&1; then
    up=1
    break
  fi
  kill -0 "$DAEMON_PID" 2>/dev/null || fail "furutad exited"
  sleep 0.5
done
[ -n "$up" ] \
  || fail "furutad did not answer \`furuta status\` within 30 s: $(cat "$TMP/status.txt")"
echo "furutad up on $URL (pid $DAEMON_PID)"

read -ra extra <<< "${FURUTA_FLOOD_ARGS:-}"
"$BENCH" --lcm-url "$URL" --config "$CONFIG" --command-key "$KEY" --tries "$TRIES" \
  --rate "$RATE" --json "$OUT/estop_under_flood.json" "${extra[@]}"
rc=$?

# Datagrams the kernel dropped at furutad's sockets (its receive buffer full), from /proc/net/udp
# of this namespace: inode in field 10, drops last.
inodes=""
for fd in "/proc/$DAEMON_PID/fd"/*; do
  target=$(readlink "$fd" 2>/dev/null) || continue
  case "$target" in socket:\[*\]) inodes+="${target//[!0-9]/} " ;; esac
done
awk -v inodes="$inodes" '
  BEGIN { n = split(inodes, list, " "); for (i = 1; i <= n; i++) ours[list[i]] = 1 }
  NR > 1 && ($10 in ours) { drops += $NF; sockets++ }
  END {
    printf "furutad: %d datagrams dropped by the kernel at its %d UDP sockets", drops, sockets
    print " (receive buffer full)"
  }' /proc/net/udp

kill -TERM "$DAEMON_PID"
for _ in $(seq 1 100); do
  kill -0 "$DAEMON_PID" 2>/dev/null || break
  sleep 0.1
done
kill -0 "$DAEMON_PID" 2>/dev/null && echo "furutad still running 10 s after SIGTERM: killed" >&2
kill -KILL "$DAEMON_PID" 2>/dev/null
wait "$DAEMON_PID"
daemon_rc=$?
DAEMON_PID=""
echo "furutad exited $daemon_rc after SIGTERM; JSON: $OUT/estop_under_flood.json"
exit "$rc"
