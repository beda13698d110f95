#include "furuta/daemon/excitation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "furuta/config/rig_config.hpp"

namespace furuta::daemon {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Bounds that keep every time computation in duty() exact enough and its loops short: a session is
// minutes long, and nothing switches faster than a 1 ms loop can follow.
constexpr double kMaxDurationS = 1.0e6;
constexpr double kMinPeriodS = 1.0e-4;

// Galois LFSR feedback masks (bit k-1 set for each exponent k of a primitive polynomial), one per
// order. Any primitive polynomial gives a maximal-length sequence; the tests check each period.
constexpr std::array<std::uint32_t, 17> kLfsrMasks = {
    0,      0,
    0x3,     // x^2 + x + 1
    0x6,     // x^3 + x^2 + 1
    0xC,     // x^4 + x^3 + 1
    0x14,    // x^5 + x^3 + 1
    0x30,    // x^6 + x^5 + 1
    0x60,    // x^7 + x^6 + 1
    0xB8,    // x^8 + x^6 + x^5 + x^4 + 1
    0x110,   // x^9 + x^5 + 1
    0x240,   // x^10 + x^7 + 1
    0x500,   // x^11 + x^9 + 1
    0xE08,   // x^12 + x^11 + x^10 + x^4 + 1
    0x1C80,  // x^13 + x^12 + x^11 + x^8 + 1
    0x3802,  // x^14 + x^13 + x^12 + x^2 + 1
    0x6000,  // x^15 + x^14 + 1
    0xD008,  // x^16 + x^15 + x^13 + x^4 + 1
};

// Enough grid points per period of the fastest multisine component that the grid maximum is within
// a few 1e-4 of the true peak before refinement; capped so construction stays in the tens of ms.
constexpr double kMultisineGridPerPeriod = 64.0;
constexpr double kMultisineMaxGridPoints = 1 << 20;

std::string show(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

[[noreturn]] void reject(std::string_view field, const std::string& problem) {
  throw std::invalid_argument(std::string(field) + ": " + problem);
}

void require_finite(std::string_view field, double value) {
  if (!std::isfinite(value)) reject(field, "must be a finite number, got " + show(value));
}

void require_positive(std::string_view field, double value) {
  require_finite(field, value);
  if (!(value > 0.0)) reject(field, "must be > 0, got " + show(value));
}

void require_non_negative(std::string_view field, double value) {
  require_finite(field, value);
  if (!(value >= 0.0)) reject(field, "must be >= 0, got " + show(value));
}

void validate(const ExcitationSpec& s) {
  if (to_string(s.kind) == "unknown") {
    reject("kind", std::to_string(static_cast<int>(s.kind)) + " is not a known profile");
  }
  if (!(s.amplitude_duty > 0.0 && s.amplitude_duty <= 1.0)) {
    reject("amplitude_duty", "must be in (0, 1], got " + show(s.amplitude_duty));
  }
  require_positive("duration_s", s.duration_s);
  if (s.duration_s > kMaxDurationS) {
    reject("duration_s", "must be at most " + show(kMaxDurationS) + ", got " + show(s.duration_s));
  }

  // Only the chosen profile's parameters are checked: the others are configured defaults that this
  // session never uses, and a bad one must not stop an unrelated profile from running.
  switch (s.kind) {
    case ProfileKind::bang_bang:
      require_non_negative("switch_period_s", s.switch_period_s);
      if (s.switch_period_s != 0.0 && s.switch_period_s < kMinPeriodS) {
        reject("switch_period_s", "must be 0 (off) or at least " + show(kMinPeriodS) + ", got " +
                                      show(s.switch_period_s));
      }
      if (!(s.switch_period_jitter >= 0.0 && s.switch_period_jitter < 1.0)) {
        reject("switch_period_jitter", "must be in [0, 1), got " + show(s.switch_period_jitter));
      }
      require_non_negative("arm_switch_rad", s.arm_switch_rad);
      if (s.switch_period_s == 0.0 && s.arm_switch_rad == 0.0) {
        reject("switch_period_s",
               "0 together with arm_switch_rad 0 leaves bang_bang nothing to switch on");
      }
      break;
    case ProfileKind::free_decay:
      break;
    case ProfileKind::step:
      require_non_negative("step_time_s", s.step_time_s);
      if (s.step_time_s >= s.duration_s) {
        reject("step_time_s", show(s.step_time_s) + " is not before the end of the session (" +
                                  "duration_s " + show(s.duration_s) + ")");
      }
      break;
    case ProfileKind::prbs:
      require_finite("prbs_bit_period_s", s.prbs_bit_period_s);
      if (!(s.prbs_bit_period_s >= kMinPeriodS)) {
        reject("prbs_bit_period_s",
               "must be at least " + show(kMinPeriodS) + ", got " + show(s.prbs_bit_period_s));
      }
      if (s.prbs_order < 2 || s.prbs_order > 16) {
        reject("prbs_order", "must be in 2..16, got " + std::to_string(s.prbs_order));
      }
      break;
    case ProfileKind::chirp:
      require_non_negative("chirp_f0_hz", s.chirp_f0_hz);
      require_non_negative("chirp_f1_hz", s.chirp_f1_hz);
      break;
    case ProfileKind::multisine:
      if (s.multisine_components < 1 ||
          s.multisine_components > static_cast<int>(kMaxMultisineComponents)) {
        reject("multisine_components", "must be in 1.." + std::to_string(kMaxMultisineComponents) +
                                           ", got " + std::to_string(s.multisine_components));
      }
      require_positive("multisine_f_min_hz", s.multisine_f_min_hz);
      require_finite("multisine_f_max_hz", s.multisine_f_max_hz);
      if (s.multisine_components > 1 && !(s.multisine_f_max_hz > s.multisine_f_min_hz)) {
        reject("multisine_f_max_hz", "must be above multisine_f_min_hz " +
                                         show(s.multisine_f_min_hz) + " when there are several " +
                                         "components, got " + show(s.multisine_f_max_hz));
      }
      break;
  }
}

// 53 random bits, so the draw does not depend on the standard library's distribution algorithm
// (which is implementation-defined): the same seed gives the same session everywhere.
double uniform01(std::mt19937_64& rng) noexcept {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

double draw_switch_period(const ExcitationSpec& s, std::mt19937_64& rng) noexcept {
  return s.switch_period_s * (1.0 + s.switch_period_jitter * (2.0 * uniform01(rng) - 1.0));
}

}  // namespace

static_assert(config::kExcitationProfiles.size() ==
                  static_cast<std::size_t>(ProfileKind::multisine) + 1,
              "every profile kind has its name in config::kExcitationProfiles, in order");

std::optional<ProfileKind> parse_profile_kind(std::string_view name) {
  for (std::size_t i = 0; i < config::kExcitationProfiles.size(); ++i) {
    if (name == config::kExcitationProfiles[i]) return static_cast<ProfileKind>(i);
  }
  return std::nullopt;
}

std::string_view to_string(ProfileKind kind) {
  const auto i = static_cast<std::size_t>(kind);
  return i < config::kExcitationProfiles.size() ? config::kExcitationProfiles[i] : "unknown";
}

Excitation::Excitation(const ExcitationSpec& spec) : spec_(spec), rng_(spec.seed) {
  validate(spec_);
  switch (spec_.kind) {
    case ProfileKind::bang_bang:
      if (spec_.switch_period_s > 0.0) {
        next_switch_s_ = draw_switch_period(spec_, rng_);
      }
      break;
    case ProfileKind::prbs: {
      // The seed picks where in the sequence the session starts; any non-zero state is on the
      // cycle.
      const std::uint32_t states = (std::uint32_t{1} << spec_.prbs_order) - 1;
      lfsr_ = 1 + static_cast<std::uint32_t>(rng_() % states);
      break;
    }
    case ProfileKind::multisine: {
      const int n = spec_.multisine_components;
      for (int k = 0; k < n; ++k) {
        const double position = n == 1 ? 0.0 : static_cast<double>(k) / (n - 1);
        ms_freq_[k] = spec_.multisine_f_min_hz *
                      std::pow(spec_.multisine_f_max_hz / spec_.multisine_f_min_hz, position);
        const double index = k + 1;  // Schroeder's phases count components from 1
        ms_phase_[k] = -std::numbers::pi * index * (index - 1.0) / n;
      }
      // The seed shifts the signal in time by up to one period of its slowest component, so that
      // sessions of other seeds are other stretches of the same signal (the phases' low crest
      // factor kept).
      const double shift_s = uniform01(rng_) / ms_freq_[0];
      for (int k = 0; k < n; ++k) ms_phase_[k] += kTwoPi * ms_freq_[k] * shift_s;
      ms_scale_ = 1.0;
      const auto magnitude = [this, n](double t) {
        double sum = 0.0;
        for (int k = 0; k < n; ++k) sum += std::sin(kTwoPi * ms_freq_[k] * t + ms_phase_[k]);
        return std::fabs(sum);
      };
      const double f_top = ms_freq_[n - 1];
      const double points = std::min(kMultisineMaxGridPoints,
                                     std::ceil(spec_.duration_s * f_top * kMultisineGridPerPeriod));
      const double h = spec_.duration_s / points;
      double best_t = 0.0;
      double best = magnitude(0.0);
      for (double i = 1.0; i < points; i += 1.0) {
        const double value = magnitude(i * h);
        if (value > best) {
          best = value;
          best_t = i * h;
        }
      }
      // The peak lies within a grid step of the best grid point; golden-section search finds it.
      double lo = std::max(0.0, best_t - h);
      double hi = std::min(spec_.duration_s, best_t + h);
      constexpr double kInvPhi = 0.6180339887498949;
      for (int iteration = 0; iteration < 60; ++iteration) {
        const double a = hi - kInvPhi * (hi - lo);
        const double b = lo + kInvPhi * (hi - lo);
        if (magnitude(a) > magnitude(b)) {
          hi = b;
        } else {
          lo = a;
        }
      }
      best = std::max(best, magnitude(0.5 * (lo + hi)));
      if (!(best > 0.0) || !std::isfinite(best)) {
        reject("multisine_components", "the components cancel out over the duration");
      }
      ms_scale_ = spec_.amplitude_duty / best;
      break;
    }
    case ProfileKind::chirp:
      // The seed picks the sweep's starting phase.
      chirp_phase_ = kTwoPi * uniform01(rng_);
      break;
    case ProfileKind::free_decay:
    case ProfileKind::step:
      break;
  }
}

double Excitation::duty(double t_s, double arm_angle_rad) noexcept {
  // Before the start, after the end, or a NaN time: the motor gets nothing. The loop ends the
  // session at the duration, so this only matters for a caller that runs on past it.
  if (!(t_s >= 0.0) || t_s >= spec_.duration_s) return 0.0;
  const double a = spec_.amplitude_duty;
  double value = 0.0;
  switch (spec_.kind) {
    case ProfileKind::bang_bang: {
      if (spec_.switch_period_s > 0.0) {
        // Every elapsed period flips once, so a loop that skipped cycles stays on the schedule.
        while (t_s >= next_switch_s_) {
          sign_ = -sign_;
          next_switch_s_ += draw_switch_period(spec_, rng_);
        }
      }
      if (spec_.arm_switch_rad > 0.0) {
        // Beyond a threshold the duty points back toward the centre whatever the timer said; when
        // that changes the sign, the timer restarts so the new direction gets a full period.
        // A NaN angle compares false and leaves the sign alone: the supervisor stops on it.
        double toward_centre = sign_;
        if (arm_angle_rad > spec_.arm_switch_rad) {
          toward_centre = -1.0;
        } else if (arm_angle_rad < -spec_.arm_switch_rad) {
          toward_centre = 1.0;
        }
        if (toward_centre != sign_) {
          sign_ = toward_centre;
          if (spec_.switch_period_s > 0.0) {
            next_switch_s_ = t_s + draw_switch_period(spec_, rng_);
          }
        }
      }
      value = sign_ * a;
      break;
    }
    case ProfileKind::free_decay:
      value = 0.0;
      break;
    case ProfileKind::step:
      value = t_s >= spec_.step_time_s ? a : 0.0;
      break;
    case ProfileKind::prbs: {
      const auto bit_index = static_cast<std::int64_t>(t_s / spec_.prbs_bit_period_s);
      while (prbs_bit_index_ < bit_index) {
        const bool bit = (lfsr_ & 1U) != 0;
        lfsr_ >>= 1;
        if (bit) lfsr_ ^= kLfsrMasks[static_cast<std::size_t>(spec_.prbs_order)];
        prbs_value_ = bit ? 1.0 : -1.0;
        ++prbs_bit_index_;
      }
      value = prbs_value_ * a;
      break;
    }
    case ProfileKind::chirp: {
      const double sweep = (spec_.chirp_f1_hz - spec_.chirp_f0_hz) / (2.0 * spec_.duration_s);
      value = a * std::sin(kTwoPi * (spec_.chirp_f0_hz * t_s + sweep * t_s * t_s) + chirp_phase_);
      break;
    }
    case ProfileKind::multisine: {
      double sum = 0.0;
      for (int k = 0; k < spec_.multisine_components; ++k) {
        sum += std::sin(kTwoPi * ms_freq_[k] * t_s + ms_phase_[k]);
      }
      value = ms_scale_ * sum;
      break;
    }
  }
  // The peak search is numerical, so a time between its grid points may land a hair above it.
  return std::clamp(value, -a, a);
}

}  // namespace furuta::daemon
