// The splitting Taylor-model flow (issue 22): a run split where one tube fails covers, at every
// sampled time, every sampled solution with one of its pieces, and reaches further than one tube.
#include "furuta/validated/taylor_model_split.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <span>
#include <vector>

#include "furuta/validated/ode.hpp"
#include "furuta/validated/research/benchmark_systems.hpp"
#include "reference.hpp"

namespace furuta::validated {
namespace {

using research::SimplePendulum;
using testing::Point;

// For every sampled solution and every time on a grid up to r.t_reached: some piece's enclosure
// at that time holds the solution (the pieces' union is what is claimed). The reference takes
// 16 RK4 steps per grid step: with 4, its own error put a corner of a tight box outside (1e-10).
template <class System, std::size_t N>
testing::SoundnessCount check_cover(const System& system, const TaylorModelSplitResult& r,
                                    const std::vector<Point<N>>& points, double dt) {
  testing::SoundnessCount count;
  for (const Point<N>& x0 : points) {
    ++count.points;
    Point<N> x = x0;
    double t = r.pieces.front().t_start;
    while (t + dt <= r.t_reached) {
      x = testing::simulate(system, x, t, t + dt, dt / 16);
      t += dt;
      ++count.checks;
      bool covered = false;
      for (const TaylorModelFlowResult& piece : r.pieces) {
        covered = covered || testing::inside(x, piece.enclosure_at(t));
      }
      count.violations += !covered;
    }
  }
  return count;
}

// The pendulum with its stiffness a carried as state of zero derivative (as the Furuta model
// carries its parameters): x1' = x2, x2' = -x3 sin x1 - 0.5 x2, x3' = 0.
struct PendulumWithStiffness {
  static constexpr std::size_t dimension = 3;

  template <class S>
  void operator()(std::span<const S> x, std::span<S> dx) const {
    using std::sin;
    dx[0] = x[1];
    dx[1] = -(x[2] * sin(x[0])) - S(0.5) * x[1];
    dx[2] = S(0.0);
  }
};

TaylorModelFlowOptions pendulum_options() {
  TaylorModelFlowOptions o;
  o.integrator = testing::furuta_test_options(3.0);
  o.integrator.order = 8;
  o.integrator.max_width = 2.0 * 3.14159265358979323846;
  o.space_order = 3;
  return o;
}

template <class System>
TaylorModelSplitResult split_on_two_threads(const System& system, const Box& x0,
                                            const TaylorModelFlowOptions& o,
                                            std::size_t max_pieces) {
  TaylorModelSplitOptions split;
  split.max_pieces = max_pieces;
  split.threads = 2;
  return integrate_taylor_models_split(system, x0, o, split);
}

// The pendulum from a box 30x the benchmark's: one order-3 tube loses it within 3 s; split into
// at most 8 pieces it goes further, and every sampled solution stays covered.
TEST(TaylorModelSplit, PendulumWideBoxIsCoveredAndCarriedFurther) {
  const SimplePendulum pendulum;
  const Box x0{Interval(-2.045, -1.445), Interval(-0.3, 0.3)};
  const TaylorModelFlowOptions o = pendulum_options();
  const TaylorModelFlowResult one = integrate_taylor_models(pendulum, x0, o);
  const TaylorModelSplitResult r = split_on_two_threads(pendulum, x0, o, 8);
  std::mt19937_64 rng(41);
  const testing::SoundnessCount c =
      check_cover(pendulum, r, testing::sample_box<2>(x0, 300, rng), 0.01);
  std::printf(
      "[ measured ] pendulum +-0.3, order 3: one tube %.3f s (%s); split %.3f s of 3 s, %zu "
      "pieces, %zu cuts (%zu in the angle), %zu runs, %.2f s wall; %zu checks, %zu violations\n",
      one.t_reached(), one.ok() ? "ok" : one.reason.c_str(), r.t_reached, r.pieces.size(), r.splits,
      r.cuts[0], r.runs, r.seconds, c.checks, c.violations);
  EXPECT_EQ(c.violations, 0U);
  EXPECT_GT(c.checks, 10000U);
  ASSERT_FALSE(one.ok());
  EXPECT_GT(r.splits, 0U);
  EXPECT_LE(r.pieces.size(), 8U);
  EXPECT_EQ(r.pieces.size(), r.paths.size());
  EXPECT_GT(r.t_reached, one.t_reached() + 0.1);
  // The hull at a time is the pieces' hull, and nothing is claimed past t_reached.
  const Box hull = r.enclosure_at(0.5 * r.t_reached);
  for (const TaylorModelFlowResult& piece : r.pieces) {
    const Box b = piece.enclosure_at(0.5 * r.t_reached);
    for (std::size_t v = 0; v < 2; ++v) EXPECT_TRUE(b[v].is_subset(hull[v]));
  }
  EXPECT_TRUE(r.enclosure_at(r.t_reached + 0.01).is_empty());
}

// A cut in a carried parameter: its halves (56 +- 1.4 is not a binary fraction, so the restricted
// parameter's model has a rounding remainder) keep the constant component out of the error part
// and go on shrink-wrapping, and reach further than one tube.
TEST(TaylorModelSplit, ACutInACarriedParameterKeepsTheHalvesWrapping) {
  const PendulumWithStiffness pendulum;
  const Box x0{Interval(-1.7455, -1.7445), Interval(-0.0005, 0.0005), Interval(53.2, 58.8)};
  TaylorModelFlowOptions o = pendulum_options();
  o.integrator.t_end = 6.0;
  const TaylorModelFlowResult one = integrate_taylor_models(pendulum, x0, o);
  const TaylorModelSplitResult r = split_on_two_threads(pendulum, x0, o, 4);
  std::mt19937_64 rng(43);
  const testing::SoundnessCount c =
      check_cover(pendulum, r, testing::sample_box<3>(x0, 200, rng), 0.01);
  std::printf(
      "[ measured ] pendulum, stiffness +-5 %% carried: one tube %.3f s (%s); split %.3f s of "
      "6 s, %zu pieces, %zu cuts in the stiffness; %zu checks, %zu violations\n",
      one.t_reached(), one.ok() ? "ok" : one.reason.c_str(), r.t_reached, r.pieces.size(),
      r.cuts[2], c.checks, c.violations);
  EXPECT_EQ(c.violations, 0U);
  ASSERT_FALSE(one.ok());
  EXPECT_GT(r.cuts[2], 0U);
  for (std::size_t i = 0; i < r.pieces.size(); ++i) {
    EXPECT_GT(r.pieces[i].shrink_wraps, 0U) << r.paths[i];
  }
  EXPECT_GT(r.t_reached, one.t_reached() + 0.2);
}

// A run that does not fail is one piece, the same tube as integrate_taylor_models; the
// deterministic result does not depend on the threads.
TEST(TaylorModelSplit, OneTubeWhenNothingFailsAndTheSameOnAnyThreads) {
  const SimplePendulum pendulum;
  const Box x0{Interval(-1.755, -1.735), Interval(-0.01, 0.01)};
  TaylorModelFlowOptions o = pendulum_options();
  o.integrator.t_end = 1.0;
  const TaylorModelFlowResult one = integrate_taylor_models(pendulum, x0, o);
  const TaylorModelSplitResult r = integrate_taylor_models_split(pendulum, x0, o, {});
  ASSERT_TRUE(one.ok());
  ASSERT_EQ(r.pieces.size(), 1U);
  EXPECT_TRUE(r.ok());
  ASSERT_EQ(r.pieces[0].steps.size(), one.steps.size());
  EXPECT_EQ(r.pieces[0].steps.back().end[0].lo(), one.steps.back().end[0].lo());

  const Box wide{Interval(-2.045, -1.445), Interval(-0.3, 0.3)};
  o.integrator.t_end = 3.0;
  TaylorModelSplitOptions split;
  split.max_pieces = 4;
  split.threads = 1;
  const TaylorModelSplitResult a = integrate_taylor_models_split(pendulum, wide, o, split);
  split.threads = 2;
  const TaylorModelSplitResult b = integrate_taylor_models_split(pendulum, wide, o, split);
  ASSERT_EQ(a.paths, b.paths);
  EXPECT_EQ(a.t_reached, b.t_reached);
  for (std::size_t i = 0; i < a.pieces.size(); ++i) {
    EXPECT_EQ(a.pieces[i].steps.size(), b.pieces[i].steps.size()) << a.paths[i];
  }

  EXPECT_THROW(integrate_taylor_models_split(pendulum, wide, o, {0, 8, 0.25, 0}),
               std::invalid_argument);
  EXPECT_THROW(integrate_taylor_models_split(pendulum, wide, o, {4, 8, 1.5, 0}),
               std::invalid_argument);
}

}  // namespace
}  // namespace furuta::validated
