#pragma once
// The readers of rig.toml's sections (private to the config library). parse_rig_config
// (rig_config.cpp) calls one per table, in an order where a section checked against another comes
// after it: [safety] against [daemon]'s period, [limits] against [safety], [excitation] against
// [limits], [identification] against the period. Each reads its whole table and rejects the keys
// it does not know.

#include <cstdint>
#include <numbers>

#include "furuta/config/rig_config.hpp"
#include "furuta/config/toml_section.hpp"

namespace furuta::config::detail {

inline constexpr double kDegToRad = std::numbers::pi / 180.0;

// Range rules several sections use (the text after "must be " is given with each).
inline bool positive(double v) {
  return v > 0;
}
inline bool fraction(double v) {
  return v > 0 && v <= 1;
}
inline bool non_negative(double v) {
  return v >= 0;
}
inline bool non_negative_integer(std::int64_t v) {
  return v >= 0;
}

// daemon_sections.cpp
DaemonConfig read_daemon(Section s);  // [daemon] and [daemon.realtime]
SafetyConfig read_safety(Section s, const DaemonConfig& daemon);
CommandLimitsConfig read_limits(Section s, const SafetyConfig& safety);
// The duty ramp is checked against the motor board's range.
ExcitationConfig read_excitation(Section s, const CommandLimitsConfig& limits,
                                 const bridge::MotorBoardKind& motor_board);

// identification_sections.cpp
IdentificationConfig read_identification(Section s, const DaemonConfig& daemon);
OutputErrorConfig read_output_error(Section s);
SiviaConfig read_sivia(Section s);
GuaranteedConfig read_guaranteed(Section s);
AutomationConfig read_automation(Section s);

}  // namespace furuta::config::detail
