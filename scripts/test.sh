#!/usr/bin/env bash
# Installs what is needed, builds with warnings as errors, and runs the whole test suite; then the
# arm64 cross build with part of the suite under qemu-user and its .deb (scripts/test_arm64.sh,
# docs/arm64.md); then the suite under AddressSanitizer + UndefinedBehaviorSanitizer (preset asan)
# and the threaded tests under ThreadSanitizer (preset tsan), docs/reliability.d/sanitizers.md.
# FURUTA_ARM64=0 and FURUTA_SANITIZERS=0 leave those out for a quick local run. CI (.ci/run) runs
# this script as it is; the time each part took is printed at its end.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset ci
cmake --build --preset ci --parallel "$(nproc)"
ctest --preset ci --parallel "$(nproc)"
echo "test.sh: ci built and tested by $SECONDS s"

if [ "${FURUTA_ARM64:-1}" != 0 ]; then
  bash scripts/test_arm64.sh build/ci
fi

if [ "${FURUTA_SANITIZERS:-1}" != 0 ]; then
  for preset in asan tsan; do
    start=$SECONDS
    cmake --preset "$preset"
    cmake --build --preset "$preset" --parallel "$(nproc)"
    built=$SECONDS
    ctest --preset "$preset" --parallel "$(nproc)"
    echo "test.sh: $preset built in $((built - start)) s, tested in $((SECONDS - built)) s"
  done
fi
echo "test.sh: all done in $SECONDS s"
