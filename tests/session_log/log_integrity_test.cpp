// The one integrity rule for a session log (log_integrity.hpp): each problem named, and the runs of
// samples that can be filtered on their own, cut at missing sequence numbers and at damage.
#include "furuta/session_log/log_integrity.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "test_support.hpp"

namespace furuta::session_log::log_integrity_test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::read_bytes;
using testing::TempDir;
using testing::write_bytes;
using Kind = LogProblem::Kind;

template <typename Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

rig_session_t record(std::int8_t event) {
  rig_session_t s{};
  s.event = event;
  s.session = "2024-06-01T12-00-00";
  s.period_ns = 16'000'000;
  s.end_reason = event == rig_session_t::EVENT_END ? "duration" : "";
  return s;
}

rig_sample_t sample(std::int64_t seq) {
  rig_sample_t s{};
  s.seq = seq;
  s.monotonic_ns = seq * 16'000'000;
  return s;
}

// A session of samples 0..19 (less `skipped`), each followed by a USB report; start and end
// records unless told otherwise.
fs::path write_session(const fs::path& dir, const std::vector<std::int64_t>& skipped = {},
                       bool with_start = true, bool with_end = true) {
  LcmLogWriter writer({dir, 1000ms}, "session");
  std::int64_t utime = 0;
  const auto put = [&](const char* channel, const std::vector<std::uint8_t>& data) {
    EXPECT_EQ(writer.write(channel, utime++, data), LogWriteStatus::ok);
  };
  if (with_start) put(kChannelSession, encode(record(rig_session_t::EVENT_START)));
  for (std::int64_t seq = 0; seq < 20; ++seq) {
    if (std::find(skipped.begin(), skipped.end(), seq) != skipped.end()) continue;
    put(kChannelSample, encode(sample(seq)));
    rig_usb_report_t usb{};
    usb.time_ns = seq * 16'000'000 + 1;
    usb.board = rig_usb_report_t::BOARD_MOTOR;
    usb.kind = rig_usb_report_t::KIND_INPUT;
    usb.bytes = {1, 2, 3, 4};
    usb.length = 4;
    put(kChannelUsb, encode(usb));
  }
  if (with_end) put(kChannelSession, encode(record(rig_session_t::EVENT_END)));
  fs::path path;
  EXPECT_EQ(writer.finish(&path), LogWriteStatus::ok);
  return path;
}

std::vector<std::pair<std::size_t, std::size_t>> runs_of(const SessionLog& log) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const SampleRun& r : contiguous_sample_runs(log)) out.emplace_back(r.begin, r.end);
  return out;
}

TEST(LogIntegrity, AWholeSessionIsIntactAndOneRun) {
  TempDir dir;
  const SessionLog log = load_session_log(write_session(dir.path()));
  EXPECT_TRUE(integrity_problems(log).empty()) << describe(integrity_problems(log));
  EXPECT_EQ(runs_of(log), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 20}}));
}

TEST(LogIntegrity, MissingSamplesAreNamedByTheirSequenceNumbersAndCutTheRuns) {
  TempDir dir;
  const SessionLog log = load_session_log(write_session(dir.path(), {10, 11, 12, 15}));
  const auto problems = integrity_problems(log);
  ASSERT_EQ(problems.size(), 1u) << describe(problems);
  EXPECT_EQ(problems[0].kind, Kind::missing_samples);
  EXPECT_EQ(problems[0].text, "4 sample(s) missing (sequence numbers 10-12, 15)");
  EXPECT_EQ(runs_of(log),
            (std::vector<std::pair<std::size_t, std::size_t>>{{0, 10}, {10, 12}, {12, 16}}));
}

TEST(LogIntegrity, ACutShortSessionAndAForeignFileAreNamed) {
  TempDir dir;
  const SessionLog cut = load_session_log(write_session(dir.path() / "a", {}, true, false));
  const auto problems = integrity_problems(cut);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].kind, Kind::cut_short);
  EXPECT_NE(problems[0].text.find("no session end record"), std::string::npos);

  const SessionLog foreign = load_session_log(write_session(dir.path() / "b", {}, false, true));
  EXPECT_TRUE(has_problem(integrity_problems(foreign), Kind::not_a_session_log));
  EXPECT_NE(describe(integrity_problems(foreign)).find("no session start record"),
            std::string::npos);
}

TEST(LogIntegrity, ATruncatedTailIsNamed) {
  TempDir dir;
  const fs::path path = write_session(dir.path());
  std::vector<std::uint8_t> bytes = read_bytes(path);
  bytes.resize(bytes.size() - 5);  // inside the end record
  write_bytes(path, bytes);
  const auto problems = integrity_problems(load_session_log(path));
  EXPECT_TRUE(has_problem(problems, Kind::truncated)) << describe(problems);
  EXPECT_TRUE(has_problem(problems, Kind::cut_short)) << describe(problems);
  EXPECT_NE(describe(problems).find("truncated: the file ends inside an event"), std::string::npos);
}

// Damage that takes only a USB report loses no sample, but the samples on either side are still
// not to be filtered as one signal: the run is cut there too.
TEST(LogIntegrity, DamageCutsTheRunsEvenWhenNoSampleIsLost) {
  TempDir dir;
  const fs::path path = write_session(dir.path());
  // The USB report after sample 8: event 1 is the start, then sample, report, sample, ...
  LcmLogReader reader(path);
  LogEvent event;
  std::uint64_t offset = 0;
  for (int i = 0; reader.next(event); ++i) {
    if (i == 1 + 2 * 8 + 1) offset = event.file_offset;
  }
  ASSERT_GT(offset, 0u);
  std::vector<std::uint8_t> bytes = read_bytes(path);
  for (std::uint64_t k = offset; k < offset + 8; ++k) bytes[k] = 0x5A;  // its sync word and more
  write_bytes(path, bytes);

  const SessionLog log = load_session_log(path);
  ASSERT_EQ(log.samples.size(), 20u);
  EXPECT_TRUE(log.missing_sequence_numbers().empty());
  const auto problems = integrity_problems(log);
  ASSERT_EQ(problems.size(), 1u) << describe(problems);
  EXPECT_EQ(problems[0].kind, Kind::damaged);
  EXPECT_EQ(runs_of(log), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 9}, {9, 20}}));
}

}  // namespace
}  // namespace furuta::session_log::log_integrity_test
