#pragma once
// A run's output directory (`furuta identify -o DIR`, `furuta simulate -o DIR`) never holds a mix
// of two runs: the files are written into a fresh sibling directory, which then takes DIR's place
// whole. An existing DIR is replaced only when it is empty or a previous run's output; anything
// else (`-o .`, `-o ~`, a folder of the user's) is refused, never emptied.
//
//   report::RunDirectory dir(options.output_dir);       // OutputDirectoryError: refused
//   report::write_identification(dir.staging(), run, version);
//   const bool replaced = dir.commit();                 // DIR now holds this run's files only

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

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

class RunDirectory {
 public:
  // Checks `dir` (OutputDirectoryError with output_directory_problem's text), creates its parent
  // when absent, and makes the staging directory `.<name>.partial-<pid>-<n>` beside it, holding the
  // marker.
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
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace furuta::report
