// tubes.json and paving.json as someone outside the project reads them: with nothing but the file
// and their own simulation, a tube can be checked against the true trajectory; the paving holds
// every box with its verdict and every sample's data boxes.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/outputs.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::report {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;
using nlohmann::json;

json read_json(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

// [lo, hi] of a tube component holds x (null bounds: unbounded).
bool holds(const json& interval, double x) {
  const bool above = interval[0].is_null() || interval[0].get<double>() <= x;
  const bool below = interval[1].is_null() || x <= interval[1].get<double>();
  return above && below;
}

TEST(DataFiles, ATubeInTubesJsonHoldsTheTrueTrajectoryAtTheSampleTimes) {
  validated::Scenario scenario = validated::paper_scenario(1);
  scenario.duration_s = 0.2;
  const model::Parameters<double> truth = model::paper_run1();
  const pipeline::Simulation simulation =
      pipeline::simulate({scenario}, {validated::point_parameters("truth", truth)}, truth, {});
  ASSERT_EQ(simulation.results.size(), 1u);
  const validated::ScenarioResult& result = simulation.results.front();
  ASSERT_EQ(result.status, validated::IntegrationResult::Status::ok) << result.reason;

  TempDir dir;
  write_simulation(dir.path(), simulation, "test", std::nullopt);
  EXPECT_EQ(read_json(dir.path() / "simulate.json")["simulation"]["tubes_file"], "tubes.json");
  const json tubes = read_json(dir.path() / "tubes.json");

  // From here on only the file and an independent simulation of the truth.
  ASSERT_EQ(tubes["runs"].size(), 1u);
  const json& run = tubes["runs"][0];
  EXPECT_EQ(run["scenario"], 1);
  EXPECT_EQ(run["parameter_set"], "truth");
  ASSERT_EQ(run["pieces"].size(), 1u);
  const json& steps = run["pieces"][0]["steps"];
  EXPECT_EQ(steps.size(), result.steps);
  EXPECT_EQ(steps.size(), result.q2_tube.size());
  EXPECT_EQ(run["steps"], result.steps);
  std::size_t q1 = 0, q2 = 0;
  for (std::size_t i = 0; i < run["components"].size(); ++i) {
    if (run["components"][i] == "q1") q1 = i;
    if (run["components"][i] == "q2") q2 = i;
  }
  ASSERT_EQ(run["components"][q1], "q1");
  ASSERT_EQ(run["components"][q2], "q2");

  // The true model from x0 (the centre of the tube's initial box), sampled every 4 ms: RK4 at
  // 1 ms, as anyone would write it.
  validated::MeasurementOptions fine;
  fine.sample_period_s = 0.004;
  const validated::ScenarioMeasurement m = validated::measure_scenario(scenario, truth, fine);
  std::size_t checked = 0;
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    bool in_some_step = false;
    for (const json& step : steps) {
      const double t0 = step["t"][0].get<double>(), t1 = step["t"][1].get<double>();
      if (m.t_s[k] < t0 || m.t_s[k] > t1) continue;
      in_some_step = true;
      EXPECT_TRUE(holds(step["over"][q1], m.q1_true_rad[k])) << "q1 at " << m.t_s[k];
      EXPECT_TRUE(holds(step["over"][q2], m.q2_true_rad[k])) << "q2 at " << m.t_s[k];
      ++checked;
    }
    EXPECT_TRUE(in_some_step) << m.t_s[k];
  }
  EXPECT_GE(checked, m.t_s.size());
  // The steps follow each other and end where the run did; each end box lies in its step's box.
  EXPECT_EQ(steps[0]["t"][0].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(steps.back()["t"][1].get<double>(), result.t_reached_s);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (i > 0) {
      EXPECT_EQ(steps[i]["t"][0], steps[i - 1]["t"][1]);
    }
    for (std::size_t c = 0; c < steps[i]["end"].size(); ++c) {
      const json& end = steps[i]["end"][c];
      EXPECT_TRUE(holds(steps[i]["over"][c], end[0].get<double>()));
      EXPECT_TRUE(holds(steps[i]["over"][c], end[1].get<double>()));
    }
  }
}

TEST(DataFiles, PavingJsonHoldsEveryBoxWithItsVerdictAndEverySamplesDataBoxes) {
  TempDir dir;
  const fs::path fit1 = furuta::testing::simulated_session_log(dir.path() / "logs", "a", 1, 4.0);
  const fs::path fit2 = furuta::testing::simulated_session_log(dir.path() / "logs", "b", 2, 4.0);
  ASSERT_FALSE(fit1.empty() || fit2.empty());
  app::IdentifyCommandOptions options;
  options.logs = {fit1, fit2};
  options.sivia = true;
  options.threads = 2;
  std::ostringstream err;
  const std::optional<pipeline::Run> run = app::run_identification(options, err);
  ASSERT_TRUE(run && run->sivia) << err.str();
  write_identification(dir.path() / "out", *run, "test");

  const json results = read_json(dir.path() / "out" / "results.json");
  EXPECT_EQ(results["sivia"]["paving_file"], "paving.json");
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "tubes.json")) << "no scenarios ran";
  const json paving = read_json(dir.path() / "out" / "paving.json");
  const interval::SubPaving& p = run->sivia->result.paving;
  std::size_t inner = 0, boundary = 0, outer = 0;
  for (const json& box : paving["boxes"]) {
    ASSERT_EQ(box["box"].size(), model::kParameterCount);
    const std::string verdict = box["verdict"];
    inner += verdict == "inner";
    boundary += verdict == "boundary";
    outer += verdict == "outer";
  }
  EXPECT_EQ(inner, p.inner.size());
  EXPECT_EQ(boundary, p.boundary.size());
  EXPECT_EQ(outer, p.outer.size());
  EXPECT_EQ(paving["unknowns"], json({"fv1", "fv2"}));
  // Every sample SIVIA was given, its data as intervals around the preprocessed values.
  const std::vector<identification::IntervalSample>& samples = run->sivia->samples;
  ASSERT_EQ(paving["samples"].size(), samples.size());
  EXPECT_EQ(samples.size(), run->sivia->result.samples);
  for (std::size_t i = 0; i < samples.size(); i += 97) {
    const json& s = paving["samples"][i];
    EXPECT_EQ(s["experiment"], samples[i].experiment);
    EXPECT_EQ(s["index"], samples[i].index);
    for (const char* channel : {"q2", "dq1", "dq2", "ddq1", "ddq2", "tau"}) {
      ASSERT_EQ(s[channel].size(), 2u) << channel;
      EXPECT_LE(s[channel][0].get<double>(), s[channel][1].get<double>()) << channel;
    }
    EXPECT_EQ(s["tau"][0].get<double>(), samples[i].tau.lo());
    EXPECT_EQ(s["tau"][1].get<double>(), samples[i].tau.hi());
  }
}

}  // namespace
}  // namespace furuta::report
