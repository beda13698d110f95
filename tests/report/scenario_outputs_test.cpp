// What a person or a program reads of the paper's scenarios (moved here from
// tests/validated/scenarios_test.cpp with the code): the scenarios' names, Table III as text and as
// JSON, the Fig. 6 figure.
#include <gtest/gtest.h>

#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "furuta/report/json.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"
#include "furuta/validated/scenarios.hpp"
#include "short_scenario_run.hpp"

namespace furuta::report {
namespace {

using namespace furuta::validated;

using ScenarioOutputs = furuta::testing::ShortScenarioRun;

TEST(ScenarioNames, ThePapersFour) {
  const std::vector<Scenario> s = paper_scenarios();
  EXPECT_EQ(scenario_label(s[0]), "(a)");
  EXPECT_EQ(scenario_label(s[3]), "(d)");
  EXPECT_EQ(scenario_description(s[0]), "x0 = [0, 0, -100 deg, 0], u = 0 N m");
  EXPECT_EQ(scenario_description(s[2]), "x0 = [0, 0, -90 deg, 0], u = 0.17 N m");
}

TEST_F(ScenarioOutputs, FigureSix) {
  const ScenarioMeasurement m = measure_scenario(scenario(), model::paper_run1());
  const ScenarioResult r =
      evaluate_tubes(scenario(), point_parameters("LSMI", model::paper_run1()), {}, m, tubes());
  const std::string svg = svg_scenario(r);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("Scenario (a): x0 = [0, 0, -100 deg, 0], u = 0 N m, LSMI"), std::string::npos);
  EXPECT_NE(svg.find("class=\"tube\""), std::string::npos);
  EXPECT_NE(svg.find("class=\"measured\""), std::string::npos);
  EXPECT_NE(svg.find(">t [s]</text>"), std::string::npos);
  EXPECT_NE(svg.find("q2 [deg]"), std::string::npos);
  const std::regex circle("<circle cx=");
  const auto circles =
      std::distance(std::sregex_iterator(svg.begin(), svg.end(), circle), std::sregex_iterator());
  EXPECT_EQ(static_cast<std::size_t>(circles), m.t_s.size() + 2);  // samples + legend's two
  std::ostringstream rate;
  rate << "step (paper) " << std::fixed << std::setprecision(1) << 100 * r.q2_step.rate() << " %";
  EXPECT_NE(svg.find(rate.str()), std::string::npos) << rate.str();
  EXPECT_EQ(svg.find("tube ends"), std::string::npos);  // it reached the end
}

// A tube that ends early: the figure marks it.
TEST_F(ScenarioOutputs, EarlyEndIsMarked) {
  Scenario longer = scenario();
  longer.duration_s = 0.8;
  const ScenarioMeasurement m = measure_scenario(longer, model::paper_run1());
  const ScenarioResult r =
      evaluate_tubes(longer, point_parameters("LSMI", model::paper_run1()), {}, m, tubes());
  EXPECT_DOUBLE_EQ(r.t_reached_s, 0.2);
  EXPECT_NE(svg_scenario(r).find("tube ends at 0.200 s"), std::string::npos);
}

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
