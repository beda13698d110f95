#include "furuta/model/model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::model {
namespace {

constexpr double kPi = std::numbers::pi;

// The simulated rig's integration step (SimulatedRigConfig::integration_step_s).
double default_step_s() {
  return 1e-4;
}

model::Parameters<double> frictionless() {
  model::Parameters<double> p = model::paper_run1();
  p.fv1 = 0.0;
  p.fv2 = 0.0;
  return p;
}

TEST(RigModel, PaperRun1IsTableIAcquisition1) {
  const model::Parameters<double> p = model::paper_run1();
  EXPECT_DOUBLE_EQ(p.mu1, 1.04082e-3);
  EXPECT_DOUBLE_EQ(p.mu2, 2.56211e-3);
  EXPECT_DOUBLE_EQ(p.mu3, 8.21e-4);
  EXPECT_DOUBLE_EQ(p.mu4, 1.31781e-3);
  EXPECT_DOUBLE_EQ(p.mug, 7.4175e-2);
  EXPECT_DOUBLE_EQ(p.fv1, 8.13e-2);
  EXPECT_DOUBLE_EQ(p.fv2, 6.42e-4);
}

// The identification regresses y = D(q, dq, ddq) p with y = [tau, 0] (docs/model.md); the
// simulator's accelerations must satisfy exactly those rows, or identification would chase a
// different model.
TEST(RigModel, ForwardDynamicsSatisfiesTheRegressorRows) {
  const model::Parameters<double> p = model::paper_run1();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> speed(-8.0, 8.0);
  std::uniform_real_distribution<double> torque(-0.5, 0.5);
  for (int i = 0; i < 200; ++i) {
    const model::PendulumState x{angle(rng), speed(rng), angle(rng), speed(rng)};
    const double tau = torque(rng);
    const model::JointAccelerations<double> a = model::forward_dynamics(p, x, tau);
    const double s = std::sin(x.q2);
    const double c = std::cos(x.q2);
    const double row1 = p.mu1 * a.ddq1 + p.mu2 * (s * s * a.ddq1 + 2 * s * c * x.dq1 * x.dq2) +
                        p.mu3 * (c * a.ddq2 - s * x.dq2 * x.dq2) + p.fv1 * x.dq1;
    const double row2 = p.mu2 * (-s * c * x.dq1 * x.dq1) + p.mu3 * c * a.ddq1 + p.mu4 * a.ddq2 +
                        p.mug * s + p.fv2 * x.dq2;
    EXPECT_NEAR(row1, tau, 1e-12);
    EXPECT_NEAR(row2, 0.0, 1e-12);
  }
}

// In intervals (the validated integrator's a priori enclosure) the accelerations over a wide range
// of the pendulum's angle stay bounded and hold every point's: det M must not be enclosed by an
// interval around 0 (s * s over sin q2's range spanning 0 would reach below 0).
TEST(RigModel, IntervalAccelerationsOverAWideAngleRangeAreBoundedAndHoldEveryPoint) {
  using interval::Interval;
  const model::Parameters<double> p = model::paper_run1();
  const model::Parameters<Interval> box =
      p.map([](double v) { return Interval(0.99 * v, 1.01 * v); });
  const Interval q2(-1.54, 0.98);
  const Interval dq1(7.5, 10.4);
  const Interval dq2(-8.5, -5.5);
  const Interval tau(0.3);
  const model::JointAccelerations<Interval> a = model::accelerations(box, q2, dq1, dq2, tau);
  ASSERT_TRUE(a.ddq1.is_bounded() && a.ddq2.is_bounded());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto pick = [&](const Interval& x) { return x.lo() + unit(rng) * x.width(); };
  for (int i = 0; i < 500; ++i) {
    const model::Parameters<double> point = box.map(pick);
    const model::JointAccelerations<double> at =
        model::accelerations(point, pick(q2), pick(dq1), pick(dq2), 0.3);
    EXPECT_TRUE(a.ddq1.contains(at.ddq1) && a.ddq2.contains(at.ddq2)) << "sample " << i;
  }
}

TEST(RigModel, ClampedArmSwingsThePendulumAlone) {
  const model::Parameters<double> p = model::paper_run1();
  const model::PendulumState x{0.3, 0.0, 0.7, -1.2};
  const model::JointAccelerations<double> a = model::forward_dynamics(p, x, 0.4, true);
  EXPECT_EQ(a.ddq1, 0.0);
  EXPECT_NEAR(p.mu4 * a.ddq2, -p.mug * std::sin(0.7) - p.fv2 * -1.2, 1e-15);
}

TEST(RigModel, EnergyRateIsTheDerivativeOfTotalEnergy) {
  const model::Parameters<double> p = model::paper_run1();
  const model::PendulumState x{0.2, 1.5, 1.1, -2.0};
  const double tau = 0.12;
  auto constant_torque = [tau](const model::PendulumState&) { return tau; };
  const double h = 1e-5;
  const model::PendulumState ahead = model::rk4_step(p, x, h, constant_torque);
  const model::PendulumState behind = model::rk4_step(p, x, -h, constant_torque);
  const double numeric = (model::total_energy(p, ahead) - model::total_energy(p, behind)) / (2 * h);
  EXPECT_NEAR(numeric, model::energy_rate(p, x, tau), 1e-8);
}

// Acceptance check 1.
TEST(RigModel, EnergyIsConservedWithoutFrictionOrTorque) {
  const model::Parameters<double> p = frictionless();
  model::PendulumState x{0.0, 3.0, 2.0, 0.0};
  const double e0 = model::total_energy(p, x);
  const double dt = default_step_s();
  auto no_torque = [](const model::PendulumState&) { return 0.0; };
  double worst = 0.0;
  const int steps = static_cast<int>(std::lround(10.0 / dt));
  for (int i = 0; i < steps; ++i) {
    x = model::rk4_step(p, x, dt, no_torque);
    worst = std::max(worst, std::abs(model::total_energy(p, x) - e0) / e0);
  }
  std::cout << "[ measured ] relative energy drift over 10 s: " << worst << "\n";
  EXPECT_LT(worst, 1e-6);
  // The swing really was large: the arm and the pendulum exchanged energy all along.
  EXPECT_GT(std::abs(x.dq2), 0.0);
}

// Acceptance check 2 (the rig-level variant of the clamped arm is in
// tests/simulator/simulated_rig_test.cpp).
TEST(RigModel, ClampedSmallOscillationHasThePendulumPeriod) {
  model::Parameters<double> p = model::paper_run1();
  p.fv2 = 0.0;  // undamped, so the period is exactly the natural one
  const double dt = default_step_s();
  model::PendulumState x{0.0, 0.0, 0.01, 0.0};
  auto no_torque = [](const model::PendulumState&) { return 0.0; };
  std::vector<double> upward_crossings;
  double t = 0.0;
  for (int i = 0; i < static_cast<int>(20.0 / dt); ++i) {
    const model::PendulumState next = model::rk4_step(p, x, dt, no_torque, true);
    if (x.q2 < 0.0 && next.q2 >= 0.0) {
      upward_crossings.push_back(t + dt * (-x.q2) / (next.q2 - x.q2));
    }
    x = next;
    t += dt;
  }
  ASSERT_GE(upward_crossings.size(), 10u);
  const double period = (upward_crossings.back() - upward_crossings.front()) /
                        static_cast<double>(upward_crossings.size() - 1);
  const double expected = 2 * kPi * std::sqrt(p.mu4 / p.mug);
  const double error = std::abs(period - expected) / expected;
  std::cout << "[ measured ] clamped period " << period << " s vs " << expected
            << " s, relative error " << error << "\n";
  EXPECT_LT(error, 1e-3);
}

TEST(RigModel, MotorTorqueFollowsEquation4) {
  const model::MotorData m;
  const double k =
      m.total_ratio() * m.motor_efficiency * m.gear_efficiency / m.speed_torque_gradient_rpm_per_nm;
  // Stall torque: the whole no-load speed is available.
  EXPECT_NEAR(m.arm_torque_nm(1.0, 0.0), k * m.no_load_speed_rpm, 1e-12);
  EXPECT_NEAR(m.arm_torque_nm(-0.5, 0.0), -0.5 * k * m.no_load_speed_rpm, 1e-12);
  // At the no-load speed (motor shaft at d * omega0) the torque vanishes.
  const double no_load_arm_rad_s = 0.4 * m.no_load_speed_rpm * 2 * kPi / 60.0 / m.total_ratio();
  EXPECT_NEAR(m.arm_torque_nm(0.4, no_load_arm_rad_s), 0.0, 1e-12);
  // Zero duty is a brake proportional to speed.
  EXPECT_LT(m.arm_torque_nm(0.0, 2.0), 0.0);
  EXPECT_NEAR(m.arm_torque_nm(0.0, 2.0), -k * m.total_ratio() * 2.0 * 60.0 / (2 * kPi), 1e-12);
}

TEST(RigModel, MotorCurrentUsesTheTorqueConstantFromNoLoadSpeed) {
  const model::MotorData m;
  const double kt = m.nominal_voltage_v / (m.no_load_speed_rpm * 2 * kPi / 60.0);
  const double arm_torque = 0.25;
  const double current = m.motor_current_a(arm_torque);
  EXPECT_NEAR(current * kt * m.total_ratio() * m.motor_efficiency * m.gear_efficiency, arm_torque,
              1e-12);
  EXPECT_NEAR(m.motor_current_a(-arm_torque), -current, 1e-15);
}

}  // namespace
}  // namespace furuta::model
