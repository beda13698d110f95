// `furuta controller design` on an identification's results.json: the file holds the gain the
// control module designs for the named parameters and the rig, with where they came from; what it
// cannot design from is refused, naming why, and nothing is written.
#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/report/json.hpp"
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
    // The gain is the control module's for these parameters on this rig, to the last digit.
    const control::DesignPlant plant{parameters, rig.motor, rig.simulation.supply_voltage_v};
    const control::BalanceGain expected =
        control::design_lqr(control::sample(control::linearize_upright(plant),
                                            static_cast<double>(rig.daemon.period_ns) * 1e-9,
                                            rig.identification.input_lag_ms.value_or(0.0) * 1e-3),
                            control::LqrWeights{});
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
