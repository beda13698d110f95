#pragma once
// Changes to a sealed session log, driven by bytes, and the check that no command calls a changed
// log intact. The same bytes give the same changes whoever supplies them: libFuzzer's input in
// fuzz/fuzz_log_mutation.cpp, a seeded generator in the GoogleTest suite.
//
// A script is up to kMaxOperations operations, each an opcode byte and its parameters (missing
// bytes read as 0): on the log's bytes (a bit flipped, a short run overwritten, a range deleted,
// the file truncated, the whole log appended to itself as `cat a a` does) or on its events (one
// duplicated, two swapped, one deleted, a sample's monotonic_ns moved, a double of a sample
// changed and encoded again so that it still decodes). Event operations read the events as the
// project's reader finds them and write them back with log_events.hpp's encoder.
//
// The property (changed_log_called_intact): a log whose bytes are not the sealed log's is never
// called intact without a word. `log info` calls a log intact when integrity_problems is empty;
// it is also silent when integrity_notes is empty. `identify` accepts a log as a whole session
// when load_batch returns a batch for it without use_intact_part; it is silent when none of the
// log's notes reaches the batch's warnings.
// Why a note is enough: the seal carries no key, so a log whose seal was removed and whose start
// record names a version older than the first that sealed every log is, byte for byte, what such
// a version wrote. Nothing can prove it changed; what can be said, and must be, is that nothing
// proves it whole (the "no seal" note). A changed log called intact with neither a problem nor
// that note is a violation.

#include <algorithm>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/pipeline/intake.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"
#include "log_events.hpp"

namespace furuta::testing {

// Enough to combine every kind of change with a few others; more only repeats them.
inline constexpr std::size_t kMaxOperations = 6;
// A log joined to itself at most until it is this many times the original's size, so that a
// script of joins stays a few megabytes at most.
inline constexpr std::size_t kMaxJoinFactor = 4;

// Each operation's parameters after its opcode (u16/u32/u64 big-endian; positions and indices
// taken modulo what the log has; "pick" is a u8 whose evenness says among the samples, else
// among all events).
enum class LogMutation : std::uint8_t {
  flip_bit,              // u32 byte, u8 bit (mod 8)
  overwrite_run,         // u32 byte, u8 length - 1 (mod 8), then the new bytes
  delete_range,          // u32 first byte, u16 length - 1 (mod 4096)
  truncate,              // u32 new size
  duplicate_event,       // pick, u16 event, u16 where the copy goes (mod events + 1)
  swap_events,           // pick, u16 event, u16 other event (the next one when the same)
  delete_event,          // pick, u16 event
  move_sample_time,      // u16 sample, u32 ns added as an i32 (0 adds 1)
  change_sample_double,  // u16 sample, u8 field, u8 how (even: flip bit how/2, odd: set), u64
  join,                  // none: the log as it is now appended to itself
  count                  // not an operation: the number of them
};

// The script's bytes, read in order; reads past the end give 0, so every byte string is a script.
class ScriptReader {
 public:
  explicit ScriptReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  bool done() const { return at_ >= bytes_.size(); }
  std::uint8_t u8() { return at_ < bytes_.size() ? bytes_[at_++] : 0; }
  // Big-endian, high part first: each part read in its own statement, since the operands of |
  // are evaluated in no fixed order.
  std::uint16_t u16() {
    const std::uint16_t high = u8();
    return static_cast<std::uint16_t>((high << 8) | u8());
  }
  std::uint32_t u32() {
    const std::uint32_t high = u16();
    return (high << 16) | u16();
  }
  std::uint64_t u64() {
    const std::uint64_t high = u32();
    return (high << 32) | u32();
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

// Writes a script operation by operation, in the layout mutate_log reads (big-endian numbers).
class ScriptWriter {
 public:
  ScriptWriter& op(LogMutation m) { return u8(static_cast<std::uint8_t>(m)); }
  ScriptWriter& u8(std::uint8_t v) {
    bytes_.push_back(v);
    return *this;
  }
  ScriptWriter& u16(std::uint16_t v) { return u8(static_cast<std::uint8_t>(v >> 8)).u8(v & 0xff); }
  ScriptWriter& u32(std::uint32_t v) {
    return u16(static_cast<std::uint16_t>(v >> 16)).u16(v & 0xffff);
  }
  ScriptWriter& u64(std::uint64_t v) {
    return u32(static_cast<std::uint32_t>(v >> 32)).u32(v & 0xffffffff);
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

namespace detail {

inline std::vector<Event> events_in(const std::vector<std::uint8_t>& bytes) {
  session_log::LogReadStats stats;
  std::vector<Event> events;
  for (auto& e : session_log::read_lcm_log_bytes(bytes, stats)) {
    events.push_back({e.event_number, e.utime, std::move(e.channel), std::move(e.data)});
  }
  return events;
}

// Index of an event: among the samples when `samples_only` and the log has any, else among all.
inline std::optional<std::size_t> pick_event(const std::vector<Event>& events, std::uint16_t raw,
                                             bool samples_only) {
  if (events.empty()) return std::nullopt;
  if (samples_only) {
    const std::vector<std::size_t> at = events_on(events, session_log::kChannelSample);
    if (!at.empty()) return at[raw % at.size()];
  }
  return raw % events.size();
}

inline std::optional<rig_sample_t> decode_sample(const Event& e) {
  if (e.channel != session_log::kChannelSample) return std::nullopt;
  rig_sample_t s;
  if (s.decode(e.data.data(), 0, static_cast<int>(e.data.size())) !=
      static_cast<int>(e.data.size())) {
    return std::nullopt;
  }
  return s;
}

inline std::vector<std::uint8_t> encode_sample(const rig_sample_t& s) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(s.getEncodedSize()));
  s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace detail

// `log` changed by the script in `script`; what was done, in words, appended to `*done` (one
// operation a line) when given. An operation that does not apply (an event operation on a log
// without events, a join past kMaxJoinFactor) does nothing.
inline std::vector<std::uint8_t> mutate_log(std::vector<std::uint8_t> log,
                                            std::span<const std::uint8_t> script,
                                            std::string* done = nullptr) {
  using namespace detail;
  const std::size_t original_size = log.size();
  ScriptReader in(script);
  std::ostringstream said;
  for (std::size_t n = 0; n < kMaxOperations && !in.done(); ++n) {
    const auto op =
        static_cast<LogMutation>(in.u8() % static_cast<std::uint8_t>(LogMutation::count));
    switch (op) {
      case LogMutation::flip_bit: {
        const std::uint32_t at = in.u32();
        const int bit = in.u8() % 8;
        if (log.empty()) break;
        log[at % log.size()] ^= static_cast<std::uint8_t>(1u << bit);
        said << "flip bit " << bit << " of byte " << at % log.size() << "\n";
        break;
      }
      case LogMutation::overwrite_run: {
        const std::uint32_t at = in.u32();
        const std::size_t length = 1 + in.u8() % 8;
        if (log.empty()) break;
        const std::size_t from = at % log.size();
        said << "overwrite bytes " << from << "..";
        for (std::size_t i = 0; i < length && from + i < log.size(); ++i) log[from + i] = in.u8();
        said << std::min(from + length, log.size()) - 1 << "\n";
        break;
      }
      case LogMutation::delete_range: {
        const std::uint32_t at = in.u32();
        const std::size_t length = 1 + in.u16() % 4096;
        if (log.empty()) break;
        const std::size_t from = at % log.size();
        const std::size_t to = std::min(log.size(), from + length);
        log.erase(log.begin() + static_cast<std::ptrdiff_t>(from),
                  log.begin() + static_cast<std::ptrdiff_t>(to));
        said << "delete bytes " << from << ".." << to - 1 << "\n";
        break;
      }
      case LogMutation::truncate: {
        const std::uint32_t at = in.u32();
        if (log.empty()) break;
        log.resize(at % log.size());
        said << "truncate to " << log.size() << " bytes\n";
        break;
      }
      case LogMutation::duplicate_event: {
        const bool samples_only = in.u8() % 2 == 0;
        const std::uint16_t which = in.u16(), where = in.u16();
        std::vector<Event> events = events_in(log);
        const auto i = pick_event(events, which, samples_only);
        if (!i) break;
        // Anywhere: next to itself (a sample logged twice) or elsewhere (one replayed later).
        const std::size_t to = where % (events.size() + 1);
        const Event copy = events[*i];
        events.insert(events.begin() + static_cast<std::ptrdiff_t>(to), copy);
        log = encode_log(events);
        said << "duplicate event " << *i << " (" << copy.channel << ") at " << to << "\n";
        break;
      }
      case LogMutation::swap_events: {
        const bool samples_only = in.u8() % 2 == 0;
        const std::uint16_t a = in.u16(), b = in.u16();
        std::vector<Event> events = events_in(log);
        const auto i = pick_event(events, a, samples_only);
        auto j = pick_event(events, b, samples_only);
        if (!i || events.size() < 2) break;
        if (*j == *i) j = (*i + 1) % events.size();
        std::swap(events[*i], events[*j]);
        log = encode_log(events);
        said << "swap events " << *i << " and " << *j << " (" << events[*j].channel << ", "
             << events[*i].channel << ")\n";
        break;
      }
      case LogMutation::delete_event: {
        const bool samples_only = in.u8() % 2 == 0;
        const std::uint16_t which = in.u16();
        std::vector<Event> events = events_in(log);
        const auto i = pick_event(events, which, samples_only);
        if (!i) break;
        said << "delete event " << *i << " (" << events[*i].channel << ")\n";
        events.erase(events.begin() + static_cast<std::ptrdiff_t>(*i));
        log = encode_log(events);
        break;
      }
      case LogMutation::move_sample_time: {
        const std::uint16_t which = in.u16();
        // Up to about +-2.1 s, never 0: from one nanosecond (seen by the seal alone) to a jump
        // back past earlier samples.
        const auto delta = static_cast<std::int32_t>(in.u32());
        std::vector<Event> events = events_in(log);
        const auto i = pick_event(events, which, true);
        if (!i) break;
        auto sample = decode_sample(events[*i]);
        if (!sample) break;
        const std::int64_t by = delta == 0 ? 1 : delta;
        sample->monotonic_ns = static_cast<std::int64_t>(
            static_cast<std::uint64_t>(sample->monotonic_ns) + static_cast<std::uint64_t>(by));
        events[*i].data = encode_sample(*sample);
        log = encode_log(events);
        said << "move sample seq " << sample->seq << " (event " << *i << ") by " << by << " ns\n";
        break;
      }
      case LogMutation::change_sample_double: {
        const std::uint16_t which = in.u16();
        const std::uint8_t field = in.u8();
        const std::uint8_t how = in.u8();
        const std::uint64_t value = in.u64();
        std::vector<Event> events = events_in(log);
        const auto i = pick_event(events, which, true);
        if (!i) break;
        auto sample = decode_sample(events[*i]);
        if (!sample) break;
        static constexpr const char* kNames[] = {"arm_angle_rad",   "pendulum_angle_rad",
                                                 "commanded_duty",  "applied_duty",
                                                 "motor_current_a", "supply_voltage_v"};
        double* const fields[] = {&sample->arm_angle_rad,   &sample->pendulum_angle_rad,
                                  &sample->commanded_duty,  &sample->applied_duty,
                                  &sample->motor_current_a, &sample->supply_voltage_v};
        const std::size_t f = field % std::size(fields);
        double& x = *fields[f];
        // Even: one bit of its representation flipped (the change of a bad memory cell or
        // wire); odd: any double (NaN and infinities included).
        if (how % 2 == 0) {
          x = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) ^ (1ull << (how / 2 % 64)));
        } else {
          x = std::bit_cast<double>(value);
        }
        events[*i].data = encode_sample(*sample);
        log = encode_log(events);
        said << "set " << kNames[f] << " of sample seq " << sample->seq << " (event " << *i
             << ") to " << x << "\n";
        break;
      }
      case LogMutation::join: {
        if (log.empty() ||
            log.size() * 2 > kMaxJoinFactor * std::max<std::size_t>(original_size, 1)) {
          break;
        }
        const std::size_t size = log.size();
        log.resize(2 * size);
        std::copy_n(log.begin(), size, log.begin() + static_cast<std::ptrdiff_t>(size));
        said << "join the log to itself (" << log.size() << " bytes)\n";
        break;
      }
      case LogMutation::count:
        break;
    }
  }
  if (done != nullptr) *done += said.str();
  return log;
}

// A script of `operations` random operations (opcode and parameters from `random`), for the
// seeded tests; the same engine reads it as it reads the fuzzer's bytes.
template <typename Random>
std::vector<std::uint8_t> random_script(Random& random, std::size_t operations) {
  std::vector<std::uint8_t> script;
  // An opcode and up to 14 bytes of parameters (change_sample_double's are the longest).
  for (std::size_t n = 0; n < operations; ++n) {
    for (int i = 0; i < 15; ++i) script.push_back(static_cast<std::uint8_t>(random()));
  }
  return script;
}

// What `log info` and `identify` make of `mutated`, a changed copy of the sealed log `original`
// (written to `dir`): a violation in words when either calls it intact without a problem or a
// note, nothing when both say what is wrong (or the bytes are the original's). Exceptions are
// left to the caller: load_batch throws only for unreadable files, so one here is a finding too.
inline std::optional<std::string> changed_log_called_intact(
    const std::vector<std::uint8_t>& original, const std::vector<std::uint8_t>& mutated,
    const std::filesystem::path& dir) {
  if (mutated == original) return std::nullopt;
  const std::filesystem::path path = dir / "mutated.lcmlog";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(mutated.data()),
              static_cast<std::streamsize>(mutated.size()));
    if (!out) throw std::runtime_error("cannot write " + path.string());
  }
  const session_log::SessionLog log = session_log::load_session_log(path);
  const auto problems = session_log::integrity_problems(log);
  const auto notes = session_log::integrity_notes(log);
  if (problems.empty() && notes.empty()) {
    return "log info calls the changed log intact: no problem, no note (" +
           std::to_string(mutated.size()) + " bytes, " + std::to_string(log.samples.size()) +
           " samples, " + (log.seal ? "sealed" : "no seal") + ")";
  }

  pipeline::BatchRequest request;
  request.logs = {path};
  const pipeline::Intake intake = pipeline::load_batch(request);
  if (!intake.batch) return std::nullopt;
  if (!problems.empty()) {
    return "identify accepts a log that is not intact as a whole session: " +
           session_log::describe(problems);
  }
  bool noted = false;
  for (const auto& recording : intake.batch->fit) {
    for (const std::string& warning : recording.experiment.warnings) {
      for (const std::string& note : notes) {
        noted = noted || warning.find(note) != std::string::npos;
      }
    }
  }
  if (!noted) return std::string("identify accepts the changed log as a whole session, no note");
  return std::nullopt;
}

}  // namespace furuta::testing
