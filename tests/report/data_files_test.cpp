// tubes.json and paving.json as someone outside the project reads them: with nothing but the file
// and their own simulation, a tube can be checked against the true trajectory; the paving holds
// every box with its verdict and every sample's data boxes.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/identification/guaranteed.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/outputs.hpp"
#include "simulated_logs.hpp"
#include "simulated_sessions.hpp"
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

// A box in tubes.json equals a box of the integrator's, bound for bound.
bool same_box(const json& written, const interval::Box& box) {
  if (written.size() != box.size()) return false;
  for (std::size_t k = 0; k < box.size(); ++k) {
    if (written[k][0].get<double>() != box[k].lo() || written[k][1].get<double>() != box[k].hi()) {
      return false;
    }
  }
  return true;
}

// A split run: the file gives what the integrator started from (the start box, the torque), each
// piece's own start box, and each step once; a piece's steps are rebuilt from the piece it
// inherits from, and they are the integrator's own, step for step.
TEST(DataFiles, ASplitRunInTubesJsonHoldsEachStepOnceAndEveryPiecesStartBox) {
  validated::Scenario scenario = validated::paper_scenario(3);  // u = 0.17 N m
  scenario.duration_s = 0.2;
  const model::Parameters<double> truth = model::paper_run1();
  const validated::ParameterSet set = validated::point_parameters("truth", truth);
  const pipeline::Simulation simulation = pipeline::simulate({scenario}, {set}, truth, {}, 4);
  TempDir dir;
  write_simulation(dir.path(), simulation, "test", std::nullopt);
  const json tubes = read_json(dir.path() / "tubes.json");
  // The same run straight from the integrator, every piece with all its steps.
  const validated::ScenarioTubes raw = validated::run_scenario_tubes(
      scenario, set.parameters, simulation.uncertainty, simulation.integrator,
      validated::scenario_split_options(4, scenario.duration_s));
  ASSERT_GT(raw.pieces.size(), 1u);

  ASSERT_EQ(tubes["runs"].size(), 1u);
  const json& run = tubes["runs"][0];
  EXPECT_TRUE(
      same_box(run["initial_box"], validated::initial_state_box(scenario, simulation.uncertainty)));
  EXPECT_EQ(run["input_torque_nm"], json({0.17, 0.17}));
  const json& pieces = run["pieces"];
  ASSERT_EQ(pieces.size(), raw.pieces.size());
  std::vector<json> steps_of(pieces.size());
  std::size_t listed = 0, integrated = 0;
  for (std::size_t j = 0; j < pieces.size(); ++j) {
    const json& piece = pieces[j];
    const validated::Tube& tube = raw.pieces[j];
    EXPECT_EQ(piece["start_t_s"], 0.0);
    EXPECT_TRUE(same_box(piece["start_box"], tube.initial)) << j;
    steps_of[j] = json::array();
    if (j == 0) {
      EXPECT_TRUE(piece["inherits"].is_null());
    } else {
      // The planned split comes after the first steps: every later piece shares them.
      ASSERT_TRUE(piece["inherits"].is_object()) << j;
      const std::size_t parent = piece["inherits"]["piece"];
      const std::size_t shared = piece["inherits"]["steps"];
      ASSERT_LT(parent, j);
      ASSERT_GT(shared, 0u);
      ASSERT_LE(shared, steps_of[parent].size());
      for (std::size_t k = 0; k < shared; ++k) steps_of[j].push_back(steps_of[parent][k]);
    }
    for (const json& step : piece["steps"]) steps_of[j].push_back(step);
    listed += piece["steps"].size();
    integrated += tube.steps.size();
    ASSERT_EQ(steps_of[j].size(), tube.steps.size()) << j;
    for (std::size_t k = 0; k < tube.steps.size(); ++k) {
      const json& step = steps_of[j][k];
      ASSERT_EQ(step["t"][0].get<double>(), tube.steps[k].t0) << j << " " << k;
      ASSERT_EQ(step["t"][1].get<double>(), tube.steps[k].t1) << j << " " << k;
      ASSERT_TRUE(same_box(step["over"], tube.steps[k].over)) << j << " " << k;
      ASSERT_TRUE(same_box(step["end"], tube.steps[k].end)) << j << " " << k;
    }
  }
  EXPECT_LT(listed, integrated) << "the steps before the split are listed once";
  // The pieces' start boxes cover the initial box: every solution starts in some piece.
  std::mt19937_64 rng(23);
  const json& initial = run["initial_box"];
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<double> x;
    for (const json& c : initial) {
      const double lo = c[0].get<double>(), hi = c[1].get<double>();
      x.push_back(lo + std::uniform_real_distribution<double>(0, 1)(rng) * (hi - lo));
    }
    bool in_some_piece = false;
    for (const json& piece : pieces) {
      bool inside = true;
      for (std::size_t k = 0; k < x.size(); ++k)
        inside = inside && holds(piece["start_box"][k], x[k]);
      in_some_piece = in_some_piece || inside;
    }
    ASSERT_TRUE(in_some_piece) << trial;
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

// paving.json read by someone who has only the file: its inner boxes, its removed parts and the
// data boxes of its samples, checked point by point against the rows of "constraint".
class PavingJsonOnOneSession : public ::testing::Test {
 protected:
  // The paper's problem (fv1, fv2 unknown, the mu's carried as Table II intervals around the
  // truth) on one simulated session, at the paper's epsilon: the inner probe gives inner boxes.
  static void SetUpTestSuite() {
    const furuta::testing::SimulatedSession session = furuta::testing::simulate(3);
    identification::GuaranteedOptions o;
    o.prior = identification::paper_prior(model::paper_run1());
    o.epsilon = 0.01;
    o.threads = 2;
    pipeline::Guaranteed g;
    g.bounds = furuta::testing::bounds_covering({session});
    g.samples =
        identification::interval_samples({&session.processed}, g.bounds, furuta::testing::trim());
    const identification::SampleConstraints constraints(g.samples, o.prior, o.unknown);
    g.result = identification::guaranteed_identification(constraints, o);
    paving_ = std::make_unique<json>(json::parse(json_text(paving_json(g))));
  }
  static void TearDownTestSuite() { paving_.reset(); }

  static interval::Interval interval_of(const json& x) {
    return interval::Interval(x[0].get<double>(), x[1].get<double>());
  }
  static double uniform_in(const json& x, std::mt19937_64& rng) {
    const double lo = x[0].get<double>(), hi = x[1].get<double>();
    return std::min(hi, lo + std::uniform_real_distribution<double>(0, 1)(rng) * (hi - lo));
  }

  // Data exist in the sample's data boxes meeting both rows at the point p, searched by brute
  // force: q2, dq1, dq2 drawn in their intervals (the centre first), tau swept over its interval;
  // the rows are then a 2x2 linear system in (ddq1, ddq2).
  static bool has_data(const json& sample, const std::vector<double>& p, std::mt19937_64& rng) {
    const auto pick = [&](const char* channel, bool centre) {
      const json& x = sample[channel];
      return centre ? 0.5 * (x[0].get<double>() + x[1].get<double>()) : uniform_in(x, rng);
    };
    const interval::Interval tau = interval_of(sample["tau"]);
    const interval::Interval ddq1 = interval_of(sample["ddq1"]), ddq2 = interval_of(sample["ddq2"]);
    for (int k = 0; k < 30; ++k) {
      const double q2 = pick("q2", k == 0), dq1 = pick("dq1", k == 0), dq2 = pick("dq2", k == 0);
      const double s = std::sin(q2), c = std::cos(q2);
      const double m11 = p[0] + p[1] * s * s, m12 = p[2] * c, m22 = p[3];
      const double rest1 = 2 * p[1] * s * c * dq1 * dq2 - p[2] * s * dq2 * dq2 + p[5] * dq1;
      const double rest2 = -p[1] * s * c * dq1 * dq1 + p[4] * s + p[6] * dq2;
      const double det = m11 * m22 - m12 * m12;
      for (int j = 0; j <= 20; ++j) {
        const double t = tau.lo() + (tau.hi() - tau.lo()) * j / 20.0;
        const double b1 = t - rest1, b2 = -rest2;
        if (ddq1.contains((m22 * b1 - m12 * b2) / det) &&
            ddq2.contains((m11 * b2 - m12 * b1) / det)) {
          return true;
        }
      }
    }
    return false;
  }

  // No data in the sample's data boxes meet both rows at p: the rows' interval enclosures over
  // the data boxes miss their outputs.
  static bool proves_no_data(const json& sample, const std::vector<double>& p) {
    const identification::RegressorEnclosure e = identification::regressor_enclosure(
        interval_of(sample["q2"]), interval_of(sample["dq1"]), interval_of(sample["dq2"]),
        interval_of(sample["ddq1"]), interval_of(sample["ddq2"]));
    interval::Interval row1(0.0), row2(0.0);
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      row1 += e.row1[k] * interval::Interval(p[k]);
      row2 += e.row2[k] * interval::Interval(p[k]);
    }
    return row1.is_disjoint(interval_of(sample["tau"])) || !row2.contains(0.0);
  }

  static std::unique_ptr<json> paving_;
};
std::unique_ptr<json> PavingJsonOnOneSession::paving_;

// A box called inner is inner for everything the file says it holds: points drawn from every
// component of the listed box, the carried mu's included, have data at every sample.
TEST_F(PavingJsonOnOneSession, InnerBoxesAreConsistentAtEveryPointTheyList) {
  const json& paving = *paving_;
  EXPECT_EQ(paving["q"], 0);
  EXPECT_EQ(paving["inner_test"], "witness");
  std::vector<const json*> inner;
  for (const json& b : paving["boxes"]) {
    if (b["verdict"] == "inner") inner.push_back(&b["box"]);
  }
  ASSERT_FALSE(inner.empty());
  // The carried components are listed at the points the proof fixed them at.
  const json& names = paving["parameters"];
  for (const json* box : inner) {
    for (std::size_t k = 0; k < names.size(); ++k) {
      const std::string name = names[k];
      if (!paving["inner_carried"].contains(name)) continue;
      EXPECT_EQ((*box)[k], paving["inner_carried"][name]) << name;
    }
  }
  std::mt19937_64 rng(17);
  const json& samples = paving["samples"];
  for (int trial = 0; trial < 30; ++trial) {
    const json& box = *inner[rng() % inner.size()];
    std::vector<double> p;
    for (const json& component : box) p.push_back(uniform_in(component, rng));
    for (std::size_t i = 0; i < samples.size(); i += 5) {
      ASSERT_TRUE(has_data(samples[i], p, rng))
          << "point " << trial << " of inner box " << box.dump() << " has no data at sample " << i;
    }
  }
}

// Every part contraction removed is listed with the box before and after, every point of before
// \ after (the carried mu's anywhere in their prior) is excluded by some sample, and with the
// inner, boundary and outer boxes the removed parts account for the whole prior.
TEST_F(PavingJsonOnOneSession, WhatContractionRemovedIsListedAndExcludedBySomeSample) {
  const json& paving = *paving_;
  const json& contractions = paving["contractions"];
  ASSERT_FALSE(contractions.empty());
  EXPECT_EQ(paving["contractions_kept"], contractions.size());
  EXPECT_EQ(paving["contraction_count"], contractions.size());
  const json& prior = paving["prior"];
  const std::size_t n = prior.size();
  const auto inside = [](const json& box, const std::vector<double>& p) {
    for (std::size_t k = 0; k < p.size(); ++k) {
      if (p[k] < box[k][0].get<double>() || p[k] > box[k][1].get<double>()) return false;
    }
    return true;
  };
  std::mt19937_64 rng(19);
  const json& samples = paving["samples"];
  std::size_t removed_points = 0;
  for (const json& c : contractions) {
    ASSERT_EQ(c["before"].size(), n);
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_LE(c["before"][k][0].get<double>(), c["after"][k][0].get<double>()) << k;
      EXPECT_GE(c["before"][k][1].get<double>(), c["after"][k][1].get<double>()) << k;
    }
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<double> p;
      for (std::size_t k = 0; k < n; ++k) p.push_back(uniform_in(c["before"][k], rng));
      if (inside(c["after"], p)) continue;
      ++removed_points;
      bool excluded = false;
      for (std::size_t i = 0; i < samples.size() && !excluded; ++i) {
        excluded = proves_no_data(samples[i], p);
      }
      ASSERT_TRUE(excluded) << "removed point " << json(p).dump() << " of " << c.dump();
    }
  }
  EXPECT_GT(removed_points, 100u);
  // Every point of the prior is in a listed box (inner boxes with the carried components at
  // their prior: the outer approximation) or in a removed part.
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<double> p;
    for (std::size_t k = 0; k < n; ++k) p.push_back(uniform_in(prior[k], rng));
    bool accounted = false;
    for (const json& b : paving["boxes"]) {
      json box = b["box"];
      for (std::size_t k = 0; k < n; ++k) {
        if (paving["inner_carried"].contains(paving["parameters"][k])) box[k] = prior[k];
      }
      accounted = accounted || inside(box, p);
    }
    for (const json& c : contractions) {
      accounted = accounted || (inside(c["before"], p) && !inside(c["after"], p));
    }
    ASSERT_TRUE(accounted) << json(p).dump();
  }
}

}  // namespace
}  // namespace furuta::report
