#pragma once
// One short real run of the paper's scenario (a), shared by the scenario tests of validated/ and of
// report/ (computed once per test executable): 0.2 s with the truth as point parameters and the
// data uncertainty on x0.

#include <gtest/gtest.h>

#include "furuta/model/model.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::testing {

class ShortScenarioRun : public ::testing::Test {
 protected:
  static const validated::Scenario& scenario() {
    static const validated::Scenario s = [] {
      validated::Scenario a = validated::paper_scenario(1);
      a.duration_s = 0.2;
      return a;
    }();
    return s;
  }
  static const validated::ScenarioTubes& tubes() {
    static const validated::ScenarioTubes t = validated::run_scenario_tubes(
        scenario(), validated::interval_parameters(model::paper_run1()), {}, {});
    return t;
  }
};

}  // namespace furuta::testing
