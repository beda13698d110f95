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
  // Beyond this arm angle the pump never drives the arm further out (it waits for the half swing
  // that pumps inwards), so the arm has room left when the catch comes.
  double pump_arm_rad = 45 * std::numbers::pi / 180;
};

// The modes' boundaries, on the angle from upright. swing_up -> catching inside catch_rad where
// the gain, on the angles and their differences, asks for at most entry_duty_ratio of max_duty
// (a pendulum that passes too fast, or an arm too far out, would drive the duty to its limit and
// the arm to its own: the swing goes on instead); catching -> swing_up beyond release_rad
// (> catch_rad: the hysteresis); catching -> balance after settle_s inside catch_rad; balance ->
// fallen beyond fall_rad. fallen is final.
struct CatchRegion {
  double catch_rad = 25 * std::numbers::pi / 180;
  double entry_duty_ratio = 0.5;
  double release_rad = 42 * std::numbers::pi / 180;
  double settle_s = 1.0;
  double fall_rad = 40 * std::numbers::pi / 180;
};

// How a duty sent at a sample reaches the motor: the board takes it lag_s later (at most
// kMaxDelayedDuties periods) and moves the duty it applies towards it at ramp_duty_per_s (0: at
// once), as the board's acceleration setting makes it.
struct DutyPath {
  double lag_s = 0;
  double ramp_duty_per_s = 0;
};

struct BalanceControllerSpec {
  double period_s = 0.016;
  // duty = -gain . [q1, q2 - pi, dq1, dq2, the `delayed` duties still on their way, oldest first]
  std::array<double, kMaxGains> gain{};
  int delayed = 0;
  // The filter's gain, m row-major 4 x 2. Each cycle's angles were read after the last sample:
  // they correct the estimate of that sample's state, x^ = x^- + m (y - y^), y = [q1, q2 - pi],
  // y^ the angles the model predicts from x^- at the instants they were read; the corrected
  // state is then carried to this sample, and balancing uses it, so its velocities are the
  // filter's.
  std::array<double, 8> observer_gain{};
  // The model the filter carries its state with, between and over samples: dx/dt = a x + b duty
  // about upright (row-major 4 x 4), the duty the board applies as the duty path says.
  std::array<double, 16> a_continuous{};
  std::array<double, 4> b_continuous{};
  DutyPath duty_path;
  double max_duty = 0.5;           // the law never asks for more, in any mode
  double duty_step = 1.0 / 255.0;  // the board's resolution: every duty is a whole number of steps
  // The model the swing-up inverts, and eq. 4 as torque = duty_torque duty - back_emf dq1.
  model::Parameters<double> parameters;
  double duty_torque_nm = 0;  // at the design's supply
  double back_emf_nm_s = 0;
  SwingUp swing_up;
  CatchRegion region;
};

// When this cycle's angles were read: each board's newest report's age at the sample instant (how
// long before it the host read the report; negative when it was read after the instant, the loop
// waking late), and whether the board reported since the last call. An angle already used is not
// used again: a board that did not report leaves the filter on the model for that angle.
struct ReadingTimes {
  double arm_age_s = 0;
  double pendulum_age_s = 0;
  bool arm_fresh = true;
  bool pendulum_fresh = true;
};

// One cycle's decision and the figures behind it.
struct BalanceStep {
  double duty = 0;  // what to command, within +-max_duty, a whole number of duty steps
  BalanceMode mode = BalanceMode::swing_up;
  double upright_error_rad = 0;  // q2 - pi wrapped into (-pi, pi]
  // The velocities the law used: each angle's difference between its last two readings while
  // swinging up, the filter's estimates while catching and balancing.
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

  // The angles of this cycle (q2 = 0 hanging down) and when they were read (by default: at this
  // instant, both fresh); returns the duty to send now. Once fallen it returns 0.
  BalanceStep step(double arm_angle_rad, double pendulum_angle_rad,
                   const ReadingTimes& times = {}) noexcept;
  // Takes over at this sample as if it had just caught the pendulum: catching, its filter's
  // estimate of the state here `estimate` = [q1, q2 - pi, dq1, dq2], no duty on its way and the
  // board applying none; returns the duty to send now (the gain on the estimate). The loop's
  // verification starts the law so, and so does its sampled check.
  BalanceStep start_catch(const std::array<double, 4>& estimate) noexcept;
  // Back to the first call's state (no velocities yet, no duties on their way, swinging up).
  void reset() noexcept;

  const BalanceControllerSpec& spec() const noexcept { return spec_; }
  BalanceMode mode() const noexcept { return mode_; }

 private:
  double limit(double duty) const noexcept;
  // The gain's duty for the state x, the duties on their way as sent.
  double gain_duty(const std::array<double, 4>& x) const noexcept;
  // The filter's step: corrects the last sample's estimate with the angles read since, then
  // predicts this sample's state with the duties sent; starts from the angles and differences on
  // its first cycle.
  void estimate(double q1, double error, double dq1, double dq2,
                const ReadingTimes& times) noexcept;
  // The model's state `after_s` past the last sample from `x` there (the board applying
  // `applied` then), with the duties the board took and ramped to over that time; and the duty it
  // applies at the end. Without `x`, the applied duty only.
  struct Carried {
    std::array<double, 4> x{};
    double applied = 0;
  };
  Carried propagate(const std::array<double, 4>* x, double applied, double after_s) const noexcept;

  BalanceControllerSpec spec_;
  // An angle's rate from its last two readings, over the time between them (a board that skips
  // a sample leaves the rate as it was rather than reading as a standstill).
  struct Difference {
    bool have = false;
    double angle = 0;
    double read_s = 0;
    double rate = 0;
    void add(double new_angle, double new_read_s) noexcept;
  };
  double clock_s_ = 0;  // the law's own time: this sample's, from the first
  Difference arm_;
  Difference pendulum_;
  BalanceMode mode_ = BalanceMode::swing_up;
  double inside_s_ = 0;      // time in the catch region while catching
  double start_s_ = 0;       // time spent starting the swing
  double arm_velocity_ = 0;  // the swing-up's arm velocity, rad/s
  double a_norm_ = 0;        // the largest row sum of |a_continuous|: propagate()'s step size
  // The filter's estimate of [q1, q2 - pi, dq1, dq2] at the last sample while balancing.
  bool estimating_ = false;
  std::array<double, 4> estimate_{};
  // The duties sent, newest last: the last `delayed` of them are still on their way.
  // One more than the delays: the filter's prediction looks back from the last sample.
  std::array<double, kMaxDelayedDuties + 1> sent_{};
  double applied_ = 0;  // the duty the board applies at the last sample, as the duty path says
};

}  // namespace furuta::control
