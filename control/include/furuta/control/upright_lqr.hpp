#pragma once
// The balance controller's design, step by step (docs/control.md):
//
//   1. linearize_upright: the model (docs/model.md) and the motor's drive (eq. 4) about the
//      upright equilibrium q2 = pi, as dx/dt = A x + B duty with x = [q1, q2 - pi, dq1, dq2];
//   2. sample: held over each loop period and reaching the board `lag_s` after its sample (the
//      data path), as x[k+1] = Phi x[k] + Gamma u[k] on a state that carries the duties still on
//      their way;
//   3. design_lqr: the discrete-time LQR of that sampled plant, its gain and closed-loop poles;
//   4. design_observer: the steady-state Kalman filter that gives the LQR its velocities from the
//      two encoders' counts (a difference over a period lags by half a period, and against an arm
//      that follows its duty within a period that lag rings at the sampling's Nyquist rate).
//
// Numbers in, numbers out: the controller file and its text are made elsewhere.

#include <Eigen/Dense>
#include <array>
#include <complex>
#include <vector>

#include "furuta/control/balance_law.hpp"
#include "furuta/model/model.hpp"

namespace furuta::control {

// The plant the controller is designed for: parameters (identified, or CAD), the drive, and the
// supply, which scales what a duty does (the PWM chops it).
struct DesignPlant {
  model::Parameters<double> parameters;
  model::MotorData motor;
  double supply_v = 12.0;
};

// Eq. 4 as it is affine in the duty and the arm's speed: torque = duty_torque duty - back_emf dq1,
// the duty scaled by the supply over the motor's nominal voltage (the PWM chops the supply).
struct DriveConstants {
  double duty_torque_nm = 0;  // kd, at the plant's supply
  double back_emf_nm_s = 0;   // kw
};
DriveConstants drive_constants(const DesignPlant& plant);

// dx/dt = a x + b duty about upright, x = [q1, q2 - pi, dq1, dq2].
struct LinearPlant {
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
};
LinearPlant linearize_upright(const DesignPlant& plant);
// The same from the parameters and eq. 4's constants (what a controller file holds).
LinearPlant linearize_upright(const model::Parameters<double>& parameters,
                              const DriveConstants& drive);

// x[k+1] = phi x[k] + gamma u[k] on z = [x; the duties sent but not yet applied, oldest first]:
// a duty computed at sample k reaches the board lag_s later and is held until the next one
// arrives. `delayed` is how many earlier duties z carries (ceil(lag / period), 0 without lag).
struct SampledPlant {
  LinearPlant continuous;  // what was sampled
  Eigen::MatrixXd phi;
  Eigen::VectorXd gamma;
  double period_s = 0;
  double lag_s = 0;
  int delayed = 0;
};
// Throws std::invalid_argument for a period that is not > 0 or a lag that is negative or not
// finite.
SampledPlant sample(const LinearPlant& plant, double period_s, double lag_s);
// The `delayed` of sample(plant, period_s, lag_s): how many duties a gain designed with that lag
// carries. Same arguments and errors as sample().
int delayed_duties(double period_s, double lag_s);

// The duty step the board's ramp is judged on: a typical correction of the balancing loop.
inline constexpr double kRampStepDuty = 0.05;
// The motor board's duty ramp (acceleration_pct_per_s, a rate r = pct / 100 duty per s) as a pure
// delay: a step of step_duty becomes a ramp lasting step_duty / r, which lags the step by half
// that on average, step_duty / (2 r). The design adds it to the data path's lag. 0 is read as no
// ramp at all, 0 s; the board adapters' own 0 ("the board's fastest") is a finite rate, but the
// rig configuration never holds 0 (it asks for the rate in the board's range), so the design is
// always given the rate the board runs at. Throws std::invalid_argument for a negative or
// non-finite rate or step.
double ramp_lag_s(double acceleration_pct_per_s, double step_duty);

// The cost sum of x' Q x + r u^2 over the samples, Q diagonal over x (the delayed duties carry no
// weight of their own).
struct LqrWeights {
  std::array<double, 4> state = {1.0, 10.0, 0.1, 0.1};  // q1, q2 - pi, dq1, dq2
  double duty = 10.0;
};

struct BalanceGain {
  // u[k] = -k z[k]: the four state gains, then one per delayed duty.
  Eigen::RowVectorXd k;
  std::vector<std::complex<double>> closed_loop_poles;  // eigenvalues of phi - gamma k
  double spectral_radius = 0;                           // the largest |pole|; < 1 is stable
  int riccati_iterations = 0;
};
// Throws std::invalid_argument for weights that are not > 0 (state >= 0, duty > 0) and
// std::runtime_error when the Riccati iteration does not settle (a plant the duty cannot
// stabilise).
BalanceGain design_lqr(const SampledPlant& plant, const LqrWeights& weights);

// What the filter assumes: the model's accelerations are off by white noise of these standard
// deviations (rad/s^2, held over each period), and each angle is read to within a count (a
// uniform error of one count, variance count^2 / 12).
struct ObserverWeights {
  // Large enough that the model's own errors (parameters 10 % off, the linearisation while
  // catching) sit inside them: a filter that trusts its model more holds no CAD-designed loop.
  double arm_acceleration_sd = 30.0;
  double pendulum_acceleration_sd = 10.0;
  double arm_count_rad = 0;  // the encoders' resolutions at the joints
  double pendulum_count_rad = 0;
  // The angles of a cycle were read this long before its sample, typically (within [0, period]):
  // the gain is designed for it; the loop takes each reading's own age.
  double reading_age_s = 0;
};
struct ObserverGain {
  // x^ = x^- + m (y - y^), y = [q1, q2 - pi], y^ = C e^(A (T - age)) x^- (the duties known): the
  // correction of the last sample's predicted state by the angles read since.
  Eigen::Matrix<double, 4, 2> m = Eigen::Matrix<double, 4, 2>::Zero();
  double reading_age_s = 0;
  // Of the estimation error's dynamics, phi (I - m H): at the design's age, and the largest over
  // readings of any age in [0, period] (the gain fixed, the age each cycle's own); both < 1.
  double spectral_radius = 0;
  double worst_spectral_radius = 0;
};
// Throws std::invalid_argument for weights or counts that are not finite and > 0 or an age outside
// [0, period], and std::runtime_error when the filter's Riccati recursion does not settle.
ObserverGain design_observer(const SampledPlant& plant, const ObserverWeights& weights);

// The spec's continuous plant (a_continuous, b_continuous) from `plant`.
void set_continuous_plant(const LinearPlant& plant, BalanceControllerSpec& spec);
// What the loop runs (balance_law.hpp) for a design: the gain, the filter's gain and the model it
// predicts with (the sampled plant's continuous one, the duty path as the board takes duties:
// its lag and ramp, which the design saw as one lag), the plant's parameters and drive, the
// swing-up's and catch region's defaults, the duty limit and step, the swing-up never asking for
// more than max_duty. Throws std::invalid_argument when the plant carries more duties than the
// law can.
BalanceControllerSpec balance_spec(const DesignPlant& plant, const SampledPlant& sampled,
                                   const BalanceGain& gain, const ObserverGain& observer,
                                   const DutyPath& duty_path, double max_duty, double duty_step);

}  // namespace furuta::control
