#pragma once
// A run's output directory (`furuta identify -o DIR`, `furuta simulate -o DIR`) never holds a mix
// of two runs: the files are written into a fresh sibling directory, which then takes DIR's place
// whole. An existing DIR is replaced only when it is empty or a previous run's output; anything
// else (`-o .`, `-o ~`, a folder of the user's) is refused, never emptied.
//
// It is made before the run's work, so that a directory it cannot use is refused at once, and it
// holds DIR's lock until it is gone, so that a second run into DIR is refused rather than one
// run's files silently replacing the other's.
//
//   report::RunDirectory dir(options.output_dir);       // OutputDirectoryError: refused
//   ... the run's work ...
//   report::write_identification(dir.staging(), run, version);
//   const bool replaced = dir.commit();                 // DIR now holds this run's files only

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace furuta::report {

// Written into every run's directory: how a later run recognises a directory it may replace.
inline constexpr const char* kRunMarkerFile = ".furuta-run";

class OutputDirectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Why `dir` cannot receive a new run, or nullopt when it can: it does not exist, or it is an empty
// directory, or a previous run's output (kRunMarkerFile, or, from before the marker, results.json
// or simulate.json beside nothing but the files these commands write). Refused too: a file, a
// symbolic link, the current directory or one that holds it.
std::optional<std::string> output_directory_problem(const std::filesystem::path& dir);

// Why files cannot be written into `dir`, or nullopt when they can: it is created (with its
// missing parents) when absent, then a file is made in it and removed. The text names the
// directory and the system's reason ("cannot create /proc/ids: No such file or directory").
std::optional<std::string> writable_directory_problem(const std::filesystem::path& dir);

// Whether two paths name one file: std::filesystem::equivalent when both exist, otherwise their
// weakly canonical forms compared (a file about to be made has no identity yet).
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// The first of `inputs` that a run replacing `dir` whole would overwrite or remove: `dir` itself,
// or a file anywhere inside it. Nothing when no input is in the way.
std::optional<std::filesystem::path> input_in_the_way(
    const std::filesystem::path& dir, const std::vector<std::filesystem::path>& inputs);

// Held while a run writes `dir`: an flock on `.<name>.lock` beside it, a file that records the
// holder's pid and is removed when the holder is done. The kernel releases the lock when its
// holder exits, however it ends (a killed run leaves the file, unlocked: the next run takes it).
class OutputLock {
 public:
  // OutputDirectoryError when another run holds it (its pid named when recorded) or the lock file
  // cannot be made. The parent directory must exist.
  explicit OutputLock(const std::filesystem::path& dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  std::filesystem::path lock_file_;
  int fd_ = -1;
};

class RunDirectory {
 public:
  // Checks `dir` (OutputDirectoryError with output_directory_problem's text), creates its parent
  // when absent and checks it can be written (writable_directory_problem), takes dir's OutputLock,
  // and makes the staging directory `.<name>.partial-<pid>-<n>` beside it, holding the marker.
  // Every refusal is an OutputDirectoryError whose text names the path and the reason.
  explicit RunDirectory(const std::filesystem::path& dir);
  // Removes the staging directory unless commit() put it in place.
  ~RunDirectory();
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;

  // Where the run's files go.
  const std::filesystem::path& staging() const { return staging_; }
  // Puts the staging directory in dir's place (an atomic exchange where the file system has one)
  // and removes the previous run's files. True when there was a previous run. When dir changed
  // meanwhile into something it may not replace, OutputDirectoryError, and the files stay in
  // staging() (named in the message).
  bool commit();

 private:
  std::filesystem::path dir_;
  std::optional<OutputLock> lock_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace furuta::report
