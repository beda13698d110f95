#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (build/zfuzz, ASan + UBSan) and runs each for a given
# time, printing executions, executions per second and findings per target.
#   scripts/fuzz.sh [seconds per target, default 60] [target ...]
# Each target starts from the seed corpus (fuzz/corpus/<target>, read only) and grows a working
# corpus in build/zfuzz/corpus/<target>; crashes, leaks and timeouts land in
# build/zfuzz/findings/<target>/. Exit status 1 when any target found something.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
all=(fuzz_codec_1065 fuzz_codec_1047 fuzz_log_reader fuzz_csv_import fuzz_config
     fuzz_command_decode fuzz_command_handler fuzz_signed_command fuzz_status_reply
     fuzz_log_mutation)
if [ $# -gt 0 ]; then targets=("$@"); else targets=("${all[@]}"); fi
build=build/zfuzz
jobs="${FUZZ_BUILD_JOBS:-2}"

command -v clang++ >/dev/null || { echo "fuzz: clang++ not found (scripts/setup.sh installs it)" >&2; exit 2; }
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DFURUTA_BUILD_FUZZERS=ON -DFURUTA_BUILD_TESTS=OFF -DFURUTA_BUILD_BENCH=OFF >/dev/null
ninja -C "$build" -j "$jobs" "${targets[@]}" >/dev/null

# Leak checking stays on: a leak per input would exhaust the daemon over time.
export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

# The log, CSV and handler targets write temporary files: keep them in the build tree.
export TMPDIR="$PWD/$build/tmp"
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"

printf '%-22s %10s %10s %9s %8s  %s\n' target seconds execs exec/s corpus findings
status=0
for t in "${targets[@]}"; do
  corpus="$build/corpus/$t"
  findings="$build/findings/$t"
  mkdir -p "$corpus" "$findings"
  log="$build/findings/$t.log"
  # -timeout: an input taking longer is a hang; -rss_limit_mb: one that eats memory is a finding.
  set +e
  "$build/fuzz/$t" "$corpus" "fuzz/corpus/$t" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -artifact_prefix="$findings/" \
    >"$log" 2>&1
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  units=$(find "$corpus" -type f | wc -l)
  found=$(find "$findings" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
  what="none"
  if [ "$rc" -ne 0 ] || [ "$found" -gt 0 ]; then
    what="$found (exit $rc; $log)"
    status=1
  fi
  printf '%-22s %10s %10s %9s %8s  %s\n' "$t" "$seconds" "$execs" "$rate" "$units" "$what"
done
exit $status
