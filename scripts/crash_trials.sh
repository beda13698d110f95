#!/usr/bin/env bash
# The long version of the daemon_crash_trials test: furutad on the simulated rig killed with SIGKILL
# at seeded random moments TRIALS times (default 2000), then the disk-full and logs-directory
# scenarios once each. Prints the `[ measured ]` figures; docs/reliability.d/crash.md records runs.
#
# usage: scripts/crash_trials.sh [BUILD_DIR [TRIALS [SEED [SCENARIOS]]]]
#   BUILD_DIR defaults to build/c; furutad and furuta_crash_trials are built there if missing.
#   FURUTA_CRASH_FLUSH_MS sets flush_interval_ms (default 50).
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD=${1:-build/c}
TRIALS=${2:-2000}
SEED=${3:-$(date +%s)}
SCENARIOS=${4:-"kill fsize small-fs dir-removed dir-readonly"}

cmake --build "$BUILD" --target furutad furuta_crash_trials
echo "crash trials: $TRIALS, seed $SEED, $(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
start=$(date +%s)
status=0
bash tests/daemon/crash_trials_test.sh "$BUILD/daemon/furutad" "$BUILD/tests/furuta_crash_trials" \
  config/rig.toml "$TRIALS" "$SEED" "$SCENARIOS" || status=$?
echo "took $(( $(date +%s) - start )) s, load after $(cut -d' ' -f1-3 /proc/loadavg)"
exit $status
