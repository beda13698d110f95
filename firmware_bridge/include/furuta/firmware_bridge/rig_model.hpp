#pragma once
// The rotary pendulum's dynamics (DESIGN.md, paper eq. 1-4) as plain functions, shared by the
// simulated rig and by tests. q1 = arm angle, q2 = pendulum angle from hanging down.

namespace furuta::bridge {

struct ModelParameters {
  double mu1 = 0, mu2 = 0, mu3 = 0, mu4 = 0;  // kg m^2
  double mug = 0;                             // kg m^2 s^-2
  double fv1 = 0, fv2 = 0;                    // N m s

  // The paper's Table I, acquisition #1: the simulated rig's default truth.
  static ModelParameters paper_run1();
};

// Maxon motor and gearbox, paper section IV.A.
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
  // Paper eq. 4: torque at the arm for PWM duty d in [-1, 1] and arm speed dq1 [rad/s].
  double arm_torque_nm(double duty, double dq1_rad_s) const;
  // Motor current for a torque at the arm (torque constant from omega0 and the nominal voltage).
  double motor_current_a(double arm_torque_nm) const;
};

struct PendulumState {
  double q1 = 0, dq1 = 0, q2 = 0, dq2 = 0;
};

struct JointAccelerations {
  double ddq1 = 0, ddq2 = 0;
};

// ddq = M^-1 (Gamma - B - Q). With the arm clamped, ddq1 = 0 and the pendulum swings alone.
JointAccelerations forward_dynamics(const ModelParameters& p, const PendulumState& x, double tau_nm,
                                    bool arm_clamped = false);

// Kinetic + potential energy, potential zero hanging down: 1/2 dq^T M dq + mug (1 - cos q2).
double total_energy(const ModelParameters& p, const PendulumState& x);

// Power fed in by the torque and lost to friction: dE/dt = tau dq1 - fv1 dq1^2 - fv2 dq2^2.
double energy_rate(const ModelParameters& p, const PendulumState& x, double tau_nm);

// One classical Runge-Kutta 4 step of dt_s. `torque` maps a state to the arm torque, so a
// speed-dependent torque (eq. 4) is evaluated inside the step.
template <typename TorqueOfState>
PendulumState rk4_step(const ModelParameters& p, const PendulumState& x, double dt_s,
                       TorqueOfState&& torque, bool arm_clamped = false) {
  auto f = [&](const PendulumState& s) {
    const JointAccelerations a = forward_dynamics(p, s, torque(s), arm_clamped);
    return PendulumState{s.dq1, a.ddq1, s.dq2, a.ddq2};
  };
  auto add = [](const PendulumState& s, const PendulumState& d, double h) {
    return PendulumState{s.q1 + h * d.q1, s.dq1 + h * d.dq1, s.q2 + h * d.q2, s.dq2 + h * d.dq2};
  };
  const PendulumState k1 = f(x);
  const PendulumState k2 = f(add(x, k1, dt_s / 2));
  const PendulumState k3 = f(add(x, k2, dt_s / 2));
  const PendulumState k4 = f(add(x, k3, dt_s));
  PendulumState out;
  out.q1 = x.q1 + dt_s / 6 * (k1.q1 + 2 * k2.q1 + 2 * k3.q1 + k4.q1);
  out.dq1 = x.dq1 + dt_s / 6 * (k1.dq1 + 2 * k2.dq1 + 2 * k3.dq1 + k4.dq1);
  out.q2 = x.q2 + dt_s / 6 * (k1.q2 + 2 * k2.q2 + 2 * k3.q2 + k4.q2);
  out.dq2 = x.dq2 + dt_s / 6 * (k1.dq2 + 2 * k2.dq2 + 2 * k3.dq2 + k4.dq2);
  if (arm_clamped) out.dq1 = 0.0;
  return out;
}

}  // namespace furuta::bridge
