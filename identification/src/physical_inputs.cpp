// The physical inputs of a guaranteed identification (physical_inputs.hpp).
#include "furuta/identification/physical_inputs.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace furuta::identification {

namespace {

// The daemon's rest check holds a start until the pendulum count stays within this many counts
// (docs/model.md, "Zeros").
constexpr double kRestCheckCounts = 2.0;

Interval rpm_per_rad_s() {
  return Interval(60.0) / (Interval(2.0) * Interval::pi());
}

Interval plus_minus(double centre, double relative) {
  return Interval(centre) * Interval(1.0 - relative, 1.0 + relative);
}

}  // namespace

RecordingBounds session_log_bounds(const config::RigConfig& rig) {
  RecordingBounds b;
  const Interval two_pi = Interval(2.0) * Interval::pi();
  const Interval arm_count = two_pi / Interval(rig.arm_encoder.counts_per_joint_rev());
  const Interval pendulum_count = two_pi / Interval(rig.pendulum_encoder.counts_per_joint_rev());
  b.arm_angle_error = {"arm_angle_error", arm_count * Interval(-0.5, 0.5), "rad",
                       InputSource::encoder_counts,
                       "[encoders.arm] counts_per_rev x [motor] motor_ratio x gear_ratio: half a "
                       "count"};
  b.pendulum_angle_error = {"pendulum_angle_error", pendulum_count * Interval(-0.5, 0.5), "rad",
                            InputSource::encoder_counts,
                            "[encoders.pendulum] counts_per_rev: half a count"};
  b.pendulum_zero = {"pendulum_zero",
                     pendulum_count * Interval(-kRestCheckCounts - 0.5, kRestCheckCounts + 0.5),
                     "rad", InputSource::rest_check,
                     "[daemon] rest_check_s: the count stayed within 2 counts before the start, "
                     "plus half a count"};
  const config::GuaranteedConfig& gc = rig.guaranteed;
  b.lag = {"lag", Interval(gc.lag_ms[0], gc.lag_ms[1]) / Interval(1000.0), "s",
           InputSource::configured, "[guaranteed] lag_ms"};
  const bridge::MotorResolution step = config::motor_resolution(rig);
  b.supply_error = {
      "supply_error", Interval(-0.5, 0.5) * Interval(step.supply_step_v), "V",
      InputSource::supply_readings,
      "[boards.motor] model " + rig.motor_board.model + ": its supply reading's step, half of it"};
  b.arm_rest_speed_rad_s = gc.arm_rest_speed_rad_s;
  return b;
}

PhysicalInputs physical_inputs(const config::RigConfig& rig,
                               std::span<const double> supply_readings_v) {
  return physical_inputs(rig, supply_readings_v, session_log_bounds(rig));
}

PhysicalInputs physical_inputs(const config::RigConfig& rig,
                               std::span<const double> supply_readings_v,
                               const RecordingBounds& bounds) {
  if (!rig.nominal) {
    throw std::invalid_argument(
        "physical inputs: the configuration has no [nominal] section (the CAD values the "
        "parameters' prior is centred on)");
  }
  if (supply_readings_v.empty() && !bounds.supply) {
    throw std::invalid_argument("physical inputs: no supply readings in the recordings");
  }
  PhysicalInputs in;
  const config::GuaranteedConfig& gc = rig.guaranteed;
  const auto add = [&](std::string quantity, const Interval& value, std::string unit,
                       InputSource source, std::string setting) {
    in.provenance.push_back(
        {std::move(quantity), value, std::move(unit), source, std::move(setting)});
  };

  in.arm_angle_error_rad = bounds.arm_angle_error.value;
  in.pendulum_angle_error_rad = bounds.pendulum_angle_error.value;
  in.pendulum_zero_rad = bounds.pendulum_zero.value;
  in.lag_s = bounds.lag.value;
  for (const PhysicalInput* b :
       {&bounds.arm_angle_error, &bounds.pendulum_angle_error, &bounds.pendulum_zero}) {
    in.provenance.push_back(*b);
  }
  const double duty_step = config::motor_resolution(rig).duty_step;
  in.duty_error = Interval(-0.5 * duty_step, 0.5 * duty_step);
  add("duty_error", in.duty_error, "1", InputSource::duty_steps,
      "[boards.motor] model " + rig.motor_board.model + ": its applied duty's step, half of it");
  in.provenance.push_back(bounds.lag);

  if (supply_readings_v.empty()) {
    in.supply_v = bounds.supply->value;
    in.provenance.push_back(*bounds.supply);
  } else {
    double lowest = supply_readings_v.front(), highest = supply_readings_v.front();
    for (double v : supply_readings_v) {
      if (!(std::isfinite(v) && v > 0)) {
        throw std::invalid_argument("physical inputs: a supply reading of " + std::to_string(v) +
                                    " V is not a voltage");
      }
      lowest = std::min(lowest, v);
      highest = std::max(highest, v);
    }
    // A constant supply read with an error in supply_error lies within the readings' range, widened
    // by that error.
    in.supply_v = Interval(lowest, highest) - bounds.supply_error.value;
    add("supply", in.supply_v, "V", bounds.supply_error.source,
        "the recordings' supply readings: their range widened by " + bounds.supply_error.setting);
  }

  const model::MotorData& m = rig.motor;
  const std::array<double, 4>& tol = gc.motor_tolerance_pct;
  in.drive.ratio = m.total_ratio();
  in.drive.factor_nm_per_rpm = plus_minus(m.motor_efficiency, tol[2] / 100) *
                               plus_minus(m.gear_efficiency, tol[3] / 100) /
                               plus_minus(m.speed_torque_gradient_rpm_per_nm, tol[1] / 100);
  // PWM scales the no-load speed by the supply (docs/model.md, "Motor torque").
  in.drive.no_load_rpm =
      plus_minus(m.no_load_speed_rpm, tol[0] / 100) * in.supply_v / Interval(m.nominal_voltage_v);
  const std::string motor_keys =
      "[motor] motor_ratio, gear_ratio, motor_efficiency, gear_efficiency, "
      "speed_torque_gradient_rpm_per_nm +- [guaranteed] motor_tolerance_pct";
  add("drive_gain", in.drive.gain_nm(), "N m", InputSource::data_sheet,
      motor_keys + ", no_load_speed_rpm x supply / nominal_voltage_v");
  add("back_emf_damping", in.drive.back_emf_damping_nm_s(), "N m s", InputSource::data_sheet,
      motor_keys);

  const model::Parameters<double>& cad = *rig.nominal;
  const double relative = gc.prior_percent / 100;
  const Interval friction(gc.friction_prior[0], gc.friction_prior[1]);
  in.prior = {plus_minus(cad.mu1, relative),
              plus_minus(cad.mu2, relative),
              plus_minus(cad.mu3, relative),
              plus_minus(cad.mu4, relative),
              plus_minus(cad.mug, relative),
              friction,
              friction};
  const auto& names = model::kParameterNames;
  const auto& units = model::kParameterUnits;
  std::size_t k = 0;
  for (const Interval& v : in.prior) {
    const bool is_friction = k >= 5;
    add(std::string("prior_") + names[k], v, units[k],
        is_friction ? InputSource::configured : InputSource::cad,
        is_friction ? "[guaranteed] friction_prior"
                    : std::string("[nominal] ") + names[k] + " +- [guaranteed] prior_percent");
    ++k;
  }
  return in;
}

Interval DriveData::gain_nm() const {
  return factor_nm_per_rpm * Interval(ratio) * no_load_rpm;
}

Interval DriveData::back_emf_damping_nm_s() const {
  return factor_nm_per_rpm * Interval(ratio) * Interval(ratio) * rpm_per_rad_s();
}

namespace {

// k_w / g = N (60 / 2 pi) / omega0_s: F cancels in the back-EMF's part of b = (fv1 + k_w) / g.
Interval back_emf_per_gain(const DriveData& drive) {
  return Interval(drive.ratio) * rpm_per_rad_s() / drive.no_load_rpm;
}

}  // namespace

model::Parameters<Interval> scaled_parameters(const model::Parameters<Interval>& p,
                                              const DriveData& drive) {
  const Interval g = drive.gain_nm();
  const Interval back_emf = back_emf_per_gain(drive);
  return {p.mu1 / g, p.mu2 / g, p.mu3 / g, p.mu4 / g, p.mug / g, p.fv1 / g + back_emf, p.fv2 / g};
}

model::Parameters<Interval> rig_parameters(const model::Parameters<Interval>& theta,
                                           const DriveData& drive) {
  const Interval g = drive.gain_nm();
  const Interval n(drive.ratio);
  const Interval fv1 =
      drive.factor_nm_per_rpm * n * (theta.fv1 * drive.no_load_rpm - n * rpm_per_rad_s());
  return {theta.mu1 * g, theta.mu2 * g, theta.mu3 * g, theta.mu4 * g,
          theta.mug * g, fv1,           theta.fv2 * g};
}

model::Parameters<Interval> rig_parameters_per_gain(const model::Parameters<Interval>& theta,
                                                    const DriveData& drive) {
  model::Parameters<Interval> out = theta;
  out.fv1 = theta.fv1 - back_emf_per_gain(drive);
  return out;
}

}  // namespace furuta::identification
