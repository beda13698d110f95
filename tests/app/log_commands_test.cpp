// Every command that reads a session log applies one integrity rule (session_log/log_integrity.hpp)
// and says what it did with a log that is not intact: `log info`, `log export-csv`, `replay`,
// `identify` (refused, or its intact parts with --use-intact-part), and a session too short to fit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/model/parameters.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/session_log.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::log_commands_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Sessions made once (virtual time), damaged per test in copies.
class LogCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    made_ = std::make_unique<TempDir>("furuta-log-commands");
    first_ = furuta::testing::simulated_session_log(made_->path(), "fit", 1);
    second_ = furuta::testing::simulated_session_log(made_->path(), "fit", 2);
    short_ = furuta::testing::simulated_session_log(made_->path(), "short", 3, 2.0);
    one_second_ = furuta::testing::simulated_session_log(made_->path(), "one-second", 4, 1.0);
  }
  static void TearDownTestSuite() { made_.reset(); }

  // A copy with `count` seeded random bytes written over the middle of the file.
  // `count` bytes overwritten from the start of the log's middle event: the damage lands among
  // the samples at the same place in the session whatever the length of the records before them.
  fs::path damaged_copy(const fs::path& log, std::size_t count = 2000) const {
    std::string bytes = read_file(log);
    std::vector<std::uint64_t> offsets;
    {
      session_log::LcmLogReader reader(log);
      session_log::LogEvent event;
      while (reader.next(event)) offsets.push_back(event.file_offset);
    }
    const std::size_t from = static_cast<std::size_t>(offsets[offsets.size() / 2]);
    std::mt19937 rng(20241125);
    std::uniform_int_distribution<int> byte(0, 255);
    for (std::size_t k = from; k < from + count; ++k) {
      bytes[k] = static_cast<char>(byte(rng));
    }
    const fs::path copy = dir_.path() / ("damaged_" + log.filename().string());
    write_file(copy, bytes);
    return copy;
  }
  // A copy cut short mid-event, as a crash leaves it when nobody recovered it.
  fs::path truncated_copy(const fs::path& log) const {
    const std::string bytes = read_file(log);
    const fs::path copy = dir_.path() / ("truncated_" + log.filename().string());
    write_file(copy, bytes.substr(0, bytes.size() - 100));
    return copy;
  }
  // Only the session start record: a session that logged no sample before it was cut short.
  fs::path start_only_copy(const fs::path& log) const {
    session_log::LcmLogReader reader(log);
    session_log::LogEvent event;
    reader.next(event);
    reader.next(event);
    const fs::path copy = dir_.path() / ("start_only_" + log.filename().string());
    write_file(copy, read_file(log).substr(0, event.file_offset));
    return copy;
  }

  static std::unique_ptr<TempDir> made_;
  static fs::path first_, second_, short_, one_second_;
  TempDir dir_;
  std::ostringstream out_, err_;
};
std::unique_ptr<TempDir> LogCommands::made_;
fs::path LogCommands::first_, LogCommands::second_, LogCommands::short_, LogCommands::one_second_;

TEST_F(LogCommands, LogInfoIsZeroForAnIntactLogOneForAnyOtherAndTwoForAForeignFile) {
  EXPECT_EQ(run_log_info_command(first_, out_, err_), 0) << err_.str();
  EXPECT_TRUE(contains(out_.str(), "integrity intact")) << out_.str();

  for (const fs::path& log : {damaged_copy(first_), truncated_copy(first_)}) {
    out_.str("");
    err_.str("");
    EXPECT_EQ(run_log_info_command(log, out_, err_), 1) << log;
    EXPECT_TRUE(contains(out_.str(), "integrity not intact")) << out_.str();
    EXPECT_TRUE(contains(err_.str(), "furuta log info: " + log.string() + " is not intact"))
        << err_.str();
  }
  // Before, a damaged region was exit 0 and a truncated tail exit 1: now both name their problem.
  out_.str("");
  err_.str("");
  run_log_info_command(damaged_copy(first_), out_, err_);
  EXPECT_TRUE(contains(err_.str(), "damaged: 1 unreadable region(s)")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "sample(s) missing (sequence numbers ")) << err_.str();

  const fs::path junk = dir_.path() / "junk.lcmlog";
  write_file(junk, "not a log at all");
  err_.str("");
  EXPECT_EQ(run_log_info_command(junk, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), junk.string() + ": not a session log: no session start record"))
      << err_.str();
}

TEST_F(LogCommands, ExportCsvWritesWhatATruncatedLogHasAndSaysItIsNotIntact) {
  const fs::path csv = dir_.path() / "out.csv";
  const fs::path log = truncated_copy(first_);
  EXPECT_EQ(run_log_export_csv_command(log, csv, out_, err_), 1);
  EXPECT_TRUE(contains(err_.str(), "furuta log export-csv: " + log.string() + " is not intact"))
      << err_.str();
  EXPECT_TRUE(contains(err_.str(), "truncated")) << err_.str();
  const std::string text = read_file(csv);
  const auto rows = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) - 1;
  EXPECT_GT(rows, 600u);
  EXPECT_TRUE(contains(err_.str(), "wrote the " + std::to_string(rows) + " samples it has"))
      << err_.str();

  EXPECT_EQ(run_log_export_csv_command(first_, csv, out_, err_), 0);
}

TEST_F(LogCommands, ExportCsvOfALogWithoutSamplesSaysNoSamplesAndOfAnEmptyFileRefuses) {
  const fs::path csv = dir_.path() / "out.csv";
  EXPECT_EQ(run_log_export_csv_command(start_only_copy(first_), csv, out_, err_), 1);
  EXPECT_TRUE(contains(err_.str(), "has no samples")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "cut short")) << err_.str();
  EXPECT_EQ(read_file(csv).find('\n') + 1, read_file(csv).size());  // the header alone

  const fs::path empty = dir_.path() / "empty.lcmlog";
  write_file(empty, "");
  err_.str("");
  fs::remove(csv);
  EXPECT_EQ(run_log_export_csv_command(empty, csv, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), empty.string() + ": not a session log")) << err_.str();
  EXPECT_FALSE(fs::exists(csv));
}

TEST_F(LogCommands, ReplayOfAnIntactLogIsIdentical) {
  EXPECT_EQ(run_replay_command(short_, "", out_, err_), 0) << out_.str() << err_.str();
  EXPECT_TRUE(contains(out_.str(), ": identical")) << out_.str();
}

// Before: "replayed 308 of 307 samples: 0 differ (first at seq -1)", exit 1 without a reason.
TEST_F(LogCommands, ReplayOfATruncatedLogComparesWhatBothHaveAndSaysTheLogIsNotIntact) {
  const fs::path log = truncated_copy(short_);
  EXPECT_EQ(run_replay_command(log, "", out_, err_), 1);
  const std::string text = out_.str();
  EXPECT_FALSE(contains(text, "seq -1")) << text;
  std::size_t compared = 0, logged = 0;
  ASSERT_EQ(std::sscanf(text.c_str(), "replayed %zu of %zu samples", &compared, &logged), 2)
      << text;
  EXPECT_LE(compared, logged);
  EXPECT_GT(compared, 0u);
  // What the truncation took (the reports after the last whole sample) may change the last
  // sample's replay: said as a difference at its sequence number, never as seq -1.
  EXPECT_TRUE(contains(text, "none of them differ") || contains(text, "differ (first at seq "))
      << text;
  EXPECT_TRUE(contains(err_.str(), "furuta replay: " + log.string() + " is not intact: "))
      << err_.str();
  EXPECT_TRUE(contains(err_.str(), "truncated")) << err_.str();
}

TEST_F(LogCommands, IdentifyRefusesADamagedFitOrHeldOutLogNamingItAndTheWayOn) {
  const fs::path damaged = damaged_copy(first_);
  IdentifyCommandOptions options;
  options.logs = {damaged, second_};
  options.output_dir = dir_.path() / "out";
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), "furuta identify: " + damaged.string() + " is not intact: "))
      << err_.str();
  EXPECT_TRUE(contains(err_.str(), "damaged: ")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "--use-intact-part")) << err_.str();
  EXPECT_FALSE(fs::exists(options.output_dir / "results.json"));

  options.logs = {first_};
  options.validate = truncated_copy(second_);
  err_.str("");
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), options.validate.string() + " is not intact: truncated"))
      << err_.str();
}

// Why a log is refused comes from the problems it has: before, an empty log or one with no
// samples was refused for "filtering and differentiating across a gap", which it has none of.
TEST_F(LogCommands, IdentifyRefusesALogForTheProblemsItHasNotAGapItLacks) {
  IdentifyCommandOptions options;
  options.output_dir = dir_.path() / "out";
  const fs::path empty = dir_.path() / "empty.lcmlog";
  write_file(empty, "");
  options.logs = {empty};
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), empty.string() + ": not a session log")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "only session logs")) << err_.str();
  EXPECT_FALSE(contains(err_.str(), "across a gap")) << err_.str();
  EXPECT_FALSE(contains(err_.str(), "--use-intact-part")) << err_.str();

  options.logs = {start_only_copy(first_)};
  err_.str("");
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), "cut short")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "a log without its end")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "no samples to fit")) << err_.str();
  EXPECT_FALSE(contains(err_.str(), "across a gap")) << err_.str();

  // A damaged one still says why a gap matters, and the way on.
  options.logs = {damaged_copy(first_)};
  err_.str("");
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  EXPECT_TRUE(contains(err_.str(), "across a gap")) << err_.str();
  EXPECT_TRUE(contains(err_.str(), "--use-intact-part")) << err_.str();
}

// Before: exit 0, "7 samples missing", mu2 1.45e-3 instead of 2.44e-3 and a residual ten times
// larger, from filtering and differentiating across the damage.
TEST_F(LogCommands, WithUseIntactPartADamagedLogFitsLikeTheIntactOne) {
  IdentifyCommandOptions options;
  options.logs = {first_, second_};
  std::ostringstream err;
  const std::optional<pipeline::Run> intact = run_identification(options, err);
  ASSERT_TRUE(intact) << err.str();

  const fs::path damaged = damaged_copy(first_);
  options.logs = {damaged, second_};
  options.use_intact_part = true;
  const std::optional<pipeline::Run> parts = run_identification(options, err);
  ASSERT_TRUE(parts) << err.str();
  ASSERT_EQ(parts->identification.processed.size(), 3u);  // two parts of the damaged log
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double a = intact->identification.combined.estimate[k];
    const double b = parts->identification.combined.estimate[k];
    std::printf("[ measured ] %s intact %.4e, intact parts %.4e (%+.2f %%)\n",
                std::string(model::kParameterNames[k]).c_str(), a, b, 100 * (b / a - 1));
    EXPECT_NEAR(b / a, 1.0, 0.03) << model::kParameterNames[k];
  }
  EXPECT_LT(parts->identification.combined.sigma, 1.5 * intact->identification.combined.sigma);
  // The output error on the parts, each with the commands written within its time.
  ASSERT_TRUE(intact->output_error.has_value());
  ASSERT_TRUE(parts->output_error.has_value());
  EXPECT_TRUE(parts->output_error->result.converged) << parts->output_error->result.message;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double a = intact->output_error->result.estimate[k];
    const double b = parts->output_error->result.estimate[k];
    std::printf("[ measured ] output error %s intact %.4e, intact parts %.4e (%+.3f %%)\n",
                std::string(model::kParameterNames[k]).c_str(), a, b, 100 * (b / a - 1));
    EXPECT_NEAR(b / a, 1.0, k == 6 ? 0.05 : 0.01) << model::kParameterNames[k];
  }
  std::string warnings;
  for (const auto& w : parts->warnings) warnings += w.text + "\n";
  EXPECT_TRUE(contains(warnings, damaged.filename().string() + ": not intact (damaged: "))
      << warnings;
  EXPECT_TRUE(contains(warnings, "separate part(s) (seq 0-")) << warnings;
}

// Done in part: before, a log fitted by its intact parts exited 0 like a whole one. Now 1, with
// what was used and what was dropped said on stderr.
TEST_F(LogCommands, WithUseIntactPartADamagedLogFitsInPartAndExits1SayingWhatWasDropped) {
  IdentifyCommandOptions options;
  const fs::path damaged = damaged_copy(first_);
  options.logs = {damaged, second_};
  options.use_intact_part = true;
  options.output_dir = dir_.path() / "in-part";
  EXPECT_EQ(run_identify_command(options, out_, err_), 1) << out_.str() << err_.str();
  EXPECT_TRUE(contains(err_.str(), "furuta identify: done in part: " + damaged.filename().string() +
                                       ": not intact (damaged: "))
      << err_.str();
  EXPECT_TRUE(contains(err_.str(), "separate part(s) (seq 0-")) << err_.str();
  EXPECT_TRUE(fs::exists(options.output_dir / "results.json"));
}

// One held-out recording per batch: the longest intact run, the other said to be set aside.
TEST_F(LogCommands, WithUseIntactPartADamagedHeldOutLogKeepsItsLongestRun) {
  IdentifyCommandOptions options;
  options.logs = {first_};
  options.validate = damaged_copy(second_);
  options.use_intact_part = true;
  std::ostringstream err;
  const std::optional<pipeline::Run> run = run_identification(options, err);
  ASSERT_TRUE(run) << err.str();
  ASSERT_TRUE(run->identification.validation.has_value());
  EXPECT_TRUE(contains(run->identification.validation->name, " (seq "))
      << run->identification.validation->name;
  std::string warnings;
  for (const auto& w : run->warnings) warnings += w.text + "\n";
  EXPECT_TRUE(contains(warnings, "(held out: only the longest run is used)")) << warnings;
}

// LSMI alone: "LSMI: 0 equations for 7 parameters" would name neither the log nor what it lacks.
TEST_F(LogCommands, WithoutTheRefinementASessionTooShortIsRefusedNamingTheLengthNeeded) {
  IdentifyCommandOptions options;
  options.logs = {one_second_};
  options.no_output_error = true;
  options.output_dir = dir_.path() / "out";
  EXPECT_EQ(run_identify_command(options, out_, err_), 2);
  const std::string text = err_.str();
  EXPECT_TRUE(contains(text, "furuta identify: " + one_second_.string() + ": too short")) << text;
  // The configuration's 31-tap differentiator: 39 samples at each end, 4 between for 7 parameters.
  EXPECT_TRUE(contains(text, "its fit needs at least 82 samples (1.31 s at 16 ms)")) << text;
  EXPECT_TRUE(contains(text, "but --no-output-error turns it off")) << text;
  EXPECT_FALSE(contains(text, "equations")) << text;
  EXPECT_FALSE(fs::exists(options.output_dir));
}

// The refinement needs no derivatives: a session too short for LSMI's filters is fitted by it
// alone from the CAD values, and nothing LSMI would have given is shown as a result.
TEST_F(LogCommands, ASessionTooShortForLsmiIsFittedByTheRefinementAlone) {
  IdentifyCommandOptions options;
  options.logs = {one_second_};
  options.validate = short_;
  options.sivia = true;
  options.output_dir = dir_.path() / "out";
  ASSERT_EQ(run_identify_command(options, out_, err_), 0) << out_.str() << err_.str();
  const std::string text = out_.str();
  EXPECT_TRUE(contains(text, "warning: LSMI did not run: ")) << text;
  EXPECT_TRUE(contains(text, "too short for LSMI: 6")) << text;
  EXPECT_TRUE(contains(text, "SIVIA skipped")) << text;
  EXPECT_FALSE(contains(text, "all experiments")) << text;
  EXPECT_TRUE(contains(text, "(angle RMSE, q1 / q2): output error ")) << text;

  const nlohmann::json results =
      nlohmann::json::parse(read_file(options.output_dir / "results.json"));
  EXPECT_FALSE(results.contains("combined"));
  EXPECT_TRUE(contains(results["sivia"]["skipped"].get<std::string>(), "LSMI did not run"));
  EXPECT_TRUE(contains(results["lsmi_skipped"].get<std::string>(), "too short for LSMI"));
  const nlohmann::json& oe = results["output_error"];
  ASSERT_TRUE(oe["converged"].get<bool>()) << oe.dump();
  EXPECT_FALSE(oe["held_out_free_run"].contains("lsmi_rmse_rad"));
  const config::RigConfig rig = config::parse_rig_config(
      session_log::load_session_log(one_second_).start->rig_config_toml, "one-second");
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const char* name = model::kParameterNames[k];
    const double truth = rig.simulation.parameters[k];
    const double sd = oe["std_dev"][name].get<double>();
    EXPECT_NEAR(oe["estimate"][name].get<double>(), truth, 3 * sd) << name;
    // One second of bang-bang pins each parameter down, if less than ten.
    EXPECT_LT(sd, 0.01 * std::abs(truth)) << name;
  }
  const std::string report = read_file(options.output_dir / "report.html");
  EXPECT_TRUE(contains(report, "Table I: output-error estimates")) << report.substr(0, 2000);
  EXPECT_TRUE(contains(report, "LSMI did not run: no torque validation.")) << report.size();

  // `furuta simulate` on it takes the refinement's estimate, the only one there is.
  SimulateCommandOptions simulate;
  simulate.results = options.output_dir / "results.json";
  simulate.scenarios = {1};
  simulate.seconds = 0.2;
  simulate.output_dir = dir_.path() / "simulation";
  std::ostringstream simulated, simulate_err;
  ASSERT_EQ(run_simulate_command(simulate, simulated, simulate_err), 0) << simulate_err.str();
  EXPECT_TRUE(contains(simulated.str(), "(a)  output error")) << simulated.str();
  EXPECT_TRUE(contains(simulated.str(), "SIVIA did not run: point parameters only"))
      << simulated.str();
}

}  // namespace
}  // namespace furuta::app::log_commands_test
