// The controller file's reader: a whole file becomes the balance law's spec, number for number;
// every mistake in it is a ConfigError at the file, line and key it is in, whether the reader
// or the balance law's own checks find it; the digest is the file's SHA-256.
#include "furuta/config/controller_file.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "furuta/control/upright_lqr.hpp"
#include "sha256sum.hpp"
#include "temp_dir.hpp"

namespace furuta::config::controller_file_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

// A file as `furuta controller design` writes it: its lags together under one period, so one duty
// on its way and a gain of five entries.
const char* const kValid = R"(# a balance controller
[controller]
kind = "upright_lqr"
rig = "furuta-lab-1"
period_ns = 16000000
lag_s = 0.002
ramp_lag_s = 0.0004
ramp_step_duty = 0.05
ramp_duty_per_s = 62.5
supply_v = 12.0
designed_by = "furuta 1.0"

[parameters]
source = "output-error"
results = "/tmp/run/results.json"
results_sha256 = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef"
mu1 = 0.0048
mu2 = 0.0011
mu3 = 0.0021
mu4 = 0.0014
mug = 0.115
fv1 = 0.0012
fv2 = 1.5e-05

[weights]
q1 = 1.0
q2 = 10.0
dq1 = 0.1
dq2 = 0.1
duty = 10.0

[gain]
k = [-0.31622776601683794, 9.876543210987654, -0.2837153, 0.9123456789012345, 0.1234]

[prediction]
closed_loop_poles_re = [0.949, 0.9, 0.5, 0.2, 0.01]
closed_loop_poles_im = [0.0, 0.0, 0.1, -0.1, 0.0]
spectral_radius = 0.949

[observer]
arm_acceleration_sd = 20.0
pendulum_acceleration_sd = 20.0
arm_count_rad = 0.000236
pendulum_count_rad = 0.00153
reading_age_s = 0.004
m = [0.9, 0.01, 0.02, 0.8, 12.0, 0.5, 0.3, 15.0]
spectral_radius = 0.6
worst_spectral_radius = 0.7

[drive]
duty_torque_nm = 0.52
back_emf_nm_s = 0.047

[swing_up]
energy_gain = 2000.0
max_acceleration = 150.0
arm_gain = 40.0
arm_damping = 8.0
max_duty = 0.5
energy_margin = 0.2
start_below_energy_ratio = 0.005
start_acceleration = 20.0
pump_arm_deg = 45.0

[catch]
catch_deg = 25.0
entry_duty_ratio = 0.5
release_deg = 42.0
settle_s = 1.0
fall_deg = 40.0

[limits]
max_duty = 0.5
duty_step = 0.00392156862745098
)";

// The 1-based line of kValid that starts with `start`.
int line_of(const std::string& start) {
  std::istringstream in(kValid);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.rfind(start, 0) == 0) return n;
  }
  ADD_FAILURE() << "no line starts with " << start;
  return -1;
}

// kValid with the line starting with `start` replaced by `by` (several lines, or none).
std::string with_line(const std::string& start, const std::string& by) {
  std::istringstream in(kValid);
  std::string line, out;
  bool found = false;
  while (std::getline(in, line)) {
    if (!found && line.rfind(start, 0) == 0) {
      found = true;
      if (!by.empty()) out += by + "\n";
    } else {
      out += line + "\n";
    }
  }
  EXPECT_TRUE(found) << start;
  return out;
}

// The [limits] table's lines, whose max_duty key the [swing_up] table has too.
int limits_line(const std::string& start) {
  return line_of("[limits]") + (start == "max_duty" ? 1 : 2);
}
std::string with_limit(const std::string& key, const std::string& value) {
  std::string text = kValid;
  const auto at = text.find(key + " = ", text.find("[limits]"));
  text.replace(at, text.find('\n', at) - at, key + " = " + value);
  return text;
}

using furuta::testing::sha256sum;

TEST(ControllerFile, AWholeFileIsTheSpecTheBalanceLawRuns) {
  const ControllerFile f = parse_controller_file(kValid, "C.toml");
  EXPECT_EQ(f.kind, "upright_lqr");
  EXPECT_EQ(f.rig, "furuta-lab-1");
  EXPECT_EQ(f.designed_by, "furuta 1.0");
  EXPECT_EQ(f.parameters_source, "output-error");
  EXPECT_EQ(f.results, "/tmp/run/results.json");
  EXPECT_EQ(f.results_sha256.substr(0, 8), "01234567");
  EXPECT_EQ(f.period_ns, 16000000);
  EXPECT_EQ(f.lag_s, 0.002);
  EXPECT_EQ(f.ramp_lag_s, 0.0004);
  EXPECT_EQ(f.ramp_step_duty, 0.05);
  EXPECT_EQ(f.supply_v, 12.0);
  EXPECT_EQ(f.text, kValid);
  EXPECT_TRUE(f.path.empty());

  const control::BalanceControllerSpec& s = f.spec;
  EXPECT_EQ(s.period_s, 16000000 * 1e-9);
  EXPECT_EQ(s.delayed, 1);
  const std::array<double, control::kMaxGains> gain = {
      -0.31622776601683794, 9.876543210987654, -0.2837153, 0.9123456789012345, 0.1234, 0, 0, 0};
  EXPECT_EQ(s.gain, gain);
  EXPECT_EQ(s.max_duty, 0.5);
  EXPECT_EQ(s.duty_step, 0.00392156862745098);
  EXPECT_EQ(s.duty_step, 1.0 / 255.0);
  EXPECT_EQ(s.parameters.mu1, 0.0048);
  EXPECT_EQ(s.parameters.mug, 0.115);
  EXPECT_EQ(s.parameters.fv2, 1.5e-05);
  EXPECT_EQ(s.duty_torque_nm, 0.52);
  EXPECT_EQ(s.back_emf_nm_s, 0.047);
  EXPECT_EQ(s.swing_up.energy_gain, 2000.0);
  EXPECT_EQ(s.swing_up.max_acceleration, 150.0);
  EXPECT_EQ(s.swing_up.arm_gain, 40.0);
  EXPECT_EQ(s.swing_up.arm_damping, 8.0);
  EXPECT_EQ(s.swing_up.max_duty, 0.5);
  EXPECT_EQ(s.swing_up.start_below_energy_ratio, 0.005);
  EXPECT_EQ(s.swing_up.start_acceleration, 20.0);
  const double deg = std::numbers::pi / 180.0;
  EXPECT_EQ(s.region.catch_rad, 25.0 * deg);
  EXPECT_EQ(s.region.entry_duty_ratio, 0.5);
  EXPECT_EQ(s.swing_up.pump_arm_rad, 45.0 * deg);
  EXPECT_EQ(s.region.release_rad, 42.0 * deg);
  EXPECT_EQ(s.region.settle_s, 1.0);
  EXPECT_EQ(s.region.fall_rad, 40.0 * deg);
  const std::array<double, 8> m = {0.9, 0.01, 0.02, 0.8, 12.0, 0.5, 0.3, 15.0};
  EXPECT_EQ(s.observer_gain, m);
  // The filter's model is the file's, linearised as the design linearised it, its duties taken
  // after the data path's lag and ramped to as the board does.
  const control::LinearPlant linear =
      control::linearize_upright(s.parameters, {s.duty_torque_nm, s.back_emf_nm_s});
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(s.b_continuous[static_cast<std::size_t>(i)], linear.b(i));
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(s.a_continuous[static_cast<std::size_t>(i * 4 + j)], linear.a(i, j));
    }
  }
  EXPECT_EQ(s.duty_path.lag_s, 0.002);
  EXPECT_EQ(s.duty_path.ramp_duty_per_s, 62.5);
  control::BalanceLaw law(s);
  EXPECT_EQ(law.spec().gain, gain);
  // Hanging at rest the law starts the swing with a whole number of duty steps.
  const control::BalanceStep step = law.step(0.0, 0.0);
  EXPECT_EQ(step.mode, control::BalanceMode::swing_up);
  EXPECT_EQ(step.duty, std::round(step.duty / s.duty_step) * s.duty_step);
}

struct Mistake {
  const char* what;
  std::string text;
  int line;           // 0: no line (a table that is missing)
  std::string field;  // the key, dotted
  std::string problem;
};

TEST(ControllerFile, EveryMistakeNamesTheFileTheLineAndTheKey) {
  const std::string k5 = "k = [-0.3, 9.8, -0.28, 0.91, 0.12";
  std::string no_gain = with_line("k =", "");
  no_gain.erase(no_gain.find("[gain]\n"), 7);
  std::string value_drive = with_line("# a balance controller", "drive = 1");
  value_drive.replace(value_drive.find("[drive]"), 7, "[drive_table]");
  const std::vector<Mistake> cases = {
      {"no [gain] table", no_gain, 0, "gain", "missing: the [gain] table"},
      {"a missing key", with_line("rig =", ""), line_of("[controller]"), "controller.rig",
       "missing: the [rig] name"},
      {"a gain too long", with_line("k =", k5 + ", 0.1, 0.1, 0.1, 0.1]"), line_of("k ="), "gain.k",
       "must be an array of 4 to 8 numbers"},
      {"a gain too short", with_line("k =", "k = [1.0, 2.0, 3.0]"), line_of("k ="), "gain.k",
       "must be an array of 4 to 8 numbers"},
      {"a gain not the length of its lag", with_line("k =", k5 + ", 0.1]"), line_of("k ="),
       "gain.k", "has 6 entries, but controller.lag_s + ramp_lag_s at its period_ns needs 5"},
      {"a gain that is not a list", with_line("k =", "k = 1.0"), line_of("k ="), "gain.k",
       "must be an array of numbers"},
      {"nan in the gain", with_line("k =", "k = [-0.3, nan, -0.28, 0.91, 0.12]"), line_of("k ="),
       "gain.k", "must be finite"},
      {"a nan", with_line("duty_torque_nm =", "duty_torque_nm = nan"), line_of("duty_torque_nm"),
       "drive.duty_torque_nm", "must be finite"},
      {"an infinity", with_line("fv1 =", "fv1 = +inf"), line_of("fv1 ="), "parameters.fv1",
       "must be finite"},
      {"a string for a number", with_line("supply_v =", "supply_v = \"12\""), line_of("supply_v"),
       "controller.supply_v", "must be a number"},
      {"a string for a number, in the catch table", with_line("settle_s =", "settle_s = \"1\""),
       line_of("settle_s"), "catch.settle_s", "must be a number"},
      {"a float for the period", with_line("period_ns =", "period_ns = 16e6"), line_of("period_ns"),
       "controller.period_ns", "must be an integer"},
      {"a period of 0", with_line("period_ns =", "period_ns = 0"), line_of("period_ns"),
       "controller.period_ns", "must be > 0"},
      {"an unknown key", with_line("arm_gain =", "arm_gain = 40.0\narm_gian = 40.0"),
       line_of("arm_gain") + 1, "swing_up.arm_gian", "unknown key"},
      {"an unknown table", std::string(kValid) + "\n[extra]\nx = 1\n", line_of("duty_step") + 2,
       "extra", "unknown key"},
      {"a table that is a value", value_drive, 1, "drive", "must be a table ([drive])"},
      {"another kind", with_line("kind =", "kind = \"pid\""), line_of("kind"), "controller.kind",
       "'pid' is not a kind this reader knows: upright_lqr"},
      {"an empty rig", with_line("rig =", "rig = \"\""), line_of("rig ="), "controller.rig",
       "must not be empty"},
      {"an unknown source", with_line("source =", "source = \"guess\""), line_of("source"),
       "parameters.source", "'guess' is not one of: output-error, lsmi, cad"},
      {"a digest that is not one", with_line("results_sha256 =", "results_sha256 = \"abc\""),
       line_of("results_sha256"), "parameters.results_sha256", "must be 64 lowercase hex digits"},
      {"a negative ramp", with_line("ramp_duty_per_s =", "ramp_duty_per_s = -1.0"),
       line_of("ramp_duty_per_s"), "controller.ramp_duty_per_s", "must be >= 0"},
      {"a negative lag", with_line("lag_s =", "lag_s = -0.002"), line_of("lag_s"),
       "controller.lag_s", "must be >= 0"},
      {"a lag past four periods", with_line("lag_s =", "lag_s = 0.07"), line_of("ramp_lag_s"),
       "controller.ramp_lag_s", "with lag_s must be at most 4 periods"},
      {"a zero duty weight", with_line("duty = ", "duty = 0.0"), line_of("duty = "), "weights.duty",
       "must be > 0"},
      {"a design predicted unstable", with_line("spectral_radius =", "spectral_radius = 1.2"),
       line_of("spectral_radius"), "prediction.spectral_radius", "must be in [0, 1)"},
      {"poles not one per state", with_line("closed_loop_poles_im =", "closed_loop_poles_im = []"),
       line_of("closed_loop_poles_im"), "prediction.closed_loop_poles_im",
       "must be an array of 5 numbers"},
      {"a syntax error", with_line("mug =", "mug = = 0.1"), line_of("mug"), "", ""},
      {"a filter gain not 4 x 2", with_line("m =", "m = [0.9, 0.01, 0.02]"), line_of("m ="),
       "observer.m", "must be an array of 8 numbers"},
      {"a filter that does not converge",
       with_line("spectral_radius = 0.6", "spectral_radius = 1.0"),
       line_of("spectral_radius = 0.6"), "observer.spectral_radius", "must be in [0, 1)"},
      {"a filter that diverges at some reading age",
       with_line("worst_spectral_radius =", "worst_spectral_radius = 1.3"),
       line_of("worst_spectral_radius"), "observer.worst_spectral_radius", "must be in [0, 1)"},
      {"a gain for angles older than a period",
       with_line("reading_age_s =", "reading_age_s = 0.02"), line_of("reading_age_s"),
       "observer.reading_age_s", "must be in [0, the period]"},
      // A file from before the filter corrected the last sample's state: its gain means another
      // thing, so it is refused, not run.
      {"a filter gain without its reading age", with_line("reading_age_s =", ""),
       line_of("[observer]"), "observer.reading_age_s",
       "missing: the filter's gain of a file without it corrects another state than the loop's "
       "filter does; design the controller again (furuta controller design)"},
      {"a count of 0", with_line("pendulum_count_rad =", "pendulum_count_rad = 0.0"),
       line_of("pendulum_count_rad"), "observer.pendulum_count_rad", "must be > 0"},
      // What the balance law refuses, at the key the value came from.
      {"the swing-up above the limit", with_line("max_duty = 0.5", "max_duty = 0.6"),
       line_of("max_duty = 0.5"), "swing_up.max_duty",
       "must be in (0, the controller's max_duty] (the balance law's swing_up.max_duty)"},
      {"a duty limit above 1", with_limit("max_duty", "1.5"), limits_line("max_duty"),
       "limits.max_duty", "must be in (0, 1] (the balance law's max_duty)"},
      {"a duty step above the limit", with_limit("duty_step", "0.75"), limits_line("duty_step"),
       "limits.duty_step", "must be in (0, max_duty]"},
      {"catch beyond release", with_line("catch_deg =", "catch_deg = 45.0"), line_of("release_deg"),
       "catch.release_deg", "must be in (catch_rad, pi) (the balance law's region.release_rad)"},
      {"catch at release", with_line("release_deg =", "release_deg = 25.0"), line_of("release_deg"),
       "catch.release_deg", "must be in (catch_rad, pi)"},
      {"catch at a right angle", with_line("catch_deg =", "catch_deg = 90.0"), line_of("catch_deg"),
       "catch.catch_deg", "must be in (0, pi/2)"},
      {"a catch that asks for more than the limit",
       with_line("entry_duty_ratio =", "entry_duty_ratio = 1.5"), line_of("entry_duty_ratio"),
       "catch.entry_duty_ratio", "must be in (0, 1]"},
      {"a pump that stops beyond a half turn", with_line("pump_arm_deg =", "pump_arm_deg = 200.0"),
       line_of("pump_arm_deg"), "swing_up.pump_arm_deg", "must be in (0, pi)"},
      {"a fall inside the catch", with_line("fall_deg =", "fall_deg = 20.0"), line_of("fall_deg"),
       "catch.fall_deg", "must be in [catch_rad, pi)"},
      {"a negative inertia", with_line("mu1 =", "mu1 = -0.0048"), line_of("mu1"), "parameters.mu1",
       "must be a finite number > 0 (the balance law's parameters.mu1)"},
      {"no drive", with_line("duty_torque_nm =", "duty_torque_nm = 0"), line_of("duty_torque_nm"),
       "drive.duty_torque_nm", "must be a finite number > 0"},
      {"a start past the acceleration limit",
       with_line("start_acceleration =", "start_acceleration = 200.0"),
       line_of("start_acceleration"), "swing_up.start_acceleration",
       "must be in (0, max_acceleration]"},
  };
  for (const Mistake& m : cases) {
    try {
      parse_controller_file(m.text, "C.toml");
      ADD_FAILURE() << m.what << ": accepted";
    } catch (const ConfigError& e) {
      const std::string message = e.what();
      EXPECT_EQ(e.file(), "C.toml") << m.what;
      EXPECT_EQ(e.line(), m.line) << m.what << ": " << message;
      EXPECT_EQ(e.field(), m.field) << m.what << ": " << message;
      const std::string where = "C.toml" +
                                (m.line > 0 ? ":" + std::to_string(m.line) : std::string()) + ": " +
                                (m.field.empty() ? std::string() : m.field + ": ");
      EXPECT_EQ(message.rfind(where, 0), 0u) << m.what << ": " << message;
      EXPECT_NE(message.find(m.problem), std::string::npos) << m.what << ": " << message;
    }
  }
}

TEST(ControllerFile, TheDigestIsTheFilesSha256AndTheTextIsVerbatim) {
  TempDir dir;
  const fs::path path = dir.path() / "controller.toml";
  std::ofstream(path, std::ios::binary) << kValid;
  const ControllerFile f = load_controller_file(path);
  EXPECT_EQ(f.path, path);
  EXPECT_EQ(f.text, kValid);
  ASSERT_EQ(f.sha256.size(), 64u);
  EXPECT_EQ(f.sha256, sha256sum(path));
  // A comment changes the digest and nothing else.
  const fs::path commented = dir.path() / "commented.toml";
  std::ofstream(commented, std::ios::binary) << kValid << "# reviewed\n";
  const ControllerFile g = load_controller_file(commented);
  EXPECT_EQ(g.sha256, sha256sum(commented));
  EXPECT_NE(g.sha256, f.sha256);
  EXPECT_EQ(g.spec.gain, f.spec.gain);
  // The digest of the text given to the parser is that of the same bytes.
  EXPECT_EQ(parse_controller_file(kValid, "C.toml").sha256, f.sha256);
}

TEST(ControllerFile, AFileThatCannotBeReadIsAnErrorNamingItsPath) {
  TempDir dir;
  const fs::path missing = dir.path() / "nowhere.toml";
  try {
    load_controller_file(missing);
    ADD_FAILURE() << "a missing file was read";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), missing.string() + ": cannot open the file");
  }
  try {
    load_controller_file(dir.path());
    ADD_FAILURE() << "a directory was read";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), dir.path().string() + ": is a directory, not a file");
  }
}

}  // namespace
}  // namespace furuta::config::controller_file_test
