// What a person or a program reads of the paper's scenarios (moved here from
// tests/validated/scenarios_test.cpp with the code): Table III as text and as JSON.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "furuta/report/json.hpp"
#include "furuta/report/tables.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::report {
namespace {

using namespace furuta::validated;

// One short real run shared by the tests below (computed once): scenario (a) for 0.2 s with the
// truth as point parameters and the data uncertainty on x0.
class ScenarioOutputs : public ::testing::Test {
 protected:
  static const Scenario& scenario() {
    static const Scenario s = [] {
      Scenario a = paper_scenario(1);
      a.duration_s = 0.2;
      return a;
    }();
    return s;
  }
  static const ScenarioTubes& tubes() {
    static const ScenarioTubes t =
        run_scenario_tubes(scenario(), interval_parameters(model::paper_run1()), {}, {});
    return t;
  }
};

TEST_F(ScenarioOutputs, TableThree) {
  const ScenarioMeasurement m = measure_scenario(scenario(), model::paper_run1());
  const ScenarioResult r =
      evaluate_tubes(scenario(), point_parameters("LSMI", model::paper_run1()), {}, m, tubes());
  const std::string table = format_table_three({r});
  EXPECT_NE(table.find("(a)"), std::string::npos);
  EXPECT_NE(table.find("LSMI"), std::string::npos);
  EXPECT_NE(table.find("0.200 / 0.2"), std::string::npos);
}

TEST_F(ScenarioOutputs, ResultsAsJson) {
  const ScenarioMeasurement m = measure_scenario(scenario(), model::paper_run1());
  const ParameterSet set = point_parameters("LSMI", model::paper_run1());
  const ScenarioResult r = evaluate_tubes(scenario(), set, {}, m, tubes());
  const nlohmann::json j = nlohmann::json::parse(json_line(scenarios_json({r})));
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["scenario"], 1);
  EXPECT_EQ(j[0]["parameter_set"], "LSMI");
  EXPECT_EQ(j[0]["status"], "ok");
  EXPECT_EQ(j[0]["coverage"]["q2_step"]["covered"], r.q2_step.covered);
  EXPECT_DOUBLE_EQ(j[0]["coverage"]["q2_interpolated"]["rate"].get<double>(),
                   r.q2_interpolated.rate());
  EXPECT_DOUBLE_EQ(j[0]["parameters"]["fv1"][0].get<double>(), set.parameters.fv1.lo());
}

}  // namespace
}  // namespace furuta::report
