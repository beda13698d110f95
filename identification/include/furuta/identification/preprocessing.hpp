#pragma once
// From a recording to the joint series the LSMI needs (paper section III.A): zero-phase low-pass of
// the angles, velocities and accelerations by the FIR differentiator, torque by eq. 4 (duty) or the
// DC-motor equation (voltage), filtered like the rest.

#include <string>
#include <vector>

#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/lsmi.hpp"
#include "furuta/model/model.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::identification {

// One experiment as recorded: uniform samples of the angles and the input.
struct RawExperiment {
  std::string name;
  double sample_period_s = 0;
  std::vector<double> t_s, q1, q2, input;
  InputKind input_kind = InputKind::duty;
  std::vector<std::string> warnings;
  // A CSV's readings as recorded, each at its own time, and its input's slew limit
  // (ImportedSeries); empty for a session log, whose OeExperiment is read from its reports.
  RecordedSeries recorded;
  double input_rate_limit_per_s = 0;
  double input_scale_sd = 0;  // the import spec's: the input gain's prior in the refinement
};

// The samples of a session log: q1, q2 as the daemon computed them, the duty the board applied
// (its echo, not the command). Warns about lost reports and overruns in the session.
// The two boards report at their own times (up to a report period apart): each channel is placed
// at the host receive time of the report it came from and resampled (cubic) onto one uniform grid,
// the motor board's times shifted by their median lag behind the cycle. The duty (a step signal)
// is resampled linearly.
RawExperiment experiment_from_log(const session_log::SessionLog& log);
RawExperiment experiment_from_csv(const ImportedSeries& series, const std::string& name);

struct PreprocessOptions {
  int butterworth_order = 8;
  double cutoff_hz = 5.0;
  int differentiator_taps = 31;  // odd
  double differentiator_passband_hz = 5.0;
  double differentiator_stopband_hz = 10.0;
  // The torque at t is formed from the input at t - input_lag_s (see torque_with_input_lag).
  double input_lag_s = 0.0;
};

// Filters and differentiates; `motor` gives eq. 4 for duty input, `voltage_motor` the DC-motor
// form.
JointSeries preprocess(const RawExperiment& experiment, const PreprocessOptions& options,
                       const model::MotorData& motor, const VoltageMotor& voltage_motor = {});

// Forms series.tau from series.input (the filtered input) delayed by lag_s, and series.dq1.
// The arm's time constant (mu1 over the back-EMF and viscous damping, about 4.4 ms on the paper's
// rig) is far below the 16 ms sample period, so the torque is a small difference of two large
// terms and mu1 moves by (fv1 + back-EMF damping) / mu1, the reciprocal of that time constant, per
// second of misalignment between input and angles: an unmodelled lag of a millisecond is a large
// bias (docs/measurements/identification.md, "LSMI against the simulated truth").
void torque_with_input_lag(JointSeries& series, double lag_s, InputKind kind,
                           const model::MotorData& motor, const VoltageMotor& voltage_motor);

// How many samples at each end the filters disturb (to trim before fitting).
std::size_t edge_samples(const PreprocessOptions& options);

}  // namespace furuta::identification
