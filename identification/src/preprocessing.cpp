#include "furuta/identification/preprocessing.hpp"

#include <algorithm>
#include <stdexcept>

#include "furuta/identification/filters.hpp"

namespace furuta::identification {

namespace {

// Catmull-Rom interpolation of (t, x) (t strictly increasing) at `at`; linear in the first and
// last intervals, held constant outside.
double cubic_at(const std::vector<double>& t, const std::vector<double>& x, double at) {
  const std::size_t n = t.size();
  if (n == 1 || at <= t.front()) return x.front();
  if (at >= t.back()) return x.back();
  const std::size_t j =
      static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), at) - t.begin()) - 1;
  const double h = t[j + 1] - t[j];
  const double u = (at - t[j]) / h;
  if (j == 0 || j + 2 >= n) return x[j] + u * (x[j + 1] - x[j]);
  // Tangents from the neighbours, scaled to this interval (non-uniform spacing allowed).
  const double m1 = (x[j + 1] - x[j - 1]) / (t[j + 1] - t[j - 1]) * h;
  const double m2 = (x[j + 2] - x[j]) / (t[j + 2] - t[j]) * h;
  const double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * x[j] + (u3 - 2 * u2 + u) * m1 + (-2 * u3 + 3 * u2) * x[j + 1] +
         (u3 - u2) * m2;
}

double linear_at(const std::vector<double>& t, const std::vector<double>& x, double at) {
  if (t.size() == 1 || at <= t.front()) return x.front();
  if (at >= t.back()) return x.back();
  const std::size_t j =
      static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), at) - t.begin()) - 1;
  const double u = (at - t[j]) / (t[j + 1] - t[j]);
  return x[j] + u * (x[j + 1] - x[j]);
}

// A channel's values at the host times of the reports they came from: one point per sample that
// had a fresh report (a stale sample repeats the last value and adds nothing).
struct TimedChannel {
  std::vector<double> t_s, value;
  void add(double t, double v) {
    if (!t_s.empty() && t <= t_s.back()) return;
    t_s.push_back(t);
    value.push_back(v);
  }
};

}  // namespace

RawExperiment experiment_from_log(const session_log::SessionLog& log) {
  RawExperiment e;
  e.name = log.start ? log.start->session : log.path.filename().string();
  e.input_kind = InputKind::duty;
  if (log.samples.size() < 2) {
    throw std::invalid_argument(log.path.string() + ": fewer than two samples");
  }
  const std::int64_t t0 = log.samples.front().monotonic_ns;
  const auto seconds = [t0](std::int64_t ns) { return static_cast<double>(ns - t0) * 1e-9; };
  TimedChannel arm, duty, pendulum;
  std::vector<double> motor_lag_s;
  for (const auto& s : log.samples) {
    const double cycle = seconds(s.monotonic_ns);
    if (s.n_motor_reports > 0) {
      const double at = seconds(s.motor_report_host_ns[s.n_motor_reports - 1]);
      arm.add(at, s.arm_angle_rad);
      duty.add(at, s.applied_duty);
      motor_lag_s.push_back(cycle - at);
    }
    if (s.n_encoder_reports > 0) {
      pendulum.add(seconds(s.encoder_report_host_ns[s.n_encoder_reports - 1]),
                   s.pendulum_angle_rad);
    }
  }
  e.sample_period_s = log.start && log.start->period_ns > 0
                          ? static_cast<double>(log.start->period_ns) * 1e-9
                          : seconds(log.samples[1].monotonic_ns);
  if (arm.t_s.size() < 2 || pendulum.t_s.size() < 2) {
    // Without report times (old or foreign logs): the samples as the daemon wrote them.
    for (const auto& s : log.samples) {
      e.t_s.push_back(seconds(s.monotonic_ns));
      e.q1.push_back(s.arm_angle_rad);
      e.q2.push_back(s.pendulum_angle_rad);
      e.input.push_back(s.applied_duty);
    }
  } else {
    std::nth_element(motor_lag_s.begin(), motor_lag_s.begin() + motor_lag_s.size() / 2,
                     motor_lag_s.end());
    const double lag = motor_lag_s[motor_lag_s.size() / 2];
    for (const auto& s : log.samples) {
      const double at = seconds(s.monotonic_ns) - lag;
      e.t_s.push_back(at);
      e.q1.push_back(cubic_at(arm.t_s, arm.value, at));
      e.q2.push_back(cubic_at(pendulum.t_s, pendulum.value, at));
      e.input.push_back(linear_at(duty.t_s, duty.value, at));
    }
  }
  const auto& last = log.samples.back();
  if (last.motor_lost_reports > 0 || last.encoder_lost_reports > 0) {
    e.warnings.push_back(e.name + ": lost reports in the session (motor board: " +
                         std::to_string(last.motor_lost_reports) +
                         ", encoder board: " + std::to_string(last.encoder_lost_reports) +
                         "); pendulum counts may be off after an encoder board's loss");
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
  // A session the safety supervisor (or a fault) ended: its last samples are the stop's, and the
  // excitation did not run as planned.
  if (log.end && !log.end->end_reason.empty() && log.end->end_reason != "duration_reached" &&
      log.end->end_reason != "stop_command") {
    e.warnings.push_back(e.name + ": the session ended by " + log.end->end_reason + " after " +
                         std::to_string(log.samples.size()) +
                         " samples (the motor was stopped; the fit uses them all)");
  }
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
  e.recorded = series.recorded;
  e.input_rate_limit_per_s = series.input_rate_limit_per_s;
  e.input_scale_sd = series.input_scale_sd;
  return e;
}

std::size_t edge_samples(const PreprocessOptions& options) {
  // The differentiator is applied twice (half its length each time) after the low-pass, whose
  // padded transient is short compared with that.
  return static_cast<std::size_t>(options.differentiator_taps) + 8;
}

JointSeries preprocess(const RawExperiment& e, const PreprocessOptions& options,
                       const model::MotorData& motor, const VoltageMotor& voltage_motor) {
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
  s.input = filtfilt(lowpass, e.input);
  torque_with_input_lag(s, options.input_lag_s, e.input_kind, motor, voltage_motor);
  return s;
}

void torque_with_input_lag(JointSeries& s, double lag_s, InputKind kind,
                           const model::MotorData& motor, const VoltageMotor& voltage_motor) {
  if (s.input.size() != s.size() || s.dq1.size() != s.size()) {
    throw std::invalid_argument(s.name +
                                ": torque needs the filtered input and dq1 at every sample");
  }
  // The filtered input is smooth (band-limited far below the sample rate), so a fractional delay
  // by linear interpolation is accurate.
  const double shift = lag_s / s.sample_period_s;
  const auto delayed = [&](std::size_t i) {
    const double at = static_cast<double>(i) - shift;
    if (at <= 0) return s.input.front();
    if (at >= static_cast<double>(s.input.size() - 1)) return s.input.back();
    const auto j = static_cast<std::size_t>(at);
    const double u = at - static_cast<double>(j);
    return s.input[j] + u * (s.input[j + 1] - s.input[j]);
  };
  s.tau.assign(s.size(), 0.0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double input = delayed(i);
    switch (kind) {
      case InputKind::duty:
        s.tau[i] = motor.arm_torque_nm(input, s.dq1[i]);
        break;
      case InputKind::voltage: {
        const double omega_motor = voltage_motor.gear_ratio * s.dq1[i];
        s.tau[i] = voltage_motor.gear_ratio * voltage_motor.efficiency *
                   voltage_motor.torque_constant_nm_per_a *
                   (input - voltage_motor.back_emf_v_s_per_rad * omega_motor) /
                   voltage_motor.resistance_ohm;
        break;
      }
      case InputKind::torque:
        s.tau[i] = input;
        break;
    }
  }
}

}  // namespace furuta::identification
