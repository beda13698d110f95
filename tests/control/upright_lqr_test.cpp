// The balance controller's design against the model it comes from: the linearisation is the
// model's derivative at upright, the sampling the exact solution of the held, delayed duty, and
// the LQR balances the nonlinear pendulum of the simulated rig, saturated and quantised as the
// board applies duties.
#include "furuta/control/upright_lqr.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <utility>

#include "furuta/config/rig_config.hpp"

namespace furuta::control::upright_lqr_test {
namespace {

constexpr double kPi = std::numbers::pi;

// The simulated rig of the project's configuration: its true parameters, motor and supply.
DesignPlant simulated_rig() {
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  return {rig.simulation.parameters, rig.simulation.motor, rig.simulation.supply_voltage_v};
}

// d/dt [q1, q2, dq1, dq2] of the nonlinear model with the duty's torque (eq. 4).
Eigen::Vector4d derivative(const DesignPlant& plant, const Eigen::Vector4d& x, double duty) {
  const double scale = plant.supply_v / plant.motor.nominal_voltage_v;
  const double tau = plant.motor.arm_torque(duty * scale, x(2));
  const auto acc = model::accelerations(plant.parameters, x(1), x(2), x(3), tau);
  return {x(2), x(3), acc.ddq1, acc.ddq2};
}

Eigen::Vector4d rk4(const DesignPlant& plant, const Eigen::Vector4d& x, double duty, double h) {
  const Eigen::Vector4d k1 = derivative(plant, x, duty);
  const Eigen::Vector4d k2 = derivative(plant, x + 0.5 * h * k1, duty);
  const Eigen::Vector4d k3 = derivative(plant, x + 0.5 * h * k2, duty);
  const Eigen::Vector4d k4 = derivative(plant, x + h * k3, duty);
  return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
}

TEST(UprightLqr, TheLinearisationIsTheModelsDerivativeAtUpright) {
  const DesignPlant plant = simulated_rig();
  const LinearPlant lin = linearize_upright(plant);
  const Eigen::Vector4d upright(0.0, kPi, 0.0, 0.0);
  constexpr double h = 1e-6;
  for (int j = 0; j < 4; ++j) {
    Eigen::Vector4d step = Eigen::Vector4d::Zero();
    step(j) = h;
    const Eigen::Vector4d column =
        (derivative(plant, upright + step, 0.0) - derivative(plant, upright - step, 0.0)) / (2 * h);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(lin.a(i, j), column(i), 1e-5 * (1.0 + std::abs(column(i)))) << i << "," << j;
    }
  }
  const Eigen::Vector4d by_duty =
      (derivative(plant, upright, h) - derivative(plant, upright, -h)) / (2 * h);
  for (int i = 0; i < 4; ++i)
    EXPECT_NEAR(lin.b(i), by_duty(i), 1e-5 * (1.0 + std::abs(by_duty(i))));
  // Upright is unstable: a real eigenvalue on the right.
  const Eigen::VectorXcd eig = lin.a.eigenvalues();
  double largest = -1e9;
  for (Eigen::Index i = 0; i < eig.size(); ++i) largest = std::max(largest, eig(i).real());
  EXPECT_GT(largest, 1.0);
}

// The sampled plant predicts what the linear plant does under duties held and delayed as the
// board applies them, for lags within a period, of whole periods and beyond.
TEST(UprightLqr, SamplingIsTheHeldDelayedDutyExactly) {
  const LinearPlant lin = linearize_upright(simulated_rig());
  constexpr double period = 0.016;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> duty(-0.5, 0.5);
  for (const double lag : {0.0, 0.002, 0.016, 0.021, 0.035}) {
    const SampledPlant s = sample(lin, period, lag);
    EXPECT_EQ(s.delayed, static_cast<int>(std::ceil(lag / period - 1e-12))) << lag;
    std::vector<double> u(40);
    for (double& v : u) v = duty(rng);
    // The truth: the continuous plant, the duty of sample j applied from j T + lag.
    Eigen::Vector4d x(0.0, 0.01, 0.0, 0.0);
    Eigen::VectorXd z = Eigen::VectorXd::Zero(s.phi.rows());
    z.head<4>() = x;
    constexpr int kSubsteps = 1600;
    const double h = period / kSubsteps;
    for (std::size_t k = 0; k < 30; ++k) {
      for (int i = 0; i < kSubsteps; ++i) {
        const double t = static_cast<double>(k) * period + (i + 0.5) * h;
        const double since = t - lag;
        const double applied = since < 0 ? 0.0 : u[static_cast<std::size_t>(since / period)];
        const auto f = [&](const Eigen::Vector4d& y) -> Eigen::Vector4d {
          return lin.a * y + lin.b * applied;
        };
        const Eigen::Vector4d k1 = f(x), k2 = f(x + 0.5 * h * k1), k3 = f(x + 0.5 * h * k2),
                              k4 = f(x + h * k3);
        x += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      z = s.phi * z + s.gamma * u[k];
      for (int i = 0; i < 4; ++i) {
        ASSERT_NEAR(z(i), x(i), 1e-9 * (1.0 + x.norm())) << "lag " << lag << ", step " << k;
      }
    }
  }
}

// The design on the simulated rig's true parameters, run on its nonlinear model with the data
// path's lag, the duty held over each period, limited to the configuration's +-0.5 and rounded to
// the board's 1/255 steps: from 3 deg off upright the pendulum is brought up and held.
TEST(UprightLqr, TheGainBalancesTheNonlinearPendulumWithLagSaturationAndQuantisation) {
  const DesignPlant plant = simulated_rig();
  constexpr double period = 0.016, lag = 0.002;
  const SampledPlant s = sample(linearize_upright(plant), period, lag);
  const BalanceGain gain = design_lqr(s, LqrWeights{});
  EXPECT_LT(gain.spectral_radius, 1.0);
  ASSERT_EQ(gain.k.size(), 5);

  Eigen::Vector4d x(0.0, kPi + 3.0 * kPi / 180.0, 0.0, 0.0);
  double previous = 0.0, applied = 0.0;
  double worst_late = 0.0, largest_duty = 0.0;
  constexpr int kSubsteps = 64;
  for (int k = 0; k < static_cast<int>(6.0 / period); ++k) {
    Eigen::VectorXd z(5);
    z << x(0), x(1) - kPi, x(2), x(3), previous;
    double duty = std::clamp(-(gain.k * z)(0), -0.5, 0.5);
    duty = std::round(duty * 255.0) / 255.0;
    largest_duty = std::max(largest_duty, std::abs(duty));
    const double h = period / kSubsteps;
    for (int i = 0; i < kSubsteps; ++i) {
      if ((i + 0.5) * h >= lag) applied = duty;
      x = rk4(plant, x, applied, h);
    }
    previous = duty;
    if (k * period > 3.0) worst_late = std::max(worst_late, std::abs(x(1) - kPi));
  }
  EXPECT_LT(worst_late, 0.5 * kPi / 180.0) << "the pendulum does not settle upright";
  EXPECT_LT(std::abs(x(0)), 0.2) << "the arm drifts";
  EXPECT_GT(largest_duty, 0.0);
}

// The filter on the sampled plant it was designed for: its error dynamics converge at every
// reading age within a period, and from a wrong start (velocities unknown) its estimate of the
// true state, fed the exact angles at each sample and the duties sent, closes in on it: the
// velocities it gives the gain are the plant's.
TEST(UprightLqr, TheFilterRecoversTheVelocitiesFromTheAngles) {
  const DesignPlant plant = simulated_rig();
  const SampledPlant s = sample(linearize_upright(plant), 0.016, 0.002);
  ObserverWeights weights;
  weights.arm_count_rad = 2 * kPi / (1024.0 * plant.motor.total_ratio());
  weights.pendulum_count_rad = 2 * kPi / 4096.0;
  const ObserverGain filter = design_observer(s, weights);
  EXPECT_GT(filter.spectral_radius, 0.0);
  EXPECT_LT(filter.spectral_radius, 1.0);
  EXPECT_GE(filter.worst_spectral_radius, filter.spectral_radius);
  EXPECT_LT(filter.worst_spectral_radius, 1.0);

  const BalanceGain gain = design_lqr(s, LqrWeights{});
  Eigen::VectorXd z = Eigen::VectorXd::Zero(5);
  z << 0.05, 0.03, 0.4, -0.6, 0.0;                 // the truth, in z's coordinates
  Eigen::Vector4d estimate(z(0), z(1), 0.0, 0.0);  // the angles only
  double duty = 0;
  for (int k = 0; k < 60; ++k) {
    // The loop: the angles read at this sample (age 0) correct the last sample's prediction,
    // which the model then carries to this sample with the duties sent; then the gain decides.
    const double sent = duty;
    Eigen::VectorXd last(5);
    last << estimate, z(4);
    z = s.phi * z + s.gamma * sent;
    const Eigen::VectorXd predicted = s.phi * last + s.gamma * sent;
    const Eigen::Vector2d innovation(z(0) - predicted(0), z(1) - predicted(1));
    last.head<4>() += filter.m * innovation;
    estimate = (s.phi * last + s.gamma * sent).head<4>();
    Eigen::VectorXd used(5);
    used << estimate, z(4);
    duty = -(gain.k * used)(0);
  }
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(estimate(i), z(i), 1e-6) << i;
  EXPECT_THROW(design_observer(s, ObserverWeights{}), std::invalid_argument);  // no counts
  weights.reading_age_s = 0.017;  // older than a period: not a reading of this cycle
  EXPECT_THROW(design_observer(s, weights), std::invalid_argument);
}

TEST(UprightLqr, TheDriveConstantsAreEq4AtTheSupply) {
  const DesignPlant plant = simulated_rig();
  const DriveConstants drive = drive_constants(plant);
  const double scale = plant.supply_v / plant.motor.nominal_voltage_v;
  // torque = kd duty - kw dq1 wherever eq. 4 is evaluated.
  for (const auto& [duty, dq1] :
       {std::pair{0.3, 0.0}, std::pair{-0.7, 4.0}, std::pair{0.0, -9.0}}) {
    EXPECT_NEAR(drive.duty_torque_nm * duty - drive.back_emf_nm_s * dq1,
                plant.motor.arm_torque(duty * scale, dq1), 1e-12)
        << duty << " " << dq1;
  }
  EXPECT_GT(drive.duty_torque_nm, 0.0);
  EXPECT_GT(drive.back_emf_nm_s, 0.0);
  // The linearisation's input column is the duty's torque through the inverse mass matrix.
  const LinearPlant lin = linearize_upright(plant);
  const model::Parameters<double>& p = plant.parameters;
  const double det = p.mu1 * p.mu4 - p.mu3 * p.mu3;
  EXPECT_NEAR(lin.b(2), p.mu4 / det * drive.duty_torque_nm, 1e-9 * std::abs(lin.b(2)));
}

TEST(UprightLqr, TheBoardsRampIsHalfItsDurationAsADelay) {
  // d / (2 r) with r = pct / 100 duty per s.
  EXPECT_DOUBLE_EQ(ramp_lag_s(6250.0, 0.05), 0.0004);
  EXPECT_DOUBLE_EQ(ramp_lag_s(6250.0, kRampStepDuty), 0.0004);
  EXPECT_DOUBLE_EQ(ramp_lag_s(25.0, 0.05), 0.1);
  EXPECT_DOUBLE_EQ(ramp_lag_s(3125.0, 0.1), 4 * ramp_lag_s(6250.0, 0.05));
  EXPECT_EQ(ramp_lag_s(0.0, 0.05), 0.0);  // no ramp
  EXPECT_EQ(ramp_lag_s(6250.0, 0.0), 0.0);
  EXPECT_THROW(ramp_lag_s(-1.0, 0.05), std::invalid_argument);
  EXPECT_THROW(ramp_lag_s(std::nan(""), 0.05), std::invalid_argument);
  EXPECT_THROW(ramp_lag_s(6250.0, -0.05), std::invalid_argument);
  EXPECT_THROW(ramp_lag_s(6250.0, HUGE_VAL), std::invalid_argument);
  // The numerical check of "half its duration": a ramp to d at rate r against a step to d lags by
  // the area between them over d.
  const double r = 62.5, d = 0.05, h = 1e-7;
  double area = 0;
  for (double t = 0.5 * h; t < d / r; t += h) area += (d - r * t) * h;
  EXPECT_NEAR(area / d, ramp_lag_s(100 * r, d), 1e-9);
}

TEST(UprightLqr, DelayedDutiesIsWhatSamplingCarries) {
  const LinearPlant lin = linearize_upright(simulated_rig());
  for (const double lag : {0.0, 0.0004, 0.002, 0.0024, 0.016, 0.021, 0.035, 0.064}) {
    EXPECT_EQ(delayed_duties(0.016, lag), sample(lin, 0.016, lag).delayed) << lag;
  }
  EXPECT_EQ(delayed_duties(0.016, 0.0), 0);
  EXPECT_EQ(delayed_duties(0.016, 0.0024), 1);
  EXPECT_EQ(delayed_duties(0.016, 0.035), 3);
  EXPECT_THROW(delayed_duties(0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(delayed_duties(0.016, -1e-3), std::invalid_argument);
  EXPECT_THROW(delayed_duties(1e-9, 1e9), std::invalid_argument);  // no count fits an int
}

TEST(UprightLqr, BadPeriodsLagsAndWeightsAreRefused) {
  const LinearPlant lin = linearize_upright(simulated_rig());
  EXPECT_THROW(sample(lin, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(sample(lin, std::nan(""), 0.0), std::invalid_argument);
  EXPECT_THROW(sample(lin, 0.016, -0.001), std::invalid_argument);
  const SampledPlant s = sample(lin, 0.016, 0.0);
  LqrWeights w;
  w.duty = 0.0;
  EXPECT_THROW(design_lqr(s, w), std::invalid_argument);
  w = LqrWeights{};
  w.state[1] = std::nan("");
  EXPECT_THROW(design_lqr(s, w), std::invalid_argument);
}

}  // namespace
}  // namespace furuta::control::upright_lqr_test
