#pragma once
// What the identification knows of the 1065's resolution (docs/phidget-protocol.md); the codec in
// firmware_bridge/ holds the same figures for the wire, a module identification does not use.

namespace furuta::identification::internal {

inline constexpr double kSupplyStep_v = 80.0 / 2048.0;  // the supply reading's step
inline constexpr double kDutyStep = 1.0 / 255.0;        // the applied duty's step, as echoed

}  // namespace furuta::identification::internal
