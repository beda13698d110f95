#include "furuta/daemon/safety.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "furuta/firmware_bridge/codec_1065.hpp"

namespace furuta::daemon {
namespace {

using furuta::rig_command_t;

constexpr ProfileKind kAllProfiles[] = {ProfileKind::bang_bang, ProfileKind::free_decay,
                                        ProfileKind::step,      ProfileKind::prbs,
                                        ProfileKind::chirp,     ProfileKind::multisine};

// Shortest round-trip form, so a value just above a limit never prints as the limit itself.
std::string shortest_text(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// A string from the wire, made safe to echo into a status reply or a log line: bounded, and every
// byte outside printable ASCII escaped.
std::string printable_quoted(std::string_view text) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    }
  }
  if (text.size() > kMaxShown) out += "...";
  out += '"';
  return out;
}

std::string known_profiles() {
  std::string out;
  for (auto kind : kAllProfiles) {
    if (!out.empty()) out += ", ";
    out += to_string(kind);
  }
  return out;
}

// "" when value is a finite number in (0, limit].
std::string check_positive_up_to(std::string_view field, double value, double limit) {
  const std::string name(field);
  if (!std::isfinite(value)) return name + ": " + shortest_text(value) + " is not a finite number";
  if (!(value > 0.0)) return name + ": " + shortest_text(value) + " is not above 0";
  if (!(value <= limit))
    return name + ": " + shortest_text(value) + " above the limit " + shortest_text(limit);
  return {};
}

// The wire says (0, 1] whatever the configuration allows.
double amplitude_limit(const CommandLimits& limits) {
  return std::min(limits.max_amplitude_duty, 1.0);
}

bool allowed_in_label(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
         c == '_' || c == '.' || c == ' ';
}

std::string check_start_session(const rig_command_t& command, const CommandLimits& limits) {
  if (!parse_profile_kind(command.profile)) {
    return "profile: " + printable_quoted(command.profile) + " is not one of " + known_profiles();
  }
  if (auto problem =
          check_positive_up_to("amplitude_duty", command.amplitude_duty, amplitude_limit(limits));
      !problem.empty()) {
    return problem;
  }
  if (auto problem = check_positive_up_to("duration_s", command.duration_s, limits.max_duration_s);
      !problem.empty()) {
    return problem;
  }
  const int max_label = std::max(0, limits.max_label_chars);
  if (command.label.size() > static_cast<std::size_t>(max_label)) {
    return "label: " + std::to_string(command.label.size()) + " characters, above the limit " +
           std::to_string(max_label);
  }
  for (std::size_t i = 0; i < command.label.size(); ++i) {
    if (!allowed_in_label(command.label[i])) {
      char byte[8];
      std::snprintf(byte, sizeof byte, "0x%02x", static_cast<unsigned char>(command.label[i]));
      return "label: " + printable_quoted(command.label) + " has " + byte + " at position " +
             std::to_string(i) +
             "; only letters, digits, '-', '_', '.' and ' ' are allowed (the label becomes part "
             "of a file name)";
    }
  }
  if (command.seed < 0) {
    return "seed: " + std::to_string(command.seed) + " is negative; it must be >= 0";
  }
  return {};
}

}  // namespace

StopReason check_safety(const SafetyLimits& limits, const SafetyInput& input) noexcept {
  // Comparisons are written so that NaN fails them: an unknown value is never taken as safe.
  if (input.motor_status_flags & bridge::k1065FlagOverTemperature) {
    return StopReason::over_temperature;
  }
  if (input.motor_status_flags & bridge::k1065FlagUnderVoltage) return StopReason::under_voltage;
  if (input.have_supply_reading && !(input.supply_voltage_v >= limits.min_supply_v &&
                                     input.supply_voltage_v <= limits.max_supply_v)) {
    return StopReason::supply_out_of_range;
  }
  if (input.cycles_without_motor_report >= limits.stale_report_cycles) {
    return StopReason::stale_motor_reports;
  }
  if (input.cycles_without_encoder_report >= limits.stale_report_cycles) {
    return StopReason::stale_encoder_reports;
  }
  if (!(std::fabs(input.arm_angle_rad) <= limits.arm_limit_rad)) return StopReason::arm_angle_limit;
  if (!(std::fabs(input.commanded_duty) <= limits.max_duty)) return StopReason::duty_limit;
  if (input.arm_still_driven_cycles >= limits.stuck_arm_cycles) {
    return StopReason::arm_encoder_stuck;
  }
  if (!(input.arm_travel_pendulum_still_rad < limits.stuck_pendulum_arm_travel_rad)) {
    return StopReason::pendulum_encoder_stuck;
  }
  return StopReason::none;
}

bool CommandValidator::Bucket::take(double per_second, std::int64_t now_ns) {
  if (tokens < 0.0) {
    tokens = per_second;
    last_refill_ns = now_ns;
  } else if (now_ns > last_refill_ns) {
    // Unsigned difference: the subtraction cannot overflow whatever the two stamps are.
    const auto elapsed_ns =
        static_cast<std::uint64_t>(now_ns) - static_cast<std::uint64_t>(last_refill_ns);
    tokens = std::min(per_second, tokens + static_cast<double>(elapsed_ns) * per_second / 1e9);
    last_refill_ns = now_ns;
  }
  // The slack absorbs rounding in refills summed over many small intervals.
  constexpr double kSlack = 1e-9;
  if (tokens + kSlack < 1.0) return false;
  tokens = std::max(0.0, tokens - 1.0);
  return true;
}

CommandDecision CommandValidator::validate(const rig_command_t& command, std::int64_t now_ns) {
  // An e-stop must get through whatever else is flooding the channel, so it neither needs nor
  // spends a token.
  if (command.kind == rig_command_t::KIND_ESTOP) return {true, {}};

  if (command.kind == rig_command_t::KIND_STATUS_REQUEST) {
    if (!status_requests_.take(std::max(0, limits_.max_status_requests_per_s), now_ns)) {
      return {false, "rate limit: more than " + std::to_string(limits_.max_status_requests_per_s) +
                         " status requests per second"};
    }
    return {true, {}};
  }
  // Everything else spends a token before being looked at, so a flood of garbage is throttled too.
  if (!commands_.take(std::max(0, limits_.max_commands_per_s), now_ns)) {
    return {false, "rate limit: more than " + std::to_string(limits_.max_commands_per_s) +
                       " commands per second"};
  }

  switch (command.kind) {
    case rig_command_t::KIND_STOP:
      return {true, {}};
    case rig_command_t::KIND_START_SESSION: {
      auto problem = check_start_session(command, limits_);
      if (!problem.empty()) return {false, std::move(problem)};
      return {true, {}};
    }
    default:
      return {false, "kind: " + std::to_string(static_cast<int>(command.kind)) +
                         " is not a known command"};
  }
}

ExcitationSpec spec_from_command(const rig_command_t& command, const ExcitationSpec& defaults) {
  const auto kind = parse_profile_kind(command.profile);
  if (!kind) {
    throw std::invalid_argument("profile: " + printable_quoted(command.profile) +
                                " is not one of " + known_profiles());
  }
  if (command.seed < 0) {
    throw std::invalid_argument("seed: " + std::to_string(command.seed) +
                                " is negative; it must be >= 0");
  }
  ExcitationSpec spec = defaults;
  spec.kind = *kind;
  spec.amplitude_duty = command.amplitude_duty;
  spec.duration_s = command.duration_s;
  spec.seed = static_cast<std::uint64_t>(command.seed);
  return spec;
}

std::string check_spec_limits(const ExcitationSpec& spec, const CommandLimits& limits) {
  if (auto problem =
          check_positive_up_to("amplitude_duty", spec.amplitude_duty, amplitude_limit(limits));
      !problem.empty()) {
    return problem;
  }
  if (auto problem = check_positive_up_to("duration_s", spec.duration_s, limits.max_duration_s);
      !problem.empty()) {
    return problem;
  }
  if (spec.kind == ProfileKind::bang_bang && !(spec.arm_switch_rad <= limits.max_arm_switch_rad)) {
    return "arm_switch_rad: " + shortest_text(spec.arm_switch_rad) + " above the limit " +
           shortest_text(limits.max_arm_switch_rad);
  }
  return {};
}

}  // namespace furuta::daemon
