#include "furuta/model/model.hpp"

#include <cmath>
#include <numbers>

namespace furuta::model {

namespace {
constexpr double kRadPerSToRpm = 60.0 / (2.0 * std::numbers::pi);
}

Parameters<double> paper_run1() {
  return {1.04082e-3, 2.56211e-3, 8.21e-4, 1.31781e-3, 7.4175e-2, 8.13e-2, 6.42e-4};
}

double MotorData::motor_current_a(double arm_torque_nm) const {
  // Derived, not from the datasheet: an ideal DC motor reaches omega0 at the nominal voltage when
  // its back-EMF equals that voltage, so k_e = V / omega0 [V s/rad], and in SI units k_t = k_e [N
  // m/A].
  const double no_load_speed_rad_s = no_load_speed_rpm / kRadPerSToRpm;
  const double torque_constant_nm_per_a = nominal_voltage_v / no_load_speed_rad_s;
  const double motor_torque_nm =
      arm_torque_nm / (total_ratio() * motor_efficiency * gear_efficiency);
  return motor_torque_nm / torque_constant_nm_per_a;
}

JointAccelerations<double> forward_dynamics(const Parameters<double>& p, const PendulumState& x,
                                            double tau_nm, bool arm_clamped) {
  if (arm_clamped) {
    // With dq1 = 0 the centrifugal term of B's second row vanishes and ddq1 = 0 removes the
    // coupling.
    return {0.0, (-p.mug * std::sin(x.q2) - p.fv2 * x.dq2) / p.mu4};
  }
  return accelerations(p, x.q2, x.dq1, x.dq2, tau_nm);
}

double total_energy(const Parameters<double>& p, const PendulumState& x) {
  const double s = std::sin(x.q2);
  const double c = std::cos(x.q2);
  const double kinetic = 0.5 * ((p.mu1 + p.mu2 * s * s) * x.dq1 * x.dq1 +
                                2.0 * p.mu3 * c * x.dq1 * x.dq2 + p.mu4 * x.dq2 * x.dq2);
  return kinetic + p.mug * (1.0 - c);
}

double energy_rate(const Parameters<double>& p, const PendulumState& x, double tau_nm) {
  return tau_nm * x.dq1 - p.fv1 * x.dq1 * x.dq1 - p.fv2 * x.dq2 * x.dq2;
}

RegressorRows regressor(double q2, double dq1, double dq2, double ddq1, double ddq2) {
  const double s = std::sin(q2);
  const double c = std::cos(q2);
  RegressorRows r;
  r.row1 = {ddq1, s * s * ddq1 + 2 * s * c * dq1 * dq2, c * ddq2 - s * dq2 * dq2, 0, 0, dq1, 0};
  r.row2 = {0, -s * c * dq1 * dq1, c * ddq1, ddq2, s, 0, dq2};
  return r;
}

}  // namespace furuta::model
