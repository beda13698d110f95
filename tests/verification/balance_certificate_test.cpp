// The balancing loop's verification (verification/): for the loop designed from the simulated
// rig's parameters it certifies 10 s from a start near upright over a parameter box; the loop
// simulated point by point (the real balance law, the nonlinear model by Runge-Kutta, the board's
// lag and ramp, angles rounded to counts) from the boxes' corners and random points stays inside
// every box; where the duty would reach its limit or the pendulum cannot be held it says so and
// when; the start region's bisection ends on a certified scale.
#include "furuta/verification/balance_certificate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "furuta/control/upright_lqr.hpp"
#include "furuta/verification/sampled_loop.hpp"
#include "simulated_rig.hpp"

namespace furuta::verification::balance_certificate_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
// A start (deg, and five times it in deg/s) one run does not certify and its pieces do.
constexpr double kStartDeg = 1.6;
// A relative spread of mu1, mu3, mu4 and a start (deg, five times it in deg/s) that one run
// certifies with the spread carried as sensitivities and not with it as a new error each period.
constexpr double kMassSpread = 1.4e-3;
constexpr double kMassStartDeg = 0.2;

using Rig = testing::SimulatedRig;
using testing::simulated_rig;

// The law as `furuta controller design` makes it for the rig: 16 ms, a 2 ms lag, the board's ramp.
control::BalanceControllerSpec designed(const Rig& rig) {
  constexpr double kLag = 0.002;
  const control::DesignPlant plant{rig.truth, rig.motor, rig.supply_v};
  const double ramp_lag = control::ramp_lag_s(6250, control::kRampStepDuty);
  const control::SampledPlant sampled =
      control::sample(control::linearize_upright(plant), 0.016, kLag + ramp_lag);
  control::ObserverWeights filter;
  filter.arm_count_rad = rig.arm_count_rad;
  filter.pendulum_count_rad = rig.pendulum_count_rad;
  filter.reading_age_s = 0.004;
  return control::balance_spec(plant, sampled, control::design_lqr(sampled, control::LqrWeights{}),
                               control::design_observer(sampled, filter),
                               control::DutyPath{kLag, 62.5}, 0.5, 1.0 / 255);
}

// The loop with each parameter within +-relative of the truth, the lag the law's.
LoopModel loop_around(const Rig& rig, const control::BalanceControllerSpec& law, double relative) {
  LoopModel loop;
  loop.parameters = rig.truth.map(
      [&](double v) { return Interval(v) * (Interval(1.0) + Interval(-relative, relative)); });
  loop.duty_torque_nm = Interval(law.duty_torque_nm);
  loop.back_emf_nm_s = Interval(law.back_emf_nm_s);
  loop.lag_s = Interval(law.duty_path.lag_s);
  loop.ramp_duty_per_s = law.duty_path.ramp_duty_per_s;
  loop.reading_age_s = 0.004;
  loop.arm_count_rad = rig.arm_count_rad;
  loop.pendulum_count_rad = rig.pendulum_count_rad;
  return loop;
}

// The pendulum within +-angle and +-rate of upright, the arm at its centre at rest; the filter's
// angles within a count of the truth, its rates within 1 deg/s.
LoopStart start_within(const Rig& rig, double angle_rad, double rate_rad_s) {
  LoopStart start;
  start.state = {Interval(0.0), Interval(-angle_rad, angle_rad), Interval(0.0),
                 Interval(-rate_rad_s, rate_rad_s)};
  start.estimate_error = {Interval(-rig.arm_count_rad, rig.arm_count_rad),
                          Interval(-rig.pendulum_count_rad, rig.pendulum_count_rad),
                          Interval(-kDeg, kDeg), Interval(-kDeg, kDeg)};
  return start;
}

LoopLimits limits_of(const control::BalanceControllerSpec& law) {
  return {law.region.fall_rad, 150 * kDeg};
}

VerifyOptions for_seconds(double horizon_s) {
  VerifyOptions options;
  options.horizon_s = horizon_s;
  return options;
}

double width_deg(const Interval& v) {
  return v.width() / kDeg;
}

TEST(BalanceCertificate, CertifiesTheDesignedLoopFromAStartNearUpright) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const BalanceCertificate c =
      verify_balance(law, loop_around(rig, law, 1e-4), start_within(rig, 0.5 * kDeg, 2.5 * kDeg),
                     limits_of(law), for_seconds(10));
  ASSERT_TRUE(c.certified()) << "failed at " << c.failure->t_s << " s, kind "
                             << static_cast<int>(c.failure->kind);
  ASSERT_EQ(c.steps.size(), 625u);
  EXPECT_DOUBLE_EQ(c.steps.back().t1_s, 10.0);
  // Held: the pendulum's box stays well inside the fall angle, and settles (its last second no
  // wider than its widest).
  double widest = 0;
  for (const LoopStepBox& s : c.steps) widest = std::max(widest, width_deg(s.over[1]));
  EXPECT_LT(widest, 2 * law.region.fall_rad / kDeg);
  EXPECT_LE(width_deg(c.steps.back().over[1]), widest);
  for (const LoopStepBox& s : c.steps) {
    EXPECT_LT(s.duty.mag(), law.max_duty);
    EXPECT_LT(s.over[1].mag(), law.region.fall_rad);
  }
}

// The sampled check (sampled_loop.hpp): corners of the parameters that move the plant most (mu1,
// mu3, mu4) and of the start's angle and rate, the rest at random inside, then random points.
TEST(BalanceCertificate, SampledTrajectoriesStayInsideEveryBox) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const LoopModel loop = loop_around(rig, law, 1e-4);
  const LoopStart start = start_within(rig, 0.5 * kDeg, 2.5 * kDeg);
  const BalanceCertificate c = verify_balance(law, loop, start, limits_of(law), for_seconds(4));
  ASSERT_TRUE(c.certified());
  const SampledCheck check = sampled_check(law, loop, start, c, 40, 2, 7);
  EXPECT_EQ(check.trajectories, 40u);
  EXPECT_EQ(check.drawn.size(), 2u);
  // Every sample's state, duty and two rates, every Runge-Kutta step's state, of 250 periods.
  EXPECT_GT(check.check.checks, 40u * 250u * 7u);
  EXPECT_EQ(check.check.outside, 0u) << "first outside at " << check.check.first_outside_s << " s";
}

// Halving the start box where its run fails: the pieces where the pendulum starts away from
// upright and moving further away carry the remainder's first order along their own transients.
TEST(BalanceCertificate, StartPiecesCertifyWhatOneRunCannot) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const LoopModel loop = loop_around(rig, law, 1e-6);
  const LoopStart start = start_within(rig, kStartDeg * kDeg, 5 * kStartDeg * kDeg);
  const BalanceCertificate whole = verify_balance(law, loop, start, limits_of(law), for_seconds(3));
  ASSERT_FALSE(whole.certified());
  SplitOptions split;
  split.max_pieces = 16;
  split.handover_s = 0;
  const BalanceCertificate pieces =
      verify_balance_split(law, loop, start, limits_of(law), for_seconds(3), split);
  ASSERT_TRUE(pieces.certified()) << "failed at " << pieces.failure->t_s << " s";
  EXPECT_GT(pieces.pieces, 1u);
  EXPECT_EQ(pieces.handover_s, 0.0);
  ASSERT_EQ(pieces.steps.size(), 188u);
  const SampledCheck check = sampled_check(law, loop, start, pieces, 40, 0, 3);
  EXPECT_EQ(check.check.outside, 0u) << "first outside at " << check.check.first_outside_s << " s";
}

// The mass matrix's parameters' spread carried as sensitivities (the state's first order in
// them, the same factor all along): one run over mu1, mu3, mu4 each within +-kMassSpread, the
// sampled check's corners of those three inside the tube.
TEST(BalanceCertificate, MassParametersSpreadInOneRun) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  LoopModel loop = loop_around(rig, law, 0.0);
  for (Interval* mu : {&loop.parameters.mu1, &loop.parameters.mu3, &loop.parameters.mu4}) {
    *mu = *mu * (Interval(1.0) + Interval(-kMassSpread, kMassSpread));
  }
  const LoopStart start = start_within(rig, kMassStartDeg * kDeg, 5 * kMassStartDeg * kDeg);
  const BalanceCertificate c = verify_balance(law, loop, start, limits_of(law), for_seconds(4));
  ASSERT_TRUE(c.certified()) << "failed at " << c.failure->t_s << " s, kind "
                             << static_cast<int>(c.failure->kind);
  const SampledCheck check = sampled_check(law, loop, start, c, 40, 0, 5);
  EXPECT_EQ(check.check.outside, 0u) << "first outside at " << check.check.first_outside_s << " s";
}

// The pieces hand over to one run from the hull of their states (the loop's whole state as a
// box): the same horizon proven, each period's boxes holding the sampled trajectories.
TEST(BalanceCertificate, HandoverTubeHoldsTheSampledTrajectories) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const LoopModel loop = loop_around(rig, law, 0.0);
  const LoopStart start = start_within(rig, 0.5 * kDeg, 2.5 * kDeg);
  SplitOptions split;
  split.handover_s = 1.0;
  const BalanceCertificate c =
      verify_balance_split(law, loop, start, limits_of(law), for_seconds(4), split);
  ASSERT_TRUE(c.certified());
  EXPECT_GT(c.handover_s, 0.0);
  ASSERT_EQ(c.steps.size(), 250u);
  for (std::size_t k = 0; k < c.steps.size(); ++k) {
    EXPECT_NEAR(c.steps[k].t1_s, 0.016 * static_cast<double>(k + 1), 1e-9);
  }
  const SampledCheck check = sampled_check(law, loop, start, c, 40, 0, 11);
  EXPECT_GT(check.check.checks, 40u * 250u * 7u);
  EXPECT_EQ(check.check.outside, 0u) << "first outside at " << check.check.first_outside_s << " s";
}

TEST(BalanceCertificate, SaysWhenTheDutyWouldReachItsLimit) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const BalanceCertificate c =
      verify_balance(law, loop_around(rig, law, 1e-4), start_within(rig, 30 * kDeg, 0.0),
                     limits_of(law), for_seconds(10));
  ASSERT_FALSE(c.certified());
  EXPECT_EQ(c.failure->kind, FailureKind::duty_limit);
  EXPECT_EQ(c.failure->t_s, 0.0);
  EXPECT_GE(c.failure->value.mag(), c.failure->limit);
  EXPECT_TRUE(c.steps.empty());
}

// A law that sends nothing lets the pendulum fall: not certified, and the proof stops where the
// pendulum's box reaches the bound or its motion can no longer be enclosed, after the steps it did
// prove.
TEST(BalanceCertificate, ALoopThatCannotHoldIsNotCertified) {
  const Rig rig = simulated_rig();
  control::BalanceControllerSpec law = designed(rig);
  law.gain.fill(0.0);
  const BalanceCertificate c =
      verify_balance(law, loop_around(rig, law, 1e-4), start_within(rig, 0.5 * kDeg, 2.5 * kDeg),
                     limits_of(law), for_seconds(10));
  ASSERT_FALSE(c.certified());
  EXPECT_TRUE(c.failure->kind == FailureKind::pendulum_limit ||
              c.failure->kind == FailureKind::law_mode ||
              c.failure->kind == FailureKind::no_enclosure);
  EXPECT_GT(c.failure->t_s, 0.1);
  EXPECT_LT(c.failure->t_s, 10.0);
  EXPECT_FALSE(c.steps.empty());
}

TEST(BalanceCertificate, RefusesWhatItCannotModel) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const LoopStart start = start_within(rig, kDeg, kDeg);
  LoopModel late = loop_around(rig, law, 1e-4);
  late.lag_s = Interval(0.0, 0.02);
  EXPECT_THROW(verify_balance(law, late, start, limits_of(law), for_seconds(1)),
               std::invalid_argument);
  LoopModel no_counts = loop_around(rig, law, 1e-4);
  no_counts.pendulum_count_rad = 0;
  EXPECT_THROW(verify_balance(law, no_counts, start, limits_of(law), for_seconds(1)),
               std::invalid_argument);
  LoopModel bad = loop_around(rig, law, 1e-4);
  bad.parameters.mu1 = Interval(-1.0, 1.0);
  EXPECT_THROW(verify_balance(law, bad, start, limits_of(law), for_seconds(1)),
               std::invalid_argument);
}

TEST(StartRegion, BisectionEndsOnACertifiedScale) {
  const Rig rig = simulated_rig();
  const control::BalanceControllerSpec law = designed(rig);
  const LoopModel loop = loop_around(rig, law, 1e-4);
  const LoopStart start = start_within(rig, 2 * kDeg, 10 * kDeg);
  const StartRegion region =
      largest_start(law, loop, start, limits_of(law), for_seconds(2), SplitOptions{1}, 1.0, 3);
  ASSERT_GT(region.scale, 0.0);
  EXPECT_LT(region.scale, 1.0);
  EXPECT_TRUE(region.certificate.certified());
  EXPECT_EQ(region.verifications, 4);
  EXPECT_NEAR(region.start.state[1].hi(), region.scale * 2 * kDeg, 1e-12);
  // One step of the bisection further out is not certified.
  const BalanceCertificate beyond = verify_balance(law, loop, {start.state, start.estimate_error},
                                                   limits_of(law), for_seconds(2));
  EXPECT_FALSE(beyond.certified());
}

}  // namespace
}  // namespace furuta::verification::balance_certificate_test
