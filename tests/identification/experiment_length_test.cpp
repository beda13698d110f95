// An experiment too short for the filters and the seven parameters is refused by name, with its
// length and the length needed, before any filtering (it used to surface as "LSMI: 0 equations for
// 7 parameters").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "furuta/identification/identify.hpp"

namespace furuta::identification {
namespace {

RawExperiment experiment(const std::string& name, std::size_t samples) {
  RawExperiment e;
  e.name = name;
  e.sample_period_s = 0.016;
  for (std::size_t i = 0; i < samples; ++i) {
    const double t = 0.016 * static_cast<double>(i);
    e.t_s.push_back(t);
    e.q1.push_back(std::sin(t));
    e.q2.push_back(0.1 * std::sin(3 * t));
    e.input.push_back(0.3 * std::sin(2 * t));
  }
  return e;
}

TEST(ExperimentLength, TheMinimumIsTheFiltersEdgeAtEachEndAndFourSamplesBetween) {
  IdentifyOptions options;  // 31 taps: an edge of 39 samples
  EXPECT_EQ(edge_samples(options.preprocess), 39u);
  EXPECT_EQ(minimum_samples(options), 82u);
  options.lsmi.trim_samples = 10;
  EXPECT_EQ(minimum_samples(options), 24u);
  EXPECT_EQ(length_problem(experiment("long", 24), options), "");
}

TEST(ExperimentLength, AShortFittedOrHeldOutExperimentIsRefusedByName) {
  const IdentifyOptions options;
  const model::MotorData motor;
  try {
    identify({experiment("long", 400), experiment("one-second", 62)}, std::nullopt, options, motor);
    FAIL() << "a 62-sample experiment was fitted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "one-second: too short for LSMI: 62 samples (0.992 s); its fit needs at least 82 "
              "samples (1.31 s at 16 ms): 39 at each end for the filters' transient and 4 between "
              "for 7 parameters");
  }
  try {
    identify({experiment("long", 400)}, experiment("held-out", 81), options, motor);
    FAIL() << "an 81-sample held-out experiment was used";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("held-out: too short for LSMI: 81 samples"),
              std::string::npos)
        << e.what();
  }
}

// For a caller whose own estimator needs no derivatives: LSMI is left out, with the reason, and
// nothing it would have given (columns, held-out torque fit) looks like a result.
TEST(ExperimentLength, WithLsmiOptionalAShortExperimentLeavesLsmiOutAndSaysWhy) {
  IdentifyOptions options;
  options.lsmi_optional = true;
  const model::MotorData motor;
  const Identification id = identify({experiment("long", 400), experiment("one-second", 62)},
                                     experiment("held-out", 400), options, motor);
  EXPECT_FALSE(id.lsmi_ran());
  EXPECT_EQ(id.lsmi_skipped.rfind("one-second: too short for LSMI: 62 samples", 0), 0u)
      << id.lsmi_skipped;
  EXPECT_TRUE(id.per_experiment.empty());
  EXPECT_FALSE(id.validation.has_value());
  EXPECT_EQ(id.processed.size(), 2u);  // the signals are still shown
  EXPECT_EQ(
      std::count(id.warnings.begin(), id.warnings.end(), "LSMI did not run: " + id.lsmi_skipped),
      1);

  // Long enough for LSMI, a short held-out one only loses its torque check.
  const Identification held =
      identify({experiment("long", 400)}, experiment("held-out", 81), options, motor);
  EXPECT_TRUE(held.lsmi_ran());
  EXPECT_FALSE(held.validation.has_value());
  EXPECT_EQ(std::count_if(held.warnings.begin(), held.warnings.end(),
                          [](const std::string& w) {
                            return w.starts_with(
                                "held-out held-out: no LSMI torque check: too "
                                "short for LSMI: 81 samples");
                          }),
            1);
}

// A held-out session long enough to use but short of two pendulum periods after trimming: its
// RMSE is given with its sample count and a warning; a long one gives no warning.
TEST(ExperimentLength, AHeldOutRmseFromFewSamplesSaysHowFew) {
  const IdentifyOptions options;
  const model::MotorData motor;
  const Identification short_one =
      identify({experiment("long", 400)}, experiment("held-out", 94), options, motor);
  ASSERT_TRUE(short_one.validation);
  EXPECT_EQ(short_one.validation->fit.samples, 94u - 2 * edge_samples(options.preprocess));
  const auto warned = [](const Identification& id) {
    return std::count_if(id.warnings.begin(), id.warnings.end(), [](const std::string& w) {
      return w.starts_with("held-out held-out: its torque RMSE rests on 16 samples");
    });
  };
  EXPECT_EQ(warned(short_one), 1);
  const Identification long_one =
      identify({experiment("long", 400)}, experiment("held-out", 400), options, motor);
  EXPECT_EQ(long_one.validation->fit.samples, 400u - 2 * edge_samples(options.preprocess));
  EXPECT_EQ(warned(long_one), 0);
}

// A free-decay or zero-duty session gives homogeneous equations: every parameter 0 +- 0.
TEST(ExperimentInput, AnInputThatNeverMovesInEveryFittedRecordingIsNothingToIdentify) {
  const IdentifyOptions options;
  const model::MotorData motor;
  RawExperiment still = experiment("free-decay", 400);
  std::fill(still.input.begin(), still.input.end(), 0.0);
  RawExperiment also_still = experiment("zero-duty", 400);
  std::fill(also_still.input.begin(), also_still.input.end(), 0.0);
  try {
    identify({still, also_still}, std::nullopt, options, motor);
    FAIL() << "recordings without input were fitted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nothing to identify: the input is constant in every fitted recording"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("free-decay (input 0"), std::string::npos) << what;
    EXPECT_NE(what.find("zero-duty (input 0"), std::string::npos) << what;
  }
  // Beside an excited one, a still recording is fitted: its equations still hold.
  EXPECT_NO_THROW(identify({experiment("excited", 400), still}, std::nullopt, options, motor));
}

}  // namespace
}  // namespace furuta::identification
