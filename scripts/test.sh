#!/usr/bin/env bash
# Installs what is needed, builds with warnings as errors, and runs the whole test suite; then the
# same suite under AddressSanitizer + UndefinedBehaviorSanitizer (preset asan) and the threaded
# tests under ThreadSanitizer (preset tsan), docs/reliability.d/sanitizers.md. The two sanitizer
# builds take most of the time (28 of 41 minutes on 2 cores); FURUTA_SANITIZERS=0 leaves them
# out for a quick local run. CI (.ci/run) runs this script as it is.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset ci
cmake --build --preset ci --parallel "$(nproc)"
ctest --preset ci --parallel "$(nproc)"

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
