#pragma once
// The balance controller as it runs in the loop (docs/control.md): from rest hanging down, an
// energy-based swing-up (Astrom and Furuta) that keeps the arm near its centre; a catch region,
// with hysteresis, where the upright LQR takes over; a fall limit once balanced.
//
// One call per loop period, in order, with the two angles the encoders give. Everything is fixed
// size: constructing allocates nothing, and step() neither allocates nor throws, so it runs inside
// the real-time cycle.

#include <array>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <string_view>

#include "furuta/model/parameters.hpp"

namespace furuta::control {

// Duties still on their way that a gain may carry (a lag of up to this many periods).
inline constexpr int kMaxDelayedDuties = 4;
inline constexpr int kMaxGains = 4 + kMaxDelayedDuties;

enum class BalanceMode : std::uint8_t { swing_up, catching, balance, fallen };
std::string_view to_string(BalanceMode mode);

// Swing-up (Astrom and Furuta): the arm's acceleration a = energy_gain (E0 - E) sign(dq2 cos q2),
// limited to +-max_acceleration, pumps energy into the swing (dE/dt = -mu3 cos(q2) dq2 ddq1 plus
// losses); minus arm_gain q1 + arm_damping v to keep the arm near its centre. The arm follows a
// duty like a velocity, so the law integrates a into the velocity v it asks for and sends the
// duty that holds v against back-EMF and friction (plus mu1 a), limited to +-max_duty. E is the
// pendulum's energy with zero hanging at rest, E0 = 2 mug upright at rest.
struct SwingUp {
  double energy_gain = 2000.0;      // rad/s^2 per J
  double max_acceleration = 150.0;  // rad/s^2
  double arm_gain = 40.0;           // rad/s^2 per rad
  double arm_damping = 8.0;         // rad/s^2 per rad/s
  double max_duty = 0.5;
  double energy_margin = 0.2;  // the pump aims at E0 (1 + energy_margin)
  // Below this E / E0 (hanging nearly at rest, where sign(dq2 cos q2) says nothing) the pump is
  // +-start_acceleration flipped every half period of the pendulum's small swing, sqrt(mug / mu4):
  // resonance starts the swing.
  double start_below_energy_ratio = 0.005;
  double start_acceleration = 20.0;  // rad/s^2
};

// The modes' boundaries, on the angle from upright. swing_up -> catching inside catch_rad;
// catching -> swing_up beyond release_rad (> catch_rad: the hysteresis); catching -> balance after
// settle_s inside catch_rad; balance -> fallen beyond fall_rad. fallen is final.
struct CatchRegion {
  double catch_rad = 25 * std::numbers::pi / 180;
  double release_rad = 42 * std::numbers::pi / 180;
  double settle_s = 1.0;
  double fall_rad = 40 * std::numbers::pi / 180;
};

struct BalanceControllerSpec {
  double period_s = 0.016;
  // duty = -gain . [q1, q2 - pi, dq1, dq2, the `delayed` duties still on their way, oldest first]
  std::array<double, kMaxGains> gain{};
  int delayed = 0;
  // The sampled plant about upright, z[k+1] = phi z[k] + gamma u[k] on the same z (row-major,
  // kMaxGains columns; the first 4 + delayed rows and columns used), and the filter's gain: from
  // each cycle's prediction x^- of [q1, q2 - pi, dq1, dq2], x^ = x^- + m ([q1, q2 - pi] -
  // x^-[0..1]), m row-major 4 x 2. Balancing uses x^, so its velocities are the filter's.
  std::array<double, kMaxGains * kMaxGains> phi{};
  std::array<double, kMaxGains> gamma{};
  std::array<double, 8> observer_gain{};
  // dx/dt = a x + b duty about upright (row-major 4 x 4): the filter takes each angle back from
  // the sample's instant to when the encoder read it.
  std::array<double, 16> a_continuous{};
  std::array<double, 4> b_continuous{};
  double max_duty = 0.5;           // the law never asks for more, in any mode
  double duty_step = 1.0 / 255.0;  // the board's resolution: every duty is a whole number of steps
  // The model the swing-up inverts, and eq. 4 as torque = duty_torque duty - back_emf dq1.
  model::Parameters<double> parameters;
  double duty_torque_nm = 0;  // at the design's supply
  double back_emf_nm_s = 0;
  SwingUp swing_up;
  CatchRegion region;
};

// One cycle's decision and the figures behind it.
struct BalanceStep {
  double duty = 0;  // what to command, within +-max_duty, a whole number of duty steps
  BalanceMode mode = BalanceMode::swing_up;
  double upright_error_rad = 0;  // q2 - pi wrapped into (-pi, pi]
  // The velocities the law used: differences over a period while swinging up and catching, the
  // filter's estimates while balancing.
  double arm_rate_rad_s = 0;
  double pendulum_rate_rad_s = 0;
  double energy_ratio = 0;  // E / E0: 0 hanging at rest, 1 upright at rest
};

// What BalanceLaw's constructor throws: the spec's member out of range, by its path in
// BalanceControllerSpec ("max_duty", "parameters.mu1", "swing_up.max_duty", "region.catch_rad"),
// so that a reader of a controller file can point at the key the value came from.
class BalanceSpecError : public std::invalid_argument {
 public:
  BalanceSpecError(std::string field, std::string rule);
  const std::string& field() const noexcept { return field_; }
  const std::string& rule() const noexcept { return rule_; }  // "must be in (0, 1]"

 private:
  std::string field_;
  std::string rule_;
};

class BalanceLaw {
 public:
  // Throws BalanceSpecError (a std::invalid_argument) naming the field that is out of range.
  explicit BalanceLaw(const BalanceControllerSpec& spec);
  BalanceLaw() = default;

  // The angles of this cycle (q2 = 0 hanging down); returns the duty to send now. Once fallen it
  // returns 0.
  // `*_age_s`: how long before this call each angle was read (its report's age; 0 when it is the
  // angle at this instant), which the filter accounts for.
  BalanceStep step(double arm_angle_rad, double pendulum_angle_rad, double arm_age_s = 0,
                   double pendulum_age_s = 0) noexcept;
  // Back to the first call's state (no velocities yet, no duties on their way, swinging up).
  void reset() noexcept;

  const BalanceControllerSpec& spec() const noexcept { return spec_; }
  BalanceMode mode() const noexcept { return mode_; }

 private:
  double limit(double duty) const noexcept;
  // The filter's step: predicts this cycle's state from the last estimate and the duties sent,
  // corrects it with the angles; starts from the angles and differences on its first cycle.
  void estimate(double q1, double error, double dq1, double dq2, double arm_age_s,
                double pendulum_age_s) noexcept;

  BalanceControllerSpec spec_;
  bool have_previous_ = false;
  double previous_q1_ = 0;
  double previous_q2_ = 0;
  BalanceMode mode_ = BalanceMode::swing_up;
  double inside_s_ = 0;      // time in the catch region while catching
  double start_s_ = 0;       // time spent starting the swing
  double arm_velocity_ = 0;  // the swing-up's arm velocity, rad/s
  // The filter's estimate of [q1, q2 - pi, dq1, dq2] while catching and balancing.
  bool estimating_ = false;
  std::array<double, 4> estimate_{};
  // The duties sent, newest last: the last `delayed` of them are still on their way.
  // One more than the delays: the filter's prediction needs the duties of the previous cycle's z.
  std::array<double, kMaxDelayedDuties + 1> sent_{};
};

}  // namespace furuta::control
