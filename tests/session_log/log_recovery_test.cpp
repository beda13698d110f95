#include <gtest/gtest.h>
#include <time.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <random>

#include "child_process.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "test_support.hpp"

namespace furuta::session_log {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::Event;
using testing::TempDir;

fs::path part_path(const fs::path& logs_dir, const std::string& name) {
  return logs_dir / ".partial" / (name + ".lcmlog.part");
}

TEST(RecoverPartialLogs, NothingToDoWithoutAPartialDirectory) {
  TempDir dir;
  EXPECT_TRUE(recover_partial_logs(dir.path()).empty());
  EXPECT_TRUE(recover_partial_logs(dir.path() / "missing").empty());
}

TEST(RecoverPartialLogs, RemovesAPartWithoutOneWholeEvent) {
  // furutad killed between creating its log and the first sync leaves an empty .part, or a start
  // record cut short; lcm-logplayer refuses an empty log, and there is nothing in it to keep.
  TempDir dir;
  fs::create_directories(dir.path() / ".partial");
  std::ofstream(dir.path() / ".partial" / "empty.lcmlog.part").flush();
  const std::vector<std::uint8_t> torn{0xED, 0xA1, 0xDA, 0x01, 0, 0, 0};
  std::ofstream(dir.path() / ".partial" / "torn.lcmlog.part", std::ios::binary)
      .write(reinterpret_cast<const char*>(torn.data()), static_cast<std::streamsize>(torn.size()));
  const std::vector<RecoveredLog> recovered = recover_partial_logs(dir.path());
  ASSERT_EQ(recovered.size(), 2u);
  for (const RecoveredLog& r : recovered) {
    EXPECT_TRUE(r.discarded) << r.path;
    EXPECT_FALSE(fs::exists(r.path)) << r.path;
  }
  EXPECT_EQ(recovered[1].bytes_dropped, torn.size());
  EXPECT_TRUE(fs::is_empty(dir.path() / ".partial"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(RecoverPartialLogs, CutsATornTailAndMarksTheLogIncomplete) {
  TempDir dir;
  const std::vector<Event> events = testing::pattern_events(9);
  fs::create_directories(dir.path() / ".partial");
  std::vector<std::uint8_t> bytes = testing::encode_log(events);
  const std::size_t intact = bytes.size();
  // Half of a tenth event: what a crash in the middle of a write leaves.
  std::vector<std::uint8_t> torn;
  testing::append_event(torn, testing::pattern_event(9));
  bytes.insert(bytes.end(), torn.begin(), torn.begin() + 40);
  testing::write_bytes(part_path(dir.path(), "s"), bytes);
  // Not ours: left alone.
  testing::write_bytes(dir.path() / ".partial" / "notes.txt", {1, 2, 3});

  const std::vector<RecoveredLog> recovered = recover_partial_logs(dir.path());
  ASSERT_EQ(recovered.size(), 1u);
  EXPECT_EQ(recovered[0].path, dir.path() / "s.incomplete.lcmlog");
  EXPECT_EQ(recovered[0].bytes_dropped, 40u);
  EXPECT_EQ(recovered[0].stats.events, 9u);
  EXPECT_TRUE(recovered[0].stats.truncated_tail);
  EXPECT_EQ(recovered[0].stats.damaged_regions, 0u);
  EXPECT_EQ(fs::file_size(recovered[0].path), intact);
  EXPECT_FALSE(fs::exists(part_path(dir.path(), "s")));
  EXPECT_TRUE(fs::exists(dir.path() / ".partial" / "notes.txt"));

  LogReadStats stats;
  const std::vector<LogEvent> got = testing::read_log(recovered[0].path, stats);
  ASSERT_EQ(got.size(), 9u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
  EXPECT_FALSE(stats.truncated_tail);

  // Idempotent: a second run finds nothing and changes nothing.
  EXPECT_TRUE(recover_partial_logs(dir.path()).empty());
  EXPECT_EQ(fs::file_size(recovered[0].path), intact);
}

TEST(RecoverPartialLogs, KeepsOnlyThePrefixBeforeDamage) {
  TempDir dir;
  const std::vector<Event> events = testing::pattern_events(6);
  std::vector<std::uint8_t> bytes = testing::encode_log(events);
  const std::size_t prefix = testing::encoded_size(events[0]) + testing::encoded_size(events[1]);
  bytes[prefix] = 0x00;  // event 2's sync word
  fs::create_directories(dir.path() / ".partial");
  testing::write_bytes(part_path(dir.path(), "d"), bytes);

  const std::vector<RecoveredLog> recovered = recover_partial_logs(dir.path());
  ASSERT_EQ(recovered.size(), 1u);
  EXPECT_EQ(recovered[0].stats.damaged_regions, 1u);
  EXPECT_EQ(recovered[0].stats.events, 5u);  // as read; the recovered file keeps the prefix
  EXPECT_EQ(recovered[0].bytes_dropped, bytes.size() - prefix);
  LogReadStats stats;
  const std::vector<LogEvent> got = testing::read_log(recovered[0].path, stats);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(stats.damaged_regions, 0u);
}

TEST(RecoverPartialLogs, RecoversAWriterThatNeverFinishedAndNeverReplacesALog) {
  TempDir dir;
  const std::vector<Event> events = testing::pattern_events(3);
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE(round);
    {
      LcmLogWriter writer({dir.path(), 1000ms}, "same");
      for (const Event& e : events) {
        ASSERT_EQ(writer.write(e.channel, e.utime, e.data), LogWriteStatus::ok);
      }
    }  // gone without finish(), as in a crash
    const std::vector<RecoveredLog> recovered = recover_partial_logs(dir.path());
    ASSERT_EQ(recovered.size(), 1u);
    // A second session of the same name, also cut short, does not replace the first.
    EXPECT_EQ(recovered[0].path,
              dir.path() / (round == 0 ? "same.incomplete.lcmlog" : "same-2.incomplete.lcmlog"));
    EXPECT_EQ(recovered[0].bytes_dropped, 0u);
    EXPECT_EQ(recovered[0].stats.events, 3u);
  }
  EXPECT_EQ(testing::read_bytes(dir.path() / "same.incomplete.lcmlog"),
            testing::read_bytes(dir.path() / "same-2.incomplete.lcmlog"));
}

// --- SIGKILL at random points ---

struct TrialSetup {
  int events_per_sync = 1;
  int syncs_before_kill = 0;
  long extra_delay_us = 0;
};

// The child: writes pattern events, forcing a sync every events_per_sync, and reports the number of
// events synced after every sync that completed (and 0 once its file exists).
int crash_child(const fs::path& logs_dir, int events_per_sync, const testing::Pipe& pipe) {
  LcmLogWriter writer({logs_dir, std::chrono::hours(1)}, "crash");
  if (!pipe.send(std::uint64_t{0})) return 3;
  for (std::int64_t i = 0; i < 20'000; ++i) {
    const Event e = testing::pattern_event(i);
    if (writer.write(e.channel, e.utime, e.data) != LogWriteStatus::ok) return 4;
    if ((i + 1) % events_per_sync == 0) {
      if (writer.sync_if_due(std::chrono::steady_clock::now(), true) != LogWriteStatus::ok) {
        return 5;
      }
      if (!pipe.send(static_cast<std::uint64_t>(i + 1))) return 6;
    }
  }
  // Not killed in time: stop without finishing, as a crash would.
  return 0;
}

struct TrialResult {
  std::uint64_t synced = 0;
  std::uint64_t recovered_events = 0;
  std::uint64_t bytes_dropped = 0;
};

TrialResult run_crash_trial(const TrialSetup& setup) {
  TempDir dir;
  testing::Pipe pipe;
  const pid_t pid = testing::fork_child([&] {
    pipe.close_read();
    return crash_child(dir.path(), setup.events_per_sync, pipe);
  });
  pipe.close_write();
  TrialResult result;
  std::uint64_t value = 0;
  int reports = 0;
  // Kill once the child has completed the chosen number of syncs, plus a random moment more:
  // it keeps writing meanwhile, so the kill lands anywhere in a write, a buffer flush or a sync.
  while (reports <= setup.syncs_before_kill && pipe.receive(value)) {
    result.synced = value;
    ++reports;
  }
  if (setup.extra_delay_us > 0) {
    const timespec delay{0, setup.extra_delay_us * 1000};
    ::nanosleep(&delay, nullptr);
  }
  ::kill(pid, SIGKILL);
  const int code = testing::wait_child(pid);
  EXPECT_TRUE(code == 128 + SIGKILL || code == 0) << "child ended with " << code;
  // Whatever it reported before dying counts: every one of those syncs completed.
  while (pipe.receive(value)) result.synced = value;
  if (reports == 0) {
    ADD_FAILURE() << "the child never created its log";
    return result;
  }

  const std::vector<RecoveredLog> recovered = recover_partial_logs(dir.path());
  EXPECT_EQ(recovered.size(), 1u);
  if (recovered.size() != 1) return result;
  result.bytes_dropped = recovered[0].bytes_dropped;
  if (recovered[0].discarded) {
    // Killed before one whole event reached the file: nothing to keep, nothing may have synced.
    EXPECT_EQ(result.synced, 0u);
    EXPECT_EQ(recovered[0].stats.events, 0u);
    EXPECT_FALSE(fs::exists(recovered[0].path));
    EXPECT_TRUE(recover_partial_logs(dir.path()).empty());
    return result;
  }
  EXPECT_EQ(recovered[0].path, dir.path() / "crash.incomplete.lcmlog");
  EXPECT_EQ(recovered[0].stats.damaged_regions, 0u);

  LogReadStats stats;
  const std::vector<LogEvent> got = testing::read_log(recovered[0].path, stats);
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_EQ(stats.bytes_skipped, 0u);
  EXPECT_FALSE(stats.truncated_tail);
  EXPECT_GE(got.size(), result.synced);
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (!testing::same_event(got[i], testing::pattern_event(static_cast<std::int64_t>(i)))) {
      ADD_FAILURE() << "recovered event " << i << " differs from what was written";
      break;
    }
  }
  result.recovered_events = got.size();
  EXPECT_TRUE(recover_partial_logs(dir.path()).empty());
  return result;
}

TEST(RecoverPartialLogs, FiftySigkilledWritersLoseNothingThatWasSynced) {
  std::mt19937 rng(4242);
  int trials = 0;
  int torn_tails = 0;
  std::uint64_t synced_total = 0;
  std::uint64_t recovered_total = 0;
  std::uint64_t lost_beyond_sync = 0;
  for (int trial = 0; trial < 50; ++trial) {
    SCOPED_TRACE(trial);
    TrialSetup setup;
    // Frequent syncs put the kill mostly inside fdatasync; long runs between syncs put it inside
    // writes and stdio buffer flushes, which tear events.
    setup.events_per_sync = trial % 2 == 0 ? std::uniform_int_distribution<int>(1, 25)(rng)
                                           : std::uniform_int_distribution<int>(100, 400)(rng);
    setup.syncs_before_kill = std::uniform_int_distribution<int>(0, 4)(rng);
    setup.extra_delay_us = std::uniform_int_distribution<long>(0, 3000)(rng);
    const TrialResult r = run_crash_trial(setup);
    ++trials;
    torn_tails += r.bytes_dropped > 0 ? 1 : 0;
    synced_total += r.synced;
    recovered_total += r.recovered_events;
    if (r.recovered_events < r.synced) lost_beyond_sync += r.synced - r.recovered_events;
  }
  EXPECT_EQ(trials, 50);
  EXPECT_EQ(lost_beyond_sync, 0u);
  RecordProperty("trials", trials);
  RecordProperty("torn_tails", torn_tails);
  RecordProperty("events_synced", static_cast<int>(synced_total));
  RecordProperty("events_recovered", static_cast<int>(recovered_total));
  std::printf(
      "SIGKILL trials: %d, torn tails cut: %d, events synced: %llu, recovered: %llu, "
      "lost beyond the last sync: %llu\n",
      trials, torn_tails, static_cast<unsigned long long>(synced_total),
      static_cast<unsigned long long>(recovered_total),
      static_cast<unsigned long long>(lost_beyond_sync));
}

}  // namespace
}  // namespace furuta::session_log
