#pragma once
// Simulated sessions with known truth for the guaranteed identification's tests and benchmark: the
// model under a smooth duty, sampled like the rig, preprocessed, beside the true signals, and data
// error bounds that contain every true error.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/identification/preprocessing.hpp"
#include "furuta/model/model.hpp"

namespace furuta::testing {

using identification::DataErrorBounds;
using identification::InputKind;
using identification::JointSeries;
using identification::PreprocessOptions;
using identification::RawExperiment;

// A 10 s session of the model under a smooth multisine duty (the seed picks the phases), RK4 at
// 1 ms, sampled every 16 ms with the encoders' quantisation, preprocessed at 5 Hz; plus the true
// signals at the samples.
struct SimulatedSession {
  JointSeries processed;
  JointSeries truth;
};

inline PreprocessOptions preprocess_options() {
  PreprocessOptions options;
  options.cutoff_hz = 5;
  options.differentiator_passband_hz = 5;
  options.differentiator_stopband_hz = 10;
  return options;
}

inline SimulatedSession simulate(std::uint64_t seed, double seconds = 10.0) {
  const model::Parameters<double> p = model::paper_run1();
  const model::MotorData motor;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0, 2 * std::numbers::pi);
  const std::array<double, 5> freq_hz = {0.3, 0.7, 1.1, 1.7, 2.3};
  std::array<double, 5> ph{};
  for (double& x : ph) x = phase(rng);
  const auto duty = [&](double t) {
    double d = 0;
    for (int k = 0; k < 5; ++k) d += 0.03 * std::sin(2 * std::numbers::pi * freq_hz[k] * t + ph[k]);
    return d;
  };
  const double dt = 1e-3, period = 0.016;
  const double pendulum_resolution = 2 * std::numbers::pi / 4096;
  const double arm_resolution = 2 * std::numbers::pi / (512 * 26.0);
  RawExperiment raw;
  raw.name = "seed" + std::to_string(seed);
  raw.sample_period_s = period;
  raw.input_kind = InputKind::duty;
  SimulatedSession out;
  out.truth.name = raw.name;
  out.truth.sample_period_s = period;
  model::PendulumState x{0, 0, 0.05, 0};
  double t = 0;
  const int steps_per_sample = static_cast<int>(std::lround(period / dt));
  for (int k = 0; t < seconds; ++k) {
    const double d = duty(t);
    const double tau = motor.arm_torque_nm(d, x.dq1);
    const model::JointAccelerations<double> a = model::forward_dynamics(p, x, tau);
    raw.t_s.push_back(t);
    raw.q1.push_back(std::round(x.q1 / arm_resolution) * arm_resolution);
    raw.q2.push_back(std::round(x.q2 / pendulum_resolution) * pendulum_resolution);
    raw.input.push_back(d);
    out.truth.t_s.push_back(t);
    out.truth.q2.push_back(x.q2);
    out.truth.dq1.push_back(x.dq1);
    out.truth.dq2.push_back(x.dq2);
    out.truth.ddq1.push_back(a.ddq1);
    out.truth.ddq2.push_back(a.ddq2);
    out.truth.tau.push_back(tau);
    for (int s = 0; s < steps_per_sample; ++s) {
      const double ts = t + s * dt;
      x = model::rk4_step(p, x, dt, [&](const model::PendulumState& st) {
        return motor.arm_torque_nm(duty(ts), st.dq1);
      });
    }
    t = (k + 1) * period;
  }
  out.processed = preprocess(raw, preprocess_options(), motor);
  return out;
}

inline std::size_t trim() {
  return edge_samples(preprocess_options());
}

// Bounds that hold by construction: the largest true error per channel over the sessions, with a
// margin.
inline DataErrorBounds bounds_covering(const std::vector<SimulatedSession>& sessions,
                                       double margin = 1.5) {
  DataErrorBounds b;
  const auto worst = [&](auto member) {
    double m = 0;
    for (const SimulatedSession& s : sessions) {
      const std::vector<double>& measured = s.processed.*member;
      const std::vector<double>& truth = s.truth.*member;
      for (std::size_t i = trim(); i + trim() < measured.size(); ++i) {
        m = std::max(m, std::abs(measured[i] - truth[i]));
      }
    }
    return margin * m + 1e-12;
  };
  b.q2.absolute = worst(&JointSeries::q2);
  b.dq1.absolute = worst(&JointSeries::dq1);
  b.dq2.absolute = worst(&JointSeries::dq2);
  b.ddq1.absolute = worst(&JointSeries::ddq1);
  b.ddq2.absolute = worst(&JointSeries::ddq2);
  b.tau.absolute = worst(&JointSeries::tau);
  return b;
}

}  // namespace furuta::testing
