#pragma once
// CSV recordings of the voltage-driven rig of tests/identification/voltage_rig_test.cpp (another
// rig, another logger; arm time constant about 150 ms), for the tests of `furuta identify --csv`.

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <numbers>

#include "furuta/model/model.hpp"

namespace furuta::testing {

inline model::Parameters<double> voltage_rig_truth() {
  return {3.0e-3, 2.56e-3, 1.2e-3, 1.32e-3, 7.4e-2, 1.5e-2, 6.4e-4};
}
inline constexpr double kVoltageRigTorquePerVolt = 4.0 * 0.9 * 0.03 / 3.0;  // gear eff k_t / R
inline constexpr double kVoltageRigBackEmfDamping = 4.0 * 4.0 * 0.9 * 0.03 * 0.03 / 3.0;

// What a logger writes of each row's (q1, q2, volts), given in the model's conventions: the
// identity, or a recording mistake (a sign, a zero, a unit).
struct CsvColumns {
  std::function<double(double)> q1 = [](double q) { return q; };
  std::function<double(double)> q2 = [](double q) { return q; };
  std::function<double(double)> volts = [](double v) { return v; };
};

// Encoders that quantise the angles as incremental ones do (floor of the count), or none (0).
struct CsvEncoders {
  double arm_counts_per_rev = 0;
  double pendulum_counts_per_rev = 0;
};

// An incremental encoder's reading of q: the floor of its count (none with 0 counts).
inline double quantised_angle(double q, double counts_per_rev) {
  if (counts_per_rev <= 0) return q;
  const double step = 2 * std::numbers::pi / counts_per_rev;
  return std::floor(q / step) * step;
}

// The voltage rig's excitation at t [V]: six sines from 0.23 to 2.69 Hz, 3.5 V RMS, each phase
// `phase` times its index.
inline double six_sine_volts(double t, double phase) {
  constexpr std::array<double, 6> hz = {0.23, 0.47, 0.83, 1.27, 1.91, 2.69};
  double sum = 0;
  for (std::size_t i = 0; i < hz.size(); ++i) {
    sum += std::sin(2 * std::numbers::pi * hz[i] * t + phase * static_cast<double>(i + 1));
  }
  return 3.5 * sum / std::sqrt(6.0);
}

// 10 s at 10 ms of a six-sine voltage (3.5 V), RK4 at 0.5 ms after 2 s of settling, in radians from
// hanging down, as columns t,q1,q2,volts (the rig's parameters p, the voltage rig's by default).
// The volts column may be written late by input_delay_s (a logger that stamps the input after the
// angles it drives; negative: the voltage reaches the motor that much after it is recorded, an
// amplifier's lag).
inline std::filesystem::path write_voltage_rig_csv(
    const std::filesystem::path& path, double phase, double input_delay_s = 0,
    const CsvColumns& columns = {}, int digits = 10, CsvEncoders encoders = {},
    const model::Parameters<double>& p = voltage_rig_truth()) {
  std::ofstream out(path);
  out << "t,q1,q2,volts\n" << std::setprecision(digits);
  const auto volts = [phase](double t) { return six_sine_volts(t, phase); };
  model::PendulumState x;
  const double h = 5e-4;
  for (int step = -4000; step < 20000; ++step) {
    const double t = step * h;
    if (step >= 0 && step % 20 == 0) {
      out << t << "," << columns.q1(quantised_angle(x.q1, encoders.arm_counts_per_rev)) << ","
          << columns.q2(quantised_angle(x.q2, encoders.pendulum_counts_per_rev)) << ","
          << columns.volts(volts(t - input_delay_s)) << "\n";
    }
    const double v = volts(t + h / 2);
    x = model::rk4_step(p, x, h, [&](const model::PendulumState& s) {
      return kVoltageRigTorquePerVolt * v - kVoltageRigBackEmfDamping * s.dq1;
    });
  }
  return path;
}

// The same rig in closed loop: every 10 ms a controller reads the quantised angles and sets the
// voltage, held until the next sample (a DAC); the row logs the voltage it set. `law(t, q1, q2)`
// adds feedback to the six-sine excitation (phase as above), so the input is correlated with the
// angles' noise, as on every rig that records a controller's output.
inline std::filesystem::path write_closed_loop_voltage_rig_csv(
    const std::filesystem::path& path, double phase,
    const std::function<double(double, double, double)>& law, CsvEncoders encoders = {}) {
  std::ofstream out(path);
  out << "t,q1,q2,volts\n" << std::setprecision(10);
  model::PendulumState x;
  const double h = 5e-4;
  double v = 0;
  for (int step = -4000; step < 20000; ++step) {
    const double t = step * h;
    if (step % 20 == 0) {
      const double q1 = quantised_angle(x.q1, encoders.arm_counts_per_rev);
      const double q2 = quantised_angle(x.q2, encoders.pendulum_counts_per_rev);
      v = six_sine_volts(t, phase) + law(t, q1, q2);
      if (step >= 0) out << t << "," << q1 << "," << q2 << "," << v << "\n";
    }
    x = model::rk4_step(voltage_rig_truth(), x, h, [&](const model::PendulumState& s) {
      return kVoltageRigTorquePerVolt * v - kVoltageRigBackEmfDamping * s.dq1;
    });
  }
  return path;
}

}  // namespace furuta::testing
