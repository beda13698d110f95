#!/usr/bin/env bash
# Board models are named only where a model is the subject: its adapter and codec
# (firmware_bridge/), the simulated boards (simulator/), configuration values and the simulated
# boards' configuration keys, docs, tests, fuzz targets and benchmarks. Everything else speaks of
# the motor board and the encoder board, so that a new board touches its adapter and a
# configuration value, nothing more (docs/adding-a-board.md).
set -euo pipefail
cd "${1:?usage: check_board_names.sh SOURCE_DIR}"

found=$(find . \( -path ./build -o -path ./tests -o -path ./fuzz -o -path ./bench -o -path ./docs \
  -o -path ./.git -o -path ./firmware_bridge -o -path ./simulator \) -prune -o \
  \( -name '*.cpp' -o -name '*.hpp' -o -name '*.lcm' -o -name 'CMakeLists.txt' \) -print |
  sed 's|^\./||' | xargs grep -nE '10(65|47)' |
  grep -vE '\b(firmware|serial)_10(65|47)\b' || true)
if [ -n "$found" ]; then
  echo "board models named outside their adapters (docs/adding-a-board.md):"
  echo "$found"
  exit 1
fi
echo "check_board_names: the board models are named only by their adapters and the configuration"
