// The LCM log reader on arbitrary bytes, both ways in: the buffer reader and the file reader (via a
// temporary file) must return the same events, account for every byte, and never throw on content;
// the typed session-log loader and the USB trace built from it must not crash either.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

using namespace furuta::session_log;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

const std::filesystem::path& temp_log() {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("furuta-fuzz-log-" + std::to_string(getpid()) + ".lcmlog");
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  LogReadStats from_bytes;
  const std::vector<LogEvent> events = read_lcm_log_bytes({data, size}, from_bytes);
  check(from_bytes.events == events.size());
  check(from_bytes.bytes_skipped <= size);
  check(from_bytes.readable_prefix_bytes <= size);
  std::uint64_t event_bytes = 0;
  for (const LogEvent& e : events) {
    check(e.file_offset < size);
    event_bytes += 28 + e.channel.size() + e.data.size();
  }
  check(event_bytes + from_bytes.bytes_skipped <= size);

  {
    std::ofstream out(temp_log(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  LcmLogReader reader(temp_log());
  LogEvent event;
  std::size_t i = 0;
  while (reader.next(event)) {
    check(i < events.size());
    check(event.channel == events[i].channel && event.data == events[i].data &&
          event.utime == events[i].utime && event.event_number == events[i].event_number &&
          event.file_offset == events[i].file_offset);
    ++i;
  }
  check(i == events.size());
  check(reader.stats().damaged_regions == from_bytes.damaged_regions);
  check(reader.stats().bytes_skipped == from_bytes.bytes_skipped);
  check(reader.stats().truncated_tail == from_bytes.truncated_tail);

  const SessionLog log = load_session_log(temp_log());
  check(log.read_stats.events == events.size());
  (void)log.missing_sequence_numbers();
  (void)integrity_problems(log);
  std::size_t covered = 0;
  for (const SampleRun& run : contiguous_sample_runs(log)) {
    check(run.begin == covered && run.end > run.begin);
    covered = run.end;
  }
  check(covered == log.samples.size());
  for (std::int8_t board :
       {furuta::rig_usb_report_t::BOARD_MOTOR, furuta::rig_usb_report_t::BOARD_ENCODER}) {
    try {
      (void)usb_trace_from_log(log, board);
    } catch (const std::runtime_error&) {
      // A log that cannot be replayed is refused with a message: fine.
    }
  }
  return 0;
}
