#!/usr/bin/env bash
# A board's input report is decoded in one place: its role adapter (firmware_bridge's
# board_adapters.cpp, board_roles.hpp). Everything above takes the adapter's reading; a second
# decoder would be a second truth about the same bytes. Tests, fuzz targets and benchmarks may call
# the codecs directly; so may the codecs' own sources and the simulated rig (the board's side of
# the wire, which decodes the host's output reports).
set -euo pipefail
cd "${1:?usage: check_decode_once.sh SOURCE_DIR}"

allowed='^(firmware_bridge/src/board_adapters\.cpp|firmware_bridge/src/codec_10[0-9]+\.cpp|firmware_bridge/include/furuta/firmware_bridge/codec_10[0-9]+\.hpp):'
sources() {
  find . -path ./build -prune -o -path ./tests -prune -o -path ./fuzz -prune -o -path ./bench \
    -prune -o -path ./.git -prune -o \( -name '*.cpp' -o -name '*.hpp' \) -print | sed 's|^\./||'
}
found=$(sources | xargs grep -nE '\bdecode_input_[0-9a-z]+\(' | grep -vE "$allowed" || true)
if [ -n "$found" ]; then
  echo "input reports decoded outside the boards' adapters (board_roles.hpp):"
  echo "$found"
  exit 1
fi
# The board side of the wire decodes only what the host writes.
found=$(sources | xargs grep -nE '\bdecode_output_[0-9a-z]+\(' |
  grep -vE "$allowed" | grep -vE '^simulator/src/simulated_rig[a-z_]*\.cpp:' || true)
if [ -n "$found" ]; then
  echo "output reports decoded outside the boards' adapters and the simulated rig:"
  echo "$found"
  exit 1
fi
echo "check_decode_once: every report is decoded by its board's adapter"
