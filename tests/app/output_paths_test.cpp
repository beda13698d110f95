// Where commands write: an output never overwrites an input, an output directory that cannot be
// made or written is refused before any work, and two runs into one directory do not both write
// it (the second is refused while the first holds the directory's lock).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/report/run_directory.hpp"
#include "log_processor.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::output_paths_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

// A directory no one can create anything in, whoever runs the test (root too).
constexpr const char* kUnwritable = "/proc/furuta-outputs";

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// One short session, made once and copied into each test's directory.
class Outputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    made_ = std::make_unique<TempDir>("furuta-outputs-logs");
    log_ = furuta::testing::simulated_session_log(made_->path(), "bang-bang", 1, 6.0);
  }
  static void TearDownTestSuite() { made_.reset(); }

  void SetUp() override {
    ASSERT_FALSE(log_.empty());
    log_copy_ = dir_.path() / "session.lcmlog";
    fs::copy_file(log_, log_copy_);
  }
  IdentifyCommandOptions identify_options(const fs::path& output_dir) const {
    IdentifyCommandOptions o;
    o.logs = {log_copy_};
    o.no_output_error = true;  // where it writes is under test, not the refinement
    o.output_dir = output_dir;
    return o;
  }
  SimulateCommandOptions simulate_options(const fs::path& output_dir) const {
    SimulateCommandOptions o;
    o.scenarios = {1};
    o.seconds = 0.02;
    o.output_dir = output_dir;
    return o;
  }

  static std::unique_ptr<TempDir> made_;
  static fs::path log_;
  TempDir dir_;
  fs::path log_copy_;
};
std::unique_ptr<TempDir> Outputs::made_;
fs::path Outputs::log_;

// Before: the log was overwritten with its own CSV, exit 0.
TEST_F(Outputs, ExportCsvOntoItsOwnLogIsRefusedAndTheLogKept) {
  const std::string before = read(log_copy_);
  for (const fs::path& csv :
       {log_copy_, dir_.path() / "." / ".." / dir_.path().filename() / log_copy_.filename()}) {
    std::ostringstream out, err;
    EXPECT_EQ(run_log_export_csv_command(log_copy_, csv, out, err), kExitNotDone) << csv;
    EXPECT_TRUE(has(err.str(), "-o " + csv.string() + " is the log " + log_copy_.string() +
                                   " itself: writing the CSV would overwrite it"))
        << err.str();
  }
  EXPECT_EQ(read(log_copy_), before);
  std::ostringstream out, err;
  EXPECT_EQ(run_log_export_csv_command(log_copy_, "", out, err), kExitNotDone);
  EXPECT_TRUE(has(err.str(), "-o is empty")) << err.str();
  // Another file is written as before.
  EXPECT_EQ(run_log_export_csv_command(log_copy_, dir_.path() / "session.csv", out, err), kExitDone)
      << err.str();
}

// Before: `-o LOG` was refused only as "not a directory", and a previous run's directory that
// held an input was replaced whole, the input with it.
TEST_F(Outputs, IdentifyNeverWritesOverAnInput) {
  std::ostringstream out, err;
  EXPECT_EQ(run_identify_command(identify_options(log_copy_), out, err), kExitNotDone);
  EXPECT_TRUE(has(err.str(),
                  "-o " + log_copy_.string() + " would overwrite the input " + log_copy_.string()))
      << err.str();

  // A previous run's directory, into which the user put the log to fit.
  const fs::path previous = dir_.path() / "identification";
  fs::create_directories(previous);
  std::ofstream(previous / report::kRunMarkerFile) << "run\n";
  const fs::path inside = previous / "kept.lcmlog";
  fs::copy_file(log_copy_, inside);
  IdentifyCommandOptions o = identify_options(previous);
  o.logs = {inside};
  std::ostringstream out2, err2;
  EXPECT_EQ(run_identify_command(o, out2, err2), kExitNotDone);
  EXPECT_TRUE(has(err2.str(), "-o " + previous.string() + " would overwrite the input " +
                                  inside.string() + " (the output directory is replaced whole)"))
      << err2.str();
  EXPECT_TRUE(fs::exists(inside));
  EXPECT_TRUE(out2.str().empty()) << out2.str();
}

// Before: the whole fit ran, then "filesystem error: cannot create directory ... [.x.partial-..]";
// `-o ''` failed after the fit with "cannot make absolute path".
TEST_F(Outputs, IdentifyRefusesAnUnusableOutputBeforeTheFit) {
  std::ostringstream out, err;
  EXPECT_EQ(run_identify_command(identify_options(kUnwritable), out, err), kExitNotDone);
  EXPECT_TRUE(has(err.str(), std::string("furuta identify: -o ") + kUnwritable +
                                 ": cannot create a file in /proc: "))
      << err.str();
  EXPECT_FALSE(has(err.str(), "filesystem error")) << err.str();
  EXPECT_TRUE(out.str().empty()) << "the fit ran: " << out.str();

  std::ostringstream out2, err2;
  EXPECT_EQ(run_identify_command(identify_options(""), out2, err2), kExitNotDone);
  EXPECT_TRUE(has(err2.str(), "furuta identify: -o is empty")) << err2.str();
  EXPECT_TRUE(out2.str().empty()) << out2.str();
}

// Before: two runs into one directory both exited 0 and printed the same report path; one run's
// files were silently lost.
TEST_F(Outputs, ARunIntoADirectoryAnotherRunIsWritingIsRefusedAtOnce) {
  const fs::path output = dir_.path() / "identification";
  {
    const report::RunDirectory other_run(output);  // a run in progress holds the directory
    std::ostringstream out, err;
    EXPECT_EQ(run_identify_command(identify_options(output), out, err), kExitNotDone);
    EXPECT_TRUE(has(err.str(), "furuta identify: -o " + output.string() +
                                   ": another run is writing " + output.string() + " now (pid " +
                                   std::to_string(::getpid()) + " holds its lock"))
        << err.str();
    EXPECT_TRUE(out.str().empty()) << "the fit ran: " << out.str();

    std::ostringstream out2, err2;
    EXPECT_EQ(run_simulate_command(simulate_options(output), out2, err2), kExitNotDone);
    EXPECT_TRUE(
        has(err2.str(), "furuta simulate: -o " + output.string() + ": another run is writing"))
        << err2.str();
  }
  // Released when that run ends: the next one writes.
  std::ostringstream out, err;
  EXPECT_EQ(run_identify_command(identify_options(output), out, err), kExitDone) << err.str();
  EXPECT_TRUE(fs::exists(output / "results.json"));
}

TEST_F(Outputs, SimulateNeverReplacesTheResultsItReads) {
  const fs::path output = dir_.path() / "identification";
  std::ostringstream fit_out, fit_err;
  ASSERT_EQ(run_identify_command(identify_options(output), fit_out, fit_err), kExitDone)
      << fit_err.str();
  const std::string results = read(output / "results.json");
  SimulateCommandOptions o = simulate_options(output);
  o.results = output / "results.json";
  std::ostringstream out, err;
  EXPECT_EQ(run_simulate_command(o, out, err), kExitNotDone);
  EXPECT_TRUE(has(err.str(), "furuta simulate: -o " + output.string() +
                                 " would overwrite the input " + o.results.string()))
      << err.str();
  EXPECT_EQ(read(output / "results.json"), results);

  std::ostringstream out2, err2;
  EXPECT_EQ(run_simulate_command(simulate_options(kUnwritable), out2, err2), kExitNotDone);
  EXPECT_TRUE(has(err2.str(), "cannot create a file in /proc: ")) << err2.str();
  EXPECT_FALSE(has(err2.str(), "filesystem error")) << err2.str();
  std::ostringstream out3, err3;
  EXPECT_EQ(run_simulate_command(simulate_options(""), out3, err3), kExitNotDone);
  EXPECT_TRUE(has(err3.str(), "furuta simulate: -o is empty")) << err3.str();
}

// Before: done/ and failed/ were made, then "filesystem error: cannot create directories".
TEST_F(Outputs, ProcessLogsRefusesAnUnusableIdentificationsDirectoryBeforeAnything) {
  const fs::path logs = dir_.path() / "logs";
  fs::create_directories(logs);
  ProcessLogsOptions o;
  o.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  o.logs_dir = logs;
  const auto refused = [&](const fs::path& identifications, const std::string& expected) {
    o.identifications_dir = identifications;
    std::ostringstream out, err;
    EXPECT_EQ(run_process_logs_command(o, out, err), kExitNotDone) << identifications;
    EXPECT_TRUE(
        has(err.str(), "furuta process-logs: -o " + identifications.string() + ": " + expected))
        << err.str();
    EXPECT_FALSE(has(err.str(), "filesystem error")) << err.str();
    EXPECT_FALSE(fs::exists(logs / "done"));
    EXPECT_FALSE(fs::exists(logs / "failed"));
  };
  refused(kUnwritable, std::string("cannot create ") + kUnwritable + ": ");
  // The pass would wait forever on the logs directory's lock, which it holds already.
  refused(logs, "is the logs directory");
  refused(logs / "done", "is " + (logs / "done").string() + ", inside the logs directory");
  refused(logs / "failed", "is " + (logs / "failed").string() + ", inside the logs directory");

  // The library refuses the same, whoever calls it.
  LogProcessorOptions processor;
  processor.logs_dir = logs;
  processor.identifications_dir = kUnwritable;
  std::ostringstream out, err;
  EXPECT_THROW(process_logs(processor, out, err), std::runtime_error);
  EXPECT_FALSE(fs::exists(logs / "done"));
}

// Before: `process-logs -o ''` used the configuration's directory, `identify -o ''` failed after
// the fit.
TEST_F(Outputs, AnEmptyOutputOnTheCommandLineIsBadUsage) {
  const std::string cli = FURUTA_CLI;
  const std::string logs = (dir_.path() / "logs").string();
  fs::create_directories(logs);
  for (const std::string& args :
       {" process-logs " + logs + " -o ''", " identify " + log_copy_.string() + " -o ''",
        std::string(" simulate --truth -o ''"), " log export-csv " + log_copy_.string() + " -o ''",
        " report " + log_copy_.string() + " -o ''"}) {
    FILE* pipe = ::popen((cli + args + " 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string text;
    char buffer[4096];
    while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) text += buffer;
    const int status = ::pclose(pipe);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kExitNotDone) << args << "\n" << text;
    EXPECT_TRUE(has(text, "--output: an empty path names no file or directory")) << args << text;
  }
  EXPECT_FALSE(fs::exists(fs::path(logs) / "done"));
}

// Before: of three runs started together into one logs directory, one ended log_error with "left
// by an earlier session: recover it" (their names have whole seconds), and the others' recovery
// moved its running log away.
TEST(ConcurrentRuns, SessionsStartedTogetherIntoOneLogsDirectoryEachKeepTheirLog) {
  TempDir logs;
  std::vector<FILE*> runs;
  for (int seed = 1; seed <= 3; ++seed) {
    const std::string command =
        std::string(FURUTA_CLI) + " run --sim --virtual-time --lcm-url memq:// --config " +
        FURUTA_SOURCE_DIR "/config/rig.toml --label bang-bang --seed " + std::to_string(seed) +
        " --duration 3 --logs-dir " + logs.path().string() + " 2>&1";
    runs.push_back(::popen(command.c_str(), "r"));
    ASSERT_NE(runs.back(), nullptr);
  }
  for (FILE* run : runs) {
    std::string text;
    char buffer[4096];
    while (std::fgets(buffer, sizeof buffer, run) != nullptr) text += buffer;
    const int status = ::pclose(run);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kExitDone) << text;
    EXPECT_TRUE(has(text, "session ended: duration_reached; log ")) << text;
    EXPECT_FALSE(has(text, "recover")) << text;
  }
  std::vector<std::string> finished;
  for (const auto& entry : fs::directory_iterator(logs.path())) {
    if (entry.is_regular_file()) finished.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(finished.size(), 3u);
  for (const std::string& name : finished) EXPECT_FALSE(has(name, "incomplete")) << name;
  EXPECT_TRUE(fs::is_empty(logs.path() / ".partial"));
}

TEST(SameFile, TwoSpellingsOfOneFileAndFilesNotYetMade) {
  TempDir dir;
  std::ofstream(dir.path() / "a") << "a";
  fs::create_symlink(dir.path() / "a", dir.path() / "link");
  EXPECT_TRUE(report::same_file(dir.path() / "a", dir.path() / "link"));
  EXPECT_TRUE(report::same_file(dir.path() / "a", dir.path() / "x" / ".." / "a"));
  EXPECT_TRUE(report::same_file(dir.path() / "new", dir.path() / "." / "new"));
  EXPECT_FALSE(report::same_file(dir.path() / "a", dir.path() / "new"));
  // "out2" is not inside "out".
  EXPECT_FALSE(report::input_in_the_way(dir.path() / "out", {dir.path() / "out2" / "r.json"}));
  EXPECT_TRUE(report::input_in_the_way(dir.path() / "out", {dir.path() / "out" / "r.json"}));
}

}  // namespace
}  // namespace furuta::app::output_paths_test
