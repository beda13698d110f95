#include "furuta/control/balance_law.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

namespace furuta::control {

std::string_view to_string(BalanceMode mode) {
  switch (mode) {
    case BalanceMode::swing_up:
      return "swing_up";
    case BalanceMode::catching:
      return "catch";
    case BalanceMode::balance:
      return "balance";
    case BalanceMode::fallen:
      return "fallen";
  }
  return "unknown";
}

BalanceSpecError::BalanceSpecError(std::string field, std::string rule)
    : std::invalid_argument("balance controller: " + field + " " + rule),
      field_(std::move(field)),
      rule_(std::move(rule)) {}

namespace {

void require(bool ok, const std::string& field, const char* rule) {
  if (!ok) throw BalanceSpecError(field, rule);
}

bool finite_positive(double x) {
  return std::isfinite(x) && x > 0;
}

// (-pi, pi]
double wrap_angle(double rad) {
  const double two_pi = 2 * std::numbers::pi;
  double r = std::fmod(rad, two_pi);
  if (r > std::numbers::pi) r -= two_pi;
  if (r <= -std::numbers::pi) r += two_pi;
  return r;
}

}  // namespace

BalanceLaw::BalanceLaw(const BalanceControllerSpec& spec) : spec_(spec) {
  require(finite_positive(spec.period_s), "period_s", "must be a finite number > 0");
  require(spec.delayed >= 0 && spec.delayed <= kMaxDelayedDuties, "delayed",
          "must be 0 to 4 (the lag, in whole periods rounded up)");
  for (const double g : spec.gain) require(std::isfinite(g), "gain", "must be finite numbers");
  for (const double v : spec.observer_gain) {
    require(std::isfinite(v), "observer_gain", "must be finite numbers");
  }
  for (const double v : spec.a_continuous) {
    require(std::isfinite(v), "a_continuous", "must be finite numbers");
  }
  for (const double v : spec.b_continuous) {
    require(std::isfinite(v), "b_continuous", "must be finite numbers");
  }
  // The duties the filter's propagate() looks back on: the lag reaches at most `delayed` samples.
  const DutyPath& path = spec.duty_path;
  require(std::isfinite(path.lag_s) && path.lag_s >= 0 &&
              path.lag_s <= spec.delayed * spec.period_s * (1 + 1e-9),
          "duty_path.lag_s", "must be in [0, delayed periods]");
  require(std::isfinite(path.ramp_duty_per_s) && path.ramp_duty_per_s >= 0,
          "duty_path.ramp_duty_per_s", "must be a finite number >= 0");
  for (std::size_t i = 0; i < 4; ++i) {
    double row = 0;
    for (std::size_t j = 0; j < 4; ++j) row += std::fabs(spec.a_continuous[i * 4 + j]);
    a_norm_ = std::max(a_norm_, row);
  }
  for (int i = 4 + spec.delayed; i < kMaxGains; ++i) {
    require(spec.gain[static_cast<std::size_t>(i)] == 0, "gain",
            "has more entries than the state (4 plus the delayed duties)");
  }
  require(finite_positive(spec.max_duty) && spec.max_duty <= 1, "max_duty", "must be in (0, 1]");
  require(finite_positive(spec.duty_step) && spec.duty_step <= spec.max_duty, "duty_step",
          "must be in (0, max_duty]");
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    const double v = spec.parameters[i];
    const bool friction = i >= 5;
    require(std::isfinite(v) && (friction ? v >= 0 : v > 0),
            std::string("parameters.") + model::kParameterNames[i],
            friction ? "must be a finite number >= 0" : "must be a finite number > 0");
  }
  require(finite_positive(spec.duty_torque_nm), "duty_torque_nm", "must be a finite number > 0");
  require(std::isfinite(spec.back_emf_nm_s) && spec.back_emf_nm_s >= 0, "back_emf_nm_s",
          "must be a finite number >= 0");
  const SwingUp& s = spec.swing_up;
  for (const auto& [value, name] : {std::pair{s.energy_gain, "swing_up.energy_gain"},
                                    std::pair{s.arm_gain, "swing_up.arm_gain"},
                                    std::pair{s.arm_damping, "swing_up.arm_damping"}}) {
    require(std::isfinite(value) && value >= 0, name, "must be a finite number >= 0");
  }
  require(std::isfinite(s.energy_margin) && s.energy_margin >= 0 && s.energy_margin < 1,
          "swing_up.energy_margin", "must be in [0, 1)");
  require(finite_positive(s.max_acceleration), "swing_up.max_acceleration",
          "must be a finite number > 0");
  require(finite_positive(s.pump_arm_rad) && s.pump_arm_rad < std::numbers::pi,
          "swing_up.pump_arm_rad", "must be in (0, pi)");
  require(finite_positive(s.start_acceleration) && s.start_acceleration <= s.max_acceleration,
          "swing_up.start_acceleration", "must be in (0, max_acceleration]");
  require(std::isfinite(s.start_below_energy_ratio) && s.start_below_energy_ratio >= 0 &&
              s.start_below_energy_ratio < 1,
          "swing_up.start_below_energy_ratio", "must be in [0, 1)");
  require(finite_positive(s.max_duty) && s.max_duty <= spec.max_duty, "swing_up.max_duty",
          "must be in (0, the controller's max_duty]");
  const CatchRegion& r = spec.region;
  require(finite_positive(r.catch_rad) && r.catch_rad < std::numbers::pi / 2, "region.catch_rad",
          "must be in (0, pi/2)");
  require(finite_positive(r.entry_duty_ratio) && r.entry_duty_ratio <= 1, "region.entry_duty_ratio",
          "must be in (0, 1]");
  require(std::isfinite(r.release_rad) && r.release_rad > r.catch_rad &&
              r.release_rad < std::numbers::pi,
          "region.release_rad", "must be in (catch_rad, pi)");
  require(std::isfinite(r.settle_s) && r.settle_s >= 0, "region.settle_s",
          "must be a finite number >= 0");
  require(std::isfinite(r.fall_rad) && r.fall_rad >= r.catch_rad && r.fall_rad < std::numbers::pi,
          "region.fall_rad", "must be in [catch_rad, pi)");
}

void BalanceLaw::reset() noexcept {
  clock_s_ = 0;
  arm_ = {};
  pendulum_ = {};
  mode_ = BalanceMode::swing_up;
  inside_s_ = 0;
  start_s_ = 0;
  arm_velocity_ = 0;
  estimating_ = false;
  estimate_.fill(0.0);
  sent_.fill(0.0);
  applied_ = 0;
}

BalanceStep BalanceLaw::start_catch(const std::array<double, 4>& estimate) noexcept {
  reset();
  const double t = spec_.period_s;
  arm_.add(estimate[0], 0.0);
  arm_.rate = estimate[2];
  pendulum_.add(estimate[1] + std::numbers::pi, 0.0);
  pendulum_.rate = estimate[3];
  clock_s_ = t;
  mode_ = BalanceMode::catching;
  estimating_ = true;
  estimate_ = estimate;
  BalanceStep out;
  out.mode = mode_;
  out.upright_error_rad = estimate[1];
  out.arm_rate_rad_s = estimate[2];
  out.pendulum_rate_rad_s = estimate[3];
  const model::Parameters<double>& p = spec_.parameters;
  out.energy_ratio =
      (0.5 * p.mu4 * estimate[3] * estimate[3] + p.mug * (1 + std::cos(estimate[1]))) / (2 * p.mug);
  out.duty = limit(gain_duty(estimate_));
  sent_.back() = out.duty;
  return out;
}

BalanceLaw::Carried BalanceLaw::propagate(const std::array<double, 4>* x, double applied,
                                          double after_s) const noexcept {
  // The duty sent n samples before the last reaches the board at lag - n T from the last sample
  // and is its target until the next one does: over [0, after_s] the board takes, in turn, the
  // duties of n = ceil(lag / T) down to 0, and its applied duty ramps to each. In every stretch
  // the applied duty is affine in time (ramping, or there), and the state's motion exact.
  const double t = spec_.period_s;
  const double lag = spec_.duty_path.lag_s;
  const double rate = spec_.duty_path.ramp_duty_per_s;
  const int oldest = lag > 0 ? std::min(static_cast<int>(std::ceil(lag / t - 1e-9)),
                                        static_cast<int>(sent_.size()) - 1)
                             : 0;
  Carried out;
  if (x != nullptr) out.x = *x;
  out.applied = applied;
  // dx/dt = a x + b u, du/dt = slope over `length` s: the Taylor series of the exact solution, in
  // sub-steps short enough (|a| h <= 1) that its terms fall below the double's rounding within 24.
  const auto integrate = [&](double length, double slope) {
    if (x != nullptr) {
      const int steps = std::max(1, static_cast<int>(std::ceil(a_norm_ * length)));
      const double h = length / steps;
      for (int step = 0; step < steps; ++step) {
        const double u0 = out.applied + slope * h * step;
        std::array<double, 4> term = out.x;
        for (int order = 1; order <= 24; ++order) {
          // The input's Taylor terms: u0, then slope h, then none.
          const double input = order == 1 ? u0 : order == 2 ? slope * h : 0.0;
          std::array<double, 4> next{};
          double largest = 0;
          double size = 0;
          for (std::size_t i = 0; i < 4; ++i) {
            double v = spec_.b_continuous[i] * input;
            for (std::size_t j = 0; j < 4; ++j) v += spec_.a_continuous[i * 4 + j] * term[j];
            next[i] = v * h / order;
            out.x[i] += next[i];
            largest = std::max(largest, std::fabs(next[i]));
            size = std::max(size, std::fabs(out.x[i]));
          }
          term = next;
          if (order > 2 && largest <= 1e-17 * size) break;
        }
      }
    }
    out.applied += slope * length;
  };
  for (int n = oldest; n >= 0; --n) {
    const double from = std::max(0.0, lag - n * t);
    const double to = n == 0 ? after_s : std::min(after_s, lag - (n - 1) * t);
    if (!(to > from)) continue;
    const double target = sent_[sent_.size() - 1 - static_cast<std::size_t>(n)];
    if (!(rate > 0)) {
      out.applied = target;
      integrate(to - from, 0.0);
      continue;
    }
    const double gap = target - out.applied;
    const double reach_s = std::fabs(gap) / rate;
    if (reach_s >= to - from) {
      integrate(to - from, std::copysign(rate, gap));
      continue;
    }
    if (reach_s > 0) integrate(reach_s, std::copysign(rate, gap));
    out.applied = target;
    integrate(to - from - reach_s, 0.0);
  }
  return out;
}

void BalanceLaw::estimate(double q1, double error, double dq1, double dq2,
                          const ReadingTimes& times) noexcept {
  if (!estimating_) {
    // The first cycle near upright starts from the angles and the differences.
    estimate_ = {q1, error, dq1, dq2};
    estimating_ = true;
    return;
  }
  // estimate_ is x^- at the last sample; the angles were read since (their age before this
  // sample, T - age after the last), each compared with the model's angle at that instant.
  const double t = spec_.period_s;
  const auto innovation = [&](bool fresh, double age_s, std::size_t angle, double measured) {
    if (!fresh || !std::isfinite(age_s)) return 0.0;
    const double after = std::clamp(t - age_s, 0.0, 2 * t);
    return measured - propagate(&estimate_, applied_, after).x[angle];
  };
  const double innovation_arm = innovation(times.arm_fresh, times.arm_age_s, 0, q1);
  const double innovation_pendulum =
      innovation(times.pendulum_fresh, times.pendulum_age_s, 1, error);
  std::array<double, 4> corrected{};
  for (std::size_t i = 0; i < 4; ++i) {
    corrected[i] = estimate_[i] + spec_.observer_gain[i * 2] * innovation_arm +
                   spec_.observer_gain[i * 2 + 1] * innovation_pendulum;
  }
  estimate_ = propagate(&corrected, applied_, t).x;
}

double BalanceLaw::limit(double duty) const noexcept {
  if (!std::isfinite(duty)) return 0.0;
  const double steps = std::round(duty / spec_.duty_step);
  const double max_steps = std::floor(spec_.max_duty / spec_.duty_step + 1e-9);
  return std::clamp(steps, -max_steps, max_steps) * spec_.duty_step;
}

double BalanceLaw::gain_duty(const std::array<double, 4>& x) const noexcept {
  double duty = 0;
  for (std::size_t i = 0; i < 4; ++i) duty -= spec_.gain[i] * x[i];
  const auto delayed = static_cast<std::size_t>(spec_.delayed);
  for (std::size_t i = 0; i < delayed; ++i) {
    duty -= spec_.gain[4 + i] * sent_[sent_.size() - delayed + i];
  }
  return duty;
}

void BalanceLaw::Difference::add(double new_angle, double new_read_s) noexcept {
  if (have && new_read_s > read_s) rate = (new_angle - angle) / (new_read_s - read_s);
  have = true;
  angle = new_angle;
  read_s = new_read_s;
}

BalanceStep BalanceLaw::step(double q1, double q2, const ReadingTimes& times) noexcept {
  BalanceStep out;
  const double t = spec_.period_s;
  // Each angle counts as read when its board read it: a missing or non-finite age, as now.
  const auto read_at = [&](double age_s) {
    return clock_s_ - (std::isfinite(age_s) ? age_s : 0.0);
  };
  if (times.arm_fresh || !arm_.have) arm_.add(q1, read_at(times.arm_age_s));
  if (times.pendulum_fresh || !pendulum_.have) pendulum_.add(q2, read_at(times.pendulum_age_s));
  clock_s_ += t;
  const double dq1 = arm_.rate;
  const double dq2 = pendulum_.rate;
  const double error = wrap_angle(q2 - std::numbers::pi);
  const model::Parameters<double>& p = spec_.parameters;
  const double mug = p.mug;
  const double energy = 0.5 * p.mu4 * dq2 * dq2 + mug * (1 - std::cos(q2));
  const double upright_energy = 2 * mug;
  out.upright_error_rad = error;
  out.arm_rate_rad_s = dq1;
  out.pendulum_rate_rad_s = dq2;
  out.energy_ratio = energy / upright_energy;

  const CatchRegion& region = spec_.region;
  const double distance = std::fabs(error);
  switch (mode_) {
    case BalanceMode::swing_up:
      if (distance < region.catch_rad &&
          std::fabs(gain_duty({q1, error, dq1, dq2})) <= region.entry_duty_ratio * spec_.max_duty) {
        mode_ = BalanceMode::catching;
        inside_s_ = 0;
      }
      break;
    case BalanceMode::catching:
      if (distance > region.release_rad) {
        mode_ = BalanceMode::swing_up;
        arm_velocity_ = dq1;
      } else {
        inside_s_ = distance < region.catch_rad ? inside_s_ + t : 0.0;
        if (inside_s_ >= region.settle_s) mode_ = BalanceMode::balance;
      }
      break;
    case BalanceMode::balance:
      if (distance > region.fall_rad) mode_ = BalanceMode::fallen;
      break;
    case BalanceMode::fallen:
      break;
  }
  out.mode = mode_;

  double duty = 0;
  if (mode_ == BalanceMode::swing_up) {
    estimating_ = false;
    const SwingUp& s = spec_.swing_up;
    const double phase = dq2 * std::cos(q2);
    // Aiming a little above E0 brings the pendulum over the top at a walking pace, into the
    // catch region, where aiming at E0 itself approaches upright ever more slowly and any loss
    // or bias in the estimated energy leaves the swing short of it.
    const double target = upright_energy * (1 + s.energy_margin);
    double pump = s.energy_gain * (target - energy) * (phase > 0 ? -1.0 : 1.0);
    if (out.energy_ratio < s.start_below_energy_ratio) {
      const double natural_rad_s = std::sqrt(p.mug / p.mu4);
      pump = std::sin(natural_rad_s * start_s_) >= 0 ? s.start_acceleration : -s.start_acceleration;
      start_s_ += t;
    } else if (std::fabs(q1) > s.pump_arm_rad && pump * q1 > 0) {
      pump = 0;
    }
    // The arm follows a duty like a velocity (its time constant, mu1 / kw, is a fraction of the
    // period): the acceleration is integrated into a velocity the duty holds, the back-EMF and
    // friction at that velocity plus the inertia's share, rather than fed back through the
    // measured velocity, which lags by half a period.
    const double acceleration = std::clamp(pump, -s.max_acceleration, s.max_acceleration) -
                                s.arm_gain * q1 - s.arm_damping * arm_velocity_;
    arm_velocity_ += acceleration * t;
    duty = ((spec_.back_emf_nm_s + p.fv1) * arm_velocity_ + p.mu1 * acceleration) /
           spec_.duty_torque_nm;
    duty = std::clamp(duty, -s.max_duty, s.max_duty);
  } else if (mode_ == BalanceMode::catching || mode_ == BalanceMode::balance) {
    // The gain on the filter's state, started from the angles and differences at the catch: a
    // difference lags by half a period and more (a board's report is up to a period old), and
    // catching, the duty swings far, where the board's ramp, which the filter follows, is slow
    // against the period.
    estimate(q1, error, dq1, dq2, times);
    out.arm_rate_rad_s = estimate_[2];
    out.pendulum_rate_rad_s = estimate_[3];
    duty = gain_duty(estimate_);
  } else {
    estimating_ = false;
  }
  out.duty = limit(duty);
  // The board's applied duty at this sample, from the duties it took since the last.
  applied_ = propagate(nullptr, applied_, t).applied;
  for (std::size_t i = 0; i + 1 < sent_.size(); ++i) sent_[i] = sent_[i + 1];
  sent_.back() = out.duty;
  return out;
}

}  // namespace furuta::control
