// The Taylor-model flow (issue 22): every sampled solution from the start box (and, for the
// Furuta model, from the parameter box carried as state) is inside every step's box over the step
// and at its end; and how far it carries the boxes the doubleton integrator loses.
#include "furuta/validated/taylor_model_flow.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "furuta/model/model.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/ode.hpp"
#include "furuta/validated/research/affine_enclosure.hpp"
#include "furuta/validated/research/benchmark_systems.hpp"
#include "reference.hpp"

namespace furuta::validated::taylor_model_flow_test {
namespace {

using research::affine_at;
using research::SimplePendulum;
using testing::Point;

constexpr double kPi = 3.14159265358979323846;

template <class System, std::size_t N>
testing::SoundnessCount check_flow(const System& system, const TaylorModelFlowResult& r,
                                   const std::vector<Point<N>>& points, int substeps) {
  const std::vector<double> switches = switch_times(system);
  testing::SoundnessCount count;
  for (const Point<N>& x0 : points) {
    ++count.points;
    Point<N> x = x0;
    for (const TaylorModelFlowStep& s : r.steps) {
      const std::size_t piece = piece_at(switches, s.t0);
      const long double h = static_cast<long double>(s.t1) - s.t0;
      for (int i = 1; i <= substeps; ++i) {
        x = testing::rk4(system, piece, x, h / substeps);
        ++count.checks;
        count.violations += !testing::inside(x, i == substeps ? s.end : s.over);
      }
    }
  }
  return count;
}

TaylorModelFlowOptions flow_options(double t_end) {
  TaylorModelFlowOptions o;
  o.integrator = testing::furuta_test_options(t_end);
  o.integrator.order = 8;
  o.integrator.max_width = 2.0 * kPi;
  o.space_order = 3;
  return o;
}

// The pendulum from a box 10x the benchmark's (one doubleton tube passes a turn's width at about
// 2 s; the split run needs 26 pieces for 3 s), with and without shrink wrapping.
TEST(TaylorModelFlow, PendulumWideBoxIsSoundAndCarriedFurther) {
  const SimplePendulum pendulum;
  const Box x0{Interval(-1.845, -1.645), Interval(-0.1, 0.1)};
  TaylorModelFlowOptions o = flow_options(3.0);
  o.space_order = 4;
  const TaylorModelFlowResult r = integrate_taylor_models(pendulum, x0, o);
  TaylorModelFlowOptions unwrapped = o;
  unwrapped.shrink_wrap_max_delta = 0.0;
  const TaylorModelFlowResult u = integrate_taylor_models(pendulum, x0, unwrapped);
  IntegratorOptions doubleton = o.integrator;
  doubleton.max_inflation = 20.0;
  const IntegrationResult d = integrate(pendulum, x0, doubleton);
  std::mt19937_64 rng(31);
  const testing::SoundnessCount c =
      check_flow(pendulum, r, testing::sample_box<2>(x0, 200, rng), 8);
  const testing::SoundnessCount cu =
      check_flow(pendulum, u, testing::sample_box<2>(x0, 200, rng), 8);
  EXPECT_EQ(c.violations, 0U);
  EXPECT_EQ(cu.violations, 0U);
  EXPECT_GT(c.checks, 1000U);
  std::printf(
      "[ measured ] pendulum +-0.1, Taylor models order 4: %.3f s of 3 s (%s), %zu steps (%zu "
      "shrink-wrapped), %.3f s wall; without shrink wrapping %.3f s; doubleton %.3f s; %zu "
      "checks, %zu violations\n",
      r.t_reached(), r.ok() ? "ok" : r.reason.c_str(), r.steps.size(), r.shrink_wraps, r.seconds,
      u.t_reached(), d.tube.t_end(), c.checks + cu.checks, c.violations + cu.violations);
  EXPECT_GT(r.shrink_wraps, 20U);
  EXPECT_GT(r.t_reached(), u.t_reached());
  EXPECT_GT(u.t_reached(), d.tube.t_end());
}

// The flow as a Tube (what coverage reads): at a step's end its end box, inside a step its box
// over the step, outside the tube nothing; a step of the flow has no Taylor form to give.
TEST(TaylorModelFlow, AsATubeItGivesTheFlowsOwnBoxes) {
  const SimplePendulum pendulum;
  const Box x0{Interval(-1.8, -1.7), Interval(-0.05, 0.05)};
  const TaylorModelFlowResult r = integrate_taylor_models(pendulum, x0, flow_options(0.5));
  ASSERT_TRUE(r.ok()) << r.reason;
  const Tube tube = as_tube(r);
  ASSERT_EQ(tube.steps.size(), r.steps.size());
  EXPECT_EQ(tube.dimension, 2U);
  EXPECT_EQ(tube.t_end(), r.t_reached());
  EXPECT_EQ(tube.enclosure_at(0.0), x0);
  const TaylorModelFlowStep& s = r.steps[r.steps.size() / 2];
  EXPECT_EQ(tube.enclosure_at(s.t1), s.end);
  EXPECT_EQ(tube.enclosure_at(0.5 * (s.t0 + s.t1)), s.over);
  EXPECT_EQ(tube.enclosure_at(0.5 * (s.t0 + s.t1)), r.enclosure_at(0.5 * (s.t0 + s.t1)));
  EXPECT_TRUE(tube.enclosure_at(0.6)[0].is_empty());
  EXPECT_FALSE(tube.steps.front().has_form());
  EXPECT_THROW((void)affine_at(tube, s.t1), std::out_of_range);
}

// The Furuta model with its seven parameters carried as state (11 variables): +-0.1 % of the
// truth, and the bench box (mu's +-2 %, fv1 +-10 %, fv2 +-50 %), scenario (a); most steps are
// shrink-wrapped, some with a start variable (the arm's velocity) left out; with the wrap's
// preconditioner over the box and at the base point.
TEST(TaylorModelFlow, FurutaWithIntervalParametersIsSound) {
  const model::Parameters<double> truth = model::paper_run1();
  const Box state = testing::scenario_a_state();
  model::Parameters<Interval> bench = parameters_around(truth, 0.02);
  bench.fv1 = Interval(truth.fv1) * Interval(0.9, 1.1);
  bench.fv2 = Interval(truth.fv2) * Interval(0.5, 1.5);
  struct Case {
    const char* name;
    model::Parameters<Interval> p;
    double t_end;
    std::size_t min_partial_wraps;
  };
  for (const bool at_base_point : {false, true}) {
    for (const Case& k : {Case{"+-0.1 %", parameters_around(truth, 1e-3), 0.3, 20},
                          Case{"bench box", bench, 0.5, 0}}) {
      const Box x0 = FurutaDynamics::initial_box(state, k.p);
      const FurutaDynamics system(Interval(0.0));
      TaylorModelFlowOptions o = flow_options(k.t_end);
      o.wrap_without_collapsed = true;  // the arm's velocity: checked here with the rest
      o.wrap_at_base_point = at_base_point;
      const TaylorModelFlowResult r = integrate_taylor_models(system, x0, o);
      IntegratorOptions doubleton = o.integrator;
      const IntegrationResult d = integrate(system, x0, doubleton);
      std::mt19937_64 rng(7);
      const testing::SoundnessCount c =
          check_flow(system, r, testing::sample_box<11>(x0, 150, rng), 4);
      EXPECT_EQ(c.violations, 0U) << k.name;
      ASSERT_GT(r.steps.size(), 5U) << k.name << ": " << r.reason;
      const Box end = r.enclosure_at(r.t_reached());
      std::printf(
          "[ measured ] Furuta 11-dim %s%s, Taylor models order 3: %.3f s of %.1f s (%s), %zu "
          "steps (%zu shrink-wrapped, %zu of them with a start variable left out), %.2f s wall, q2 "
          "width %.3g; doubleton %.3f s; %zu checks, %zu violations\n",
          k.name, at_base_point ? ", wrapped at the base point" : "", r.t_reached(), k.t_end,
          r.ok() ? "ok" : r.reason.c_str(), r.steps.size(), r.shrink_wraps, r.partial_wraps,
          r.seconds, end[FurutaDynamics::q2].width(), d.tube.t_end(), c.checks, c.violations);
      EXPECT_GT(r.shrink_wraps, 20U) << k.name;
      // At the base point the whole wrap passes more often (20 of 101 steps with a slot left out).
      EXPECT_GE(r.partial_wraps, at_base_point ? k.min_partial_wraps / 2 : k.min_partial_wraps)
          << k.name;
    }
  }
}

// The board's ramp as the input's state (12 variables): a rest start, the duty ramped up to 0.3
// and later down through 0 at 62.5 per second; every sampled solution is inside every step's box,
// and the input's component is the ramp itself (a point: it carries no spread into the flow).
TEST(TaylorModelFlow, FurutaWithARampedInputIsSoundAndItsInputExact) {
  const model::Parameters<double> truth = model::paper_run1();
  const double ramp_s = 0.3 / 62.5;
  const FurutaRampedDynamics system({{0.0, Interval(62.5)},
                                     {ramp_s, Interval(0.0)},
                                     {0.1, Interval(-62.5)},
                                     {0.1 + 2 * ramp_s, Interval(0.0)}});
  const Box rest{Interval(-2e-4, 2e-4), Interval(-0.01, 0.01), Interval(-4e-3, 4e-3),
                 Interval(-0.03, 0.03)};
  const Box x0 =
      FurutaRampedDynamics::initial_box(rest, parameters_around(truth, 1e-3), Interval(0.0));
  ASSERT_EQ(x0.size(), 12U);
  TaylorModelFlowOptions o = flow_options(0.15);
  o.wrap_without_collapsed = true;
  o.wrap_at_base_point = true;
  const TaylorModelFlowResult r = integrate_taylor_models(system, x0, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  std::mt19937_64 rng(11);
  const testing::SoundnessCount c = check_flow(system, r, testing::sample_box<12>(x0, 60, rng), 2);
  EXPECT_EQ(c.violations, 0U);
  EXPECT_GT(c.checks, 1000U);
  const Box end = r.enclosure_at(r.t_reached());
  EXPECT_NEAR(end[FurutaRampedDynamics::input].mid(), -0.3, 1e-12);
  EXPECT_LT(end[FurutaRampedDynamics::input].width(), 1e-12);
  std::printf(
      "[ measured ] Furuta 12-dim with a ramped input: %.3f s, %zu steps (%zu shrink-wrapped), "
      "%.2f s wall, q2 width %.3g; %zu checks, %zu violations\n",
      r.t_reached(), r.steps.size(), r.shrink_wraps, r.seconds, end[FurutaDynamics::q2].width(),
      c.checks, c.violations);
}

}  // namespace
}  // namespace furuta::validated::taylor_model_flow_test
