#include "furuta/daemon/safety.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "furuta/common/wire_text.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/config/rig_config.hpp"

namespace furuta::daemon {
namespace {

using furuta::rig_command_t;

// Shortest round-trip form, so a value just above a limit never prints as the limit itself.
std::string shortest_text(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// A string from the wire, made safe to echo into a status reply or a log line: bounded, and every
// byte outside printable ASCII escaped.
std::string printable_quoted(std::string_view text) {
  return text::wire_quoted(text, 48);
}

std::string known_profiles() {
  std::string out;
  for (const char* name : config::kExcitationProfiles) {
    if (!out.empty()) out += ", ";
    out += name;
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
  const bool balance = command.profile == kBalanceProfile;
  if (!balance && !parse_profile_kind(command.profile)) {
    return "profile: " + printable_quoted(command.profile) + " is not one of " + known_profiles() +
           ", " + std::string(kBalanceProfile);
  }
  if (balance && command.controller_path.empty()) {
    return "controller_path: a balance session needs its controller file";
  }
  if (balance && !config::is_sha256_hex(command.controller_sha256)) {
    return "controller_sha256: " + printable_quoted(command.controller_sha256) +
           " is not a SHA-256 in lowercase hex (64 characters)";
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

std::string start_session_problem(const rig_command_t& command, const CommandLimits& limits) {
  return check_start_session(command, limits);
}

StopReason check_safety(const SafetyLimits& limits, const SafetyInput& input) noexcept {
  // Comparisons are written so that NaN fails them: an unknown value is never taken as safe.
  if (input.motor_over_temperature) return StopReason::over_temperature;
  if (input.motor_under_voltage) return StopReason::under_voltage;
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

bool TokenBucket::take(double per_second, std::int64_t now_ns) {
  if (tokens_ < 0.0) {
    tokens_ = per_second;
    last_refill_ns_ = now_ns;
  } else if (now_ns > last_refill_ns_) {
    // Unsigned difference: the subtraction cannot overflow whatever the two stamps are.
    const auto elapsed_ns =
        static_cast<std::uint64_t>(now_ns) - static_cast<std::uint64_t>(last_refill_ns_);
    tokens_ = std::min(per_second, tokens_ + static_cast<double>(elapsed_ns) * per_second / 1e9);
    last_refill_ns_ = now_ns;
  }
  // The slack absorbs rounding in refills summed over many small intervals.
  constexpr double kSlack = 1e-9;
  if (tokens_ + kSlack < 1.0) return false;
  tokens_ = std::max(0.0, tokens_ - 1.0);
  return true;
}

CommandDecision CommandValidator::validate(const rig_command_t& command, std::int64_t now_ns) {
  // An e-stop must get through whatever else is flooding the channel, so it neither needs nor
  // spends a token.
  if (command.kind == rig_command_t::KIND_ESTOP) return {true, {}};
  // Each kind spends its own budget before being looked at, so a flood of garbage is throttled
  // too, and never at the expense of another kind.
  const auto over = [](const char* what, int per_second, CommandRefusal refusal) {
    return CommandDecision{
        false, "rate limit: more than " + std::to_string(per_second) + " " + what + " per second",
        refusal};
  };
  switch (command.kind) {
    case rig_command_t::KIND_STATUS_REQUEST:
      if (!status_requests_.take(std::max(0, limits_.max_status_requests_per_s), now_ns)) {
        return over("status requests", limits_.max_status_requests_per_s,
                    CommandRefusal::status_budget);
      }
      return {true, {}};
    case rig_command_t::KIND_STOP:
      if (!stops_.take(std::max(0, limits_.max_stops_per_s), now_ns)) {
        return over("stops", limits_.max_stops_per_s, CommandRefusal::stop_budget);
      }
      return {true, {}};
    default:
      break;
  }
  if (!starts_.take(std::max(0, limits_.max_commands_per_s), now_ns)) {
    return over("starts", limits_.max_commands_per_s, CommandRefusal::start_budget);
  }
  if (command.kind == rig_command_t::KIND_START_SESSION) {
    auto problem = check_start_session(command, limits_);
    if (!problem.empty()) return {false, std::move(problem), CommandRefusal::invalid};
    return {true, {}};
  }
  return {false,
          "kind: " + std::to_string(static_cast<int>(command.kind)) + " is not a known command",
          CommandRefusal::invalid};
}

ExcitationSpec spec_from_command(const rig_command_t& command, const ExcitationSpec& defaults) {
  // A balance session's excitation only times it: the law drives the motor, free decay sends 0.
  const auto kind = command.profile == kBalanceProfile ? std::optional(ProfileKind::free_decay)
                                                       : parse_profile_kind(command.profile);
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
