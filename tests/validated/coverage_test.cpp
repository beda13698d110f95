// Coverage rates on hand-built tubes: the paper's step test against the interpolated one, samples
// past the end, step boundaries, several pieces, bad arguments.
#include "furuta/validated/coverage.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace furuta::validated {
namespace {

// A 2-dimensional tube of order 1 whose component 0 is the band a + b t +- w exactly (the Taylor
// form is c0 + c1 s with c0 = a + b t0 +- w, c1 = b) and whose component 1 is [100, 101], with
// steps ending at the given times.
Tube band_tube(double a, double b, double w, const std::vector<double>& step_ends,
               double t_start = 0.0) {
  Tube tube;
  tube.dimension = 2;
  tube.order = 1;
  tube.t_start = t_start;
  const auto at = [&](double t) { return Interval(a + b * t - w, a + b * t + w); };
  const Interval other(100.0, 101.0);
  tube.initial = Box{at(t_start), other};
  tube.r0 = {Interval(0.0), Interval(0.0)};
  double t0 = t_start;
  for (const double t1 : step_ends) {
    TubeStep s;
    s.t0 = t0;
    s.t1 = t1;
    s.h = Interval(t1) - Interval(t0);
    s.over = Box{hull(at(t0), at(t1)), other};
    s.apriori = s.over;
    s.end = Box{at(t1), other};
    s.c = {0.0, 0.0, 0.0, 0.0};
    s.b = {0.0, 0.0, 0.0, 0.0};
    s.r = {Interval(0.0), Interval(0.0)};
    s.centre = {at(t0), other, Interval(b), Interval(0.0)};
    s.jacobian.assign(2 * 2 * 2, Interval(0.0));
    s.second.assign(2 * 2, Interval(0.0));
    s.remainder = {Interval(0.0), Interval(0.0)};
    tube.steps.push_back(s);
    t0 = t1;
  }
  return tube;
}

TEST(Coverage, StepTestUsesTheWholeStepBoxInterpolatedTheInstant) {
  // y = t +- 0.01, steps of 0.1 s up to 1 s.
  const Tube tube = band_tube(0.0, 1.0, 0.01, {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0});
  const std::vector<const Tube*> pieces = {&tube};
  // On the line; 0.04 above it inside a step (the step's box spans 0.1 + 2 w); off both.
  const std::vector<double> t = {0.05, 0.25, 0.45, 0.65};
  const std::vector<double> y = {0.05, 0.29, 0.45 - 0.2, 0.68};
  std::vector<bool> flags;
  const Coverage step = coverage(pieces, 0, t, y, CoverageMode::step, &flags);
  EXPECT_EQ(step.measurements, 4u);
  EXPECT_EQ(step.in_time, 4u);
  EXPECT_EQ(step.covered, 3u);  // 0.05, 0.29 (in [0.19, 0.31]) and 0.68 (in [0.59, 0.71])
  EXPECT_EQ(flags, (std::vector<bool>{true, true, false, true}));
  EXPECT_DOUBLE_EQ(step.rate(), 0.75);
  EXPECT_DOUBLE_EQ(step.rate_in_time(), 0.75);

  const Coverage interpolated = coverage(pieces, 0, t, y, CoverageMode::interpolated, &flags);
  EXPECT_EQ(interpolated.covered, 1u);  // only the sample on the line: 0.29 is 0.04 off at 0.25
  EXPECT_EQ(flags, (std::vector<bool>{true, false, false, false}));
  // The interpolated enclosure is inside the step's box: never covers more.
  EXPECT_LE(interpolated.covered, step.covered);
}

TEST(Coverage, ComponentIsChosen) {
  const Tube tube = band_tube(0.0, 1.0, 0.01, {0.5, 1.0});
  const std::vector<double> t = {0.2, 0.7};
  const std::vector<double> y = {100.5, 100.5};
  EXPECT_EQ(coverage({&tube}, 1, t, y, CoverageMode::step).covered, 2u);
  EXPECT_EQ(coverage({&tube}, 1, t, y, CoverageMode::interpolated).covered, 2u);
  EXPECT_EQ(coverage({&tube}, 0, t, y, CoverageMode::step).covered, 0u);
}

TEST(Coverage, SamplesPastTheEndAreNotCoveredAndCountedApart) {
  const Tube tube = band_tube(0.0, 0.0, 0.5, {0.25, 0.5, 0.75, 1.0});  // y in [-0.5, 0.5]
  const std::vector<double> t = {0.0, 0.5, 0.9, 1.0, 1.1, 2.0};
  const std::vector<double> y(t.size(), 0.0);
  for (const CoverageMode mode : {CoverageMode::step, CoverageMode::interpolated}) {
    const Coverage c = coverage({&tube}, 0, t, y, mode);
    EXPECT_EQ(c.measurements, 6u) << to_string(mode);
    EXPECT_EQ(c.in_time, 4u) << to_string(mode);
    EXPECT_EQ(c.covered, 4u) << to_string(mode);
    EXPECT_EQ(c.outside_time, 2u) << to_string(mode);
    EXPECT_DOUBLE_EQ(c.t_reached_s, 1.0);
    EXPECT_DOUBLE_EQ(c.rate(), 4.0 / 6.0);
    EXPECT_DOUBLE_EQ(c.rate_in_time(), 1.0);
  }
}

TEST(Coverage, SamplesBeforeTheStartAreOutsideToo) {
  const Tube tube = band_tube(0.0, 0.0, 0.5, {1.5, 2.0}, 1.0);
  const std::vector<double> t = {0.5, 1.0, 1.75};
  const std::vector<double> y = {0.0, 0.0, 0.0};
  const Coverage c = coverage({&tube}, 0, t, y, CoverageMode::step);
  EXPECT_EQ(c.outside_time, 1u);
  EXPECT_EQ(c.covered, 2u);
  EXPECT_DOUBLE_EQ(c.t_start_s, 1.0);
}

TEST(Coverage, AStepEndBelongsToBothItsSteps) {
  // y = t +- 0.01 with steps [0, 0.5], [0.5, 1]: at t = 0.5 the first step's box is [-0.01, 0.51]
  // and the second's [0.49, 1.01], so 0.0 and 1.0 are both covered there (but not at once by the
  // interpolated test, whose enclosure at a step end is the end box [0.49, 0.51]).
  const Tube tube = band_tube(0.0, 1.0, 0.01, {0.5, 1.0});
  const std::vector<double> t = {0.5, 0.5};
  const std::vector<double> y = {0.0, 1.0};
  EXPECT_EQ(coverage({&tube}, 0, t, y, CoverageMode::step).covered, 2u);
  EXPECT_EQ(coverage({&tube}, 0, t, y, CoverageMode::interpolated).covered, 0u);
}

TEST(Coverage, UnsortedTimesGiveTheSameCounts) {
  const Tube tube = band_tube(0.0, 1.0, 0.01, {0.1, 0.2, 0.3, 0.4});
  const std::vector<double> t = {0.35, 0.05, 0.15, 0.38, 0.6};
  const std::vector<double> y = {0.35, 0.2, 0.15, 0.0, 0.6};
  // Sorted by time: 0.05 (0.2: out), 0.15 (in), 0.35 (in), 0.38 (0.0: out), 0.6 (past the end).
  const std::vector<double> ts = {0.05, 0.15, 0.35, 0.38, 0.6};
  const std::vector<double> ys = {0.2, 0.15, 0.35, 0.0, 0.6};
  for (const CoverageMode mode : {CoverageMode::step, CoverageMode::interpolated}) {
    const Coverage a = coverage({&tube}, 0, t, y, mode);
    const Coverage b = coverage({&tube}, 0, ts, ys, mode);
    EXPECT_EQ(a.covered, 2u);
    EXPECT_EQ(a.covered, b.covered);
    EXPECT_EQ(a.outside_time, 1u);
    EXPECT_EQ(a.outside_time, b.outside_time);
  }
}

TEST(Coverage, PiecesCoverTheirUnionUpToTheEarliestEnd) {
  // Two pieces of a split run: y in [0, 1] up to 2 s, and y in [2, 3] up to 1 s only. After 1 s
  // the second piece's solutions are no longer enclosed, so nothing after 1 s is covered.
  const Tube low = band_tube(0.5, 0.0, 0.5, {0.5, 1.0, 1.5, 2.0});
  const Tube high = band_tube(2.5, 0.0, 0.5, {0.5, 1.0});
  const std::vector<const Tube*> pieces = {&low, &high};
  const std::vector<double> t = {0.2, 0.4, 0.6, 1.5};
  const std::vector<double> y = {0.5, 2.5, 1.5, 0.5};
  for (const CoverageMode mode : {CoverageMode::step, CoverageMode::interpolated}) {
    const Coverage c = coverage(pieces, 0, t, y, mode);
    EXPECT_EQ(c.covered, 2u) << to_string(mode);  // 0.5 by the low piece, 2.5 by the high one
    EXPECT_EQ(c.in_time, 3u) << to_string(mode);
    EXPECT_EQ(c.outside_time, 1u) << to_string(mode);
    EXPECT_DOUBLE_EQ(c.t_reached_s, 1.0);
  }
  EXPECT_DOUBLE_EQ(time_reached(pieces), 1.0);
  const Interval both = enclosure_at(pieces, 0, 0.7);
  EXPECT_DOUBLE_EQ(both.lo(), 0.0);
  EXPECT_DOUBLE_EQ(both.hi(), 3.0);
  EXPECT_TRUE(enclosure_at(pieces, 0, 1.5).is_empty());
}

TEST(Coverage, NoMeasurementsGiveZeroRates) {
  const Tube tube = band_tube(0.0, 0.0, 1.0, {1.0});
  const Coverage c = coverage({&tube}, 0, {}, {}, CoverageMode::step);
  EXPECT_EQ(c.measurements, 0u);
  EXPECT_EQ(c.rate(), 0.0);
  EXPECT_EQ(c.rate_in_time(), 0.0);
}

TEST(Coverage, BadArgumentsAreRefused) {
  const Tube tube = band_tube(0.0, 0.0, 1.0, {1.0});
  const Tube later = band_tube(0.0, 0.0, 1.0, {2.0}, 1.0);
  const std::vector<double> one = {0.5};
  const std::vector<double> two = {0.5, 0.6};
  EXPECT_THROW(coverage({}, 0, one, one, CoverageMode::step), std::invalid_argument);
  EXPECT_THROW(coverage({nullptr}, 0, one, one, CoverageMode::step), std::invalid_argument);
  EXPECT_THROW(coverage({&tube}, 2, one, one, CoverageMode::step), std::invalid_argument);
  EXPECT_THROW(coverage({&tube}, 0, one, two, CoverageMode::step), std::invalid_argument);
  EXPECT_THROW(coverage({&tube, &later}, 0, one, one, CoverageMode::step), std::invalid_argument);
}

}  // namespace
}  // namespace furuta::validated
