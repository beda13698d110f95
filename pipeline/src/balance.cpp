#include "furuta/pipeline/balance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>
#include <utility>

#include "furuta/config/controller_file.hpp"

namespace furuta::pipeline {

std::optional<BalanceSummary> summarize_balance(const session_log::SessionLog& log) {
  if (log.control.empty()) return std::nullopt;
  constexpr double kDeg = 180.0 / std::numbers::pi;
  std::unordered_map<std::int64_t, const furuta::rig_sample_t*> sample_of;
  for (const furuta::rig_sample_t& s : log.samples) sample_of[s.seq] = &s;
  const std::int64_t start_ns =
      log.start ? log.start->monotonic_ns : log.control.front().monotonic_ns;
  BalanceSummary out;
  double sum_error2 = 0;
  double sum_duty2 = 0;
  std::int64_t balance_cycles = 0;
  std::vector<std::int64_t> law_ns;
  std::optional<double> catch_began;
  for (const furuta::rig_control_t& c : log.control) {
    const auto found = sample_of.find(c.seq);
    if (found == sample_of.end()) continue;  // the sample was lost: its cycle is not counted
    const furuta::rig_sample_t& s = *found->second;
    const double t = static_cast<double>(c.monotonic_ns - start_ns) * 1e-9;
    ++out.cycles;
    out.time_s.push_back(t);
    out.mode.push_back(c.mode);
    out.upright_error_deg.push_back(c.upright_error_rad * kDeg);
    out.arm_deg.push_back(s.arm_angle_rad * kDeg);
    out.duty.push_back(s.commanded_duty);
    out.max_abs_duty = std::max(out.max_abs_duty, std::fabs(s.commanded_duty));
    out.max_abs_arm_deg = std::max(out.max_abs_arm_deg, std::fabs(s.arm_angle_rad) * kDeg);
    law_ns.push_back(c.law_time_ns);
    if (c.mode == furuta::rig_control_t::MODE_SWING_UP) catch_began.reset();
    if (c.mode == furuta::rig_control_t::MODE_CATCH && !catch_began) catch_began = t;
    if (c.mode == furuta::rig_control_t::MODE_BALANCE) {
      ++balance_cycles;
      sum_error2 += c.upright_error_rad * c.upright_error_rad;
      sum_duty2 += s.commanded_duty * s.commanded_duty;
      out.upright_max_deg = std::max(out.upright_max_deg, std::fabs(c.upright_error_rad) * kDeg);
    }
  }
  // A catch that never reached balance (the session ended while catching) still counts as caught
  // from its start; one that fell back to swinging up does not.
  out.caught_at_s = catch_began;
  const double period_s = log.start ? static_cast<double>(log.start->period_ns) * 1e-9 : 0.0;
  out.balanced_s = static_cast<double>(balance_cycles) * period_s;
  if (balance_cycles > 0) {
    out.upright_rms_deg = std::sqrt(sum_error2 / static_cast<double>(balance_cycles)) * kDeg;
    out.duty_rms = std::sqrt(sum_duty2 / static_cast<double>(balance_cycles));
  }
  // The end reason may carry its detail after the kind ("pendulum_fell: beyond the fall limit").
  if (log.end) out.end_reason = log.end->end_reason;
  out.fell = out.end_reason.rfind("pendulum_fell", 0) == 0;
  if (!law_ns.empty()) {
    std::sort(law_ns.begin(), law_ns.end());
    out.law_time_p50_ns = law_ns[law_ns.size() / 2];
    out.law_time_max_ns = law_ns.back();
  }
  if (log.controller) {
    BalanceController c;
    c.path = log.controller->path;
    c.sha256 = log.controller->sha256;
    // The file as the loop read it; one that no longer reads (a newer format) still names itself
    // by path and digest.
    try {
      const config::ControllerFile file =
          config::parse_controller_file(log.controller->controller_toml, c.path);
      c.parameters_source = file.parameters_source;
      c.results = file.results;
      c.rig = file.rig;
    } catch (const config::ConfigError& e) {
      c.unreadable = e.what();
    }
    out.controller = std::move(c);
  }
  return out;
}

}  // namespace furuta::pipeline
