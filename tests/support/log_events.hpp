#pragma once
// LCM log events as plain values, laid out straight from the format (sync word, event number,
// utime, channel and data lengths, all big-endian, then channel and data), independently of the
// code under test: to write logs byte by byte, and to change a real log event by event (a sample
// repeated, a byte flipped, two files joined) and write it back.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/session_log/lcm_log.hpp"

namespace furuta::testing {

struct Event {
  std::int64_t number = 0;
  std::int64_t utime = 0;
  std::string channel;
  std::vector<std::uint8_t> data;
};

inline void put_be(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

// One event as lcm-logger lays it out.
inline void append_event(std::vector<std::uint8_t>& out, const Event& e) {
  put_be(out, 0xEDA1DA01u, 4);
  put_be(out, static_cast<std::uint64_t>(e.number), 8);
  put_be(out, static_cast<std::uint64_t>(e.utime), 8);
  put_be(out, e.channel.size(), 4);
  put_be(out, e.data.size(), 4);
  out.insert(out.end(), e.channel.begin(), e.channel.end());
  out.insert(out.end(), e.data.begin(), e.data.end());
}

inline std::vector<std::uint8_t> encode_log(const std::vector<Event>& events) {
  std::vector<std::uint8_t> out;
  for (const Event& e : events) append_event(out, e);
  return out;
}

// Every event the checked reader finds in a log.
inline std::vector<Event> events_of(const std::filesystem::path& path) {
  std::vector<Event> out;
  session_log::LcmLogReader reader(path);
  session_log::LogEvent e;
  while (reader.next(e)) out.push_back({e.event_number, e.utime, e.channel, e.data});
  return out;
}

// The events as a log file at `path` (replaced); returns the path.
inline std::filesystem::path write_events(const std::filesystem::path& path,
                                          const std::vector<Event>& events) {
  const std::vector<std::uint8_t> bytes = encode_log(events);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
  return path;
}

// The positions of the events on `channel`.
inline std::vector<std::size_t> events_on(const std::vector<Event>& events,
                                          const std::string& channel) {
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i].channel == channel) at.push_back(i);
  }
  return at;
}

}  // namespace furuta::testing
