#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/resource.h>

#include <chrono>
#include <fstream>

#include "child_process.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "test_support.hpp"

namespace furuta::session_log {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::Event;
using testing::TempDir;

LogWriteStatus write_event(LcmLogWriter& writer, const Event& e) {
  return writer.write(e.channel, e.utime, e.data);
}

TEST(LcmLogWriter, WritesTheLcmLoggerLayoutByteForByte) {
  TempDir dir;
  const std::vector<Event> events = testing::pattern_events(12);
  LcmLogWriter writer({dir.path(), 1000ms}, "session-1");
  EXPECT_EQ(writer.partial_path(), dir.path() / ".partial" / "session-1.lcmlog.part");
  for (const Event& e : events) ASSERT_EQ(write_event(writer, e), LogWriteStatus::ok);
  EXPECT_EQ(writer.events_written(), 12u);

  fs::path final_path;
  ASSERT_EQ(writer.finish(&final_path), LogWriteStatus::ok);
  EXPECT_EQ(final_path, dir.path() / "session-1.lcmlog");
  // Event numbers from 0, big-endian fields, channel then data: the bytes of the format itself.
  EXPECT_EQ(testing::read_bytes(final_path), testing::encode_log(events));
  EXPECT_FALSE(fs::exists(writer.partial_path()));
  EXPECT_TRUE(fs::is_empty(dir.path() / ".partial"));
}

TEST(LcmLogWriter, CreatesTheLogsDirectoryAndItsPartialDirectory) {
  TempDir dir;
  const fs::path logs = dir.path() / "a" / "b";
  LcmLogWriter writer({logs, 1000ms}, "s");
  EXPECT_TRUE(fs::is_directory(logs / ".partial"));
  EXPECT_TRUE(fs::exists(logs / ".partial" / "s.lcmlog.part"));
  fs::path final_path;
  ASSERT_EQ(writer.finish(&final_path), LogWriteStatus::ok);
  EXPECT_EQ(fs::file_size(final_path), 0u);  // an empty session is an empty, valid log
}

TEST(LcmLogWriter, SyncsWhenDueOrForced) {
  TempDir dir;
  LcmLogWriter writer({dir.path(), std::chrono::hours(1)}, "s");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Event> events = testing::pattern_events(4);
  for (int i = 0; i < 3; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);

  // Not due: the events are still in LogFile's stdio buffer (three small events, well under it).
  ASSERT_EQ(writer.sync_if_due(start), LogWriteStatus::ok);
  EXPECT_EQ(fs::file_size(writer.partial_path()), 0u);

  // Due: on disk, readable from the .part while the writer is still open.
  ASSERT_EQ(writer.sync_if_due(start + std::chrono::hours(2)), LogWriteStatus::ok);
  LogReadStats stats;
  EXPECT_EQ(testing::read_log(writer.partial_path(), stats).size(), 3u);
  EXPECT_FALSE(stats.truncated_tail);

  ASSERT_EQ(write_event(writer, events[3]), LogWriteStatus::ok);
  // The interval now counts from the last sync.
  ASSERT_EQ(writer.sync_if_due(start + std::chrono::hours(2) + 1s), LogWriteStatus::ok);
  EXPECT_EQ(testing::read_log(writer.partial_path(), stats).size(), 3u);
  ASSERT_EQ(writer.sync_if_due(start + std::chrono::hours(2) + 1s, true), LogWriteStatus::ok);
  const std::vector<LogEvent> got = testing::read_log(writer.partial_path(), stats);
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
}

TEST(LcmLogWriter, NeverHoldsMoreThanTheFlushIntervalOfDataUnsynced) {
  // A writer that fell behind writes a burst with no wall-clock sync between its events; what a
  // crash can lose must still span at most flush_interval of the events' own time (16 ms apart).
  TempDir dir;
  LcmLogWriter writer({dir.path(), 50ms}, "s");
  std::vector<Event> events = testing::pattern_events(9);
  for (Event& e : events) e.data.resize(40);  // all nine fit in LogFile's stdio buffer
  LogReadStats stats;
  auto on_disk = [&] { return testing::read_log(writer.partial_path(), stats).size(); };
  for (int i = 0; i < 4; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);
  EXPECT_EQ(on_disk(), 0u);  // 0..48 ms: within the interval, still buffered
  ASSERT_EQ(write_event(writer, events[4]), LogWriteStatus::ok);
  EXPECT_EQ(on_disk(), 4u);  // 64 ms would make 64 ms unsynced: the first four went to disk first
  for (int i = 5; i < 8; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);
  EXPECT_EQ(on_disk(), 4u);
  ASSERT_EQ(write_event(writer, events[8]), LogWriteStatus::ok);
  const std::vector<LogEvent> got = testing::read_log(writer.partial_path(), stats);
  ASSERT_EQ(got.size(), 8u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
}

TEST(LcmLogWriter, RejectsUnsafeNamesNamingThem) {
  TempDir dir;
  // Each with how the message shows it (control characters escaped, a NUL would end it).
  const std::vector<std::pair<std::string, std::string>> names = {
      {"", ""},
      {"a/b", "a/b"},
      {"/abs", "/abs"},
      {"..", ".."},
      {"../up", "../up"},
      {".", "."},
      {".hidden", ".hidden"},
      {"x..y", "x..y"},
      {"tab\there", "tab\\x09here"},
      {std::string("nul\0x", 5), "nul\\x00x"},
      {std::string(201, 'n'), std::string(201, 'n')},
  };
  for (const auto& [name, shown] : names) {
    SCOPED_TRACE(shown);
    try {
      LcmLogWriter writer({dir.path(), 1000ms}, name);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + shown + "'"), std::string::npos) << e.what();
    }
  }
  // Nothing was created for them.
  EXPECT_TRUE(fs::is_empty(dir.path()));
  LcmLogWriter fine({dir.path(), 1000ms}, "2024-06-01T12-00-00_bang-bang.run 3");
  EXPECT_EQ(fine.finish(), LogWriteStatus::ok);
}

TEST(LcmLogWriter, NeverOverwritesALogOrAPartLeftBehind) {
  TempDir dir;
  {
    LcmLogWriter first({dir.path(), 1000ms}, "s");
    ASSERT_EQ(first.write("A", 1, std::vector<std::uint8_t>{1}), LogWriteStatus::ok);
    ASSERT_EQ(first.finish(), LogWriteStatus::ok);
  }
  EXPECT_THROW(LcmLogWriter({dir.path(), 1000ms}, "s"), std::runtime_error);

  std::vector<std::uint8_t> left_behind;
  {
    LcmLogWriter crashed({dir.path(), 1000ms}, "t");
    ASSERT_EQ(crashed.write("A", 1, std::vector<std::uint8_t>{1, 2}), LogWriteStatus::ok);
  }  // never finished: its .part stays for recovery
  left_behind = testing::read_bytes(dir.path() / ".partial" / "t.lcmlog.part");
  ASSERT_FALSE(left_behind.empty());
  try {
    LcmLogWriter again({dir.path(), 1000ms}, "t");
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("t.lcmlog.part"), std::string::npos) << e.what();
  }
  EXPECT_EQ(testing::read_bytes(dir.path() / ".partial" / "t.lcmlog.part"), left_behind);
}

// Before: a second writer of a running session's name was told its .part was "left by an earlier
// session: recover it", and a recovery run meanwhile moved the live session's file away.
TEST(LcmLogWriter, ARunningSessionsPartIsInUseNotLeftByACrash) {
  TempDir dir;
  LcmLogWriter running({dir.path(), 1000ms}, "s");
  ASSERT_EQ(running.write("A", 1, std::vector<std::uint8_t>{1}), LogWriteStatus::ok);
  ASSERT_EQ(running.sync_if_due(std::chrono::steady_clock::now(), true), LogWriteStatus::ok);
  try {
    LcmLogWriter second({dir.path(), 1000ms}, "s");
    ADD_FAILURE() << "accepted";
  } catch (const LogNameInUse& e) {
    EXPECT_NE(std::string(e.what()).find("s.lcmlog.part: another session is writing it now"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find("recover it"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(recover_partial_logs(dir.path()).empty());
  ASSERT_TRUE(fs::exists(running.partial_path()));
  ASSERT_EQ(running.write("A", 2, std::vector<std::uint8_t>{2}), LogWriteStatus::ok);
  EXPECT_EQ(running.finish(), LogWriteStatus::ok);

  // A writer gone without finishing (its process killed: the kernel dropped its lock) left its
  // .part for recovery: that advice stands.
  { LcmLogWriter crashed({dir.path(), 1000ms}, "t"); }
  try {
    LcmLogWriter again({dir.path(), 1000ms}, "t");
    ADD_FAILURE() << "accepted";
  } catch (const LogNameInUse& e) {
    ADD_FAILURE() << "a leftover taken for a running session: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("left by an earlier session: recover it"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(recover_partial_logs(dir.path()).size(), 1u);
}

// A session finished under a name holds it too: a writer of that name is told to take another
// (the daemon then does), and the finished log is untouched.
TEST(LcmLogWriter, AFinishedLogsNameIsInUse) {
  TempDir dir;
  {
    LcmLogWriter first({dir.path(), 1000ms}, "s");
    ASSERT_EQ(first.write("A", 1, std::vector<std::uint8_t>{1}), LogWriteStatus::ok);
    ASSERT_EQ(first.finish(), LogWriteStatus::ok);
  }
  const std::vector<std::uint8_t> finished = testing::read_bytes(dir.path() / "s.lcmlog");
  try {
    LcmLogWriter second({dir.path(), 1000ms}, "s");
    ADD_FAILURE() << "accepted";
  } catch (const LogNameInUse& e) {
    EXPECT_NE(std::string(e.what()).find("s.lcmlog already exists"), std::string::npos) << e.what();
  }
  EXPECT_EQ(testing::read_bytes(dir.path() / "s.lcmlog"), finished);
  EXPECT_TRUE(fs::is_empty(dir.path() / ".partial"));
}

TEST(LcmLogWriter, ChannelsAndSizesLcmCannotCarryAreProgrammingErrors) {
  TempDir dir;
  LcmLogWriter writer({dir.path(), 1000ms}, "s");
  const std::vector<std::uint8_t> data{1};
  EXPECT_THROW(writer.write("", 0, data), std::invalid_argument);
  EXPECT_THROW(writer.write(std::string(64, 'C'), 0, data), std::invalid_argument);
  EXPECT_EQ(writer.write(std::string(63, 'C'), 0, data), LogWriteStatus::ok);
  EXPECT_EQ(writer.events_written(), 1u);
}

TEST(LcmLogWriter, FinishedMeansClosed) {
  TempDir dir;
  LcmLogWriter writer({dir.path(), 1000ms}, "s");
  ASSERT_EQ(writer.finish(), LogWriteStatus::ok);
  const std::vector<std::uint8_t> data{1};
  EXPECT_EQ(writer.write("A", 0, data), LogWriteStatus::closed);
  EXPECT_EQ(writer.sync_if_due(std::chrono::steady_clock::now(), true), LogWriteStatus::closed);
  EXPECT_EQ(writer.finish(), LogWriteStatus::closed);
  EXPECT_EQ(to_string(LogWriteStatus::ok), "ok");
  EXPECT_EQ(to_string(LogWriteStatus::disk_full), "disk_full");
  EXPECT_EQ(to_string(LogWriteStatus::io_error), "io_error");
  EXPECT_EQ(to_string(LogWriteStatus::closed), "closed");
}

TEST(LcmLogWriter, UnfinishedWriterLeavesEverythingWrittenInItsPart) {
  TempDir dir;
  const std::vector<Event> events = testing::pattern_events(5);
  fs::path part;
  {
    LcmLogWriter writer({dir.path(), std::chrono::hours(1)}, "s");
    for (const Event& e : events) ASSERT_EQ(write_event(writer, e), LogWriteStatus::ok);
    part = writer.partial_path();
  }
  EXPECT_EQ(testing::read_bytes(part), testing::encode_log(events));
  EXPECT_FALSE(fs::exists(dir.path() / "s.lcmlog"));
}

// What a child writing until the disk is full reports.
struct FullDiskReport {
  LogWriteStatus status = LogWriteStatus::ok;  // of the write or sync that failed
  LogWriteStatus write_after = LogWriteStatus::ok;
  LogWriteStatus sync_after = LogWriteStatus::ok;
  LogWriteStatus finish_after = LogWriteStatus::ok;
  std::uint64_t synced = 0;   // events synced before the failure
  std::uint64_t written = 0;  // events accepted before it
};

// Writes pattern events, syncing every 5, until something fails.
FullDiskReport write_until_full(const fs::path& logs_dir) {
  FullDiskReport r;
  LcmLogWriter writer({logs_dir, std::chrono::hours(1)}, "full");
  for (std::int64_t i = 0; i < 100'000 && r.status == LogWriteStatus::ok; ++i) {
    r.status = write_event(writer, testing::pattern_event(i));
    if (r.status == LogWriteStatus::ok && (i + 1) % 5 == 0) {
      r.status = writer.sync_if_due(std::chrono::steady_clock::now(), true);
      if (r.status == LogWriteStatus::ok) r.synced = static_cast<std::uint64_t>(i + 1);
    }
  }
  r.written = writer.events_written();
  const std::vector<std::uint8_t> one{1};
  r.write_after = writer.write("A", 0, one);
  r.sync_after = writer.sync_if_due(std::chrono::steady_clock::now(), true);
  r.finish_after = writer.finish();
  return r;
}

// What the disk kept: every synced event, intact, in order, and no damage before the cut.
void expect_synced_prefix_readable(const fs::path& part, const FullDiskReport& r) {
  EXPECT_EQ(r.status, LogWriteStatus::disk_full);
  EXPECT_EQ(r.write_after, LogWriteStatus::closed);
  EXPECT_EQ(r.sync_after, LogWriteStatus::closed);
  EXPECT_EQ(r.finish_after, LogWriteStatus::closed);
  EXPECT_GE(r.synced, 5u);
  LogReadStats stats;
  const std::vector<LogEvent> got = testing::read_log(part, stats);
  EXPECT_GE(got.size(), r.synced);
  EXPECT_LE(got.size(), r.written);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(testing::same_event(got[i], testing::pattern_event(static_cast<std::int64_t>(i))))
        << i;
  }
  EXPECT_EQ(stats.damaged_regions, 0u);
}

TEST(LcmLogWriter, LogsDirectoryRemovedMidSessionIsFoundAtTheNextSyncAndTheLogGoesOn) {
  // rm -r of the logs directory under a running session: writes into the unlinked file succeed
  // and would all be lost at close. The sync notices, writes everything back to a new .part in a
  // recreated directory and goes on writing there, so what comes while the session is being
  // stopped is kept too.
  TempDir dir;
  const fs::path logs = dir.path() / "logs";
  const std::vector<Event> events = testing::pattern_events(12);
  LcmLogWriter writer({logs, 1000ms}, "removed");
  for (int i = 0; i < 5; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);
  ASSERT_EQ(writer.sync_if_due(std::chrono::steady_clock::now(), true), LogWriteStatus::ok);
  for (int i = 5; i < 8; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);
  fs::remove_all(logs);
  EXPECT_EQ(writer.sync_if_due(std::chrono::steady_clock::now(), true),
            LogWriteStatus::file_removed);
  EXPECT_EQ(writer.removal_save_error(), "");
  ASSERT_TRUE(writer.is_open());
  ASSERT_TRUE(fs::exists(writer.partial_path()));
  for (int i = 8; i < 12; ++i) ASSERT_EQ(write_event(writer, events[i]), LogWriteStatus::ok);
  ASSERT_EQ(writer.sync_if_due(std::chrono::steady_clock::now(), true), LogWriteStatus::ok);

  // A crash now would keep all twelve, numbered on as if nothing had happened.
  LogReadStats stats;
  std::vector<LogEvent> got = testing::read_log(writer.partial_path(), stats);
  ASSERT_EQ(got.size(), events.size());
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_EQ(got[8].event_number, 8);

  fs::path final_path;
  ASSERT_EQ(writer.finish(&final_path), LogWriteStatus::ok);
  EXPECT_EQ(final_path, logs / "removed.lcmlog");
  got = testing::read_log(final_path, stats);
  ASSERT_EQ(got.size(), events.size());
  EXPECT_EQ(stats.damaged_regions, 0u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(testing::same_event(got[i], events[i])) << i;
  }
}

TEST(LcmLogWriter, ARemovedLogThatCannotBeSavedAgainSaysWhy) {
  // The logs directory removed and a regular file put in its place: the .part cannot be written
  // again, and the writer says so instead of claiming the data was saved.
  TempDir dir;
  const fs::path logs = dir.path() / "logs";
  const std::vector<Event> events = testing::pattern_events(3);
  LcmLogWriter writer({logs, 1000ms}, "removed");
  for (const Event& e : events) ASSERT_EQ(write_event(writer, e), LogWriteStatus::ok);
  fs::remove_all(logs);
  std::ofstream(logs) << "not a directory";
  EXPECT_EQ(writer.sync_if_due(std::chrono::steady_clock::now(), true),
            LogWriteStatus::file_removed);
  EXPECT_NE(writer.removal_save_error().find("cannot recreate"), std::string::npos)
      << writer.removal_save_error();
  EXPECT_FALSE(fs::exists(writer.partial_path()));
}

TEST(LogsDirProblem, NamesWhatStopsASessionFromBeingLogged) {
  TempDir dir;
  // Fine, and .partial created on the way.
  EXPECT_EQ(logs_dir_problem(dir.path() / "logs", 0), "");
  EXPECT_TRUE(fs::is_directory(dir.path() / "logs" / ".partial"));
  // Under a regular file: never creatable.
  std::ofstream(dir.path() / "file") << "x";
  EXPECT_NE(logs_dir_problem(dir.path() / "file" / "logs", 0).find("cannot create"),
            std::string::npos);
  // Not enough room (no file system has this much).
  const std::string full = logs_dir_problem(dir.path() / "logs", ~std::uint64_t{0});
  EXPECT_NE(full.find("is full"), std::string::npos) << full;
  // Read-only: root passes permission checks, so only as another user.
  if (::geteuid() != 0) {
    fs::permissions(dir.path() / "logs" / ".partial", fs::perms(0555));
    EXPECT_NE(logs_dir_problem(dir.path() / "logs", 0).find("Permission denied"),
              std::string::npos);
    fs::permissions(dir.path() / "logs" / ".partial", fs::perms(0755));
  }
}

TEST(LcmLogWriterDiskFull, FileSizeLimitStopsTheWriterAndKeepsTheSyncedPrefix) {
  TempDir dir;
  testing::Pipe pipe;
  const pid_t pid = testing::fork_child([&] {
    pipe.close_read();
    // EFBIG instead of death by SIGXFSZ, as a daemon that sets a file size limit would have it.
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{50'000, 50'000};
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) return 3;
    return pipe.send(write_until_full(dir.path())) ? 0 : 4;
  });
  pipe.close_write();
  FullDiskReport report;
  const bool got_report = pipe.receive(report);
  ASSERT_EQ(testing::wait_child(pid), 0);
  ASSERT_TRUE(got_report);
  const fs::path part = dir.path() / ".partial" / "full.lcmlog.part";
  EXPECT_LE(fs::file_size(part), 50'000u);
  expect_synced_prefix_readable(part, report);
  EXPECT_FALSE(fs::exists(dir.path() / "full.lcmlog"));
}

// In a user and mount namespace of its own (so it needs no privilege and leaves no mount behind),
// the child mounts a 64 KiB tmpfs and writes into it until ENOSPC.
int run_on_tiny_tmpfs(const fs::path& mount_point, const fs::path& copy_to,
                      const testing::Pipe& pipe) {
  const uid_t uid = ::getuid();
  const gid_t gid = ::getgid();
  if (::unshare(CLONE_NEWUSER | CLONE_NEWNS) != 0) return testing::kChildSkip;
  const auto write_file = [](const char* path, const std::string& text) {
    std::ofstream out(path);
    out << text;
    return static_cast<bool>(out.flush());
  };
  write_file("/proc/self/setgroups", "deny");
  if (!write_file("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1") ||
      !write_file("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1")) {
    return testing::kChildSkip;
  }
  if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) return testing::kChildSkip;
  if (::mount("tmpfs", mount_point.c_str(), "tmpfs", 0, "size=64k") != 0) {
    return testing::kChildSkip;
  }
  const FullDiskReport report = write_until_full(mount_point);
  // The tmpfs goes with this namespace: hand the parent a copy.
  fs::copy_file(mount_point / ".partial" / "full.lcmlog.part", copy_to);
  return pipe.send(report) ? 0 : 4;
}

TEST(LcmLogWriterDiskFull, NoSpaceLeftOnATinyTmpfsKeepsTheSyncedPrefix) {
  TempDir dir;
  const fs::path mount_point = dir.path() / "mnt";
  const fs::path copy = dir.path() / "copy.lcmlog.part";
  fs::create_directory(mount_point);
  testing::Pipe pipe;
  const pid_t pid = testing::fork_child([&] {
    pipe.close_read();
    return run_on_tiny_tmpfs(mount_point, copy, pipe);
  });
  pipe.close_write();
  FullDiskReport report;
  const bool got_report = pipe.receive(report);
  const int code = testing::wait_child(pid);
  if (code == testing::kChildSkip) GTEST_SKIP() << "cannot mount a tmpfs in a user namespace here";
  ASSERT_EQ(code, 0);
  ASSERT_TRUE(got_report);
  EXPECT_TRUE(fs::is_empty(mount_point));  // the mount never showed outside the child
  EXPECT_LE(fs::file_size(copy), 64u * 1024u);
  expect_synced_prefix_readable(copy, report);
}

}  // namespace
}  // namespace furuta::session_log
