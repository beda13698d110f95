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
    model_tests config_tests lcmtypes_tests firmware_bridge_tests simulator_tests \
    command_auth_tests session_log_tests daemon_tests interval_tests identification_tests
fi
built=$SECONDS
ctest --preset arm64 --parallel "$(nproc)"
tested=$SECONDS

# Rounding is where architectures differ: the same seeds must reach the same operands and so make
# the same number of checks, with no violation, on both. The counts are read from the two test runs'
# logs (each MPFR property test prints its own); the amd64 tests are run again only when its last
# ctest run did not include them.
counts() { sed -n 's/^\[ measured \] \([^:]*: [0-9]* point checks, [0-9]* violations\).*/\1/p' | sort; }
if [ -x "$amd64_build/tests/interval_tests" ]; then
  arm64_counts=$(counts <build/arm64/Testing/Temporary/LastTest.log)
  amd64_counts=$(counts 2>/dev/null <"$amd64_build/Testing/Temporary/LastTest.log" || true)
  if ! grep -q '^add: ' <<<"$amd64_counts"; then
    amd64_counts=$("$amd64_build/tests/interval_tests" --gtest_filter='IntervalMpfr.*' | counts)
  fi
  if ! grep -q '^add: ' <<<"$arm64_counts"; then
    echo "test_arm64: no MPFR counts in the arm64 run's log" >&2
    exit 1
  fi
  if ! diff <(echo "$amd64_counts") <(echo "$arm64_counts"); then
    echo "test_arm64: the MPFR property tests made other checks on arm64 (<: amd64, >: arm64)" >&2
    exit 1
  fi
  echo "test_arm64: MPFR property tests, arm64 as amd64: $(wc -l <<<"$arm64_counts") properties," \
    "$(awk '{c += $(NF - 4); v += $(NF - 1)} END {print c " point checks, " v " violations"}' \
      <<<"$arm64_counts")"
fi
echo "test_arm64: built in $((built - start)) s, tested in $((tested - built)) s," \
  "compared in $((SECONDS - tested)) s"
