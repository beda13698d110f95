#pragma once
// The rotary pendulum's dynamics (docs/model.md, paper eq. 1-3): M(q) ddq + B(q, dq) + Q(q) =
// Gamma, q1 the arm angle, q2 the pendulum angle from hanging down. One formulation for every
// scalar: the simulated rig integrates it in double, the validated integrator in intervals and
// Taylor jets.

#include <cmath>
#include <type_traits>

#include "furuta/model/parameters.hpp"

namespace furuta::model {

struct PendulumState {
  double q1 = 0, dq1 = 0, q2 = 0, dq2 = 0;
};

template <class S>
struct JointAccelerations {
  S ddq1{}, ddq2{};
};

// The mass matrix M(q) = [m11 m12; m12 m22]; det M > 0 for parameters in the physical region.
template <class S>
struct MassMatrix {
  S m11{}, m12{}, m22{};
};

template <class S>
MassMatrix<S> mass_matrix(const Parameters<S>& p, const S& q2) {
  using std::cos;
  using std::sin;
  const S s = sin(q2);
  return {p.mu1 + p.mu2 * s * s, p.mu3 * cos(q2), p.mu4};
}

// Scalars that enclose sets (intervals, interval jets, Taylor models, the validated integrator's
// recorder) square with `sqr`, found by argument-dependent lookup.
template <class S>
concept EnclosureScalar = requires(const S& x) {
  sqr(x);
};

// ddq = M^-1 (Gamma - B - Q) with the 2x2 inverse written out, det M = (mu1 + mu2 s^2) mu4 -
// mu3^2 c^2 (s = sin q2, c = cos q2). The order of operations is part of the contract: the
// simulated rig's logs are reproduced bit for bit, so doubles (and Ceres' jets) multiply as
// written. Enclosure scalars take each square with sqr: x * x over an interval spanning 0 is no
// square's enclosure (sin q2 in [-1, 0.8] gives s * s down to -0.8, and with mu2 above mu1, m11
// and det M would reach 0: a validated step would then find no a priori enclosure).
template <class S>
JointAccelerations<S> accelerations(const Parameters<S>& p, const S& q2, const S& dq1, const S& dq2,
                                    const S& tau) {
  using std::cos;
  using std::sin;
  const S s = sin(q2);
  const S c = cos(q2);
  const S m12 = p.mu3 * c;
  const S sc = s * c;
  if constexpr (EnclosureScalar<S>) {
    const S m11 = p.mu1 + p.mu2 * sqr(s);
    const S b1 = S(2.0) * p.mu2 * sc * dq1 * dq2 - p.mu3 * s * sqr(dq2);
    const S b2 = -(p.mu2 * sc * sqr(dq1));
    const S rhs1 = tau - p.fv1 * dq1 - b1;
    const S rhs2 = -(p.fv2 * dq2) - b2 - p.mug * s;
    const S det = m11 * p.mu4 - sqr(m12);
    return {(p.mu4 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det};
  } else {
    const S m11 = p.mu1 + p.mu2 * s * s;
    const S b1 = S(2.0) * p.mu2 * sc * dq1 * dq2 - p.mu3 * s * dq2 * dq2;
    const S b2 = -(p.mu2 * sc * dq1 * dq1);
    const S rhs1 = tau - p.fv1 * dq1 - b1;
    const S rhs2 = -(p.fv2 * dq2) - b2 - p.mug * s;
    const S det = m11 * p.mu4 - m12 * m12;
    return {(p.mu4 * rhs1 - m12 * rhs2) / det, (m11 * rhs2 - m12 * rhs1) / det};
  }
}

// The accelerations at a state. With the arm clamped (a physics check of the pendulum alone),
// ddq1 = 0 and the pendulum swings by itself.
JointAccelerations<double> forward_dynamics(const Parameters<double>& p, const PendulumState& x,
                                            double tau_nm, bool arm_clamped = false);

// Kinetic + potential energy, potential zero hanging down: 1/2 dq^T M dq + mug (1 - cos q2).
double total_energy(const Parameters<double>& p, const PendulumState& x);

// Power fed in by the torque and lost to friction: dE/dt = tau dq1 - fv1 dq1^2 - fv2 dq2^2.
double energy_rate(const Parameters<double>& p, const PendulumState& x, double tau_nm);

// One classical Runge-Kutta 4 step of dt_s. `torque` maps a state to the arm torque, so a
// speed-dependent torque (eq. 4) is evaluated inside the step; or a state and the stage's time as
// a fraction of the step (0, 1/2, 1/2, 1), for an input that changes within the step.
template <typename TorqueOfState>
PendulumState rk4_step(const Parameters<double>& p, const PendulumState& x, double dt_s,
                       TorqueOfState&& torque, bool arm_clamped = false) {
  auto f = [&](const PendulumState& s, double fraction) {
    double tau = 0.0;
    if constexpr (std::is_invocable_v<TorqueOfState&, const PendulumState&, double>) {
      tau = torque(s, fraction);
    } else {
      (void)fraction;
      tau = torque(s);
    }
    const JointAccelerations<double> a = forward_dynamics(p, s, tau, arm_clamped);
    return PendulumState{s.dq1, a.ddq1, s.dq2, a.ddq2};
  };
  auto add = [](const PendulumState& s, const PendulumState& d, double h) {
    return PendulumState{s.q1 + h * d.q1, s.dq1 + h * d.dq1, s.q2 + h * d.q2, s.dq2 + h * d.dq2};
  };
  const PendulumState k1 = f(x, 0.0);
  const PendulumState k2 = f(add(x, k1, dt_s / 2), 0.5);
  const PendulumState k3 = f(add(x, k2, dt_s / 2), 0.5);
  const PendulumState k4 = f(add(x, k3, dt_s), 1.0);
  PendulumState out;
  out.q1 = x.q1 + dt_s / 6 * (k1.q1 + 2 * k2.q1 + 2 * k3.q1 + k4.q1);
  out.dq1 = x.dq1 + dt_s / 6 * (k1.dq1 + 2 * k2.dq1 + 2 * k3.dq1 + k4.dq1);
  out.q2 = x.q2 + dt_s / 6 * (k1.q2 + 2 * k2.q2 + 2 * k3.q2 + k4.q2);
  out.dq2 = x.dq2 + dt_s / 6 * (k1.dq2 + 2 * k2.dq2 + 2 * k3.dq2 + k4.dq2);
  if (arm_clamped) out.dq1 = 0.0;
  return out;
}

}  // namespace furuta::model
