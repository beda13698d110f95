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
  for (const double v : spec.phi) require(std::isfinite(v), "phi", "must be finite numbers");
  for (const double v : spec.gamma) require(std::isfinite(v), "gamma", "must be finite numbers");
  for (const double v : spec.observer_gain) {
    require(std::isfinite(v), "observer_gain", "must be finite numbers");
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
  require(std::isfinite(r.release_rad) && r.release_rad > r.catch_rad &&
              r.release_rad < std::numbers::pi,
          "region.release_rad", "must be in (catch_rad, pi)");
  require(std::isfinite(r.settle_s) && r.settle_s >= 0, "region.settle_s",
          "must be a finite number >= 0");
  require(std::isfinite(r.fall_rad) && r.fall_rad >= r.catch_rad && r.fall_rad < std::numbers::pi,
          "region.fall_rad", "must be in [catch_rad, pi)");
}

void BalanceLaw::reset() noexcept {
  have_previous_ = false;
  previous_q1_ = previous_q2_ = 0;
  mode_ = BalanceMode::swing_up;
  inside_s_ = 0;
  start_s_ = 0;
  arm_velocity_ = 0;
  estimating_ = false;
  estimate_.fill(0.0);
  sent_.fill(0.0);
}

void BalanceLaw::estimate(double q1, double error, double dq1, double dq2, double arm_age_s,
                          double pendulum_age_s) noexcept {
  if (!estimating_) {
    // The first cycle near upright starts from the angles and the differences.
    estimate_ = {q1, error, dq1, dq2};
    estimating_ = true;
    return;
  }
  // z[k - 1] = [x^[k - 1]; u[k - 1 - d], ..., u[k - 2]], u[k - 1] the newest duty sent.
  const auto delayed = static_cast<std::size_t>(spec_.delayed);
  std::array<double, kMaxGains> previous{};
  for (std::size_t i = 0; i < 4; ++i) previous[i] = estimate_[i];
  for (std::size_t i = 0; i < delayed; ++i) {
    previous[4 + i] = sent_[sent_.size() - 1 - delayed + i];
  }
  const double newest = sent_.back();
  std::array<double, 4> predicted{};
  for (std::size_t i = 0; i < 4; ++i) {
    double v = spec_.gamma[i] * newest;
    for (std::size_t j = 0; j < 4 + delayed; ++j) v += spec_.phi[i * kMaxGains + j] * previous[j];
    predicted[i] = v;
  }
  // Each angle was read `age` before this instant: the prediction taken back to then along the
  // model (second order in the age, the duty applied now held), x(t - a) = x - a x' + a^2 / 2 x''.
  std::array<double, 4> rate{};
  for (std::size_t i = 0; i < 4; ++i) {
    double v = spec_.b_continuous[i] * newest;
    for (std::size_t j = 0; j < 4; ++j) v += spec_.a_continuous[i * 4 + j] * predicted[j];
    rate[i] = v;
  }
  const auto back = [&](std::size_t angle, double age) {
    if (!(age > 0) || !std::isfinite(age)) return predicted[angle];
    return predicted[angle] - age * rate[angle] + 0.5 * age * age * rate[angle + 2];
  };
  const double innovation_arm = q1 - back(0, arm_age_s);
  const double innovation_pendulum = error - back(1, pendulum_age_s);
  for (std::size_t i = 0; i < 4; ++i) {
    estimate_[i] = predicted[i] + spec_.observer_gain[i * 2] * innovation_arm +
                   spec_.observer_gain[i * 2 + 1] * innovation_pendulum;
  }
}

double BalanceLaw::limit(double duty) const noexcept {
  if (!std::isfinite(duty)) return 0.0;
  const double steps = std::round(duty / spec_.duty_step);
  const double max_steps = std::floor(spec_.max_duty / spec_.duty_step + 1e-9);
  return std::clamp(steps, -max_steps, max_steps) * spec_.duty_step;
}

BalanceStep BalanceLaw::step(double q1, double q2, double arm_age_s,
                             double pendulum_age_s) noexcept {
  BalanceStep out;
  const double t = spec_.period_s;
  const double dq1 = have_previous_ ? (q1 - previous_q1_) / t : 0.0;
  const double dq2 = have_previous_ ? (q2 - previous_q2_) / t : 0.0;
  have_previous_ = true;
  previous_q1_ = q1;
  previous_q2_ = q2;
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
      if (distance < region.catch_rad) {
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
    // Catching, the pendulum may be far from where the linear model holds and fast: the
    // differences. Balancing, near upright, the filter, started from the differences.
    std::array<double, 4> x = {q1, error, dq1, dq2};
    if (mode_ == BalanceMode::balance) {
      estimate(q1, error, dq1, dq2, arm_age_s, pendulum_age_s);
      x = estimate_;
      out.arm_rate_rad_s = x[2];
      out.pendulum_rate_rad_s = x[3];
    }
    for (std::size_t i = 0; i < 4; ++i) duty -= spec_.gain[i] * x[i];
    const auto delayed = static_cast<std::size_t>(spec_.delayed);
    for (std::size_t i = 0; i < delayed; ++i) {
      duty -= spec_.gain[4 + i] * sent_[sent_.size() - delayed + i];
    }
  } else {
    estimating_ = false;
  }
  out.duty = limit(duty);
  for (std::size_t i = 0; i + 1 < sent_.size(); ++i) sent_[i] = sent_[i + 1];
  sent_.back() = out.duty;
  return out;
}

}  // namespace furuta::control
