// The rig.toml parser on arbitrary text: it either returns a configuration whose safety limits are
// all in range, or throws ConfigError naming this file. Any other exception, a crash or UB is a
// finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "furuta/config/rig_config.hpp"

using namespace furuta::config;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string name = "fuzz.toml";
  try {
    const RigConfig c = parse_rig_config(text, name);
    // What the daemon relies on, whatever the file said.
    const SafetyConfig& s = c.safety;
    check(finite_in(s.arm_limit_rad, 1e-300, 4 * M_PI + 1e-9));
    check(finite_in(s.max_duty, 1e-300, 1.0));
    check(s.stale_report_cycles >= 1 && s.stale_report_cycles <= 1000);
    check(finite_in(s.min_supply_v, 0, 1e308) && finite_in(s.max_supply_v, 0, 1e308));
    check(s.min_supply_v < s.max_supply_v);
    check(finite_in(s.stop_braking_fraction, 0, 1));
    check(s.stuck_arm_cycles >= 1 && s.stuck_arm_cycles <= 1000);
    check(finite_in(s.stuck_arm_min_duty, 1e-300, 1.0));
    check(finite_in(s.stuck_pendulum_arm_travel_rad, 1e-300, 36000 * M_PI / 180 + 1e-9));
    const CommandLimitsConfig& l = c.limits;
    check(finite_in(l.max_amplitude_duty, 1e-300, s.max_duty));
    check(finite_in(l.max_duration_s, 1e-300, 1e308));
    check(finite_in(l.max_arm_switch_rad, 1e-300, s.arm_limit_rad) &&
          l.max_arm_switch_rad < s.arm_limit_rad);
    check(l.max_commands_per_s >= 1 && l.max_commands_per_s <= 1000);
    const ExcitationConfig& e = c.excitation;
    check(finite_in(e.amplitude_duty, 1e-300, l.max_amplitude_duty));
    check(finite_in(e.arm_switch_rad, 0, l.max_arm_switch_rad));
    check(c.daemon.period_ns >= 100'000 && c.daemon.period_ns <= 1'000'000'000);
    check(c.pendulum_channel >= 0 && c.pendulum_channel <= 3);
    check(std::isfinite(c.arm_encoder.counts_per_rev) && c.arm_encoder.counts_per_rev > 0);
    check(std::isfinite(c.pendulum_encoder.counts_per_rev) &&
          c.pendulum_encoder.counts_per_rev > 0);
    check(std::isfinite(c.arm_encoder.gear_ratio) && c.arm_encoder.gear_ratio > 0);
  } catch (const ConfigError& e) {
    check(e.file() == name);
    check(std::string(e.what()).rfind(name, 0) == 0);
    check(e.line() >= 0);
  }
  return 0;
}
