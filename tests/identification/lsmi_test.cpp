// LSMI on data straight from the model (no filters): it must recover the parameters exactly, and
// say when the data cannot identify them.
#include "furuta/identification/lsmi.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace furuta::identification {
namespace {

// Simulates the model under a rich torque and records exact states and accelerations.
JointSeries exact_experiment(const model::Parameters<double>& p, double seconds, bool arm_clamped,
                             double torque_scale = 0.2) {
  JointSeries s;
  s.name = "exact";
  s.sample_period_s = 0.016;
  model::PendulumState x{0, 0, 0.3, 0};
  const double h = 1e-4;
  auto torque = [&](double t) {
    return torque_scale * (std::sin(2 * M_PI * 0.7 * t) + 0.5 * std::sin(2 * M_PI * 2.3 * t + 1) +
                           0.3 * std::sin(2 * M_PI * 4.1 * t + 2));
  };
  double t = 0;
  const int steps_per_sample = static_cast<int>(std::lround(s.sample_period_s / h));
  while (t < seconds) {
    const double tau = arm_clamped ? 0.0 : torque(t);
    const model::JointAccelerations<double> a = model::forward_dynamics(p, x, tau, arm_clamped);
    s.t_s.push_back(t);
    s.q1.push_back(x.q1);
    s.q2.push_back(x.q2);
    s.dq1.push_back(x.dq1);
    s.dq2.push_back(x.dq2);
    s.ddq1.push_back(a.ddq1);
    s.ddq2.push_back(a.ddq2);
    s.tau.push_back(tau);
    for (int k = 0; k < steps_per_sample; ++k) {
      const double tk = t + k * h;
      x = model::rk4_step(
          p, x, h, [&](const model::PendulumState&) { return torque(tk); }, arm_clamped);
    }
    t += s.sample_period_s;
  }
  return s;
}

TEST(Lsmi, RegressorRowsReproduceTheModelsTorqueAndZero) {
  const model::Parameters<double> p = model::paper_run1();
  const model::PendulumState x{0.4, 1.3, -0.7, 2.1};
  const double tau = 0.05;
  const model::JointAccelerations<double> a = model::forward_dynamics(p, x, tau);
  const model::RegressorRows d = model::regressor(x.q2, x.dq1, x.dq2, a.ddq1, a.ddq2);
  const model::Parameters<double> v = p;
  double y1 = 0, y2 = 0;
  for (std::size_t j = 0; j < v.size(); ++j) {
    y1 += d.row1[j] * v[j];
    y2 += d.row2[j] * v[j];
  }
  EXPECT_NEAR(y1, tau, 1e-12);
  EXPECT_NEAR(y2, 0.0, 1e-12);
}

TEST(Lsmi, RecoversTheParametersExactlyFromExactData) {
  const model::Parameters<double> truth = model::paper_run1();
  const JointSeries e = exact_experiment(truth, 20.0, false);
  const LsmiResult r = solve_lsmi({&e});
  const model::Parameters<double> v = truth;
  for (std::size_t j = 0; j < model::kParameterCount; ++j) {
    const auto k = static_cast<std::size_t>(j);
    EXPECT_NEAR(r.estimate[k], v[k], 1e-9 * std::abs(v[k]) + 1e-15) << model::kParameterNames[k];
  }
  EXPECT_EQ(r.rank, model::kParameterCount);
  EXPECT_LT(r.sigma, 1e-10);
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_EQ(r.rows, 2 * e.size());
  EXPECT_LT(torque_fit(e, r.estimate).rmse_nm, 1e-10);
}

TEST(Lsmi, StandardDeviationsScaleWithTheNoiseAndCoverTheTruth) {
  const model::Parameters<double> truth = model::paper_run1();
  JointSeries e = exact_experiment(truth, 30.0, false);
  // Bounded pseudo-noise on the torque: the estimate moves, the standard deviation says by how
  // much.
  for (std::size_t i = 0; i < e.size(); ++i) e.tau[i] += 2e-3 * std::sin(12345.678 * i);
  const LsmiResult r = solve_lsmi({&e});
  const model::Parameters<double> v = truth;
  EXPECT_GT(r.sigma, 5e-4);
  for (std::size_t k = 0; k < v.size(); ++k) {
    EXPECT_GT(r.std_dev[k], 0.0) << model::kParameterNames[k];
    EXPECT_LT(std::abs(r.estimate[k] - v[k]), 5 * r.std_dev[k] + 1e-12)
        << model::kParameterNames[k];
  }
}

TEST(Lsmi, AnArmHeldStillCannotIdentifyTheArmParametersAndSaysSo) {
  // With the arm clamped, the columns of mu1 and fv1 (and the torque) are zero: rank deficient.
  const JointSeries e = exact_experiment(model::paper_run1(), 10.0, true);
  const LsmiResult r = solve_lsmi({&e});
  EXPECT_LT(r.rank, model::kParameterCount);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.front().find("rank"), std::string::npos) << r.warnings.front();
}

TEST(Lsmi, TooFewSamplesIsAnError) {
  JointSeries e;
  e.t_s = {0, 1, 2};
  e.q1 = e.q2 = e.dq1 = e.dq2 = e.ddq1 = e.ddq2 = e.tau = {0, 0, 0};
  EXPECT_THROW(solve_lsmi({&e}), std::invalid_argument);
}

TEST(Lsmi, TorqueFitReportsRmseAndPercentOfRange) {
  JointSeries e;
  e.t_s = {0, 1, 2, 3};
  e.q1 = e.q2 = e.dq2 = e.ddq1 = e.ddq2 = {0, 0, 0, 0};
  e.dq1 = {1, 2, 3, 4};
  e.tau = {0.1, 0.2, 0.3, 0.5};  // fv1 = 0.1 predicts 0.1, 0.2, 0.3, 0.4
  model::Parameters<double> p{};
  p[5] = 0.1;
  const TorqueFit fit = torque_fit(e, p);
  EXPECT_NEAR(fit.rmse_nm, 0.05, 1e-12);               // sqrt(0.1^2 / 4)
  EXPECT_NEAR(fit.rmse_percent_of_range, 12.5, 1e-9);  // 0.05 / 0.4
}

}  // namespace
}  // namespace furuta::identification
