#!/usr/bin/env bash
# The daemon latency benchmark in its four configurations (16 ms and 1 ms, with and without
# SCHED_FIFO), 60 s each, LCM over real UDP multicast (ttl=0) in a private network namespace.
# Needs root (or CAP_NET_ADMIN for the namespace, CAP_SYS_NICE for SCHED_FIFO). About 8 minutes.
# Usage: bench/run_daemon_latency.sh [BUILD_DIR] [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
seconds="${2:-60}"
out="${FURUTA_BENCH_OUT:-out/bench}"
mkdir -p "$out"
url="udpm://239.255.77.$((RANDOM % 200 + 10)):$((20000 + RANDOM % 20000))?ttl=0"
for period in 16000 1000; do
  for fifo in "" "--fifo --cpu 1"; do
    name="daemon_${period}us${fifo:+_fifo_cpu1}"
    echo "== $name"
    unshare -n sh -c "ip link set lo up && ip route add 224.0.0.0/4 dev lo && \
      '$build/bench/daemon_latency' --config config/rig.toml --period-us $period \
      --seconds $seconds $fifo --lcm-url '$url' --json '$out/$name.json'" | tee "$out/$name.txt"
  done
done
