// `furuta report` on balance sessions of the simulated rig: report.html and balance.json whose
// figures are summarize_balance's, the four plots of each session; another session's log said to
// be one (exit 1, named); output directories refused as identify refuses them (exit 2, nothing
// written). And `furuta identify` on balance sessions alone: its report shows each one, and the
// warning on LSMI's estimate names the closed loop, not the pendulum's encoder.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/pipeline/balance.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/session_log/session_log.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::report_command_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;
using nlohmann::json;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// A balance session of `seconds` on the simulated rig in virtual time, with `controller`.
fs::path balance_session(const fs::path& logs, const fs::path& controller, double seconds,
                         const std::string& label) {
  RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = logs;
  options.lcm_url = "memq://";
  options.session.balance = controller;
  options.session.duration_s = seconds;
  options.session.label = label;
  std::ostringstream out, err;
  EXPECT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  const std::string text = out.str();
  const auto at = text.find("; log ");
  if (at == std::string::npos) return {};
  return fs::path(text.substr(at + 6, text.find('\n', at) - at - 6));
}

// Two balance sessions (35 s and 30 s) and a bang-bang one, made once for the suite.
class ReportCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>("furuta-report-command");
    ControllerDesignOptions design;
    design.results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
    design.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
    design.output = dir_->path() / "controller.toml";
    std::ostringstream out, err;
    ASSERT_EQ(run_controller_design_command(design, out, err), 0) << err.str();
    balance_a_ = balance_session(dir_->path() / "logs", design.output, 35, "balance-a");
    balance_b_ = balance_session(dir_->path() / "logs", design.output, 30, "balance-b");
    bang_bang_ = furuta::testing::simulated_session_log(dir_->path() / "logs", "bang", 1, 6.0);
  }
  static void TearDownTestSuite() { dir_.reset(); }
  void SetUp() override {
    ASSERT_FALSE(balance_a_.empty() || balance_b_.empty() || bang_bang_.empty());
  }

  struct Ran {
    int code = -1;
    std::string out, err;
  };
  static Ran report(const std::vector<fs::path>& logs, const fs::path& output) {
    ReportCommandOptions options;
    options.logs = logs;
    options.output_dir = output;
    std::ostringstream out, err;
    Ran ran;
    ran.code = run_report_command(options, out, err);
    ran.out = out.str();
    ran.err = err.str();
    return ran;
  }

  static std::unique_ptr<TempDir> dir_;
  static fs::path balance_a_, balance_b_, bang_bang_;
};
std::unique_ptr<TempDir> ReportCommand::dir_;
fs::path ReportCommand::balance_a_, ReportCommand::balance_b_, ReportCommand::bang_bang_;

TEST_F(ReportCommand, WritesThePageAndBalanceJsonWithTheSummarysFigures) {
  TempDir dir("furuta-report-out");
  const fs::path output = dir.path() / "report";
  const Ran ran = report({balance_a_}, output);
  ASSERT_EQ(ran.code, kExitDone) << ran.out << ran.err;
  EXPECT_TRUE(ran.err.empty()) << ran.err;
  EXPECT_TRUE(has(ran.out, "report: " + (output / "report.html").string())) << ran.out;
  EXPECT_TRUE(has(ran.out, "  balance   caught at ")) << ran.out;

  const session_log::SessionLog log = session_log::load_session_log(balance_a_);
  const auto b = pipeline::summarize_balance(log);
  ASSERT_TRUE(b.has_value());
  ASSERT_TRUE(b->caught_at_s.has_value()) << "the controller caught the pendulum";
  const json j = json::parse(read_text(output / "balance.json"));
  ASSERT_EQ(j["logs"].size(), 1u);
  EXPECT_EQ(j["logs"][0]["log"], balance_a_.string());
  EXPECT_EQ(j["logs"][0]["profile"], "balance");
  EXPECT_EQ(j["logs"][0]["samples"].get<std::size_t>(), log.samples.size());
  EXPECT_EQ(j["logs"][0]["end_reason"], log.end->end_reason);
  EXPECT_TRUE(j["logs"][0]["intact"].get<bool>());
  const json& f = j["logs"][0]["balance"];
  EXPECT_EQ(f["cycles"].get<std::int64_t>(), b->cycles);
  EXPECT_EQ(f["caught_at_s"].get<double>(), *b->caught_at_s);
  EXPECT_EQ(f["balanced_s"].get<double>(), b->balanced_s);
  EXPECT_EQ(f["upright_rms_deg"].get<double>(), b->upright_rms_deg);
  EXPECT_EQ(f["upright_max_deg"].get<double>(), b->upright_max_deg);
  EXPECT_EQ(f["duty_rms"].get<double>(), b->duty_rms);
  EXPECT_EQ(f["max_abs_duty"].get<double>(), b->max_abs_duty);
  EXPECT_EQ(f["max_abs_arm_deg"].get<double>(), b->max_abs_arm_deg);
  EXPECT_EQ(f["fell"].get<bool>(), b->fell);
  EXPECT_EQ(f["law_time_p50_ns"].get<std::int64_t>(), b->law_time_p50_ns);
  EXPECT_EQ(f["law_time_max_ns"].get<std::int64_t>(), b->law_time_max_ns);
  EXPECT_EQ(f["controller"]["path"], log.controller->path);
  EXPECT_EQ(f["controller"]["sha256"], log.controller->sha256);
  EXPECT_EQ(f["controller"]["parameters_source"], "output-error");

  const std::string html = read_text(output / "report.html");
  EXPECT_TRUE(has(html, "<figure id=\"fig-balance-1\">"));
  for (const char* panel : {"upright", "arm", "duty", "mode"}) {
    EXPECT_TRUE(has(html, "<g class=\"panel\" id=\"fig-balance-1-" + std::string(panel) + "\">"))
        << panel;
  }
  EXPECT_TRUE(has(html, "data-mode=\"balance\""));
  EXPECT_TRUE(has(html, "<td>" + log.controller->sha256 + "</td>"));
  EXPECT_TRUE(has(html, "<td>no</td>")) << "it did not fall";
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_TRUE(fs::exists(output / "balance_1.svg"));
  EXPECT_TRUE(fs::exists(output / report::kRunMarkerFile));

  // Again into the same directory: the previous report is replaced whole.
  const Ran again = report({balance_a_, balance_b_}, output);
  ASSERT_EQ(again.code, kExitDone) << again.err;
  EXPECT_TRUE(has(again.out, "were replaced")) << again.out;
  EXPECT_EQ(json::parse(read_text(output / "balance.json"))["logs"].size(), 2u);
  EXPECT_TRUE(fs::exists(output / "balance_2.svg"));
}

TEST_F(ReportCommand, ALogThatIsNoBalanceSessionIsSaidToBeOneAndNamedWithExit1) {
  TempDir dir("furuta-report-out");
  const fs::path output = dir.path() / "report";
  const Ran ran = report({balance_a_, bang_bang_}, output);
  EXPECT_EQ(ran.code, kExitPartOrRefused) << ran.out << ran.err;
  EXPECT_TRUE(has(ran.err, "furuta report: done in part: " + bang_bang_.string() +
                               " is not a balance session (profile bang_bang)"))
      << ran.err;
  EXPECT_FALSE(has(ran.err, balance_a_.string())) << ran.err;
  const json j = json::parse(read_text(output / "balance.json"));
  ASSERT_EQ(j["logs"].size(), 2u);
  EXPECT_TRUE(j["logs"][1]["balance"].is_null());
  EXPECT_EQ(j["logs"][1]["profile"], "bang_bang");
  const std::string html = read_text(output / "report.html");
  EXPECT_TRUE(
      has(html, "Not a balance session: profile bang_bang, " +
                    std::to_string(session_log::load_session_log(bang_bang_).samples.size()) +
                    " samples"))
      << html.substr(0, 2000);
  EXPECT_TRUE(has(html, "<figure id=\"fig-balance-1\">"));
  EXPECT_FALSE(has(html, "fig-balance-2"));
}

TEST_F(ReportCommand, ALogCutShortIsReportedAsFarAsItGoesWithExit1) {
  TempDir dir("furuta-report-out");
  // The balance log without its last 40 % of bytes: no end record.
  const std::string bytes = read_text(balance_b_);
  const fs::path cut = dir.path() / "cut.lcmlog";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 6 / 10);
  const Ran ran = report({cut}, dir.path() / "report");
  EXPECT_EQ(ran.code, kExitPartOrRefused) << ran.out << ran.err;
  EXPECT_TRUE(has(ran.err, "furuta report: done in part: " + cut.string() + " is not intact"))
      << ran.err;
  const json j = json::parse(read_text(dir.path() / "report" / "balance.json"));
  EXPECT_FALSE(j["logs"][0]["intact"].get<bool>());
  EXPECT_FALSE(j["logs"][0]["problems"].empty());
  EXPECT_TRUE(j["logs"][0]["end_reason"].is_null()) << "cut short: no end record";
  EXPECT_TRUE(j["logs"][0]["balance"].is_object());
}

TEST_F(ReportCommand, OutputsItMayNotUseAndFilesThatAreNoLogsAreRefusedWithNothingWritten) {
  TempDir dir("furuta-report-out");
  // Empty -o.
  Ran ran = report({balance_a_}, "");
  EXPECT_EQ(ran.code, kExitNotDone);
  EXPECT_TRUE(has(ran.err, "furuta report: -o is empty")) << ran.err;
  // -o holding the log: replacing it whole would delete it.
  ran = report({balance_a_}, balance_a_.parent_path());
  EXPECT_EQ(ran.code, kExitNotDone);
  EXPECT_TRUE(has(ran.err, "would overwrite the input " + balance_a_.string())) << ran.err;
  EXPECT_TRUE(fs::exists(balance_a_));
  // A directory of someone's files is never emptied.
  const fs::path theirs = dir.path() / "theirs";
  fs::create_directories(theirs);
  std::ofstream(theirs / "notes.txt") << "mine";
  ran = report({balance_a_}, theirs);
  EXPECT_EQ(ran.code, kExitNotDone);
  EXPECT_TRUE(has(ran.err, "furuta report: -o " + theirs.string() + ": ")) << ran.err;
  EXPECT_EQ(read_text(theirs / "notes.txt"), "mine");
  EXPECT_FALSE(fs::exists(theirs / "report.html"));
  // A directory another run is writing.
  const fs::path busy = dir.path() / "busy";
  {
    const report::RunDirectory other_run(busy);
    ran = report({balance_a_}, busy);
    EXPECT_EQ(ran.code, kExitNotDone);
    EXPECT_TRUE(has(ran.err, "another run is writing " + busy.string() + " now (pid " +
                                 std::to_string(::getpid())))
        << ran.err;
  }
  EXPECT_FALSE(fs::exists(busy / "report.html"));
  // A file that is no session log: bad input, nothing written.
  const fs::path foreign = dir.path() / "notes.lcmlog";
  std::ofstream(foreign) << "not a log";
  ran = report({balance_a_, foreign}, dir.path() / "out");
  EXPECT_EQ(ran.code, kExitNotDone);
  EXPECT_TRUE(has(ran.err, "furuta report: " + foreign.string() + ": ")) << ran.err;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  EXPECT_TRUE(ran.out.empty()) << ran.out;
}

TEST_F(ReportCommand, TheCommandLineNeedsLogsAndAnOutput) {
  const std::string cli = FURUTA_CLI;
  const auto status = [](const std::string& command, std::string& text) {
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (pipe == nullptr) return -1;
    std::array<char, 4096> buffer{};
    while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) text += buffer.data();
    const int s = ::pclose(pipe);
    return WIFEXITED(s) ? WEXITSTATUS(s) : -1;
  };
  TempDir dir("furuta-report-cli");
  std::string text;
  EXPECT_EQ(status(cli + " report " + balance_a_.string(), text), kExitNotDone) << text;
  EXPECT_TRUE(has(text, "--output is required")) << text;
  text.clear();
  EXPECT_EQ(status(cli + " report -o " + (dir.path() / "r").string(), text), kExitNotDone);
  EXPECT_TRUE(has(text, "LOG is required")) << text;
  text.clear();
  EXPECT_EQ(status(cli + " report /nonexistent.lcmlog -o " + (dir.path() / "r").string(), text),
            kExitNotDone);
  text.clear();
  EXPECT_EQ(
      status(cli + " report " + balance_a_.string() + " -o " + (dir.path() / "r").string(), text),
      kExitDone)
      << text;
  EXPECT_TRUE(fs::exists(dir.path() / "r" / "report.html"));
}

// Identifying balance sessions alone: least squares on closed-loop data is biased (the duty
// follows the measured angles, noise included) and the warning on a non-physical LSMI estimate
// said to check the pendulum encoder's zero and sign. It names the loop now, and the report shows
// each balance session's figures beside the fit. LSMI only (the refinement is the remedy the
// warning names, not what is tested here).
TEST_F(ReportCommand, IdentifyingBalanceSessionsNamesTheLoopAndShowsEachSession) {
  TempDir dir("furuta-report-identify");
  IdentifyCommandOptions options;
  options.logs = {balance_a_, balance_b_};
  options.output_dir = dir.path() / "identification";
  options.no_output_error = true;
  std::ostringstream out, err;
  ASSERT_EQ(run_identify_command(options, out, err), kExitDone) << out.str() << err.str();
  const json results = json::parse(read_text(options.output_dir / "results.json"));
  // Whether least squares lands outside the physical region depends on how much the loop's duty
  // follows the measurement noise; when it does, the cause named is the loop, never the
  // pendulum encoder's zero and sign (PhysicalCheck.OnClosedLoopRecordings... tests the choice).
  std::string all;
  for (const auto& w : results["warnings"])
    all += (w.is_string() ? w.get<std::string>() : w.dump());
  EXPECT_FALSE(has(all, "zero upright")) << all;
  EXPECT_FALSE(has(all, "[encoders.pendulum]")) << all;
  if (has(all, "not physical: the LSMI estimate")) {
    EXPECT_TRUE(has(all, "Likely cause: closed-loop data")) << all;
    EXPECT_TRUE(has(out.str(), "Likely cause: closed-loop data")) << out.str();
  }

  const std::string html = read_text(options.output_dir / "report.html");
  EXPECT_FALSE(has(html, "zero upright"));
  ASSERT_TRUE(has(html, "<section id=\"balance\">"));
  EXPECT_TRUE(has(html, "<h3>" + balance_a_.filename().string() + "</h3>"));
  EXPECT_TRUE(has(html, "<h3>" + balance_b_.filename().string() + "</h3>"));
  for (const char* id : {"fig-balance-1", "fig-balance-2"}) {
    EXPECT_TRUE(has(html, "<figure id=\"" + std::string(id) + "\">")) << id;
    EXPECT_TRUE(has(html, "id=\"" + std::string(id) + "-mode\"")) << id;
  }
}

}  // namespace
}  // namespace furuta::app::report_command_test
