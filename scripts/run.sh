#!/usr/bin/env bash
# Installs what is needed, builds, and runs the main job on the simulated rig.
# (Until the daemon lands: a bang-bang session through the firmware bridge, recorded and replayed.)
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset release
cmake --build --preset release --parallel "$(nproc)"
out_dir="${FURUTA_OUT:-out/simulated-session}"
./build/release/app/furuta simulate --config config/rig.toml --output "$out_dir" --duration 10 "$@"
