#pragma once
// Shared by the session_log tests: temporary directories, files as bytes, and LCM log events
// encoded independently of the code under test (straight from the format description), so the
// writer and the reader are checked against the format and not against each other.

#include <stdlib.h>  // mkdtemp

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/session_log/lcm_log.hpp"
#include "log_events.hpp"
#include "temp_dir.hpp"

namespace furuta::session_log::testing {

using furuta::testing::TempDir;

namespace fs = std::filesystem;

inline std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

using furuta::testing::append_event;
using furuta::testing::encode_log;
using furuta::testing::Event;
using furuta::testing::put_be;

inline std::size_t encoded_size(const Event& e) {
  return 28 + e.channel.size() + e.data.size();
}

// Deterministic content for event i: varied lengths (some empty, some beyond a stdio buffer).
inline std::vector<std::uint8_t> pattern_data(std::int64_t i) {
  std::size_t n = static_cast<std::size_t>((i * 37) % 301);
  if (i % 11 == 5) n = 5000 + static_cast<std::size_t>(i % 7);
  std::vector<std::uint8_t> data(n);
  for (std::size_t k = 0; k < n; ++k) {
    data[k] = static_cast<std::uint8_t>((static_cast<std::uint64_t>(i) * 131 + k * 7) & 0xFF);
  }
  return data;
}

inline Event pattern_event(std::int64_t i) {
  return Event{i, 1'700'000'000'000'000 + i * 16'000, i % 3 == 0 ? "RIG_SAMPLE" : "RIG_USB",
               pattern_data(i)};
}

inline std::vector<Event> pattern_events(int n) {
  std::vector<Event> events;
  for (int i = 0; i < n; ++i) events.push_back(pattern_event(i));
  return events;
}

inline std::vector<LogEvent> read_log(const fs::path& path, LogReadStats& stats) {
  LcmLogReader reader(path);
  std::vector<LogEvent> events;
  LogEvent e;
  while (reader.next(e)) events.push_back(e);
  stats = reader.stats();
  return events;
}

inline bool same_event(const LogEvent& got, const Event& want) {
  return got.event_number == want.number && got.utime == want.utime &&
         got.channel == want.channel && got.data == want.data;
}

}  // namespace furuta::session_log::testing
