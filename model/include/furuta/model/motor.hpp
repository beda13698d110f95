#pragma once
// The arm's drive: a Maxon DC motor and gearbox driven by the motor board's PWM duty (paper
// section IV.A, eq. 4; docs/model.md).

#include <numbers>

namespace furuta::model {

struct MotorData {
  double rotor_inertia_kg_m2 = 9.06e-7;
  double no_load_speed_rpm = 11700.0;                 // omega0 at nominal voltage
  double speed_torque_gradient_rpm_per_nm = 34000.0;  // Rv
  double motor_efficiency = 0.906;                    // eta_m
  double gear_efficiency = 0.90;                      // eta_g
  double motor_ratio = 5.2;                           // Nm
  double gear_ratio = 5.0;                            // Ng
  double nominal_voltage_v = 12.0;                    // supply at which omega0 holds

  double total_ratio() const { return motor_ratio * gear_ratio; }
  bool operator==(const MotorData&) const = default;
  // Paper eq. 4: torque at the arm for PWM duty d in [-1, 1] and arm speed dq1 [rad/s], over any
  // scalar (automatic differentiation passes its Jets through).
  template <class T>
  T arm_torque(const T& duty, const T& dq1_rad_s) const {
    constexpr double kRadPerSToRpm = 60.0 / (2.0 * std::numbers::pi);
    const T motor_speed_rpm = total_ratio() * dq1_rad_s * kRadPerSToRpm;
    return total_ratio() * motor_efficiency * gear_efficiency *
           (duty * no_load_speed_rpm - motor_speed_rpm) / speed_torque_gradient_rpm_per_nm;
  }
  double arm_torque_nm(double duty, double dq1_rad_s) const { return arm_torque(duty, dq1_rad_s); }
  // Motor current for a torque at the arm (torque constant from omega0 and the nominal voltage).
  double motor_current_a(double arm_torque_nm) const;
};

}  // namespace furuta::model
