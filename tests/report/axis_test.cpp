// The figures' axes: nice ticks (1-2-5 steps) over ordinary, multi-turn, tiny and zero ranges,
// their labels, and Fig. 2/3 drawn with a labelled time axis and each signal on its own axis.
#include "furuta/report/axis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "furuta/report/svg.hpp"

namespace furuta::report {
namespace {

// The step is 1, 2 or 5 times a power of ten.
bool nice(double step) {
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (std::abs(mantissa - m) < 1e-9) return true;
  }
  return false;
}

void expect_well_formed(const Ticks& t, double lo, double hi, std::size_t min_count) {
  EXPECT_TRUE(nice(t.step)) << t.step;
  ASSERT_GE(t.values.size(), min_count);
  EXPECT_LE(t.values.size(), 3 * min_count);
  for (std::size_t i = 0; i < t.values.size(); ++i) {
    EXPECT_GE(t.values[i], t.lo - 1e-9 * t.step);
    EXPECT_LE(t.values[i], t.hi + 1e-9 * t.step);
    if (i > 0) {
      EXPECT_NEAR(t.values[i] - t.values[i - 1], t.step, 1e-9 * t.step);
    }
    // On the step's grid: k * step.
    EXPECT_NEAR(t.values[i] / t.step, std::round(t.values[i] / t.step), 1e-6);
  }
  EXPECT_LE(t.lo, lo);
  EXPECT_GE(t.hi, hi);
}

TEST(NiceTicks, ATimeAxisKeepsItsRangeAndStepsByOneTwoOrFive) {
  const Ticks t = nice_ticks(0, 6.0, 5);
  expect_well_formed(t, 0, 6.0, 5);
  EXPECT_EQ(t.lo, 0);
  EXPECT_EQ(t.hi, 6.0);
  EXPECT_EQ(t.step, 1.0);
  EXPECT_EQ(t.values, (std::vector<double>{0, 1, 2, 3, 4, 5, 6}));
  const Ticks short_run = nice_ticks(0, 0.3, 5);
  expect_well_formed(short_run, 0, 0.3, 5);
  EXPECT_DOUBLE_EQ(short_run.step, 0.05);
}

TEST(NiceTicks, AMultiTurnArmFrom80To328RadHasItsOwnTicks) {
  const Ticks t = nice_ticks(80, 328, 4, true);
  expect_well_formed(t, 80, 328, 4);
  EXPECT_EQ(t.step, 50);
  EXPECT_EQ(t.lo, 50);
  EXPECT_EQ(t.hi, 350);
  EXPECT_EQ(t.values.front(), 50);
  EXPECT_EQ(t.values.back(), 350);
  EXPECT_EQ(tick_label(150, t.step), "150");
}

TEST(NiceTicks, APendulumSwingAndNegativeRanges) {
  const Ticks t = nice_ticks(-0.31, 0.27, 4, true);
  expect_well_formed(t, -0.31, 0.27, 4);
  EXPECT_DOUBLE_EQ(t.step, 0.1);
  EXPECT_EQ(tick_label(t.values.front(), t.step), "-0.4");
  // Zero is a tick of its own, "0", never "-0.0".
  bool zero = false;
  for (const double v : t.values) zero = zero || tick_label(v, t.step) == "0";
  EXPECT_TRUE(zero);
}

TEST(NiceTicks, TinyRangesGetTicksAndReadableLabels) {
  const Ticks t = nice_ticks(2.0e-6, 2.6e-6, 4, true);
  expect_well_formed(t, 2.0e-6, 2.6e-6, 4);
  EXPECT_DOUBLE_EQ(t.step, 2e-7);
  EXPECT_EQ(tick_label(2.2e-6, t.step), "2.2e-06");
  // A small swing about a large offset: the labels tell the ticks apart.
  const Ticks offset = nice_ticks(100.0001, 100.0004, 4);
  expect_well_formed(offset, 100.0001, 100.0004, 4);
  EXPECT_NE(tick_label(offset.values[0], offset.step), tick_label(offset.values[1], offset.step));
  EXPECT_EQ(tick_label(0.05, 0.05), "0.05");
  EXPECT_EQ(tick_label(3.0e7, 1.0e7), "3e+07");
}

TEST(NiceTicks, AZeroOrNonFiniteRangeStillHasAnAxis) {
  const Ticks constant = nice_ticks(5, 5, 4, true);
  expect_well_formed(constant, 5, 5, 4);
  EXPECT_LT(constant.lo, 5);
  EXPECT_GT(constant.hi, 5);
  const Ticks zero = nice_ticks(0, 0, 4, true);
  expect_well_formed(zero, 0, 0, 4);
  EXPECT_LE(zero.lo, -1);
  EXPECT_GE(zero.hi, 1);
  const Ticks nothing = nice_ticks(NAN, INFINITY, 4, true);
  EXPECT_GE(nothing.values.size(), 4u);
  EXPECT_TRUE(std::isfinite(nothing.lo) && std::isfinite(nothing.hi));
  const Ticks reversed = nice_ticks(3, 1, 4);
  expect_well_formed(reversed, 1, 3, 4);
}

// The number of ticks of each axis of a figure, from the data-ticks the axes carry.
std::vector<int> tick_counts(const std::string& svg, const std::string& axis) {
  std::vector<int> counts;
  const std::regex marked("class=\"axis " + axis + "\" data-ticks=\"([0-9]+)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), marked); it != std::sregex_iterator();
       ++it) {
    counts.push_back(std::stoi((*it)[1].str()));
  }
  return counts;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(SignalsFigure, EverySignalOnItsOwnAxisWithATimeAxis) {
  // A multi-turn arm (80 to 328 rad) and a pendulum swinging by 0.3 rad: on a shared axis (the
  // figure before) the pendulum was a flat line.
  identification::RawExperiment raw;
  identification::JointSeries p;
  p.name = "2026-11-25T08-02-00Z_bang-bang";
  const std::size_t n = 600;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = 0.01 * static_cast<double>(i);
    p.t_s.push_back(t);
    raw.q1.push_back(80 + 248 * t / 6.0);
    raw.q2.push_back(0.3 * std::sin(5 * t));
    p.q2.push_back(raw.q2.back());
    p.dq1.push_back(41.3);
    p.dq2.push_back(1.5 * std::cos(5 * t));
    p.ddq1.push_back(0.0);
    p.ddq2.push_back(-7.5 * std::sin(5 * t));
    p.tau.push_back(0.02 * std::sin(t));
  }
  const std::string svg = svg_signals(raw, p, 2 * 3.14159265358979 / 4096);
  const std::vector<int> x = tick_counts(svg, "x"), y = tick_counts(svg, "y");
  ASSERT_EQ(x.size(), 7u) << "q1, q2, dq1, dq2, ddq1, ddq2, tau each on a panel";
  ASSERT_EQ(y.size(), 7u);
  for (const int c : x) EXPECT_GE(c, 3);
  for (const int c : y) EXPECT_GE(c, 3);
  EXPECT_EQ(count(svg, ">t [s]</text>"), 7u);
  for (const char* name :
       {">q1 [rad]<", ">q2 [rad]<", ">dq1 [rad/s]<", ">ddq2 [rad/s^2]<", ">tau [N m]<"}) {
    EXPECT_NE(svg.find(name), std::string::npos) << name;
  }
  // The arm's axis counts in tens of rad, the pendulum's in tenths.
  EXPECT_NE(svg.find(">100</text>"), std::string::npos) << "q1's axis has 100 rad";
  EXPECT_NE(svg.find(">300</text>"), std::string::npos) << "q1's axis has 300 rad";
  EXPECT_NE(svg.find(">-0.2</text>"), std::string::npos) << "q2's axis has -0.2 rad";
  // A constant (dq1) still gets an axis, not a division by zero.
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

}  // namespace
}  // namespace furuta::report
