#include "furuta/verification/sampled_loop.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "furuta/model/dynamics.hpp"

namespace furuta::verification {

namespace {

model::PendulumState absolute(const std::array<double, 4>& x) {
  return {x[0], x[2], x[1] + std::numbers::pi, x[3]};
}

std::array<double, 4> relative(const model::PendulumState& s) {
  return {s.q1, s.q2 - std::numbers::pi, s.dq1, s.dq2};
}

// The angle rounded to the nearest whole count from `offset` counts.
double reading(double angle, double count, double offset) {
  return (std::round(angle / count - offset) + offset) * count;
}

}  // namespace

LoopTrajectory simulate_loop(const control::BalanceControllerSpec& spec, const LoopModel& loop,
                             const LoopPoint& point, double horizon_s, int steps_per_period) {
  control::BalanceLaw law(spec);
  const double period = spec.period_s;
  const double h_max = period / std::max(1, steps_per_period);
  const double rate = loop.ramp_duty_per_s;
  LoopTrajectory out;
  model::PendulumState x = absolute(point.state);
  const control::BalanceStep first = law.start_catch(point.estimate);
  out.samples.push_back(
      {0.0, point.state, first.duty, first.arm_rate_rad_s, first.pendulum_rate_rad_s, first.mode});
  double applied = 0;
  double old_target = 0;
  double new_target = first.duty;
  const auto periods = static_cast<std::size_t>(std::ceil(horizon_s / period - 1e-9));
  double arm_read = 0;
  double pendulum_read = 0;
  for (std::size_t k = 0; k < periods; ++k) {
    const double t0 = static_cast<double>(k) * period;
    const double read_at = period - loop.reading_age_s;
    // Over [from, to] with `target` as the board's: ramps, then holds.
    double now = 0;
    const auto take_readings = [&] {
      arm_read = reading(x.q1, loop.arm_count_rad, point.arm_count_offset);
      pendulum_read = reading(x.q2, loop.pendulum_count_rad, point.pendulum_count_offset);
    };
    if (read_at <= 0) take_readings();
    const auto advance = [&](double to, double target) {
      while (now < to) {
        double end = to;
        double slope = 0;
        bool reaches = false;
        if (applied != target) {
          if (!(rate > 0)) {
            applied = target;
            continue;
          }
          slope = std::copysign(rate, target - applied);
          const double reach_at = now + std::fabs(target - applied) / rate;
          if (reach_at <= to) {
            end = reach_at;
            reaches = true;
          }
        }
        // The readings' instant splits a stretch so that the angles are taken there.
        const bool reads = now < read_at && read_at <= end;
        if (reads && read_at < end) {
          end = read_at;
          reaches = false;
        }
        const double length = end - now;
        const int steps = std::max(1, static_cast<int>(std::ceil(length / h_max - 1e-9)));
        const double h = length / steps;
        for (int i = 0; i < steps; ++i) {
          const double u0 = applied + slope * h * i;
          x = model::rk4_step(point.parameters, x, h,
                              [&](const model::PendulumState& s, double fraction) {
                                return point.duty_torque_nm * (u0 + slope * h * fraction) -
                                       point.back_emf_nm_s * s.dq1;
                              });
          out.inner_t_s.push_back(t0 + now + h * (i + 1));
          out.inner_state.push_back(relative(x));
        }
        applied = reaches ? target : applied + slope * length;
        now = end;
        if (reads) take_readings();
      }
    };
    advance(std::min(point.lag_s, period), old_target);
    advance(period, new_target);
    const control::ReadingTimes times{loop.reading_age_s, loop.reading_age_s, true, true};
    const control::BalanceStep step = law.step(arm_read, pendulum_read, times);
    out.samples.push_back({t0 + period, relative(x), step.duty, step.arm_rate_rad_s,
                           step.pendulum_rate_rad_s, step.mode});
    old_target = new_target;
    new_target = step.duty;
  }
  return out;
}

TubeCheck check_inside(const BalanceCertificate& certificate, const LoopTrajectory& trajectory) {
  TubeCheck out;
  const std::vector<LoopStepBox>& steps = certificate.steps;
  if (steps.empty()) return out;
  const double period = steps.front().t1_s - steps.front().t0_s;
  const auto note = [&](bool inside, double t_s) {
    ++out.checks;
    if (!inside) {
      ++out.outside;
      if (std::isnan(out.first_outside_s)) out.first_outside_s = t_s;
    }
  };
  // Sample k (k >= 1) closes step k - 1.
  for (const LoopSample& s : trajectory.samples) {
    const auto k = static_cast<std::size_t>(std::llround(s.t_s / period));
    if (k == 0 || k > steps.size()) continue;
    const LoopStepBox& box = steps[k - 1];
    for (std::size_t i = 0; i < 4; ++i) note(box.at_end[i].contains(s.state[i]), s.t_s);
    note(box.duty.contains(s.duty), s.t_s);
    note(box.estimate[2].contains(s.arm_rate_rad_s), s.t_s);
    note(box.estimate[3].contains(s.pendulum_rate_rad_s), s.t_s);
  }
  for (std::size_t j = 0; j < trajectory.inner_t_s.size(); ++j) {
    const double t = trajectory.inner_t_s[j];
    // An instant on a sample belongs to both periods: the earlier one's box holds it.
    const auto k = static_cast<std::size_t>(std::ceil(t / period - 1e-9));
    if (k == 0 || k > steps.size()) continue;
    const LoopStepBox& box = steps[k - 1];
    for (std::size_t i = 0; i < 4; ++i) note(box.over[i].contains(trajectory.inner_state[j][i]), t);
  }
  return out;
}

SampledCheck sampled_check(const control::BalanceControllerSpec& law, const LoopModel& loop,
                           const LoopStart& start, const BalanceCertificate& certificate,
                           std::size_t count, std::size_t draw, unsigned seed,
                           int steps_per_period) {
  SampledCheck out;
  if (certificate.steps.empty()) return out;
  const double horizon = certificate.steps.back().t1_s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // A corner (bit 0 or 1) or, with bit -1, a point inside at random.
  const auto pick = [&](const Interval& v, int bit) {
    if (bit < 0) return v.lo() + unit(rng) * (v.hi() - v.lo());
    return bit ? v.hi() : v.lo();
  };
  constexpr std::size_t kCorners = 32;
  for (std::size_t n = 0; n < count; ++n) {
    const bool corner = n < kCorners;
    const auto bit = [&](int k) { return corner ? static_cast<int>((n >> k) & 1u) : -1; };
    const auto coin = [&] { return corner ? static_cast<int>(unit(rng) < 0.5) : -1; };
    LoopPoint point;
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      const int b = k == 0 ? bit(0) : k == 2 ? bit(1) : k == 3 ? bit(2) : coin();
      point.parameters[k] = pick(loop.parameters[k], b);
    }
    point.duty_torque_nm = pick(loop.duty_torque_nm, coin());
    point.back_emf_nm_s = pick(loop.back_emf_nm_s, coin());
    point.lag_s = pick(loop.lag_s, coin());
    point.arm_count_offset = unit(rng) - 0.5;
    point.pendulum_count_offset = unit(rng) - 0.5;
    for (std::size_t i = 0; i < 4; ++i) {
      const int b = i == 1 ? bit(3) : i == 3 ? bit(4) : coin();
      point.state[i] = pick(start.state[i], b);
      point.estimate[i] = point.state[i] + pick(start.estimate_error[i], coin());
    }
    LoopTrajectory trajectory = simulate_loop(law, loop, point, horizon, steps_per_period);
    const TubeCheck check = check_inside(certificate, trajectory);
    ++out.trajectories;
    out.check.checks += check.checks;
    out.check.outside += check.outside;
    if (!std::isnan(check.first_outside_s) && (std::isnan(out.check.first_outside_s) ||
                                               check.first_outside_s < out.check.first_outside_s)) {
      out.check.first_outside_s = check.first_outside_s;
    }
    if (out.drawn.size() < draw) out.drawn.push_back(std::move(trajectory));
  }
  return out;
}

}  // namespace furuta::verification
