// A run's output directory, replaced whole (run_directory.hpp).
#include "furuta/report/run_directory.hpp"

#include <fcntl.h>     // AT_FDCWD, open
#include <stdio.h>     // renameat2, RENAME_EXCHANGE (glibc >= 2.28)
#include <sys/file.h>  // flock
#include <sys/stat.h>  // fstat, stat
#include <unistd.h>    // getpid

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <system_error>
#include <vector>

#include "furuta/report/outputs.hpp"

namespace furuta::report {

namespace {

namespace fs = std::filesystem;

// "out/" and "out" name the same directory; "." and ".." are resolved so that their real name
// (and so their sibling) is known.
fs::path normalised(const fs::path& dir) {
  if (dir.empty()) return dir;
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p;
}

// What `furuta identify` and `furuta simulate` wrote before the marker existed (report/README.md).
bool legacy_output_name(const std::string& name) {
  static constexpr std::array<std::string_view, 11> fixed = {
      "results.json", "table.txt",   "table3.txt", "report.html",           "sivia.json",
      "sivia.svg",    "paving.json", "tubes.json", "torque_validation.svg", "simulate.json",
      "batch.json"};
  for (const std::string_view f : fixed) {
    if (name == f) return true;
  }
  return name.ends_with(".svg") && (name.starts_with("signals_") || name.starts_with("scenario_"));
}

bool is_previous_run(const fs::path& dir, std::vector<std::string>& foreign) {
  if (fs::is_regular_file(dir / kRunMarkerFile)) return true;
  bool key_file = false;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && legacy_output_name(name)) {
      key_file = key_file || name == "results.json" || name == "simulate.json";
    } else {
      foreign.push_back(name);
    }
  }
  return key_file && foreign.empty();
}

std::string quoted_list(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < 3; ++i) {
    text += (i == 0 ? "'" : ", '") + names[i] + "'";
  }
  if (names.size() > 3) text += " and " + std::to_string(names.size() - 3) + " more";
  return text;
}

std::system_error last_error(const std::string& what) {
  return std::system_error(errno, std::generic_category(), what);
}

// The path with symbolic links and "..", as far as it exists, resolved: how two spellings of one
// place are told to be the same.
fs::path resolved(const fs::path& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return ec ? fs::absolute(path).lexically_normal() : p;
}

// Whether `path` is `dir` or lies under it, component by component ("out2" is not under "out").
bool is_within(const fs::path& path, const fs::path& dir) {
  return std::mismatch(dir.begin(), dir.end(), path.begin(), path.end()).first == dir.end();
}

}  // namespace

std::optional<std::string> writable_directory_problem(const fs::path& dir) {
  if (dir.empty()) return std::string("an empty path names no directory");
  const fs::path path = normalised(dir);
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) return "cannot create " + path.string() + ": " + ec.message();
  if (!fs::is_directory(path, ec)) return path.string() + " is not a directory";
  // Only making a file tells: permissions, a read-only mount, or a file system that takes no new
  // entries (/proc) each refuse it in their own way.
  const fs::path probe = path / (".furuta-probe-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) return "cannot create a file in " + path.string() + ": " + std::strerror(errno);
  ::close(fd);
  ::unlink(probe.c_str());
  return std::nullopt;
}

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool equivalent = fs::equivalent(a, b, ec);
    if (!ec) return equivalent;
  }
  return resolved(a) == resolved(b);
}

std::optional<fs::path> input_in_the_way(const fs::path& dir, const std::vector<fs::path>& inputs) {
  if (dir.empty()) return std::nullopt;
  const fs::path where = resolved(dir);
  for (const fs::path& input : inputs) {
    if (input.empty()) continue;
    if (same_file(dir, input) || is_within(resolved(input), where)) return input;
  }
  return std::nullopt;
}

OutputLock::OutputLock(const fs::path& dir) {
  const fs::path path = normalised(dir);
  lock_file_ = path.parent_path() / ("." + path.filename().string() + ".lock");
  // The holder removes the file when it is done: a lock taken on a file removed meanwhile guards
  // nothing, so the lock counts only once the name still leads to the locked file.
  for (;;) {
    fd_ = ::open(lock_file_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) {
      throw OutputDirectoryError("cannot create the lock file " + lock_file_.string() + ": " +
                                 std::strerror(errno));
    }
    int locked = -1;
    while ((locked = ::flock(fd_, LOCK_EX | LOCK_NB)) != 0 && errno == EINTR) {
    }
    if (locked != 0) {
      const int err = errno;
      std::string holder;
      if (err == EWOULDBLOCK) {
        char text[32] = {};
        const ssize_t n = ::pread(fd_, text, sizeof text - 1, 0);
        holder = std::string(text, n > 0 ? static_cast<std::size_t>(n) : 0);
        while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) {
          holder.pop_back();
        }
      }
      ::close(fd_);
      fd_ = -1;
      if (err != EWOULDBLOCK) {
        throw OutputDirectoryError("cannot lock " + lock_file_.string() + ": " +
                                   std::strerror(err));
      }
      throw OutputDirectoryError("another run is writing " + path.string() + " now (" +
                                 (holder.empty() ? std::string("its") : holder + " holds its") +
                                 " lock " + lock_file_.string() +
                                 "): wait for it to end, or give another directory");
    }
    struct stat held {};
    struct stat named {};
    if (::fstat(fd_, &held) == 0 && ::stat(lock_file_.c_str(), &named) == 0 &&
        held.st_dev == named.st_dev && held.st_ino == named.st_ino) {
      break;
    }
    ::close(fd_);
    fd_ = -1;
  }
  // Who holds it, for the message of a run refused meanwhile.
  const std::string holder = "pid " + std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd_, holder.data(), holder.size(), 0);
  }
}

OutputLock::~OutputLock() {
  if (fd_ < 0) return;
  // Removed while still held, so that no run locks the file between the two steps; one that
  // opened it before finds it gone and takes a new one.
  ::unlink(lock_file_.c_str());
  ::close(fd_);  // releases the flock
}

std::optional<std::string> output_directory_problem(const fs::path& dir) {
  if (dir.empty()) return std::string("an empty path names no directory");
  const fs::path path = normalised(dir);
  const fs::file_status link = fs::symlink_status(path);
  if (!fs::exists(link)) return std::nullopt;
  if (fs::is_symlink(link)) {
    return path.string() + " is a symbolic link: give the directory itself (it is replaced whole)";
  }
  if (!fs::is_directory(link)) return path.string() + " exists and is not a directory";
  const fs::path cwd = normalised(fs::current_path());
  if (std::mismatch(path.begin(), path.end(), cwd.begin(), cwd.end()).first == path.end()) {
    return path.string() + " is the current directory or holds it: give a directory of the " +
           "run's own, e.g. a new subdirectory (it is replaced whole)";
  }
  if (fs::is_empty(path)) return std::nullopt;
  std::vector<std::string> foreign;
  if (is_previous_run(path, foreign)) return std::nullopt;
  return path.string() + " is not empty and not a previous run's output (" +
         (foreign.empty() ? std::string("no ") + kRunMarkerFile + ", no results.json"
                          : "it holds " + quoted_list(foreign)) +
         "): give a new or empty directory; only a previous run's is replaced";
}

RunDirectory::RunDirectory(const fs::path& dir) : dir_(normalised(dir)) {
  if (const auto problem = output_directory_problem(dir_)) throw OutputDirectoryError(*problem);
  if (const auto problem = writable_directory_problem(dir_.parent_path())) {
    throw OutputDirectoryError(*problem);
  }
  lock_.emplace(dir_);
  // mkdir rather than mkdtemp: the directory keeps the umask's mode (mkdtemp's is 0700), as one
  // made in place would. mkdir is atomic, so a name taken by a concurrent run is skipped.
  const std::string stem =
      "." + dir_.filename().string() + ".partial-" + std::to_string(::getpid());
  for (int n = 0; staging_.empty(); ++n) {
    const fs::path candidate = dir_.parent_path() / (stem + "-" + std::to_string(n));
    std::error_code ec;
    if (fs::create_directory(candidate, ec)) staging_ = candidate;
    if (ec) throw OutputDirectoryError("cannot create " + candidate.string() + ": " + ec.message());
  }
  try {
    write_text_file(staging_ / kRunMarkerFile,
                    "A furuta identify or simulate run's files: the next run into this directory "
                    "replaces them all.\n");
  } catch (const std::runtime_error& e) {
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
    throw OutputDirectoryError(e.what());
  }
}

RunDirectory::~RunDirectory() {
  if (committed_ || staging_.empty()) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

bool RunDirectory::commit() {
  if (const auto problem = output_directory_problem(dir_)) {
    committed_ = true;  // keep the files: the run may have taken hours
    throw OutputDirectoryError(*problem + "; this run's files are in " + staging_.string());
  }
  if (!fs::exists(fs::symlink_status(dir_)) || fs::is_empty(dir_)) {
    // rename(2) replaces an empty directory in one step.
    fs::rename(staging_, dir_);
    committed_ = true;
    return false;
  }
  // Swapped in one step, so that a reader or a crash sees the old run or the new, never a mix;
  // the old run then sits under the staging name and is removed.
  if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) != 0) {
    if (errno != EINVAL && errno != ENOSYS && errno != EOPNOTSUPP) {
      throw last_error("cannot put " + staging_.string() + " in place of " + dir_.string());
    }
    // A file system without the exchange: the old run steps aside first.
    const fs::path old = staging_.string() + ".old";
    fs::rename(dir_, old);
    fs::rename(staging_, dir_);
    fs::rename(old, staging_);
  }
  committed_ = true;
  fs::remove_all(staging_);
  return true;
}

}  // namespace furuta::report
