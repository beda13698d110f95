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
using furuta::testing::events_of;
using furuta::testing::write_events;
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

constexpr const char* kSession = "2024-06-01T12-00-00";
constexpr std::int64_t kSamples = 20;

rig_session_t record(std::int8_t event) {
  rig_session_t s{};
  s.event = event;
  s.session = kSession;
  s.period_ns = 16'000'000;
  s.end_reason = event == rig_session_t::EVENT_END ? "duration" : "";
  s.samples = event == rig_session_t::EVENT_END ? kSamples : 0;
  return s;
}

rig_sample_t sample(std::int64_t seq) {
  rig_sample_t s{};
  s.seq = seq;
  s.session = kSession;
  s.monotonic_ns = seq * 16'000'000;
  return s;
}

// A session of samples 0..19 (less `skipped`), each followed by a USB report; start and end
// records unless told otherwise; sealed when asked (as the daemon writes a log).
fs::path write_session(const fs::path& dir, const std::vector<std::int64_t>& skipped = {},
                       bool with_start = true, bool with_end = true, bool sealed = false) {
  LcmLogWriter writer({dir, 1000ms}, "session");
  std::int64_t utime = 0;
  const auto put = [&](const char* channel, const std::vector<std::uint8_t>& data) {
    EXPECT_EQ(writer.write(channel, utime++, data), LogWriteStatus::ok);
  };
  if (with_start) put(kChannelSession, encode(record(rig_session_t::EVENT_START)));
  for (std::int64_t seq = 0; seq < kSamples; ++seq) {
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
  if (sealed) {
    EXPECT_EQ(write_seal(writer, kSession, kSamples - static_cast<std::int64_t>(skipped.size())),
              LogWriteStatus::ok);
  }
  fs::path path;
  EXPECT_EQ(writer.finish(&path), LogWriteStatus::ok);
  return path;
}

std::vector<std::pair<std::size_t, std::size_t>> runs_of(const SessionLog& log) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const SampleRun& r : contiguous_sample_runs(log)) out.emplace_back(r.begin, r.end);
  return out;
}

std::vector<Kind> kinds_of(const std::vector<LogProblem>& problems) {
  std::vector<Kind> kinds;
  for (const auto& p : problems) kinds.push_back(p.kind);
  return kinds;
}

TEST(LogIntegrity, AWholeSessionIsIntactAndOneRun) {
  TempDir dir;
  const SessionLog log = load_session_log(write_session(dir.path()));
  EXPECT_TRUE(integrity_problems(log).empty()) << describe(integrity_problems(log));
  EXPECT_EQ(runs_of(log), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 20}}));
  // Written without a seal: read, with a note saying what that means.
  EXPECT_FALSE(log.seal);
  ASSERT_EQ(integrity_notes(log).size(), 1u);
  EXPECT_NE(integrity_notes(log)[0].find("no seal"), std::string::npos);
}

TEST(LogIntegrity, ASealedSessionMatchesItsSealAndTwoCopiesShareTheirDigest) {
  TempDir dir;
  const fs::path path = write_session(dir.path() / "a", {}, true, true, true);
  const SessionLog log = load_session_log(path);
  ASSERT_TRUE(log.seal);
  EXPECT_TRUE(log.seal_digest_matches);
  EXPECT_EQ(log.seal->events, 1 + 2 * kSamples + 1);
  EXPECT_EQ(log.seal->samples, kSamples);
  EXPECT_TRUE(integrity_problems(log).empty()) << describe(integrity_problems(log));
  EXPECT_TRUE(integrity_notes(log).empty());
  EXPECT_EQ(log.digest_hex.size(), 64u);

  fs::create_directories(dir.path() / "b");
  fs::copy_file(path, dir.path() / "b" / "copy.lcmlog");
  EXPECT_EQ(load_session_log(dir.path() / "b" / "copy.lcmlog").digest_hex, log.digest_hex);
  // Another session with the same samples is another log.
  const SessionLog other = load_session_log(write_session(dir.path() / "c", {3}, true, true, true));
  EXPECT_NE(other.digest_hex, log.digest_hex);
}

// Each change a log can suffer after it was written, on a sealed log: each is named, and none
// leaves the log intact.
TEST(LogIntegrity, AChangedSealedLogIsNeverIntact) {
  TempDir dir;
  const fs::path original = write_session(dir.path(), {}, true, true, true);
  const std::vector<testing::Event> events = events_of(original);
  const std::vector<std::size_t> samples = furuta::testing::events_on(events, kChannelSample);
  const auto check = [&](const char* name, std::vector<testing::Event> changed,
                         std::vector<Kind> expected) {
    const SessionLog log = load_session_log(write_events(dir.path() / name, changed));
    const auto problems = integrity_problems(log);
    EXPECT_EQ(kinds_of(problems), expected) << name << ": " << describe(problems);
    EXPECT_EQ(usable_in_part(problems),
              std::find(expected.begin(), expected.end(), Kind::altered) == expected.end() &&
                  std::find(expected.begin(), expected.end(), Kind::joined) == expected.end())
        << name;
  };
  {  // one bit of one sample's value: the message still decodes
    auto e = events;
    e[samples[7]].data.back() ^= 0x10;
    check("bit", e, {Kind::altered});
  }
  {  // one sample twice
    auto e = events;
    e.insert(e.begin() + static_cast<std::ptrdiff_t>(samples[7]) + 1, e[samples[7]]);
    check("duplicated", e, {Kind::out_of_order, Kind::time_goes_back, Kind::altered});
  }
  {  // two samples swapped
    auto e = events;
    std::swap(e[samples[7]], e[samples[8]]);
    check("reordered", e, {Kind::out_of_order, Kind::time_goes_back, Kind::altered});
  }
  {  // the first samples removed, the end record kept
    auto e = events;
    for (int k = 4; k >= 0; --k) e.erase(e.begin() + static_cast<std::ptrdiff_t>(samples[k]));
    check("head_cut", e, {Kind::missing_samples, Kind::altered});
  }
  {  // the last samples removed, the end record kept
    auto e = events;
    for (int k = kSamples - 1; k >= kSamples - 3; --k) {
      e.erase(e.begin() + static_cast<std::ptrdiff_t>(samples[static_cast<std::size_t>(k)]));
    }
    check("tail_cut", e, {Kind::count_mismatch, Kind::altered});
  }
  {  // every sample removed
    auto e = events;
    std::erase_if(e, [](const testing::Event& x) { return x.channel == kChannelSample; });
    check("no_samples", e, {Kind::count_mismatch, Kind::altered});
  }
  {  // one sample's time moved back, the rest as written
    auto e = events;
    rig_sample_t s = sample(7);
    s.monotonic_ns -= 4'300'000'000;
    e[samples[7]].data = encode(s);
    check("time_back", e, {Kind::time_goes_back, Kind::altered});
  }
  {  // the seal's own header: its time, then its number
    auto e = events;
    e.back().utime += 1;
    check("seal_time", e, {Kind::altered});
    e = events;
    e.back().number += 1;
    check("seal_number", e, {Kind::altered});
  }
  {  // the file twice, as `cat a a` makes it
    auto e = events;
    e.insert(e.end(), events.begin(), events.end());
    check("joined", e, {Kind::joined, Kind::out_of_order, Kind::time_goes_back});
  }
}

// Without a seal, what the sequence numbers, times and counts can show is still found.
TEST(LogIntegrity, AnUnsealedLogIsCheckedByItsNumbersTimesAndCounts) {
  TempDir dir;
  const std::vector<testing::Event> events = events_of(write_session(dir.path()));
  const std::vector<std::size_t> samples = furuta::testing::events_on(events, kChannelSample);
  auto duplicated = events;
  duplicated.insert(duplicated.begin() + static_cast<std::ptrdiff_t>(samples[3]),
                    events[samples[3]]);
  EXPECT_EQ(
      kinds_of(integrity_problems(load_session_log(write_events(dir.path() / "dup", duplicated)))),
      (std::vector<Kind>{Kind::out_of_order, Kind::time_goes_back}));
  auto head_cut = events;
  head_cut.erase(head_cut.begin() + static_cast<std::ptrdiff_t>(samples[0]));
  const auto problems =
      integrity_problems(load_session_log(write_events(dir.path() / "head", head_cut)));
  EXPECT_EQ(kinds_of(problems), (std::vector<Kind>{Kind::missing_samples}));
  EXPECT_NE(describe(problems).find("sequence numbers 0)"), std::string::npos)
      << describe(problems);
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
  ASSERT_EQ(problems.size(), 1u) << describe(problems);
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
