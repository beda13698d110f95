// Recovery of logs whose writer never finished (a crash, a kill, a power cut): keep what can be
// read, cut the rest, and move the log where finished logs are, marked incomplete.

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

#include "furuta/session_log/lcm_log.hpp"
#include "lcm_log_format.hpp"

namespace furuta::session_log {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void throw_io(const std::string& what, const fs::path& path, int err) {
  throw fs::filesystem_error("recover_partial_logs: " + what, path,
                             std::error_code(err, std::generic_category()));
}

RecoveredLog recover_one(const fs::path& logs_dir, const fs::path& part) {
  RecoveredLog recovered;
  const std::uint64_t size = fs::file_size(part);
  {
    LcmLogReader reader(part);
    LogEvent event;
    while (reader.next(event)) {
    }
    recovered.stats = reader.stats();
  }
  if (recovered.stats.events == 0) {
    if (::unlink(part.c_str()) != 0) throw_io("remove", part, errno);
    recovered.path = part;
    recovered.bytes_dropped = size;
    recovered.discarded = true;
    return recovered;
  }
  const std::uint64_t keep = std::min(recovered.stats.readable_prefix_bytes, size);
  recovered.bytes_dropped = size - keep;
  if (recovered.bytes_dropped > 0) {
    // Cut to the readable prefix before the rename: a crash in between leaves a .part that reads
    // the same, so running again finishes the job.
    const detail::UniqueFd fd(::open(part.c_str(), O_WRONLY | O_CLOEXEC));
    if (!fd.valid()) throw_io("open", part, errno);
    if (::ftruncate(fd.get(), static_cast<off_t>(keep)) != 0) throw_io("truncate", part, errno);
    if (::fsync(fd.get()) != 0) throw_io("fsync", part, errno);
  }

  std::string name = part.filename().string();
  name.resize(name.size() - std::strlen(detail::kPartSuffix));
  // Session names are unique in practice; should one repeat, neither log is replaced.
  fs::path target = logs_dir / (name + detail::kIncompleteSuffix);
  for (int n = 2;; ++n) {
    const int err = detail::rename_no_replace(part, target);
    if (err == 0) break;
    if (err != EEXIST || n > 1000) throw_io("rename to " + target.string(), part, err);
    target = logs_dir / (name + "-" + std::to_string(n) + detail::kIncompleteSuffix);
  }
  recovered.path = target;
  return recovered;
}

}  // namespace

std::vector<RecoveredLog> recover_partial_logs(const fs::path& logs_dir) {
  std::vector<RecoveredLog> recovered;
  const fs::path partial_dir = logs_dir / detail::kPartialDir;
  std::error_code ec;
  if (!fs::is_directory(partial_dir, ec)) return recovered;

  const std::string_view suffix = detail::kPartSuffix;
  std::vector<fs::path> parts;
  for (const fs::directory_entry& entry : fs::directory_iterator(partial_dir)) {
    const std::string leaf = entry.path().filename().string();
    if (!entry.is_regular_file() || leaf.size() <= suffix.size() || !leaf.ends_with(suffix)) {
      continue;
    }
    parts.push_back(entry.path());
  }
  // Oldest name first, the same order every time.
  std::sort(parts.begin(), parts.end());
  for (const fs::path& part : parts) {
    // A session running now (this process's or another's) holds its .part's lock: not left by a
    // crash, never cut or moved. Held here while recovering, so that two recoveries at once do
    // not both take one file; one gone meanwhile was taken by the other.
    const detail::UniqueFd lock(::open(part.c_str(), O_RDONLY | O_CLOEXEC));
    if (!lock.valid() && errno == ENOENT) continue;
    if (!lock.valid()) throw_io("open", part, errno);
    if (::flock(lock.get(), LOCK_EX | LOCK_NB) != 0) {
      if (errno == EWOULDBLOCK) continue;
      throw_io("lock", part, errno);
    }
    if (!fs::exists(part)) continue;
    recovered.push_back(recover_one(logs_dir, part));
  }

  if (!recovered.empty()) {
    if (const int err = detail::fsync_directory(logs_dir); err != 0) {
      throw_io("fsync", logs_dir, err);
    }
    detail::fsync_directory(partial_dir);
  }
  return recovered;
}

}  // namespace furuta::session_log
