#pragma once
// LCM event logs (the format lcm-logger writes and lcm-logplayer plays): writing one crash-safely,
// reading any file without trusting it.
//
// Each event on disk: sync word 0xEDA1DA01, event number (u64), timestamp in microseconds (i64),
// channel length (u32), data length (u32), all big-endian, then the channel and the data.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace furuta::session_log {

// --- reading ---

struct LogEvent {
  std::int64_t event_number = 0;
  std::int64_t utime = 0;
  std::string channel;
  std::vector<std::uint8_t> data;
  std::uint64_t file_offset = 0;  // where its sync word starts
};

struct LogReadStats {
  std::uint64_t events = 0;
  std::uint64_t damaged_regions =
      0;                            // places where the reader had to search for the next sync word
  std::uint64_t bytes_skipped = 0;  // bytes in those places, not part of any event returned
  bool truncated_tail = false;      // the file ends inside an event (a crash while writing)
  std::uint64_t readable_prefix_bytes = 0;  // end of the last good event before any damage
};

// Reads events one by one. Every length is checked against the file before use; after damage it
// resynchronises on the next sync word whose event is plausible and fits. Never throws on content.
class LcmLogReader {
 public:
  // Throws std::runtime_error naming the file when it cannot be opened.
  explicit LcmLogReader(const std::filesystem::path& path);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  bool next(LogEvent& event);  // false at the end of the file
  const LogReadStats& stats() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// Checks a buffer instead of a file (fuzzing, tests).
std::vector<LogEvent> read_lcm_log_bytes(std::span<const std::uint8_t> bytes, LogReadStats& stats);

// --- writing ---

// file_removed: the .part lost its last link (the logs directory or the file was deleted under a
// running session); the writer has written what it had synced to a new .part at the same path
// (directories recreated) and, when that worked, goes on writing there (is_open()).
enum class LogWriteStatus : std::uint8_t { ok, disk_full, io_error, closed, file_removed };
std::string_view to_string(LogWriteStatus status);

struct LogWriterOptions {
  std::filesystem::path logs_dir;                  // finished logs land here
  std::chrono::milliseconds flush_interval{1000};  // at most this much is lost to a crash
};

// One session's log. Written as <logs_dir>/.partial/<name>.lcmlog.part, flushed and fdatasync'd at
// least every flush_interval of wall time and before the unsynced events would span more than
// flush_interval of their own timestamps (utime), renamed to <logs_dir>/<name>.lcmlog by finish().
// On any write error the writer stops accepting events; what reached the disk before stays
// readable.
// The name is taken, by a session writing its .part now or by a finished log: another name is
// needed.
class LogNameInUse : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class LcmLogWriter {
 public:
  // Throws std::runtime_error naming the path when the file cannot be created: LogNameInUse when
  // a live writer holds that name's .part or the finished log exists. The writer holds an flock on
  // its .part while it lives.
  LcmLogWriter(const LogWriterOptions& options, const std::string& name);
  ~LcmLogWriter();  // a writer never finished leaves its .part for recovery
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;

  LogWriteStatus write(std::string_view channel, std::int64_t utime,
                       std::span<const std::uint8_t> data);
  // Flushes and fdatasyncs when flush_interval has passed since the last sync (or when forced).
  LogWriteStatus sync_if_due(std::chrono::steady_clock::time_point now, bool force = false);
  // Syncs, closes and renames into logs_dir (and fsyncs the directory). Returns the final path.
  LogWriteStatus finish(std::filesystem::path* final_path = nullptr);

  const std::filesystem::path& partial_path() const;
  std::uint64_t events_written() const;
  std::int64_t last_utime() const;  // of the last event written (0 before the first)
  // SHA-256 over every event written so far, each as its event number, utime, channel and data
  // (the digest a session log's seal carries; session_log.hpp, write_seal).
  std::vector<std::uint8_t> digest() const;
  // After file_removed: empty when what was synced was written again to partial_path(), else
  // why it could not be (the session's data is then lost).
  const std::string& removal_save_error() const;
  // False after an error, after finish(), and after a file_removed it could not write again.
  bool is_open() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// Why a session could not be logged in `logs_dir` now, or "" when it can: creates `.partial/` if
// missing, probes that a file can be created there (a directory removed, read-only or not ours is
// found here, not after the motor has started) and that the file system has at least
// `min_free_bytes` available. Cheap enough to ask before every session.
std::string logs_dir_problem(const std::filesystem::path& logs_dir, std::uint64_t min_free_bytes);

struct RecoveredLog {
  std::filesystem::path path;  // <logs_dir>/<name>.incomplete.lcmlog (discarded: the .part removed)
  LogReadStats stats;
  std::uint64_t bytes_dropped = 0;  // the unreadable tail cut off
  // Not one whole event (a kill before the first sync): removed rather than kept as an empty log,
  // which lcm-logplayer refuses ("Failed to read first event") and which holds nothing.
  bool discarded = false;
};
// For each .part left by a session cut short: keep the readable prefix, rename it into logs_dir
// marked incomplete (or remove it when it holds no whole event). A .part a live writer holds (a
// session running now, in any process) is left alone. Safe to run at every start.
std::vector<RecoveredLog> recover_partial_logs(const std::filesystem::path& logs_dir);

}  // namespace furuta::session_log
