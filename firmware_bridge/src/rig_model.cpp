#include "furuta/firmware_bridge/rig_model.hpp"

#include <cmath>
#include <numbers>

namespace furuta::bridge {

namespace {
constexpr double kRadPerSToRpm = 60.0 / (2.0 * std::numbers::pi);
}

ModelParameters ModelParameters::paper_run1() {
  ModelParameters p;
  p.mu1 = 1.04082e-3;
  p.mu2 = 2.56211e-3;
  p.mu3 = 8.21e-4;
  p.mu4 = 1.31781e-3;
  p.mug = 7.4175e-2;
  p.fv1 = 8.13e-2;
  p.fv2 = 6.42e-4;
  return p;
}

double MotorData::arm_torque_nm(double duty, double dq1_rad_s) const {
  const double motor_speed_rpm = total_ratio() * dq1_rad_s * kRadPerSToRpm;
  return total_ratio() * motor_efficiency * gear_efficiency *
         (duty * no_load_speed_rpm - motor_speed_rpm) / speed_torque_gradient_rpm_per_nm;
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

JointAccelerations forward_dynamics(const ModelParameters& p, const PendulumState& x, double tau_nm,
                                    bool arm_clamped) {
  const double s = std::sin(x.q2);
  const double c = std::cos(x.q2);
  if (arm_clamped) {
    // With dq1 = 0 the centrifugal term of B's second row vanishes and ddq1 = 0 removes the
    // coupling.
    return {0.0, (-p.mug * s - p.fv2 * x.dq2) / p.mu4};
  }
  const double m11 = p.mu1 + p.mu2 * s * s;
  const double m12 = p.mu3 * c;
  const double m22 = p.mu4;
  const double b1 = 2.0 * p.mu2 * s * c * x.dq1 * x.dq2 - p.mu3 * s * x.dq2 * x.dq2;
  const double b2 = -p.mu2 * s * c * x.dq1 * x.dq1;
  const double rhs1 = tau_nm - p.fv1 * x.dq1 - b1;
  const double rhs2 = -p.fv2 * x.dq2 - b2 - p.mug * s;
  const double det = m11 * m22 - m12 * m12;
  return {(m22 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det};
}

double total_energy(const ModelParameters& p, const PendulumState& x) {
  const double s = std::sin(x.q2);
  const double c = std::cos(x.q2);
  const double kinetic = 0.5 * ((p.mu1 + p.mu2 * s * s) * x.dq1 * x.dq1 +
                                2.0 * p.mu3 * c * x.dq1 * x.dq2 + p.mu4 * x.dq2 * x.dq2);
  return kinetic + p.mug * (1.0 - c);
}

double energy_rate(const ModelParameters& p, const PendulumState& x, double tau_nm) {
  return tau_nm * x.dq1 - p.fv1 * x.dq1 * x.dq1 - p.fv2 * x.dq2 * x.dq2;
}

}  // namespace furuta::bridge
