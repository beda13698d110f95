// The windowed set's figure: each scaled parameter's search box, set, estimate and truth at their
// offsets in the estimate's sd, and the step that narrowed each; a set the windows left alone says
// so.
#include <gtest/gtest.h>

#include <string>

#include "furuta/identification/physical_inputs.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/svg.hpp"

namespace furuta::report {
namespace {

using interval::Interval;

// Estimate 1 +- 0.1 for every parameter, searched +- 5 sd; b narrowed to +-1 sd by the second of
// three steps, fv2/g to +-2 sd by the first; the rest left at the search box.
pipeline::WindowedGuaranteed narrowed_b_and_fv2() {
  pipeline::WindowedGuaranteed w;
  w.search_sd = 5;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    w.estimate_scaled[k] = 1.0;
    w.std_dev_scaled[k] = 0.1;
    w.result.search[k] = Interval(0.5, 1.5);
  }
  w.truth_scaled = w.estimate_scaled;
  (*w.truth_scaled)[5] = 1.05;
  w.result.set = w.result.search;
  w.result.set[5] = Interval(0.9, 1.1);
  w.result.set[6] = Interval(0.8, 1.2);
  model::Parameters<Interval> after1 = w.result.search;
  after1[5] = Interval(0.7, 1.3);
  after1[6] = w.result.set[6];
  w.result.set_after_step = {after1, w.result.set, w.result.set};
  return w;
}

TEST(WindowedSetFigure, SaysWhichStepNarrowedEachParameter) {
  const pipeline::WindowedGuaranteed w = narrowed_b_and_fv2();
  EXPECT_EQ(deciding_step(w, 0), 0U);
  EXPECT_EQ(deciding_step(w, 5), 2U);
  EXPECT_EQ(deciding_step(w, 6), 1U);
  const std::string svg = svg_windowed_set(w);
  EXPECT_NE(svg.find("+-1 sd, step 2"), std::string::npos) << svg;
  EXPECT_NE(svg.find("+-2 sd, step 1"), std::string::npos);
  EXPECT_NE(svg.find("+-5 sd, not narrowed"), std::string::npos);
  for (const char* name : identification::kScaledParameterNames) {
    EXPECT_NE(svg.find(std::string("data-parameter=\"") + name + "\""), std::string::npos) << name;
  }
  EXPECT_NE(svg.find("class=\"truth\""), std::string::npos);
  EXPECT_NE(svg.find("class=\"axis x\""), std::string::npos);
  EXPECT_EQ(svg.find("class=\"axis y\""), std::string::npos) << "rows named, not a y axis";
}

// The bars sit where the numbers say: b's set spans +-1 sd of an axis reaching +-5.5 sd, so its
// width is 2/11 of the search box's 10/11 share: a fifth of it.
TEST(WindowedSetFigure, BarsAreToScale) {
  const std::string svg = svg_windowed_set(narrowed_b_and_fv2());
  const auto width_of = [&](const std::string& cls, const std::string& parameter) {
    const std::string key = "class=\"" + cls + "\" data-parameter=\"" + parameter + "\"";
    const auto at = svg.find(key);
    EXPECT_NE(at, std::string::npos) << key;
    const auto w = svg.find("width=\"", at) + 7;
    return std::stod(svg.substr(w, svg.find('"', w) - w));
  };
  EXPECT_NEAR(width_of("set", "b") / width_of("search", "b"), 0.2, 1e-9);
  EXPECT_NEAR(width_of("set", "mu1/g") / width_of("search", "mu1/g"), 1.0, 1e-9);
}

}  // namespace
}  // namespace furuta::report
