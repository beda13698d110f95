#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "furuta/session_log/lcm_log.hpp"
#include "test_support.hpp"

namespace furuta::session_log {
namespace {

using testing::Event;
using testing::TempDir;

// Events' bytes and the skipped bytes together make up the whole input: nothing is read twice,
// nothing is left unaccounted for.
std::uint64_t accounted_bytes(const std::vector<LogEvent>& events, const LogReadStats& stats) {
  std::uint64_t total = stats.bytes_skipped;
  for (const LogEvent& e : events) total += 28 + e.channel.size() + e.data.size();
  return total;
}

std::vector<LogEvent> read_bytes(const std::vector<std::uint8_t>& bytes, LogReadStats& stats) {
  return read_lcm_log_bytes(bytes, stats);
}

TEST(LcmLogReader, ReadsEveryEventOfAnIntactLog) {
  const std::vector<Event> events = testing::pattern_events(40);
  const std::vector<std::uint8_t> bytes = testing::encode_log(events);
  LogReadStats stats;
  const std::vector<LogEvent> got = read_bytes(bytes, stats);
  ASSERT_EQ(got.size(), events.size());
  std::uint64_t offset = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(testing::same_event(got[i], events[i])) << i;
    EXPECT_EQ(got[i].file_offset, offset);
    offset += testing::encoded_size(events[i]);
  }
  EXPECT_EQ(stats.events, 40u);
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_EQ(stats.bytes_skipped, 0u);
  EXPECT_FALSE(stats.truncated_tail);
  EXPECT_EQ(stats.readable_prefix_bytes, bytes.size());
}

TEST(LcmLogReader, FileAndBufferGiveTheSameAnswer) {
  // The same core behind both; checked on a log with a damaged middle and a cut-off tail, bigger
  // than the file reader's window.
  std::vector<Event> events = testing::pattern_events(150);
  std::vector<std::uint8_t> bytes = testing::encode_log(events);
  ASSERT_GT(bytes.size(), 64u * 1024u);
  std::size_t middle = 0;
  for (int i = 0; i < 100; ++i)
    middle += testing::encoded_size(events[static_cast<std::size_t>(i)]);
  for (std::size_t k = 24; k < 28; ++k) bytes[middle + k] = 0xFF;  // event 100's data length
  bytes.resize(bytes.size() - 10);
  std::vector<std::uint8_t> garbage(70'000, 0xED);  // a window-sized run of near-sync bytes
  bytes.insert(bytes.begin() + 1000, garbage.begin(), garbage.end());

  TempDir dir;
  const auto file = dir.path() / "x.lcmlog";
  testing::write_bytes(file, bytes);
  LogReadStats from_file;
  LogReadStats from_buffer;
  const std::vector<LogEvent> a = testing::read_log(file, from_file);
  const std::vector<LogEvent> b = read_bytes(bytes, from_buffer);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].file_offset, b[i].file_offset);
    EXPECT_EQ(a[i].event_number, b[i].event_number);
    EXPECT_EQ(a[i].channel, b[i].channel);
    EXPECT_EQ(a[i].data, b[i].data);
  }
  EXPECT_EQ(from_file.events, from_buffer.events);
  EXPECT_EQ(from_file.damaged_regions, from_buffer.damaged_regions);
  EXPECT_EQ(from_file.bytes_skipped, from_buffer.bytes_skipped);
  EXPECT_EQ(from_file.truncated_tail, from_buffer.truncated_tail);
  EXPECT_EQ(from_file.readable_prefix_bytes, from_buffer.readable_prefix_bytes);
  EXPECT_GE(from_file.damaged_regions, 2u);
  EXPECT_TRUE(from_file.truncated_tail);
  EXPECT_EQ(accounted_bytes(a, from_file), bytes.size());
}

TEST(LcmLogReader, ZeroLengthFile) {
  TempDir dir;
  const auto file = dir.path() / "empty.lcmlog";
  testing::write_bytes(file, {});
  LogReadStats stats;
  stats.events = 99;  // overwritten, not accumulated
  EXPECT_TRUE(testing::read_log(file, stats).empty());
  EXPECT_EQ(stats.events, 0u);
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_EQ(stats.bytes_skipped, 0u);
  EXPECT_FALSE(stats.truncated_tail);
  EXPECT_EQ(stats.readable_prefix_bytes, 0u);
  EXPECT_TRUE(read_bytes({}, stats).empty());
  EXPECT_EQ(stats.events, 0u);
}

TEST(LcmLogReader, MissingFileOrDirectoryThrowsNamingIt) {
  TempDir dir;
  try {
    LcmLogReader reader(dir.path() / "nope.lcmlog");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.lcmlog"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LcmLogReader reader(dir.path()), std::runtime_error);
}

TEST(LcmLogReader, TruncationAtEveryOffset) {
  const std::vector<Event> events = testing::pattern_events(6);
  const std::vector<std::uint8_t> full = testing::encode_log(events);
  std::vector<std::uint64_t> ends;
  std::uint64_t end = 0;
  for (const Event& e : events) ends.push_back(end += testing::encoded_size(e));

  for (std::size_t cut = 0; cut <= full.size(); ++cut) {
    SCOPED_TRACE(cut);
    const std::vector<std::uint8_t> bytes(full.begin(), full.begin() + static_cast<long>(cut));
    LogReadStats stats;
    const std::vector<LogEvent> got = read_bytes(bytes, stats);
    const auto complete =
        static_cast<std::size_t>(std::upper_bound(ends.begin(), ends.end(), cut) - ends.begin());
    const std::uint64_t prefix = complete == 0 ? 0 : ends[complete - 1];
    ASSERT_EQ(got.size(), complete);
    for (std::size_t i = 0; i < got.size(); ++i)
      EXPECT_TRUE(testing::same_event(got[i], events[i]));
    EXPECT_EQ(stats.events, complete);
    EXPECT_EQ(stats.damaged_regions, 0u);
    EXPECT_EQ(stats.truncated_tail, cut != prefix);
    EXPECT_EQ(stats.readable_prefix_bytes, prefix);
    EXPECT_EQ(stats.bytes_skipped, cut - prefix);
  }
}

TEST(LcmLogReader, GarbagePrefixIsSkippedAsOneRegion) {
  const std::vector<Event> events = testing::pattern_events(8);
  std::vector<std::uint8_t> bytes = testing::encode_log(events);
  std::mt19937 rng(7);
  std::vector<std::uint8_t> garbage(333);
  for (auto& b : garbage) b = static_cast<std::uint8_t>(rng());
  // A sync word and a plausible header inside the garbage, whose event does not land anywhere.
  const std::vector<std::uint8_t> fake = {0xED, 0xA1, 0xDA, 0x01, 0, 0, 0,   0,   0,   0,  0,
                                          1,    0,    0,    0,    0, 0, 0,   0,   2,   0,  0,
                                          0,    4,    0,    0,    0, 9, 'A', 'B', 'C', 'D'};
  std::copy(fake.begin(), fake.end(), garbage.begin() + 100);
  bytes.insert(bytes.begin(), garbage.begin(), garbage.end());

  LogReadStats stats;
  const std::vector<LogEvent> got = read_bytes(bytes, stats);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
  EXPECT_EQ(got[0].file_offset, garbage.size());
  EXPECT_EQ(stats.damaged_regions, 1u);
  EXPECT_EQ(stats.bytes_skipped, garbage.size());
  EXPECT_FALSE(stats.truncated_tail);
  EXPECT_EQ(stats.readable_prefix_bytes, 0u);  // the damage comes first
}

TEST(LcmLogReader, HugeLengthFieldsAreDamageNotAllocations) {
  std::vector<Event> events = testing::pattern_events(5);
  const std::vector<std::uint8_t> intact = testing::encode_log(events);
  const std::size_t third = testing::encoded_size(events[0]) + testing::encoded_size(events[1]);

  struct Case {
    std::uint32_t channel_len;
    std::uint32_t data_len;
  };
  for (const Case c : {Case{0xFFFFFFFF, 0xFFFFFFFF}, Case{0x7FFFFFFF, 0}, Case{5, 0xFFFFFFF0},
                       Case{0, 10}, Case{1000, 0}, Case{10, (1u << 28) + 1}, Case{10, 1u << 28}}) {
    SCOPED_TRACE(std::to_string(c.channel_len) + "/" + std::to_string(c.data_len));
    std::vector<std::uint8_t> bytes = intact;
    for (int i = 0; i < 4; ++i) {
      bytes[third + 20 + static_cast<std::size_t>(i)] =
          static_cast<std::uint8_t>(c.channel_len >> (24 - 8 * i));
      bytes[third + 24 + static_cast<std::size_t>(i)] =
          static_cast<std::uint8_t>(c.data_len >> (24 - 8 * i));
    }
    LogReadStats stats;
    const std::vector<LogEvent> got = read_bytes(bytes, stats);
    ASSERT_EQ(got.size(), 4u);
    EXPECT_TRUE(testing::same_event(got[1], events[1]));
    EXPECT_TRUE(testing::same_event(got[2], events[3]));
    EXPECT_EQ(stats.damaged_regions, 1u);
    EXPECT_EQ(stats.bytes_skipped, testing::encoded_size(events[2]));
    EXPECT_EQ(stats.readable_prefix_bytes, third);
    EXPECT_FALSE(stats.truncated_tail);
  }

  // The last event claiming more than the file holds: what a crash mid-event looks like.
  std::vector<std::uint8_t> bytes = intact;
  const std::size_t last = intact.size() - testing::encoded_size(events[4]);
  bytes[last + 24] = 0x0F;  // 251 MiB of data, within LCM's limit, far beyond the file
  LogReadStats stats;
  EXPECT_EQ(read_bytes(bytes, stats).size(), 4u);
  EXPECT_TRUE(stats.truncated_tail);
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_EQ(stats.readable_prefix_bytes, last);
}

TEST(LcmLogReader, SyncWordsInsideDataDoNotConfuseAnIntactLog) {
  std::vector<Event> events = testing::pattern_events(4);
  std::vector<std::uint8_t> inner;
  testing::append_event(inner, Event{0, 1, "FAKE", {1, 2, 3}});
  events[1].data = inner;
  events[2].data = {0xED, 0xA1, 0xDA, 0x01, 0xED, 0xA1, 0xDA};
  const std::vector<std::uint8_t> bytes = testing::encode_log(events);
  LogReadStats stats;
  const std::vector<LogEvent> got = read_bytes(bytes, stats);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
  EXPECT_EQ(stats.damaged_regions, 0u);
}

TEST(LcmLogReader, EveryFlippedByteLosesAtMostTheEventItHits) {
  std::vector<Event> events = testing::pattern_events(7);
  for (Event& e : events) e.data.resize(std::min<std::size_t>(e.data.size(), 40));
  const std::vector<std::uint8_t> intact = testing::encode_log(events);
  std::vector<std::uint64_t> starts;
  std::uint64_t offset = 0;
  for (const Event& e : events) {
    starts.push_back(offset);
    offset += testing::encoded_size(e);
  }
  const auto event_containing = [&](std::uint64_t at) {
    return static_cast<std::size_t>(std::upper_bound(starts.begin(), starts.end(), at) -
                                    starts.begin()) -
           1;
  };

  int runs = 0;
  for (const std::uint8_t mask : {std::uint8_t{0xFF}, std::uint8_t{0x01}, std::uint8_t{0x80}}) {
    for (std::size_t at = 0; at < intact.size(); ++at) {
      SCOPED_TRACE("offset " + std::to_string(at) + " mask " + std::to_string(mask));
      std::vector<std::uint8_t> bytes = intact;
      bytes[at] ^= mask;
      LogReadStats stats;
      const std::vector<LogEvent> got = read_bytes(bytes, stats);
      ++runs;
      EXPECT_EQ(stats.events, got.size());
      EXPECT_EQ(accounted_bytes(got, stats), bytes.size());
      const std::size_t hit = event_containing(at);
      // Every event returned at an original place, other than the one hit, is the original.
      std::size_t originals_back = 0;
      for (const LogEvent& e : got) {
        const auto it = std::find(starts.begin(), starts.end(), e.file_offset);
        ASSERT_NE(it, starts.end()) << "an event at " << e.file_offset << " was never written";
        const auto index = static_cast<std::size_t>(it - starts.begin());
        if (index != hit) {
          EXPECT_TRUE(testing::same_event(e, events[index]));
          ++originals_back;
        }
      }
      EXPECT_EQ(originals_back, events.size() - 1);
      // The readable prefix stops at the event hit: before it when the hit shows, after it when
      // the flip made its length shorter (data is not checksummed; the message decoder catches it).
      if (stats.damaged_regions > 0 || stats.truncated_tail) {
        EXPECT_GE(stats.readable_prefix_bytes, starts[hit]);
        EXPECT_LE(stats.readable_prefix_bytes, starts[hit] + testing::encoded_size(events[hit]));
      } else {
        EXPECT_EQ(stats.readable_prefix_bytes, bytes.size());
      }
    }
  }
  EXPECT_EQ(runs, 3 * static_cast<int>(intact.size()));
}

TEST(LcmLogReader, SeededRandomBytesNeverCrash) {
  std::mt19937_64 rng(20240601);
  std::uint64_t total_events = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<std::uint8_t> bytes(rng() % 3000);
    for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
    // Some trials are biased toward the sync word's bytes and small lengths, so headers are
    // found and examined, not just rejected at the first byte.
    if (trial % 2 == 1) {
      static constexpr std::uint8_t kBias[] = {0xED, 0xA1, 0xDA, 0x01, 0x00, 0x00, 0x05};
      for (auto& b : bytes) {
        if (rng() % 2 == 0) b = kBias[rng() % std::size(kBias)];
      }
    }
    LogReadStats stats;
    const std::vector<LogEvent> got = read_bytes(bytes, stats);
    total_events += got.size();
    ASSERT_EQ(accounted_bytes(got, stats), bytes.size()) << trial;
    for (const LogEvent& e : got) {
      ASSERT_GE(e.channel.size(), 1u);
      ASSERT_LE(e.channel.size(), 999u);
      ASSERT_LE(e.file_offset + 28 + e.channel.size() + e.data.size(), bytes.size());
    }
  }
  // Random bytes should almost never pass for an event (and, for this seed, never do).
  EXPECT_EQ(total_events, 0u);
}

TEST(LcmLogReader, SeededMutationsOfARealLogKeepTheUntouchedEvents) {
  const std::vector<Event> events = testing::pattern_events(30);
  const std::vector<std::uint8_t> intact = testing::encode_log(events);
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 200; ++trial) {
    SCOPED_TRACE(trial);
    std::vector<std::uint8_t> bytes = intact;
    // One burst of damage: overwrite, delete or insert a run of random bytes.
    const std::size_t at = rng() % bytes.size();
    const std::size_t n = 1 + rng() % 64;
    const auto pos = bytes.begin() + static_cast<long>(at);
    switch (rng() % 3) {
      case 0:
        for (std::size_t k = at; k < std::min(bytes.size(), at + n); ++k) {
          bytes[k] = static_cast<std::uint8_t>(rng());
        }
        break;
      case 1:
        bytes.erase(pos, bytes.begin() + static_cast<long>(std::min(bytes.size(), at + n)));
        break;
      default: {
        std::vector<std::uint8_t> junk(n);
        for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
        bytes.insert(pos, junk.begin(), junk.end());
      }
    }
    LogReadStats stats;
    const std::vector<LogEvent> got = read_bytes(bytes, stats);
    ASSERT_EQ(accounted_bytes(got, stats), bytes.size());
    // Events wholly before the damage come back unchanged and in order; so do those wholly after
    // it (found again by their content, as deletion and insertion shift them).
    std::size_t before = 0;
    std::uint64_t end = 0;
    while (before < events.size() && end + testing::encoded_size(events[before]) <= at) {
      end += testing::encoded_size(events[before]);
      ++before;
    }
    ASSERT_GE(got.size(), before);
    for (std::size_t i = 0; i < before; ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
    std::size_t found_after = 0;
    std::size_t expected_after = 0;
    std::uint64_t start = 0;
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::uint64_t size = testing::encoded_size(events[i]);
      if (start > at + n) {
        ++expected_after;
        found_after +=
            static_cast<std::size_t>(std::count_if(got.begin(), got.end(), [&](const LogEvent& e) {
              return testing::same_event(e, events[i]);
            }));
      }
      start += size;
    }
    EXPECT_EQ(found_after, expected_after);
  }
}

}  // namespace
}  // namespace furuta::session_log
