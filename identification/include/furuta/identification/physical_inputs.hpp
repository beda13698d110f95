#pragma once
// The physical inputs of a guaranteed identification: what the encoders, the board, the
// clocks, the motor's data sheet and the rig's CAD bound, as intervals, each with where it came
// from. Every other bound a guaranteed method uses is derived from these and the model
// (docs/guaranteed-bounds.md).
//
// The model is linear in its seven parameters and in the drive: dividing eq. 1-4 by the drive gain
// g (tau = g d - k_w dq1) leaves the applied duty as the input and the scaled parameters
// theta = [mu1, mu2, mu3, mu4, mug] / g, b = (fv1 + k_w) / g, fv2 / g, which the angles determine.
// The rig's parameters follow from theta with g's and k_w's intervals: so no guaranteed set is
// narrower than the drive's own tolerance.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/model/model.hpp"

namespace furuta::identification {

using interval::Interval;

// Where a physical input came from.
enum class InputSource {
  encoder_counts,   // half a count of the encoder's resolution
  rest_check,       // the daemon's rest check before a session starts
  duty_steps,       // the motor board applies (and echoes) duties in its adapter's steps of 1/255
  supply_readings,  // the motor board's supply readings of the session, and their step
  data_sheet,       // [motor]'s figures with [guaranteed] motor_tolerance_pct
  configured,       // a [guaranteed] setting (a bound no recording gives)
  cad,              // [nominal] (CAD values) with [guaranteed] prior_percent
  import_spec,      // a CSV import spec's [guaranteed] table: what another logger states
};

// One input and its provenance, for the report and results.json.
struct PhysicalInput {
  std::string quantity;  // an identifier: "arm_angle", "drive_gain", "prior_mu1", ...
  Interval value;        // the enclosure (or, for an error, the interval the error lies in)
  std::string unit;      // "rad", "N m", ...
  InputSource source = InputSource::configured;
  std::string setting;  // the configuration key(s) or datum it was computed from
};

// Eq. 4 as intervals: tau = F N (omega0_s d - N omega), F = eta_m eta_g / Rv [N m per rpm], N the
// total ratio, omega0_s the no-load speed at the session's supply, omega the arm's speed in rpm.
// F is common to the drive gain g = F N omega0_s and the back-EMF damping k_w = F N^2 (60 / 2 pi),
// which keeps fv1 = b g - k_w = F N (b omega0_s - N 60 / 2 pi) from counting F's tolerance twice.
struct DriveData {
  Interval factor_nm_per_rpm;              // F
  Interval no_load_rpm;                    // omega0_s
  double ratio = 1;                        // N
  Interval gain_nm() const;                // g
  Interval back_emf_damping_nm_s() const;  // k_w
};

// What the recording's own logger bounds: for a session log the daemon (encoder counts, its rest
// check, the motor board's supply readings) and [guaranteed] lag_ms; for a CSV its import spec's
// [guaranteed] table. Each value is the interval its error lies in.
struct RecordingBounds {
  PhysicalInput arm_angle_error;       // rad: true angle minus reading
  PhysicalInput pendulum_angle_error;  // rad: the same, without the zero
  PhysicalInput pendulum_zero;         // rad: the pendulum's true angle where it read 0, at rest
  PhysicalInput lag;                   // s: a reading's time minus its state's, against the input's
  PhysicalInput supply_error;          // V: a supply reading minus the supply
  // The supply itself, for a recording without supply readings; unused when there are readings.
  std::optional<PhysicalInput> supply;
  double arm_rest_speed_rad_s = 0;  // |dq1| at the first command, the rig at rest before it
};

// A session log's bounds: the configuration's encoders (half a count), the daemon's rest check,
// [guaranteed] lag_ms and arm_rest_speed_rad_s, the motor board's supply step (its adapter's).
RecordingBounds session_log_bounds(const config::RigConfig& rig);

struct PhysicalInputs {
  Interval arm_angle_error_rad;       // true angle minus reading, after the joint's zero
  Interval pendulum_angle_error_rad;  // the same, without the zero
  Interval pendulum_zero_rad;         // the pendulum's true angle when its count was zeroed
  Interval duty_error;                // applied duty minus its echo
  Interval lag_s;                     // the data path (see config::GuaranteedConfig)
  Interval supply_v;                  // the supply during the session
  DriveData drive;
  model::Parameters<Interval> prior;  // the rig's parameters before any data
  std::vector<PhysicalInput> provenance;
};

// From the configuration and the session's supply readings (volts, each reading of the motor
// board; at least one). Throws std::invalid_argument without [nominal] (the prior's centre) or
// readings, or with a reading that is not a finite positive voltage.
PhysicalInputs physical_inputs(const config::RigConfig& rig,
                               std::span<const double> supply_readings_v);
// The same with the recording's bounds stated (a CSV's import spec): the drive and the prior from
// `rig`, the rest from `bounds`. Without supply readings the supply is bounds.supply; without
// either it throws std::invalid_argument.
PhysicalInputs physical_inputs(const config::RigConfig& rig,
                               std::span<const double> supply_readings_v,
                               const RecordingBounds& bounds);

// The scaled parameters' names, in model::kParameterNames' order: mu_k / g, b = (fv1 + k_w) / g,
// fv2 / g.
inline constexpr const char* kScaledParameterNames[model::kParameterCount] = {
    "mu1/g", "mu2/g", "mu3/g", "mu4/g", "mug/g", "b", "fv2/g"};

// The scaled parameters of p (see above) for the drive: every rig parameter in `p` maps into the
// result, for every drive in `drive`.
model::Parameters<Interval> scaled_parameters(const model::Parameters<Interval>& p,
                                              const DriveData& drive);
// The rig parameters of scaled parameters theta: the inverse map, over every drive in `drive`.
model::Parameters<Interval> rig_parameters(const model::Parameters<Interval>& theta,
                                           const DriveData& drive);
// The rig's parameters per unit of its gain, p / g, of scaled parameters theta for every drive in
// `drive`: theta with b's back-EMF part taken out of fv1 (fv1 / g = b - N (60 / 2 pi) /
// omega0_s). The model moves the same with p under a torque u as with p / g under u / g, so a
// scaled set simulates the rig's motions under a torque without the gain's tolerance on the
// parameters (validated::ParameterSet::torque_scale).
model::Parameters<Interval> rig_parameters_per_gain(const model::Parameters<Interval>& theta,
                                                    const DriveData& drive);

}  // namespace furuta::identification
