// Balance sessions as a user runs them, in virtual time on the simulated rig: a controller designed
// from the main job's results swings the pendulum up, catches and holds it, and the log says so
// (controller record, a controller cycle beside each sample, intact, replayable); a small tap is
// recovered from and a large one ends in a fall with the motor at zero; a controller file for
// another rig, or one that does not read, is refused before anything moves.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "commands.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/pipeline/balance.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"
#include "temp_dir.hpp"

namespace furuta::app::balance_session_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// `furuta controller design` on the main job's results, with the configuration at `config`.
fs::path design(const fs::path& dir,
                const fs::path& config = FURUTA_SOURCE_DIR "/config/rig.toml") {
  ControllerDesignOptions options;
  options.results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
  options.config_path = config;
  options.output = dir / "controller.toml";
  std::ostringstream out, err;
  EXPECT_EQ(run_controller_design_command(options, out, err), 0) << err.str();
  return options.output;
}

// The shipped configuration with each (from, to) replaced in its text.
fs::path configuration(const fs::path& dir,
                       std::initializer_list<std::pair<std::string, std::string>> edits) {
  std::string text = read_text(FURUTA_SOURCE_DIR "/config/rig.toml");
  for (const auto& [from, to] : edits) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  const fs::path path = dir / "rig.toml";
  std::ofstream(path) << text;
  return path;
}

struct Ran {
  int code = -1;
  std::string out, err;
  fs::path log;  // empty: none written
};

Ran run_balance(const fs::path& dir, const fs::path& controller, double duration_s,
                const fs::path& config = FURUTA_SOURCE_DIR "/config/rig.toml") {
  RunOptions options;
  options.config_path = config;
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = dir / "logs";
  options.lcm_url = "memq://";
  options.session.balance = controller;
  options.session.duration_s = duration_s;
  options.session.label = "balance";
  std::ostringstream out, err;
  Ran ran;
  ran.code = run_session_command(options, out, err);
  ran.out = out.str();
  ran.err = err.str();
  if (fs::exists(options.logs_dir)) {
    for (const auto& entry : fs::directory_iterator(options.logs_dir)) {
      if (entry.path().extension() == ".lcmlog") ran.log = entry.path();
    }
  }
  return ran;
}

TEST(BalanceSession, SwingsUpCatchesAndBalancesAndTheLogSaysSo) {
  TempDir dir("furuta-balance");
  const fs::path controller = design(dir.path());
  const Ran ran = run_balance(dir.path(), controller, 30);
  ASSERT_EQ(ran.code, 0) << ran.out << ran.err;
  EXPECT_NE(ran.out.find("session ended: duration_reached"), std::string::npos) << ran.out;
  EXPECT_NE(ran.out.find("  balance   caught at "), std::string::npos) << ran.out;

  const session_log::SessionLog log = session_log::load_session_log(ran.log);
  EXPECT_TRUE(session_log::integrity_problems(log).empty())
      << session_log::describe(session_log::integrity_problems(log));
  ASSERT_TRUE(log.start.has_value());
  EXPECT_EQ(log.start->profile, "balance");
  ASSERT_TRUE(log.controller.has_value());
  EXPECT_EQ(log.controller->controller_toml, read_text(controller));
  EXPECT_EQ(log.controller->sha256, config::load_controller_file(controller).sha256);
  ASSERT_EQ(log.control.size(), log.samples.size());
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    ASSERT_EQ(log.control[i].seq, log.samples[i].seq);
    // What was sent is what the law asked for while the session ran.
    ASSERT_EQ(log.control[i].law_duty, log.samples[i].commanded_duty) << i;
  }

  const auto b = pipeline::summarize_balance(log);
  ASSERT_TRUE(b.has_value());
  ASSERT_TRUE(b->caught_at_s.has_value());
  EXPECT_LT(*b->caught_at_s, 10.0);
  EXPECT_GT(b->balanced_s, 18.0);
  EXPECT_LT(b->upright_rms_deg, 1.0);
  EXPECT_FALSE(b->fell);
  EXPECT_LT(b->max_abs_arm_deg, 150.0);
  // The controller the session ran, from its record: the file's digest and what it was designed
  // from.
  ASSERT_TRUE(b->controller.has_value());
  EXPECT_EQ(b->controller->sha256, log.controller->sha256);
  EXPECT_EQ(b->controller->parameters_source, "output-error");
  EXPECT_TRUE(b->controller->unreadable.empty()) << b->controller->unreadable;
  // Held upright: the last seconds are all balance.
  EXPECT_EQ(log.control.back().mode, +furuta::rig_control_t::MODE_BALANCE);

  // A log like any other: its replay runs the same law on the same traffic, sample for sample.
  std::ostringstream out, err;
  EXPECT_EQ(run_replay_command(ran.log, FURUTA_SOURCE_DIR "/config/rig.toml", out, err), 0)
      << out.str() << err.str();
}

// At 8 ms, the boards' own report period, each angle the loop reads is up to a period old and a
// board may have no new report in a cycle; designed and run with that period, the same holds.
TEST(BalanceSession, AtTheBoardsReportPeriodItBalancesToo) {
  TempDir dir("furuta-balance-8ms");
  const fs::path config = configuration(dir.path(), {{"period_ms = 16", "period_ms = 8"}});
  const fs::path controller = design(dir.path(), config);
  EXPECT_EQ(config::load_controller_file(controller).period_ns, 8'000'000);
  const Ran ran = run_balance(dir.path(), controller, 30, config);
  ASSERT_EQ(ran.code, 0) << ran.out << ran.err;
  const auto b = pipeline::summarize_balance(session_log::load_session_log(ran.log));
  ASSERT_TRUE(b.has_value());
  ASSERT_TRUE(b->caught_at_s.has_value());
  EXPECT_LT(*b->caught_at_s, 10.0);
  EXPECT_GT(b->balanced_s, 18.0);
  EXPECT_LT(b->upright_rms_deg, 1.0);
  EXPECT_LT(b->duty_rms, 0.05);
  EXPECT_FALSE(b->fell);
  EXPECT_LT(b->max_abs_arm_deg, 150.0);
}

TEST(BalanceSession, ASmallTapIsRecoveredFromAndALargeOneEndsInAFallWithTheMotorOff) {
  TempDir dir("furuta-balance-tap");
  const fs::path controller = design(dir.path());
  {
    TempDir run_dir("furuta-balance-small");
    const fs::path config =
        configuration(run_dir.path(), {{"tap_times_s = []", "tap_times_s = [15.0]"},
                                       {"tap_impulse_mnm_s = 0.0", "tap_impulse_mnm_s = 2.0"}});
    const Ran ran = run_balance(run_dir.path(), controller, 25, config);
    ASSERT_EQ(ran.code, 0) << ran.out << ran.err;
    const auto b = pipeline::summarize_balance(session_log::load_session_log(ran.log));
    ASSERT_TRUE(b.has_value());
    EXPECT_FALSE(b->fell);
    EXPECT_GT(b->upright_max_deg, 3.0);  // the tap was felt
    EXPECT_LT(b->upright_rms_deg, 1.0);
  }
  TempDir run_dir("furuta-balance-large");
  const fs::path config =
      configuration(run_dir.path(), {{"tap_times_s = []", "tap_times_s = [15.0]"},
                                     {"tap_impulse_mnm_s = 0.0", "tap_impulse_mnm_s = 20.0"}});
  const Ran ran = run_balance(run_dir.path(), controller, 25, config);
  EXPECT_EQ(ran.code, 1) << ran.out << ran.err;
  EXPECT_NE(ran.out.find("session ended: pendulum_fell"), std::string::npos) << ran.out;
  const session_log::SessionLog log = session_log::load_session_log(ran.log);
  ASSERT_TRUE(log.end.has_value());
  EXPECT_EQ(log.end->end_reason.rfind("pendulum_fell", 0), 0u) << log.end->end_reason;
  EXPECT_NE(log.end->end_reason.find("beyond the fall limit"), std::string::npos)
      << log.end->end_reason;
  EXPECT_TRUE(session_log::integrity_problems(log).empty());
  // Fell after the tap, and the last thing written to the motor was the zero.
  const double fell_at_s =
      static_cast<double>(log.samples.back().monotonic_ns - log.start->monotonic_ns) * 1e-9;
  EXPECT_GT(fell_at_s, 13.0);
  EXPECT_EQ(log.samples.back().commanded_duty, 0.0);
  EXPECT_EQ(log.control.back().mode, +furuta::rig_control_t::MODE_FALLEN);
  // The end reason carries the fall's detail; the summary still knows it fell.
  const auto fallen = pipeline::summarize_balance(log);
  ASSERT_TRUE(fallen.has_value());
  EXPECT_TRUE(fallen->fell);
  EXPECT_EQ(fallen->end_reason, log.end->end_reason);
  const auto writes = session_log::motor_command_writes(log, "1065");
  ASSERT_FALSE(writes.empty());
  EXPECT_EQ(writes.back().duty, 0.0);
}

TEST(BalanceSession, AControllerForAnotherRigIsRefusedWithoutMotion) {
  TempDir dir("furuta-balance-rig");
  const fs::path other =
      configuration(dir.path(), {{"name = \"furuta-lab-1\"", "name = \"furuta-lab-2\""}});
  const fs::path controller = design(dir.path(), other);
  const Ran ran = run_balance(dir.path(), controller, 5);
  EXPECT_EQ(ran.code, 1) << ran.out << ran.err;
  EXPECT_NE(ran.err.find("was designed for rig 'furuta-lab-2', this is 'furuta-lab-1'"),
            std::string::npos)
      << ran.err;
  EXPECT_TRUE(ran.log.empty()) << "a session ran: " << ran.log;
}

TEST(BalanceSession, AControllerFileThatDoesNotReadIsRefusedBeforeAnythingRuns) {
  TempDir dir("furuta-balance-bad");
  const fs::path controller = design(dir.path());
  std::string text = read_text(controller);
  const auto at = text.find("max_acceleration = ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("max_acceleration = ").size(), "max_acceleration = -");
  std::ofstream(controller) << text;
  const Ran ran = run_balance(dir.path(), controller, 5);
  EXPECT_EQ(ran.code, 2) << ran.out << ran.err;
  // The file, its line and the key.
  EXPECT_NE(ran.err.find(controller.string() + ":"), std::string::npos) << ran.err;
  EXPECT_NE(ran.err.find("max_acceleration"), std::string::npos) << ran.err;
  EXPECT_NE(ran.err.find("nothing was started"), std::string::npos) << ran.err;
  EXPECT_TRUE(ran.log.empty());
  EXPECT_EQ(ran.out.find("furuta run: rig:"), std::string::npos) << "the rig was opened";
}

}  // namespace
}  // namespace furuta::app::balance_session_test
