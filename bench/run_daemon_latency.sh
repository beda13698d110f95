#!/usr/bin/env bash
# The daemon latency benchmark in its four configurations (16 ms and 1 ms, with and without
# SCHED_FIFO), SECONDS each (60 by default), LCM over real UDP multicast (ttl=0) in a private
# network namespace. Needs root (or CAP_NET_ADMIN for the namespace, CAP_SYS_NICE for SCHED_FIFO).
# About 8 minutes; with a controller file, 2 minutes more.
# Usage: bench/run_daemon_latency.sh [BUILD_DIR] [SECONDS] [CONTROLLER.toml]
# With CONTROLLER.toml (designed for config/rig.toml at 16 ms: `furuta controller design
# tests/data/golden/results.json -o CONTROLLER.toml`), the 16 ms configurations run a balance
# session after the bang-bang one, under the same set-up; the 1 ms ones stay bang-bang only, the
# controller being designed for the rig's 16 ms period. FURUTA_BENCH_SESSIONS sets their order
# (daemon_latency --session: `both` by default; e.g. bang-bang,balance,balance,bang-bang).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
seconds="${2:-60}"
controller="${3:-}"
out="${FURUTA_BENCH_OUT:-out/bench}"
mkdir -p "$out"
url="udpm://239.255.77.$((RANDOM % 200 + 10)):$((20000 + RANDOM % 20000))?ttl=0"
for period in 16000 1000; do
  sessions=""
  if [ -n "$controller" ] && [ "$period" = 16000 ]; then
    sessions="--session ${FURUTA_BENCH_SESSIONS:-both} --balance '$controller'"
  fi
  for fifo in "" "--fifo --cpu 1"; do
    name="daemon_${period}us${fifo:+_fifo_cpu1}"
    echo "== $name"
    unshare -n sh -c "ip link set lo up && ip route add 224.0.0.0/4 dev lo && \
      '$build/bench/daemon_latency' --config config/rig.toml --period-us $period \
      --seconds $seconds $fifo $sessions --lcm-url '$url' --json '$out/$name.json'" \
      | tee "$out/$name.txt"
  done
done
