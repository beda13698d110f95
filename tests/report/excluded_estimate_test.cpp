// A guaranteed set that excludes the output-error estimate is said so: in the terminal's text, in
// the report's warnings and in results.json, with the parameter and how many sd away.
#include <gtest/gtest.h>

#include <string>

#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {
namespace {

pipeline::Run run_whose_set_excludes_fv2() {
  pipeline::Run run;
  pipeline::Guaranteed guaranteed;
  guaranteed.result.paving.prior = interval::Box(model::kParameterCount, interval::Interval(0, 1));
  guaranteed.result.paving.boundary.push_back(guaranteed.result.paving.prior);
  guaranteed.result.paving.boundary.back()[6] = interval::Interval(1e-3, 2e-3);
  guaranteed.result.unknown[6] = true;
  run.sivia = guaranteed;
  model::Parameters<double> estimate{0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 6.4e-4};
  model::Parameters<double> sd{0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 1e-4};
  run.sivia_excludes_output_error =
      pipeline::estimates_outside(guaranteed.result.paving.outer_hull(), estimate, sd);
  return run;
}

TEST(ExcludedEstimate, TheTerminalNamesTheParameterAndTheDistance) {
  const pipeline::Run run = run_whose_set_excludes_fv2();
  ASSERT_EQ(run.sivia_excludes_output_error.size(), 1u);
  const std::string text = terminal_text_after_lsmi(run);
  EXPECT_NE(text.find("warning: the set excludes the output-error estimate of fv2: 0.00064 lies "
                      "3.6 sd below [0.001, 0.002]"),
            std::string::npos)
      << text;
}

TEST(ExcludedEstimate, ResultsJsonListsItOnlyWhenTheSetExcludesIt) {
  pipeline::Run run = run_whose_set_excludes_fv2();
  const Json j = results_json(run, "test");
  ASSERT_TRUE(j["sivia"].contains("excludes_output_error")) << j["sivia"].dump();
  const Json& e = j["sivia"]["excludes_output_error"][0];
  EXPECT_EQ(e["parameter"], "fv2");
  EXPECT_NEAR(e["sd_away"].get<double>(), 3.6, 1e-9);
  EXPECT_DOUBLE_EQ(e["output_error_estimate"].get<double>(), 6.4e-4);
  run.sivia_excludes_output_error.clear();
  EXPECT_FALSE(results_json(run, "test")["sivia"].contains("excludes_output_error"));
}

}  // namespace
}  // namespace furuta::report
