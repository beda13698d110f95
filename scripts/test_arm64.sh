#!/usr/bin/env bash
# The arm64 rig computer's build (docs/arm64.md): makes the sysroot of Debian 12's arm64 packages,
# cross-builds the whole project (preset arm64), runs the chosen tests on the arm64 executables under
# qemu-user (the arm64 test preset: codecs, the loop in virtual time, the log writer and reader,
# LSMI and the identification, the interval core against MPFR, SIVIA, the .deb), and checks that
# the interval core's MPFR property tests make as many checks there as in the amd64 build.
# Usage: scripts/test_arm64.sh [AMD64_BUILD_DIR]   (default build/ci; the comparison is skipped
# when it has no interval_tests). scripts/test.sh runs it after the amd64 tests.
set -euo pipefail
cd "$(dirname "$0")/.."
amd64_build="${1:-build/ci}"

start=$SECONDS
bash scripts/setup.sh
bash scripts/arm64_sysroot.sh
cmake --preset arm64
# What the arm64 tests run and what the .deb holds; `cmake --build --preset arm64` builds the rest
# (the app, pipeline, report and validated suites, the benchmarks), FURUTA_ARM64_ALL=1 here.
if [ "${FURUTA_ARM64_ALL:-0}" = 1 ]; then
  cmake --build --preset arm64 --parallel "$(nproc)"
else
  cmake --build --preset arm64 --parallel "$(nproc)" --target furuta furutad common_tests \
    model_tests config_tests lcmtypes_tests firmware_bridge_tests command_auth_tests \
    session_log_tests daemon_tests interval_tests identification_tests
fi
built=$SECONDS
ctest --preset arm64 --parallel "$(nproc)"
tested=$SECONDS

# Rounding is where architectures differ: the same seeds must reach the same operands and so make
# the same number of checks, with no violation, on both.
counts() { sed -n 's/^\[ measured \] \([^:]*: [0-9]* point checks, [0-9]* violations\).*/\1/p'; }
if [ -x "$amd64_build/tests/interval_tests" ]; then
  mpfr_log=build/arm64/interval_mpfr.log
  qemu=$(sed -n 's/^FURUTA_QEMU_AARCH64:[A-Z]*=//p' build/arm64/CMakeCache.txt)
  "$qemu" -L build/arm64-sysroot/root build/arm64/tests/interval_tests \
    --gtest_filter='IntervalMpfr.*' >"$mpfr_log"
  if ! diff <("$amd64_build/tests/interval_tests" --gtest_filter='IntervalMpfr.*' | counts) \
    <(counts <"$mpfr_log"); then
    echo "test_arm64: the MPFR property tests made other checks on arm64 (<: amd64, >: arm64)" >&2
    exit 1
  fi
  echo "test_arm64: MPFR property tests, arm64 as amd64: $(grep -F '(all MPFR' "$mpfr_log")"
  grep -F 'largest error' "$mpfr_log"
fi
echo "test_arm64: built in $((built - start)) s, tested in $((tested - built)) s," \
  "compared in $((SECONDS - tested)) s"
