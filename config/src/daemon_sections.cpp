// rig.toml's sections for the daemon: [daemon], [daemon.realtime], [safety], [limits],
// [excitation].
#include <cmath>
#include <sstream>
#include <string>

#include "sections.hpp"

namespace furuta::config::detail {

namespace {

void read_realtime(Section rt, DaemonConfig& dc) {
  dc.realtime = rt.boolean("enabled", dc.realtime);
  dc.fifo_priority = static_cast<int>(rt.integer(
      "fifo_priority", dc.fifo_priority, [](std::int64_t v) { return v >= 1 && v <= 99; },
      "in [1, 99]"));
  dc.cpu = static_cast<int>(rt.integer(
      "cpu", dc.cpu, [](std::int64_t v) { return v >= -1 && v < 1024; }, ">= -1"));
  dc.lock_memory = rt.boolean("lock_memory", dc.lock_memory);
  rt.reject_unknown_keys();
}

// [safety]'s supply voltage range, min below max.
void read_supply_range(Section& s, SafetyConfig& sc) {
  sc.min_supply_v = s.number("min_supply_v", sc.min_supply_v, non_negative, ">= 0");
  sc.max_supply_v = s.number("max_supply_v", sc.max_supply_v, positive, "> 0");
  if (sc.max_supply_v <= sc.min_supply_v) {
    // Blame the value the file gave: a min_supply_v above the default max is the min's fault.
    if (s.has("max_supply_v") || !s.has("min_supply_v")) {
      s.fail("max_supply_v", s.node("max_supply_v"), "must be above min_supply_v");
    }
    s.fail("min_supply_v", s.node("min_supply_v"), "must be below max_supply_v");
  }
}

// [excitation]'s step, PRBS, chirp and multisine shapes.
void read_profile_shapes(Section& e, ExcitationConfig& ec) {
  ec.step_time_s = e.number("step_time_s", ec.step_time_s, non_negative, ">= 0");
  ec.prbs_bit_period_s = e.number("prbs_bit_period_s", ec.prbs_bit_period_s, positive, "> 0");
  ec.prbs_order = static_cast<int>(e.integer(
      "prbs_order", ec.prbs_order, [](std::int64_t v) { return v >= 2 && v <= 16; }, "in [2, 16]"));
  ec.chirp_f0_hz = e.number("chirp_f0_hz", ec.chirp_f0_hz, non_negative, ">= 0");
  ec.chirp_f1_hz = e.number("chirp_f1_hz", ec.chirp_f1_hz, positive, "> 0");
  ec.multisine_components = static_cast<int>(e.integer(
      "multisine_components", ec.multisine_components,
      [](std::int64_t v) { return v >= 1 && v <= 16; }, "in [1, 16]"));
  ec.multisine_f_min_hz = e.number("multisine_f_min_hz", ec.multisine_f_min_hz, positive, "> 0");
  ec.multisine_f_max_hz = e.number("multisine_f_max_hz", ec.multisine_f_max_hz, positive, "> 0");
}

}  // namespace

DaemonConfig read_daemon(Section d) {
  DaemonConfig dc;
  const double period_ms = d.number(
      "period_ms", 16.0, [](double v) { return v >= 0.1 && v <= 1000.0; }, "in [0.1, 1000]");
  dc.period_ns = std::llround(period_ms * 1e6);
  dc.lcm_url = d.text("lcm_url", dc.lcm_url);
  dc.logs_dir = d.text("logs_dir", dc.logs_dir);
  if (dc.logs_dir.empty()) d.fail("logs_dir", d.node("logs_dir"), "must not be empty");
  dc.flush_interval_ms = d.integer(
      "flush_interval_ms", dc.flush_interval_ms,
      [](std::int64_t v) { return v >= 10 && v <= 60'000; }, "in [10, 60000]");
  dc.rest_check_s = d.number(
      "rest_check_s", dc.rest_check_s, [](double v) { return v >= 0 && v <= 60; }, "in [0, 60]");
  dc.reconnect_interval_ms = d.integer(
      "reconnect_interval_ms", dc.reconnect_interval_ms,
      [](std::int64_t v) { return v >= 10 && v <= 10'000; }, "in [10, 10000]");
  dc.queue_capacity = d.integer(
      "queue_capacity", dc.queue_capacity, [](std::int64_t v) { return v >= 64 && v <= 1'000'000; },
      "in [64, 1000000]");
  dc.command_key_file = d.text("command_key_file", dc.command_key_file);
  if (dc.command_key_file.empty())
    d.fail("command_key_file", d.node("command_key_file"), "must not be empty");
  dc.command_window_s = d.number(
      "command_window_s", dc.command_window_s, [](double v) { return v >= 1 && v <= 3600; },
      "in [1, 3600]");
  dc.command_clock_skew_s = d.number(
      "command_clock_skew_s", dc.command_clock_skew_s, [](double v) { return v >= 0 && v <= 60; },
      "in [0, 60]");
  for (auto [key, value] : {std::pair{"command_state_file", &dc.command_state_file},
                            std::pair{"daemon_key_file", &dc.daemon_key_file},
                            std::pair{"daemon_public_key_file", &dc.daemon_public_key_file}}) {
    *value = d.text(key, *value);
    if (value->empty()) d.fail(key, d.node(key), "must not be empty");
  }
  read_realtime(d.child("realtime"), dc);
  d.reject_unknown_keys();
  return dc;
}

// Safety limits have no silent defaults from a typo: unknown keys are rejected, and each value is
// range-checked.
SafetyConfig read_safety(Section s, const DaemonConfig& daemon) {
  SafetyConfig sc;
  sc.arm_limit_rad = s.number(
                         "arm_limit_deg", sc.arm_limit_rad / kDegToRad,
                         [](double v) { return v > 0 && v <= 720; }, "in (0, 720]") *
                     kDegToRad;
  sc.max_duty = s.number("max_duty", sc.max_duty, fraction, "in (0, 1]");
  sc.stale_report_cycles = static_cast<int>(s.integer(
      "stale_report_cycles", sc.stale_report_cycles,
      [](std::int64_t v) { return v >= 1 && v <= 1000; }, "in [1, 1000]"));
  // The boards report every 8 ms: fewer than two report periods of silence is not a fault.
  if (static_cast<double>(sc.stale_report_cycles) * static_cast<double>(daemon.period_ns) < 16e6) {
    s.fail("stale_report_cycles", s.node("stale_report_cycles"),
           std::to_string(sc.stale_report_cycles) + " cycles of " +
               std::to_string(daemon.period_ns / 1000) +
               " us are shorter than two 8 ms report periods");
  }
  read_supply_range(s, sc);
  sc.stop_braking_fraction = s.number(
      "stop_braking", sc.stop_braking_fraction, [](double v) { return v >= 0 && v <= 1; },
      "in [0, 1]");
  sc.stuck_arm_cycles = static_cast<int>(s.integer(
      "stuck_arm_cycles", sc.stuck_arm_cycles, [](std::int64_t v) { return v >= 1 && v <= 1000; },
      "in [1, 1000]"));
  sc.stuck_arm_min_duty =
      s.number("stuck_arm_min_duty", sc.stuck_arm_min_duty, fraction, "in (0, 1]");
  sc.stuck_pendulum_arm_travel_rad =
      s.number(
          "stuck_pendulum_arm_travel_deg", sc.stuck_pendulum_arm_travel_rad / kDegToRad,
          [](double v) { return v > 0 && v <= 36000; }, "in (0, 36000]") *
      kDegToRad;
  s.reject_unknown_keys();
  return sc;
}

CommandLimitsConfig read_limits(Section l, const SafetyConfig& safety) {
  CommandLimitsConfig lc;
  lc.max_amplitude_duty =
      l.number("max_amplitude_duty", lc.max_amplitude_duty, fraction, "in (0, 1]");
  if (lc.max_amplitude_duty > safety.max_duty) {
    l.fail("max_amplitude_duty", l.node("max_amplitude_duty"), "must not exceed safety.max_duty");
  }
  lc.max_duration_s = l.number("max_duration_s", lc.max_duration_s, positive, "> 0");
  lc.max_arm_switch_rad =
      l.number("max_arm_switch_deg", lc.max_arm_switch_rad / kDegToRad, positive, "> 0") *
      kDegToRad;
  if (lc.max_arm_switch_rad >= safety.arm_limit_rad) {
    l.fail("max_arm_switch_deg", l.node("max_arm_switch_deg"),
           "must be below safety.arm_limit_deg");
  }
  lc.max_commands_per_s = static_cast<int>(l.integer(
      "max_commands_per_s", lc.max_commands_per_s,
      [](std::int64_t v) { return v >= 1 && v <= 1000; }, "in [1, 1000]"));
  lc.max_stops_per_s = static_cast<int>(l.integer(
      "max_stops_per_s", lc.max_stops_per_s, [](std::int64_t v) { return v >= 1 && v <= 1000; },
      "in [1, 1000]"));
  l.reject_unknown_keys();
  return lc;
}

ExcitationConfig read_excitation(Section e, const CommandLimitsConfig& limits,
                                 const bridge::MotorBoardKind& motor_board) {
  ExcitationConfig ec;
  ec.profile = e.choice("profile", ec.profile, kExcitationProfiles);
  ec.amplitude_duty = e.number("amplitude_duty", ec.amplitude_duty, fraction, "in (0, 1]");
  if (ec.amplitude_duty > limits.max_amplitude_duty) {
    e.fail("amplitude_duty", e.node("amplitude_duty"), "must not exceed limits.max_amplitude_duty");
  }
  ec.duration_s = e.number("duration_s", ec.duration_s, positive, "> 0");
  ec.seed = e.integer("seed", ec.seed, non_negative_integer, ">= 0");
  ec.switch_period_s = e.number("switch_period_s", ec.switch_period_s, non_negative, ">= 0");
  ec.switch_period_jitter = e.number(
      "switch_period_jitter", ec.switch_period_jitter, [](double v) { return v >= 0 && v < 1; },
      "in [0, 1)");
  ec.arm_switch_rad =
      e.number("arm_switch_deg", ec.arm_switch_rad / kDegToRad, non_negative, ">= 0") * kDegToRad;
  if (ec.arm_switch_rad > limits.max_arm_switch_rad) {
    e.fail("arm_switch_deg", e.node("arm_switch_deg"), "must not exceed limits.max_arm_switch_deg");
  }
  read_profile_shapes(e, ec);
  std::ostringstream range;
  range << "in [" << motor_board.min_acceleration_pct_per_s << ", "
        << motor_board.max_acceleration_pct_per_s << "] (the motor board's range)";
  ec.board_acceleration_pct_per_s = e.number(
      "board_acceleration_pct_per_s", ec.board_acceleration_pct_per_s,
      [&](double v) {
        return v >= motor_board.min_acceleration_pct_per_s &&
               v <= motor_board.max_acceleration_pct_per_s;
      },
      range.str().c_str());
  e.reject_unknown_keys();
  return ec;
}

}  // namespace furuta::config::detail
