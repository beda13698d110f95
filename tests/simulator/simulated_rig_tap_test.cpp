// Taps on the simulated rig: an angular impulse on the pendulum's joint changes the generalized
// momentum M(q) dq by [0, J] at the tap's instant, and nothing else.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "furuta/model/dynamics.hpp"
#include "simulated_rig_bench.hpp"

namespace furuta::sim::simulated_rig_tap_test {

using namespace rig_test;  // NOLINT(google-build-using-namespace): the rig tests' own helpers

constexpr double kImpulse = 2e-3;  // N m s (2 mN m s)

// The velocity jump M(q2)^-1 [0, J], from the model's mass matrix.
model::PendulumState jumped(const model::Parameters<double>& p, model::PendulumState x, double j) {
  const model::MassMatrix<double> m = model::mass_matrix(p, x.q2);
  const double det = m.m11 * m.m22 - m.m12 * m.m12;
  x.dq1 += -m.m12 * j / det;
  x.dq2 += m.m11 * j / det;
  return x;
}

// 1/2 dq' M dq.
double kinetic(const model::Parameters<double>& p, const model::PendulumState& x) {
  const model::MassMatrix<double> m = model::mass_matrix(p, x.q2);
  return 0.5 * (m.m11 * x.dq1 * x.dq1 + 2.0 * m.m12 * x.dq1 * x.dq2 + m.m22 * x.dq2 * x.dq2);
}

bool at_rest(const model::PendulumState& x) {
  return x.q1 == 0.0 && x.dq1 == 0.0 && x.q2 == 0.0 && x.dq2 == 0.0;
}

TEST(SimulatedRigTap, ATapOnTheHangingPendulumJumpsItsVelocitiesByTheInverseMassMatrix) {
  SimulatedRigConfig config;
  // At a 1065 report's time, so that report's truth is the state just after the tap.
  config.taps = {{0.016, kImpulse}};
  Bench b(config);
  b.run_until(100 * kMs);
  const model::Parameters<double>& p = b.rig.true_parameters();

  ASSERT_EQ(b.rig.taps().size(), 1u);
  const TapRecord& tap = b.rig.taps()[0];
  EXPECT_EQ(tap.time_ns, 16 * kMs);
  EXPECT_EQ(tap.impulse_nm_s, kImpulse);
  EXPECT_TRUE(at_rest(tap.before)) << "no command: the hanging pendulum stays still until the tap";
  const model::PendulumState expected = jumped(p, tap.before, kImpulse);
  ASSERT_GT(expected.dq2, 1.0);  // about 3 rad/s: a tap a controller has to answer
  EXPECT_NEAR(tap.after.dq2, expected.dq2, 1e-12 * expected.dq2);
  EXPECT_NEAR(tap.after.dq1, expected.dq1, 1e-12 * std::abs(expected.dq1));
  EXPECT_LT(tap.after.dq1, 0.0) << "the arm recoils against the pendulum";
  EXPECT_EQ(tap.after.q1, 0.0);
  EXPECT_EQ(tap.after.q2, 0.0);

  // Hanging at rest, all the energy after is the tap's kinetic energy, 1/2 J dq2.
  const double energy = model::total_energy(p, tap.after);
  EXPECT_NEAR(energy, kinetic(p, expected), 1e-12 * energy);
  EXPECT_NEAR(energy, 0.5 * kImpulse * expected.dq2, 1e-12 * energy);

  // The truth stream: the motor board's report at the tap's instant carries the new state and the
  // impulse; the encoder board's next report (3 ms later) the impulse; the reports before and
  // after them none.
  for (const TruthRecord& t : b.truth_of(RigBoard::motor_1065)) {
    if (t.generated_ns < 16 * kMs) {
      EXPECT_TRUE(at_rest(t.state));
      EXPECT_EQ(t.tap_impulse_nm_s, 0.0);
    } else if (t.generated_ns == 16 * kMs) {
      EXPECT_EQ(t.tap_impulse_nm_s, kImpulse);
      EXPECT_NEAR(t.state.dq2, expected.dq2, 1e-12 * expected.dq2);
      EXPECT_NEAR(t.state.dq1, expected.dq1, 1e-12 * std::abs(expected.dq1));
    } else {
      EXPECT_EQ(t.tap_impulse_nm_s, 0.0);
    }
  }
  for (const TruthRecord& t : b.truth_of(RigBoard::encoder_1047)) {
    EXPECT_EQ(t.tap_impulse_nm_s, t.generated_ns == 19 * kMs ? kImpulse : 0.0) << t.generated_ns;
  }
}

TEST(SimulatedRigTap, WithoutATapTheHangingPendulumStaysAtRest) {
  Bench b;
  b.run_until(45 * kS);
  EXPECT_TRUE(b.rig.taps().empty());
  EXPECT_TRUE(at_rest(b.rig.true_state()));
  ASSERT_GT(b.rig.truth().size(), 11'000u);
  for (const TruthRecord& t : b.rig.truth()) {
    ASSERT_TRUE(at_rest(t.state)) << t.generated_ns;
    ASSERT_EQ(t.tap_impulse_nm_s, 0.0);
  }
}

TEST(SimulatedRigTap, ATapOnASwingingPendulumAddsJToItsMomentumAtItsExactTime) {
  SimulatedRigConfig config;
  // The second tap half-way between two integration steps, against the swing the first one set.
  config.taps = {{0.0, kImpulse}, {0.10005, -0.5 * kImpulse}};
  Bench b(config);
  b.run_until(200 * kMs);
  const model::Parameters<double>& p = b.rig.true_parameters();
  ASSERT_EQ(b.rig.taps().size(), 2u);
  EXPECT_EQ(b.rig.taps()[0].time_ns, 0);
  EXPECT_TRUE(at_rest(b.rig.taps()[0].before));

  const TapRecord& tap = b.rig.taps()[1];
  EXPECT_EQ(tap.time_ns, 100'050'000);
  // It meets the state of that instant: the one a rig without it has then.
  SimulatedRigConfig first_only = config;
  first_only.taps.pop_back();
  Bench untapped(first_only);
  untapped.run_until(tap.time_ns);
  EXPECT_EQ(untapped.rig.physics_time_ns(), tap.time_ns);
  const model::PendulumState then = untapped.rig.true_state();
  EXPECT_EQ(tap.before.q1, then.q1);
  EXPECT_EQ(tap.before.dq1, then.dq1);
  EXPECT_EQ(tap.before.q2, then.q2);
  EXPECT_EQ(tap.before.dq2, then.dq2);
  ASSERT_GT(std::abs(tap.before.q2), 0.05);
  ASSERT_GT(std::abs(tap.before.dq1), 0.01);
  // The angles do not move, and M(q) (dq_after - dq_before) = [0, J].
  EXPECT_EQ(tap.after.q1, tap.before.q1);
  EXPECT_EQ(tap.after.q2, tap.before.q2);
  const model::MassMatrix<double> m = model::mass_matrix(p, tap.before.q2);
  const double d1 = tap.after.dq1 - tap.before.dq1;
  const double d2 = tap.after.dq2 - tap.before.dq2;
  EXPECT_NEAR(m.m11 * d1 + m.m12 * d2, 0.0, 1e-15);
  EXPECT_NEAR(m.m12 * d1 + m.m22 * d2, -0.5 * kImpulse, 1e-15);
  const model::PendulumState expected = jumped(p, tap.before, -0.5 * kImpulse);
  EXPECT_NEAR(tap.after.dq2, expected.dq2, 1e-12);
  EXPECT_NEAR(tap.after.dq1, expected.dq1, 1e-12);
  // The potential energy stays; the kinetic energy is the new velocity's.
  EXPECT_NEAR(model::total_energy(p, tap.after) - model::total_energy(p, tap.before),
              kinetic(p, tap.after) - kinetic(p, tap.before), 1e-15);

  // The tap lands at its time whatever the host's polling: the same state on another schedule.
  Bench other(config);
  other.run_until(200 * kMs, 3 * kMs);
  ASSERT_EQ(other.rig.taps().size(), 2u);
  const model::PendulumState a = b.rig.true_state();
  const model::PendulumState c = other.rig.true_state();
  EXPECT_EQ(a.q1, c.q1);
  EXPECT_EQ(a.dq1, c.dq1);
  EXPECT_EQ(a.q2, c.q2);
  EXPECT_EQ(a.dq2, c.dq2);
}

TEST(SimulatedRigTap, ATapOnAClampedArmTurnsThePendulumAlone) {
  SimulatedRigConfig config;
  config.taps = {{0.05, kImpulse}};
  Bench b(config);
  b.rig.clamp_arm(true);
  b.run_until(60 * kMs);
  ASSERT_EQ(b.rig.taps().size(), 1u);
  const TapRecord& tap = b.rig.taps()[0];
  EXPECT_EQ(tap.after.dq1, 0.0);
  EXPECT_NEAR(tap.after.dq2, kImpulse / b.rig.true_parameters().mu4, 1e-15);
}

TEST(SimulatedRigTap, TheRecordsAreKeptWithoutAllocatingAfterConstruction) {
  SimulatedRigConfig config;
  config.record_truth = false;
  config.taps = {{0.01, kImpulse}, {0.02, -kImpulse}, {0.03, kImpulse}};
  Bench b(config);
  const TapRecord* storage = b.rig.taps().data();
  ASSERT_GE(b.rig.taps().capacity(), 3u);
  b.run_until(50 * kMs);
  EXPECT_EQ(b.rig.taps().size(), 3u);
  EXPECT_EQ(b.rig.taps().data(), storage);
}

TEST(SimulatedRigTap, BadTapsAreRefusedAtConstruction) {
  VirtualClock clock;
  const double nan = std::nan("");
  const std::vector<std::vector<Tap>> bad = {
      {{2.0, kImpulse}, {1.0, kImpulse}},
      {{1.0, kImpulse}, {1.0, kImpulse}},
      {{-1.0, kImpulse}},
      {{nan, kImpulse}},
      {{2e9, kImpulse}},
      {{1.0, nan}},
      {{1.0, std::numeric_limits<double>::infinity()}},
  };
  for (const std::vector<Tap>& taps : bad) {
    SimulatedRigConfig config;
    config.taps = taps;
    EXPECT_THROW(SimulatedRig(config, clock), std::invalid_argument);
  }
}

}  // namespace furuta::sim::simulated_rig_tap_test
