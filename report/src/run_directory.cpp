// A run's output directory, replaced whole (run_directory.hpp).
#include "furuta/report/run_directory.hpp"

#include <fcntl.h>   // AT_FDCWD
#include <stdio.h>   // renameat2, RENAME_EXCHANGE (glibc >= 2.28)
#include <unistd.h>  // getpid

#include <algorithm>
#include <array>
#include <cerrno>
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

}  // namespace

std::optional<std::string> output_directory_problem(const fs::path& dir) {
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
  fs::create_directories(dir_.parent_path());
  // mkdir rather than mkdtemp: the directory keeps the umask's mode (mkdtemp's is 0700), as one
  // made in place would. mkdir is atomic, so a name taken by a concurrent run is skipped.
  const std::string stem =
      "." + dir_.filename().string() + ".partial-" + std::to_string(::getpid());
  for (int n = 0; staging_.empty(); ++n) {
    const fs::path candidate = dir_.parent_path() / (stem + "-" + std::to_string(n));
    if (fs::create_directory(candidate)) staging_ = candidate;
  }
  write_text_file(staging_ / kRunMarkerFile,
                  "A furuta identify or simulate run's files: the next run into this directory "
                  "replaces them all.\n");
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
