#!/usr/bin/env bash
# Installs what is needed, builds, and runs the main job on the simulated rig: two bang-bang
# sessions and one validation session through the daemon's loop (virtual time), then the pass the
# identification trigger runs when logs land (furuta-identify.path -> furuta process-logs), which
# identifies them as config/rig.toml's [automation] says and writes the report.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset release
cmake --build --preset release --parallel "$(nproc)"

furuta=${FURUTA_BIN:-./build/release/app/furuta}
# A directory of its own per run: the trigger takes the oldest pending logs first, and the report
# must come from the sessions just run, not from a batch left over by an earlier run.
run="${FURUTA_OUT:-out}/$(date -u +%Y-%m-%dT%H-%M-%SZ)"
logs="$run/logs"
mkdir -p "$logs"
session() {
  "$furuta" run --config config/rig.toml --sim --virtual-time --logs-dir "$logs" \
    --lcm-url memq:// "$@"
}
session --label bang-bang --seed 1
session --label bang-bang --seed 2
session --label validation --seed 3

"$furuta" process-logs "$logs" --config config/rig.toml -o "$run/identifications" |
  tee "$run/process-logs.txt"
report=$(sed -n 's/^report: //p' "$run/process-logs.txt" | tail -n 1)
if [ -z "$report" ] || [ ! -f "$report" ]; then
  echo "run.sh: the trigger wrote no report (see $run/process-logs.txt)" >&2
  exit 1
fi
ln -sfn "$(basename "$run")" "${FURUTA_OUT:-out}/latest"
echo
echo "report: $(realpath "$report")"
