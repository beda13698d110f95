#pragma once
// Excitation profiles: the duty cycle to command at each cycle of a session.
// Everything that allocates happens in the constructor; duty() runs on the real-time loop.

#include <array>
#include <cstdint>
#include <optional>
#include <random>
#include <string_view>

namespace furuta::daemon {

enum class ProfileKind : std::uint8_t { bang_bang, free_decay, step, prbs, chirp, multisine };
std::optional<ProfileKind> parse_profile_kind(std::string_view name);  // "bang_bang", ...
std::string_view to_string(ProfileKind kind);
// The session kind a start command names instead of a profile when the balance controller drives
// the motor (rig_command_t::controller_path, controller_sha256).
inline constexpr std::string_view kBalanceProfile = "balance";

inline constexpr std::size_t kMaxMultisineComponents = 16;

struct ExcitationSpec {
  ProfileKind kind = ProfileKind::bang_bang;
  double amplitude_duty = 0.3;  // (0, 1]: every profile stays within +-amplitude
  double duration_s = 10.0;
  std::uint64_t seed = 1;

  // bang-bang (the paper's): the sign flips every switch period, optionally randomised, and/or when
  // the arm crosses +-arm_switch_rad so it stays in its safe range.
  // The sign starts +. Each elapsed period flips it once (period n drawn uniformly in
  // T*(1 +- jitter) from the seeded generator). With thresholds, whenever the arm is beyond one the
  // sign points back toward the centre (- above +arm_switch_rad, + below -arm_switch_rad),
  // overriding the timer; when that changes the sign, the timer restarts from that cycle with a
  // fresh period.
  double switch_period_s = 0.5;       // 0: no time-based switching (thresholds only)
  double switch_period_jitter = 0.0;  // [0, 1): each period drawn uniformly in T*(1 +- jitter)
  double arm_switch_rad = 0.0;        // 0: no threshold switching
  // step: zero, then +amplitude from step_time_s on.
  double step_time_s = 0.5;
  // PRBS: a maximal-length LFSR sequence of +-amplitude, one bit per bit_period_s.
  double prbs_bit_period_s = 0.048;
  int prbs_order = 9;  // 2..16: period 2^order - 1 bits
  // chirp: amplitude * sin of a linear sweep from f0 to f1 over the duration, from a starting phase
  // the seed picks.
  double chirp_f0_hz = 0.2;
  double chirp_f1_hz = 5.0;
  // multisine: components log-spaced in [f_min, f_max], Schroeder phases, scaled to peak amplitude;
  // the seed shifts it in time by up to a period of f_min.
  int multisine_components = 8;  // 1..16
  double multisine_f_min_hz = 0.2;
  double multisine_f_max_hz = 5.0;
};

class Excitation {
 public:
  // Throws std::invalid_argument naming the field; only the chosen profile's fields are checked.
  // A multisine searches its peak here (about 50 ms for 600 s and 16 components): construct the
  // excitation before handing it to the loop.
  explicit Excitation(const ExcitationSpec& spec);
  Excitation() : Excitation(ExcitationSpec{}) {}

  // Duty for time t_s since the session start, given the newest arm angle. Non-decreasing t_s.
  // 0 outside [0, duration_s) (and for a NaN time); never beyond +-amplitude_duty.
  double duty(double t_s, double arm_angle_rad) noexcept;
  bool finished(double t_s) const noexcept { return t_s >= spec_.duration_s; }
  const ExcitationSpec& spec() const noexcept { return spec_; }

 private:
  ExcitationSpec spec_;
  std::mt19937_64 rng_;
  // bang-bang state
  double sign_ = 1.0;
  double next_switch_s_ = 0.0;
  // prbs state
  std::uint32_t lfsr_ = 1;
  std::int64_t prbs_bit_index_ = -1;
  double prbs_value_ = 1.0;
  // multisine
  std::array<double, kMaxMultisineComponents> ms_freq_{};
  std::array<double, kMaxMultisineComponents> ms_phase_{};
  double ms_scale_ = 1.0;
  // chirp
  double chirp_phase_ = 0.0;
};

}  // namespace furuta::daemon
