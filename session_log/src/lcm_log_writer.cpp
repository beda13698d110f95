// The writer lays events out with LCM's lcm_eventlog, the code lcm-logger itself writes with, so
// our logs are LCM logs by construction. Around it we add what a session needs and lcm_eventlog
// lacks: an exclusive .part file, periodic fflush + fdatasync through its FILE*, error
// classification, refusal after the first error, and an atomic, durable rename when the session
// ends. The C API rather than lcm-cpp's LogFile: a log written again after its directory was
// removed goes on in append mode, and only the C struct lets its event numbers go on too.

#include <fcntl.h>
#include <lcm/eventlog.h>
#include <stdio_ext.h>  // __fpurge
#include <sys/file.h>   // flock
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "furuta/session_log/lcm_log.hpp"
#include "lcm_log_format.hpp"
#include "log_digest.hpp"

namespace furuta::session_log {

namespace fs = std::filesystem;

namespace {

using detail::kFinalSuffix;
using detail::kPartialDir;
using detail::kPartSuffix;

struct EventLogCloser {
  void operator()(lcm_eventlog_t* log) const { lcm_eventlog_destroy(log); }
};
using EventLog = std::unique_ptr<lcm_eventlog_t, EventLogCloser>;

// NAME_MAX is 255; leave room for the longest suffix a log ever wears (".incomplete.lcmlog" and a
// collision counter from recovery).
constexpr std::size_t kMaxNameBytes = 200;

// A name becomes a file name inside logs_dir and nothing else: no path separators, no way up, no
// hidden files (".partial" is ours), nothing a terminal or a shell line would mangle.
// The name as a message can show it: control characters (a NUL would end what()) as \xNN.
std::string printable(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0x0F];
    } else {
      out += c;
    }
  }
  return out;
}

void check_name(const std::string& name) {
  const auto reject = [&](const char* why) {
    throw std::invalid_argument("LCM log name '" + printable(name) + "' " + why);
  };
  if (name.empty()) reject("is empty");
  if (name.size() > kMaxNameBytes) reject("is too long");
  if (name.find('/') != std::string::npos) reject("contains '/'");
  if (name.find("..") != std::string::npos) reject("contains '..'");
  if (name.front() == '.') reject("starts with '.'");
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) reject("contains a control character");
  }
}

LogWriteStatus status_from_errno(int err) {
  // EFBIG is the file size limit (RLIMIT_FSIZE, or the file system's): as final as a full disk.
  return (err == ENOSPC || err == EFBIG || err == EDQUOT) ? LogWriteStatus::disk_full
                                                          : LogWriteStatus::io_error;
}

}  // namespace

std::string_view to_string(LogWriteStatus status) {
  switch (status) {
    case LogWriteStatus::ok:
      return "ok";
    case LogWriteStatus::disk_full:
      return "disk_full";
    case LogWriteStatus::io_error:
      return "io_error";
    case LogWriteStatus::closed:
      return "closed";
    case LogWriteStatus::file_removed:
      return "file_removed";
  }
  return "unknown";
}

class LcmLogWriter::Impl {
 public:
  Impl(const LogWriterOptions& options, const std::string& name)
      : options_(options),
        partial_dir_(options.logs_dir / kPartialDir),
        partial_path_(partial_dir_ / (name + kPartSuffix)),
        final_path_(options.logs_dir / (name + kFinalSuffix)) {
    std::error_code ec;
    const bool created = fs::create_directories(partial_dir_, ec);
    if (ec) {
      throw std::runtime_error("cannot create " + partial_dir_.string() + ": " + ec.message());
    }
    if (created) detail::fsync_directory(options.logs_dir);
    if (fs::exists(final_path_, ec)) {
      throw LogNameInUse("LCM log " + final_path_.string() + " already exists");
    }
    detail::UniqueFd created_fd = create_locked_part();
    part_lock_ = std::move(created_fd);
    file_.reset(lcm_eventlog_create(partial_path_.c_str(), "w"));
    if (!file_) {
      const int err = errno;
      file_.reset();
      ::unlink(partial_path_.c_str());
      throw std::runtime_error("cannot open LCM log " + partial_path_.string() + ": " +
                               std::strerror(err));
    }
    set_close_on_exec();
    detail::fsync_directory(partial_dir_);
    last_sync_ = std::chrono::steady_clock::now();
  }

  // The new .part, created and flock'ed, held while this writer lives: recovery and other writers
  // tell a running session's .part from one a crash left (the kernel drops the lock with the
  // process). Where the file system allows, it is made unnamed, locked, then linked under its
  // name, so that nobody ever sees it unlocked; elsewhere it is created (O_EXCL) and locked at
  // once. A .part left by a crash holds a session nobody has recovered yet: never truncated.
  detail::UniqueFd create_locked_part() {
    const auto refuse = [&](int err) {
      if (err == EEXIST && detail::held_by_a_writer(partial_path_)) {
        throw LogNameInUse("cannot create LCM log " + partial_path_.string() +
                           ": another session is writing it now");
      }
      throw std::runtime_error("cannot create LCM log " + partial_path_.string() + ": " +
                               std::strerror(err) +
                               (err == EEXIST ? " (left by an earlier session: recover it)" : ""));
    };
    const auto lock = [&](detail::UniqueFd& fd) {
      if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
        throw std::runtime_error("cannot lock LCM log " + partial_path_.string() + ": " +
                                 std::strerror(errno));
      }
    };
    detail::UniqueFd unnamed(::open(partial_dir_.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644));
    if (unnamed.valid()) {
      lock(unnamed);
      const std::string self = "/proc/self/fd/" + std::to_string(unnamed.get());
      if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, partial_path_.c_str(), AT_SYMLINK_FOLLOW) ==
          0) {
        return unnamed;
      }
      if (errno == EEXIST) refuse(EEXIST);
      // No /proc, or a file system that links no unnamed file: the plain way below.
    }
    detail::UniqueFd created(
        ::open(partial_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644));
    if (!created.valid()) refuse(errno);
    lock(created);
    return created;
  }

  LogWriteStatus write(std::string_view channel, std::int64_t utime,
                       std::span<const std::uint8_t> data) {
    if (!file_) return LogWriteStatus::closed;
    // The channel names and message sizes are the program's own: a wrong one is a bug, not I/O.
    if (channel.empty() || channel.size() > detail::kMaxWriterChannelBytes) {
      throw std::invalid_argument("LCM channel '" + std::string(channel) + "' must have 1 to " +
                                  std::to_string(detail::kMaxWriterChannelBytes) + " bytes");
    }
    if (data.size() > detail::kMaxDataBytes) {
      throw std::invalid_argument("LCM message of " + std::to_string(data.size()) +
                                  " bytes on channel '" + std::string(channel) +
                                  "', more than LCM carries");
    }
    // Bound what a crash loses by the data's own span too, not only by the wall clock: a writer
    // that fell behind (a stalled thread, a slow disk) catches up in a burst, and a burst written
    // between two wall-clock syncs could hold more than flush_interval of data.
    if (dirty_ && utime - first_unsynced_utime_ > flush_interval_us()) {
      const LogWriteStatus synced = sync_if_due(std::chrono::steady_clock::now(), true);
      if (synced != LogWriteStatus::ok) return synced;
    }
    lcm_eventlog_event_t event{};
    event.timestamp = utime;
    event.channellen = static_cast<std::int32_t>(channel.size());
    // The struct is for reading and writing alike; writing only reads the channel (by its length,
    // no terminator needed) and the data.
    event.channel = const_cast<char*>(channel.data());
    event.datalen = static_cast<std::int32_t>(data.size());
    event.data = const_cast<std::uint8_t*>(data.data());
    errno = 0;
    if (lcm_eventlog_write_event(file_.get(), &event) != 0) return fail(errno);
    digest_.add(static_cast<std::int64_t>(events_written_), utime, channel, data);
    ++events_written_;
    last_utime_ = utime;
    if (!dirty_) first_unsynced_utime_ = utime;
    dirty_ = true;
    return LogWriteStatus::ok;
  }

  LogWriteStatus sync_if_due(std::chrono::steady_clock::time_point now, bool force) {
    if (!file_) return LogWriteStatus::closed;
    if (!force && now - last_sync_ < options_.flush_interval) return LogWriteStatus::ok;
    if (dirty_) {
      FILE* f = file_->f;
      errno = 0;
      if (std::fflush(f) != 0) return fail(errno);
      if (::fdatasync(::fileno(f)) != 0) return fail(errno);
      dirty_ = false;
    }
    last_sync_ = now;
    // Writing to a file nobody can reach any more (its directory was deleted) succeeds and loses
    // everything when it is closed: find out at every sync, while the data is still in hand.
    struct stat st {};
    if (::fstat(::fileno(file_->f), &st) == 0 && st.st_nlink == 0) {
      removal_save_error_ = save_unlinked_file();
      __fpurge(file_->f);
      file_.reset();
      // Saved again: the rest of the session goes on into the new file, so the events that come
      // while the session is being stopped (its end record too) are not lost as well.
      if (removal_save_error_.empty()) reopen_for_append();
      return LogWriteStatus::file_removed;
    }
    return LogWriteStatus::ok;
  }

  LogWriteStatus finish(fs::path* final_path) {
    if (!file_) return LogWriteStatus::closed;
    const LogWriteStatus synced = sync_if_due(std::chrono::steady_clock::now(), true);
    if (synced != LogWriteStatus::ok) return synced;
    // Everything is on disk already, so closing cannot lose data.
    file_.reset();
    // On failure the .part stays where recovery will find it.
    if (detail::rename_no_replace(partial_path_, final_path_) != 0) return LogWriteStatus::io_error;
    const int dir_err = detail::fsync_directory(options_.logs_dir);
    detail::fsync_directory(partial_dir_);
    if (final_path != nullptr) *final_path = final_path_;
    return dir_err == 0 ? LogWriteStatus::ok : LogWriteStatus::io_error;
  }

  const fs::path& partial_path() const { return partial_path_; }
  std::uint64_t events_written() const { return events_written_; }
  std::int64_t last_utime() const { return last_utime_; }
  std::vector<std::uint8_t> digest() const {
    const detail::Digest d = digest_.value();
    return {d.begin(), d.end()};
  }
  const std::string& removal_save_error() const { return removal_save_error_; }
  bool is_open() const { return file_ != nullptr; }

 private:
  // After an error the file's tail may hold half an event. What stdio still buffers is dropped
  // rather than flushed by lcm_eventlog's close, so nothing lands after the failure and what was
  // synced before stays a readable prefix. Closing now also hands the descriptor back.
  LogWriteStatus fail(int err) {
    __fpurge(file_->f);
    file_.reset();
    return status_from_errno(err);
  }

  // lcm_eventlog's fopen does not ask for close-on-exec; whatever the daemon starts must not
  // inherit the log.
  void set_close_on_exec() {
    const int fd = ::fileno(file_->f);
    ::fcntl(fd, F_SETFD, ::fcntl(fd, F_GETFD) | FD_CLOEXEC);
  }

  void reopen_for_append() {
    EventLog file(lcm_eventlog_create(partial_path_.c_str(), "a"));
    if (!file) return;  // what was saved stays saved; the writer stays closed
    // Append mode would number from 0 again: the events go on from where they were.
    file->eventcount = static_cast<std::int64_t>(events_written_);
    file_ = std::move(file);
    set_close_on_exec();
    dirty_ = false;
  }

  // Copies the (synced, unlinked) file to a new .part at the old path, directories recreated, so
  // that recovery at the next start finds it. Returns empty on success, else what failed: the
  // caller reports the removal either way and says whether the data was saved.
  std::string save_unlinked_file() {
    std::error_code ec;
    fs::create_directories(partial_dir_, ec);
    if (ec) return "cannot recreate " + partial_dir_.string() + ": " + ec.message();
    const detail::UniqueFd to(
        ::open(partial_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644));
    if (!to.valid()) return "cannot create " + partial_path_.string() + ": " + std::strerror(errno);
    // The log's own descriptor is write-only; /proc reopens the unlinked file for reading.
    const std::string self_fd = "/proc/self/fd/" + std::to_string(::fileno(file_->f));
    const detail::UniqueFd from(::open(self_fd.c_str(), O_RDONLY | O_CLOEXEC));
    if (!from.valid())
      return "cannot reopen the removed file: " + std::string(std::strerror(errno));
    std::vector<char> buffer(64 * 1024);
    for (off_t offset = 0;;) {
      const ssize_t n = ::pread(from.get(), buffer.data(), buffer.size(), offset);
      if (n < 0) return "cannot read the removed file: " + std::string(std::strerror(errno));
      if (n == 0) break;
      if (::write(to.get(), buffer.data(), static_cast<std::size_t>(n)) != n) {
        return "cannot write " + partial_path_.string() + ": " + std::strerror(errno);
      }
      offset += n;
    }
    if (::fdatasync(to.get()) != 0) {
      return "cannot sync " + partial_path_.string() + ": " + std::strerror(errno);
    }
    detail::fsync_directory(partial_dir_);
    detail::fsync_directory(options_.logs_dir);
    return {};
  }

  LogWriterOptions options_;
  fs::path partial_dir_;
  fs::path partial_path_;
  fs::path final_path_;
  detail::UniqueFd part_lock_;  // the .part's flock
  EventLog file_;
  std::uint64_t events_written_ = 0;
  detail::LogDigest digest_;
  std::int64_t last_utime_ = 0;
  std::string removal_save_error_;
  std::int64_t flush_interval_us() const {
    return std::chrono::duration_cast<std::chrono::microseconds>(options_.flush_interval).count();
  }

  bool dirty_ = false;
  std::int64_t first_unsynced_utime_ = 0;  // the oldest event not yet on disk
  std::chrono::steady_clock::time_point last_sync_;
};

std::string logs_dir_problem(const fs::path& logs_dir, std::uint64_t min_free_bytes) {
  const fs::path partial_dir = logs_dir / kPartialDir;
  std::error_code ec;
  fs::create_directories(partial_dir, ec);
  if (ec) return "cannot create " + partial_dir.string() + ": " + ec.message();
  // An unnamed file: the same permission, read-only and existence checks as the session's log,
  // and nothing left behind whatever happens next.
  detail::UniqueFd probe(::open(partial_dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600));
  if (!probe.valid() && errno != EOPNOTSUPP && errno != EISDIR) {
    return "cannot create a file in " + partial_dir.string() + ": " + std::strerror(errno);
  }
  struct statvfs fs_stats {};
  if (::statvfs(partial_dir.c_str(), &fs_stats) == 0) {
    const std::uint64_t free_bytes = static_cast<std::uint64_t>(fs_stats.f_bavail) *
                                     static_cast<std::uint64_t>(fs_stats.f_frsize);
    if (free_bytes < min_free_bytes) {
      return "the file system of " + logs_dir.string() + " is full (" +
             std::to_string(free_bytes / 1024) + " KiB free, a session needs " +
             std::to_string(min_free_bytes / 1024) + " KiB to start)";
    }
  }
  return {};
}

LcmLogWriter::LcmLogWriter(const LogWriterOptions& options, const std::string& name) {
  check_name(name);
  impl_ = std::make_unique<Impl>(options, name);
}

LcmLogWriter::~LcmLogWriter() = default;

LogWriteStatus LcmLogWriter::write(std::string_view channel, std::int64_t utime,
                                   std::span<const std::uint8_t> data) {
  return impl_->write(channel, utime, data);
}

LogWriteStatus LcmLogWriter::sync_if_due(std::chrono::steady_clock::time_point now, bool force) {
  return impl_->sync_if_due(now, force);
}

LogWriteStatus LcmLogWriter::finish(std::filesystem::path* final_path) {
  return impl_->finish(final_path);
}

const std::filesystem::path& LcmLogWriter::partial_path() const {
  return impl_->partial_path();
}

std::uint64_t LcmLogWriter::events_written() const {
  return impl_->events_written();
}

std::int64_t LcmLogWriter::last_utime() const {
  return impl_->last_utime();
}

std::vector<std::uint8_t> LcmLogWriter::digest() const {
  return impl_->digest();
}

bool LcmLogWriter::is_open() const {
  return impl_->is_open();
}
const std::string& LcmLogWriter::removal_save_error() const {
  return impl_->removal_save_error();
}

}  // namespace furuta::session_log
