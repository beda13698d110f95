#!/usr/bin/env bash
# The long fault soak (issue 8): the daemon on the simulated rig in virtual time, session after
# session under a seeded schedule of every fault kind, every invariant checked after every fault
# (tests/daemon/fault_soak_test.cpp). CI runs half a virtual hour of it inside daemon_tests; this
# runs as long as asked.
#
#   scripts/soak.sh [HOURS [SEED...]]     default: 8 virtual hours, seed 1
#   FURUTA_SOAK_BUILD_DIR=build/ci scripts/soak.sh 24 1 2 3
#
# Builds daemon_tests first if needed (RelWithDebInfo, warnings as errors, in build/soak unless
# FURUTA_SOAK_BUILD_DIR names an existing build). Prints the [ measured ] figures of each seed and
# exits non-zero if any run found a violation. About 12-18 s of wall time per virtual hour.
set -euo pipefail
cd "$(dirname "$0")/.."

hours="${1:-8}"
shift || true
seeds=("$@")
[ "${#seeds[@]}" -gt 0 ] || seeds=(1)

build="${FURUTA_SOAK_BUILD_DIR:-build/soak}"
if [ ! -f "$build/build.ninja" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFURUTA_WERROR=ON \
    -DFURUTA_BUILD_BENCH=OFF
fi
cmake --build "$build" --target daemon_tests --parallel "${FURUTA_SOAK_JOBS:-2}"

status=0
for seed in "${seeds[@]}"; do
  echo "== fault soak: ${hours} virtual hours, seed ${seed}, $(date -u +%Y-%m-%dT%H:%M:%SZ)," \
    "load $(cut -d' ' -f1-3 /proc/loadavg)"
  FURUTA_SOAK_HOURS="$hours" FURUTA_SOAK_SEED="$seed" \
    "$build/tests/daemon_tests" --gtest_filter='FaultSoak.*' --gtest_brief=1 || status=1
done
exit "$status"
