#!/usr/bin/env bash
# Installs what is needed, builds, and runs the main job on the simulated rig: a bang-bang session
# through the daemon's loop (virtual time), its log summarised, and its USB traffic replayed.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset release
cmake --build --preset release --parallel "$(nproc)"

furuta=./build/release/app/furuta
logs="${FURUTA_OUT:-out}/logs"
mkdir -p "$logs"
count_logs() { find "$logs" -maxdepth 1 -name '*.lcmlog' | wc -l; }
before=$(count_logs)
"$furuta" run --config config/rig.toml --sim --virtual-time --logs-dir "$logs" --lcm-url memq:// \
  --label bang-bang "$@"
[ "$(count_logs)" -gt "$before" ] || { echo "run.sh: no new log" >&2; exit 1; }
log=$(ls -t "$logs"/*.lcmlog | head -n 1)
"$furuta" log info "$log"
"$furuta" replay "$log"
"$furuta" log export-csv "$log" -o "${log%.lcmlog}.csv"
