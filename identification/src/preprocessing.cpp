#include "furuta/identification/preprocessing.hpp"

#include <stdexcept>

#include "furuta/identification/filters.hpp"

namespace furuta::identification {

RawExperiment experiment_from_log(const session_log::SessionLog& log) {
  RawExperiment e;
  e.name = log.start ? log.start->session : log.path.filename().string();
  e.input_kind = InputKind::duty;
  if (log.samples.size() < 2) {
    throw std::invalid_argument(log.path.string() + ": fewer than two samples");
  }
  const std::int64_t t0 = log.samples.front().monotonic_ns;
  for (const auto& s : log.samples) {
    e.t_s.push_back(static_cast<double>(s.monotonic_ns - t0) * 1e-9);
    e.q1.push_back(s.arm_angle_rad);
    e.q2.push_back(s.pendulum_angle_rad);
    e.input.push_back(s.applied_duty);
  }
  e.sample_period_s = log.start && log.start->period_ns > 0
                          ? static_cast<double>(log.start->period_ns) * 1e-9
                          : e.t_s[1] - e.t_s[0];
  const auto& last = log.samples.back();
  if (last.motor_lost_reports > 0 || last.encoder_lost_reports > 0) {
    e.warnings.push_back(
        e.name + ": lost reports in the session (1065: " + std::to_string(last.motor_lost_reports) +
        ", 1047: " + std::to_string(last.encoder_lost_reports) +
        "); pendulum counts may be off after a 1047 loss");
  }
  if (last.overruns > 0) {
    e.warnings.push_back(e.name + ": " + std::to_string(last.overruns) +
                         " missed cycles: samples are not uniform there");
  }
  if (!log.missing_sequence_numbers().empty()) {
    e.warnings.push_back(e.name + ": " + std::to_string(log.missing_sequence_numbers().size()) +
                         " samples missing from the log");
  }
  if (!log.complete()) e.warnings.push_back(e.name + ": the session was cut short");
  return e;
}

RawExperiment experiment_from_csv(const ImportedSeries& series, const std::string& name) {
  RawExperiment e;
  e.name = name;
  e.sample_period_s = series.sample_period_s;
  e.t_s = series.t_s;
  e.q1 = series.q1_rad;
  e.q2 = series.q2_rad;
  e.input = series.input;
  e.input_kind = series.input_kind;
  e.warnings = series.warnings;
  return e;
}

std::size_t edge_samples(const PreprocessOptions& options) {
  // The differentiator is applied twice (half its length each time) after the low-pass, whose
  // padded transient is short compared with that.
  return static_cast<std::size_t>(options.differentiator_taps) + 8;
}

JointSeries preprocess(const RawExperiment& e, const PreprocessOptions& options,
                       const bridge::MotorData& motor, const VoltageMotor& voltage_motor) {
  if (e.sample_period_s <= 0) throw std::invalid_argument(e.name + ": no sample period");
  const double fs = 1.0 / e.sample_period_s;
  const IirFilter lowpass =
      design_butterworth_lowpass(options.butterworth_order, options.cutoff_hz, fs);
  const FirDifferentiator diff =
      design_fir_differentiator(options.differentiator_taps, options.differentiator_passband_hz,
                                options.differentiator_stopband_hz, fs);
  JointSeries s;
  s.name = e.name;
  s.sample_period_s = e.sample_period_s;
  s.t_s = e.t_s;
  s.q1 = filtfilt(lowpass, e.q1);
  s.q2 = filtfilt(lowpass, e.q2);
  s.dq1 = differentiate(diff, s.q1);
  s.dq2 = differentiate(diff, s.q2);
  s.ddq1 = differentiate(diff, s.dq1);
  s.ddq2 = differentiate(diff, s.dq2);

  if (e.input_kind == InputKind::voltage && !(voltage_motor.resistance_ohm > 0)) {
    throw std::invalid_argument(e.name + ": voltage input needs the motor's resistance (> 0)");
  }
  // The input goes through the same low-pass as the angles, and the torque is formed from the
  // filtered input and the filtered velocity. Eq. 4 and the DC-motor form are linear, so this
  // equals the low-passed torque; forming it from the raw input and filtering afterwards would
  // low-pass the velocity twice and bias every inertia.
  const std::vector<double> input = filtfilt(lowpass, e.input);
  std::vector<double> tau(input.size());
  for (std::size_t i = 0; i < tau.size(); ++i) {
    switch (e.input_kind) {
      case InputKind::duty:
        tau[i] = motor.arm_torque_nm(input[i], s.dq1[i]);
        break;
      case InputKind::voltage: {
        const double omega_motor = voltage_motor.gear_ratio * s.dq1[i];
        tau[i] = voltage_motor.gear_ratio * voltage_motor.efficiency *
                 voltage_motor.torque_constant_nm_per_a *
                 (input[i] - voltage_motor.back_emf_v_s_per_rad * omega_motor) /
                 voltage_motor.resistance_ohm;
        break;
      }
      case InputKind::torque:
        tau[i] = input[i];
        break;
    }
  }
  s.tau = std::move(tau);
  return s;
}

}  // namespace furuta::identification
