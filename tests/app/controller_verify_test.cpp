// `furuta controller verify` on the controller designed from the main job's results: certified
// from a start near upright over the output-error estimate's box, with the report's three files
// and the sampled check all inside; not certified where the duty would reach its limit (exit 1, the
// bound and the time named); a box file with a bad key or a results file without standard
// deviations refused (exit 2, named), nothing written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "temp_dir.hpp"

namespace furuta::app::controller_verify_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

constexpr const char* kRigConfig = FURUTA_SOURCE_DIR "/config/rig.toml";
constexpr const char* kResults = FURUTA_TEST_DATA_DIR "/golden/results.json";

struct Outcome {
  int status = -1;
  std::string out, err;
};

// The controller `furuta controller design` makes from the main job's output-error estimate.
fs::path designed(const TempDir& dir) {
  ControllerDesignOptions o;
  o.results = kResults;
  o.config_path = kRigConfig;
  o.output = dir.path() / "controller.toml";
  std::ostringstream out, err;
  EXPECT_EQ(run_controller_design_command(o, out, err), kExitDone) << err.str();
  return o.output;
}

ControllerVerifyOptions options_for(const TempDir& dir, const fs::path& controller) {
  ControllerVerifyOptions o;
  o.controller = controller;
  o.parameters = kResults;
  o.sd = 1;
  o.config_path = kRigConfig;
  o.start_deg = 0.5;
  o.start_deg_s = 2.5;
  o.horizon_s = 2;
  o.sampled = 8;
  o.output_dir = dir.path() / "verification";
  return o;
}

Outcome verify(const ControllerVerifyOptions& options) {
  std::ostringstream out, err;
  const int status = run_controller_verify_command(options, out, err);
  return {status, out.str(), err.str()};
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(ControllerVerify, CertifiesTheDesignedLoopNearUprightAndWritesTheReport) {
  TempDir dir;
  const ControllerVerifyOptions options = options_for(dir, designed(dir));
  const Outcome r = verify(options);
  ASSERT_EQ(r.status, kExitDone) << r.out << r.err;
  EXPECT_NE(r.out.find("certified for 2 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("8 trajectories"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 outside the tube"), std::string::npos) << r.out;
  for (const char* file : {"report.html", "verification.json", "verification.svg"}) {
    EXPECT_TRUE(fs::exists(options.output_dir / file)) << file;
  }
  const nlohmann::json j = read_json(options.output_dir / "verification.json");
  EXPECT_TRUE(j["certified"].get<bool>());
  EXPECT_EQ(j["steps"].size(), 125u);
  EXPECT_EQ(j["sampled"]["trajectories"].get<int>(), 8);
  EXPECT_EQ(j["sampled"]["outside"].get<int>(), 0);
  // The box is the estimate +- 1 sd of results.json.
  const nlohmann::json results = read_json(kResults);
  const double mu1 = results["output_error"]["estimate"]["mu1"].get<double>();
  const double sd = results["output_error"]["std_dev"]["mu1"].get<double>();
  EXPECT_NEAR(j["assumptions"]["parameters"]["mu1"][0].get<double>(), mu1 - sd, 1e-15);
  EXPECT_NEAR(j["assumptions"]["parameters"]["mu1"][1].get<double>(), mu1 + sd, 1e-15);
}

TEST(ControllerVerify, NamesTheBoundAndTheTimeWhenNotCertified) {
  TempDir dir;
  ControllerVerifyOptions options = options_for(dir, designed(dir));
  options.start_deg = 30;
  const Outcome r = verify(options);
  EXPECT_EQ(r.status, kExitPartOrRefused) << r.out << r.err;
  EXPECT_NE(r.out.find("not certified: the law's duty may reach its limit"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("at t = 0 s"), std::string::npos) << r.out;
  const nlohmann::json j = read_json(options.output_dir / "verification.json");
  EXPECT_FALSE(j["certified"].get<bool>());
  EXPECT_EQ(j["failure"]["kind"], "duty_limit");
}

TEST(ControllerVerify, RefusesABadBoxOrResultsWithoutDeviationsAndWritesNothing) {
  TempDir dir;
  ControllerVerifyOptions options = options_for(dir, designed(dir));
  options.parameters = dir.path() / "box.toml";
  std::ofstream(options.parameters) << "[parameters]\nmu1 = [1.0e-3, 1.1e-3]\n";
  Outcome r = verify(options);
  EXPECT_EQ(r.status, kExitNotDone);
  EXPECT_NE(r.err.find("box.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("parameters.mu2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(options.output_dir));

  nlohmann::json results = read_json(kResults);
  results["output_error"].erase("std_dev");
  options.parameters = dir.path() / "results.json";
  std::ofstream(options.parameters) << results.dump();
  r = verify(options);
  EXPECT_EQ(r.status, kExitNotDone);
  EXPECT_NE(r.err.find("output_error.std_dev"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(options.output_dir));
}

}  // namespace
}  // namespace furuta::app::controller_verify_test
