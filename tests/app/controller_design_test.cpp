// `furuta controller design` on an identification's results.json: the file holds the gain the
// control module designs for the named parameters and the rig, with where they came from; what it
// cannot design from is refused, naming why, and nothing is written.
#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/control/balance_law.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/report/json.hpp"
#include "sha256sum.hpp"
#include "temp_dir.hpp"

namespace furuta::app::controller_design_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

constexpr const char* kRigConfig = FURUTA_SOURCE_DIR "/config/rig.toml";
// The main job's results (tests/data/golden): LSMI, the converged refinement, CAD and the truth.
constexpr const char* kResults = FURUTA_TEST_DATA_DIR "/golden/results.json";

struct Outcome {
  int status = -1;
  std::string out, err;
};

Outcome design(ControllerDesignOptions options) {
  std::ostringstream out, err;
  const int status = run_controller_design_command(options, out, err);
  return {status, out.str(), err.str()};
}

ControllerDesignOptions options_for(const fs::path& output, ControllerParameters source) {
  ControllerDesignOptions o;
  o.results = kResults;
  o.parameters = source;
  o.config_path = kRigConfig;
  o.output = output;
  return o;
}

// The project's rig.toml with `from` replaced by `to`, written into `dir`.
fs::path rig_with(const fs::path& dir, const std::string& from, const std::string& to) {
  std::ifstream in(kRigConfig);
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const auto at = toml.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  toml.replace(at, from.size(), to);
  const fs::path path = dir / "rig.toml";
  std::ofstream(path) << toml;
  return path;
}

// The gain the control module designs for these parameters on this rig, with the data path's
// lag plus `ramp_lag_s`.
control::BalanceGain design_for(const config::RigConfig& rig,
                                const model::Parameters<double>& parameters, double ramp_lag_s) {
  const control::DesignPlant plant{parameters, rig.motor, rig.simulation.supply_voltage_v};
  return control::design_lqr(
      control::sample(control::linearize_upright(plant),
                      static_cast<double>(rig.daemon.period_ns) * 1e-9,
                      rig.identification.input_lag_ms.value_or(0.0) * 1e-3 + ramp_lag_s),
      control::LqrWeights{});
}

using furuta::testing::sha256sum;

TEST(ControllerDesign, TheFileHoldsTheGainOfTheNamedParametersAndWhereTheyCameFrom) {
  TempDir dir;
  const report::ResultsFile results = report::read_results(kResults);
  const config::RigConfig rig = config::load_rig_config(kRigConfig);
  const std::pair<ControllerParameters, model::Parameters<double>> cases[] = {
      {ControllerParameters::output_error, *results.output_error},
      {ControllerParameters::lsmi, *results.lsmi},
      {ControllerParameters::cad, *results.nominal}};
  std::vector<double> first_gains;
  for (const auto& [source, parameters] : cases) {
    const fs::path file = dir.path() / (std::string(to_string(source)) + ".toml");
    const Outcome o = design(options_for(file, source));
    ASSERT_EQ(o.status, 0) << o.out << o.err;
    EXPECT_NE(o.out.find("stable"), std::string::npos) << o.out;
    const toml::table t = toml::parse_file(file.string());
    EXPECT_EQ(t["parameters"]["source"].value_or(std::string()), to_string(source));
    EXPECT_EQ(t["parameters"]["results_sha256"].value_or(std::string()).size(), 64u);
    EXPECT_EQ(t["parameters"]["mu3"].value_or(0.0), parameters.mu3);
    EXPECT_EQ(t["controller"]["period_ns"].value_or(std::int64_t{0}), rig.daemon.period_ns);
    // The gain is the control module's for these parameters on this rig, with the board's ramp
    // as a delay, to the last digit.
    const control::BalanceGain expected = design_for(
        rig, parameters,
        control::ramp_lag_s(rig.excitation.board_acceleration_pct_per_s, control::kRampStepDuty));
    const toml::array* k = t["gain"]["k"].as_array();
    ASSERT_NE(k, nullptr);
    ASSERT_EQ(static_cast<Eigen::Index>(k->size()), expected.k.size());
    std::vector<double> gains;
    for (std::size_t i = 0; i < k->size(); ++i) {
      gains.push_back((*k)[i].value_or(0.0));
      EXPECT_EQ(gains.back(), expected.k(static_cast<Eigen::Index>(i))) << i;
    }
    EXPECT_LT(t["prediction"]["spectral_radius"].value_or(2.0), 1.0);
    if (first_gains.empty()) {
      first_gains = gains;
    } else {
      EXPECT_NE(gains, first_gains) << "another source, the same gains";
    }
  }
}

TEST(ControllerDesign, TheFileReadsBackIntoTheSpecTheLoopRuns) {
  TempDir dir;
  const report::ResultsFile results = report::read_results(kResults);
  const config::RigConfig rig = config::load_rig_config(kRigConfig);
  const fs::path path = dir.path() / "controller.toml";
  const Outcome o = design(options_for(path, ControllerParameters::output_error));
  ASSERT_EQ(o.status, 0) << o.out << o.err;
  const config::ControllerFile f = config::load_controller_file(path);
  EXPECT_EQ(f.kind, "upright_lqr");
  EXPECT_EQ(f.rig, rig.name);
  EXPECT_FALSE(f.designed_by.empty());
  EXPECT_EQ(f.parameters_source, "output-error");
  EXPECT_EQ(fs::path(f.results), fs::weakly_canonical(kResults));
  EXPECT_EQ(f.results_sha256, identification::sha256_file(kResults));
  EXPECT_EQ(f.sha256, sha256sum(path));
  EXPECT_EQ(f.period_ns, rig.daemon.period_ns);
  EXPECT_EQ(f.lag_s, rig.identification.input_lag_ms.value_or(0.0) * 1e-3);
  EXPECT_EQ(f.ramp_step_duty, control::kRampStepDuty);
  EXPECT_EQ(f.ramp_lag_s,
            control::ramp_lag_s(rig.excitation.board_acceleration_pct_per_s, f.ramp_step_duty));
  EXPECT_GT(f.ramp_lag_s, 0.0);
  EXPECT_EQ(f.supply_v, rig.simulation.supply_voltage_v);

  // The gain, to the last digit, and the duties on their way it carries.
  const control::BalanceGain expected = design_for(rig, *results.output_error, f.ramp_lag_s);
  const control::BalanceControllerSpec& s = f.spec;
  ASSERT_EQ(4 + s.delayed, expected.k.size());
  for (Eigen::Index i = 0; i < expected.k.size(); ++i) {
    EXPECT_EQ(s.gain[static_cast<std::size_t>(i)], expected.k(i)) << i;
  }
  for (std::size_t i = 4 + static_cast<std::size_t>(s.delayed); i < s.gain.size(); ++i) {
    EXPECT_EQ(s.gain[i], 0.0) << i;
  }
  EXPECT_EQ(s.period_s, static_cast<double>(rig.daemon.period_ns) * 1e-9);
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    EXPECT_EQ(s.parameters[i], (*results.output_error)[i]) << model::kParameterNames[i];
  }
  const control::DriveConstants drive =
      control::drive_constants({*results.output_error, rig.motor, rig.simulation.supply_voltage_v});
  EXPECT_EQ(s.duty_torque_nm, drive.duty_torque_nm);
  EXPECT_EQ(s.back_emf_nm_s, drive.back_emf_nm_s);
  EXPECT_EQ(s.max_duty, rig.limits.max_amplitude_duty);
  EXPECT_EQ(s.duty_step, 1.0 / 255.0);
  const control::SwingUp swing;
  EXPECT_EQ(s.swing_up.energy_gain, swing.energy_gain);
  EXPECT_EQ(s.swing_up.max_acceleration, swing.max_acceleration);
  EXPECT_EQ(s.swing_up.arm_gain, swing.arm_gain);
  EXPECT_EQ(s.swing_up.arm_damping, swing.arm_damping);
  EXPECT_EQ(s.swing_up.max_duty, std::min(swing.max_duty, rig.limits.max_amplitude_duty));
  EXPECT_EQ(s.swing_up.start_below_energy_ratio, swing.start_below_energy_ratio);
  EXPECT_EQ(s.swing_up.start_acceleration, swing.start_acceleration);
  // Through degrees and back: the same angle but for the last bit.
  const control::CatchRegion region;
  EXPECT_DOUBLE_EQ(s.region.catch_rad, region.catch_rad);
  EXPECT_DOUBLE_EQ(s.region.release_rad, region.release_rad);
  EXPECT_EQ(s.region.settle_s, region.settle_s);
  EXPECT_DOUBLE_EQ(s.region.fall_rad, region.fall_rad);
  const toml::table t = toml::parse_file(path.string());
  EXPECT_NEAR(t["catch"]["catch_deg"].value_or(0.0), region.catch_rad * 180 / std::numbers::pi,
              1e-12);
  control::BalanceLaw law(s);
  EXPECT_EQ(law.mode(), control::BalanceMode::swing_up);
}

TEST(ControllerDesign, TheRampEntersTheDesignAndTheSwingUpKeepsWithinTheLimit) {
  TempDir dir;
  const report::ResultsFile results = report::read_results(kResults);
  // A ramp ten times slower than the shipped one, and a lower duty limit than the swing-up's own.
  const fs::path slow = rig_with(dir.path(), "board_acceleration_pct_per_s = 6250",
                                 "board_acceleration_pct_per_s = 625");
  ControllerDesignOptions o = options_for(dir.path() / "slow.toml", ControllerParameters::lsmi);
  o.config_path = slow;
  ASSERT_EQ(design(o).status, 0);
  const config::RigConfig slow_rig = config::load_rig_config(slow);
  const config::ControllerFile s = config::load_controller_file(o.output);
  EXPECT_DOUBLE_EQ(s.ramp_lag_s, 10 * control::ramp_lag_s(6250, control::kRampStepDuty));
  const control::BalanceGain expected = design_for(slow_rig, *results.lsmi, s.ramp_lag_s);
  const control::BalanceGain without_ramp = design_for(slow_rig, *results.lsmi, 0.0);
  for (Eigen::Index i = 0; i < expected.k.size(); ++i) {
    EXPECT_EQ(s.spec.gain[static_cast<std::size_t>(i)], expected.k(i)) << i;
  }
  EXPECT_NE(s.spec.gain[1], without_ramp.k(1)) << "the ramp left the design unchanged";

  const fs::path low = rig_with(dir.path(), "max_amplitude_duty = 0.5", "max_amplitude_duty = 0.3");
  o = options_for(dir.path() / "low.toml", ControllerParameters::lsmi);
  o.config_path = low;
  ASSERT_EQ(design(o).status, 0);
  const config::ControllerFile l = config::load_controller_file(o.output);
  EXPECT_EQ(l.spec.max_duty, 0.3);
  EXPECT_EQ(l.spec.swing_up.max_duty, 0.3);
  const toml::table t = toml::parse_file(o.output.string());
  EXPECT_EQ(t["swing_up"]["max_duty"].value_or(0.0), 0.3);
  EXPECT_EQ(t["limits"]["duty_step"].value_or(0.0), 1.0 / 255.0);
}

TEST(ControllerDesign, ARampTooSlowToBalanceWithIsRefusedAndNothingIsWritten) {
  TempDir dir;
  // The board's slowest ramp is a delay of several loop periods: more than a gain can carry.
  const fs::path slowest = rig_with(dir.path(), "board_acceleration_pct_per_s = 6250",
                                    "board_acceleration_pct_per_s = 25");
  ControllerDesignOptions o = options_for(dir.path() / "c.toml", ControllerParameters::lsmi);
  o.config_path = slowest;
  const Outcome r = design(o);
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.err.find("the design failed: a lag of "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the balance law carries at most 4"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(o.output));
}

TEST(ControllerDesign, WhatCannotBeDesignedFromIsRefusedAndNothingIsWritten) {
  TempDir dir;
  // A results file without the refinement (LSMI alone): --parameters output-error has nothing.
  std::ifstream in(kResults);
  std::stringstream text;
  text << in.rdbuf();
  std::string json = text.str();
  const auto at = json.find("\"output_error\"");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, 14, "\"not_refined\"");
  const fs::path lsmi_only = dir.path() / "lsmi_only.json";
  std::ofstream(lsmi_only) << json;
  ControllerDesignOptions o =
      options_for(dir.path() / "c.toml", ControllerParameters::output_error);
  o.results = lsmi_only;
  Outcome r = design(o);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no converged output-error estimate"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(o.output));

  o = options_for(kResults, ControllerParameters::lsmi);  // -o the results file itself
  r = design(o);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("is one of the inputs"), std::string::npos) << r.err;

  const fs::path broken = dir.path() / "broken.json";
  std::ofstream(broken) << "{\"combined\": {\"estimate\": {\"mu1\": \"x\"}}}";
  o = options_for(dir.path() / "c.toml", ControllerParameters::lsmi);
  o.results = broken;
  r = design(o);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("combined.estimate.mu1: not a finite number"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(o.output));
}

}  // namespace
}  // namespace furuta::app::controller_design_test
