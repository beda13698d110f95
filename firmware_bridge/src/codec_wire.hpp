#pragma once
// Big-endian field access shared by the board codecs (internal to the firmware bridge).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

namespace furuta::bridge::wire {

inline std::uint16_t get_u16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint16_t>((b[at] << 8) | b[at + 1]);
}

inline std::uint32_t get_u24(std::span<const std::uint8_t> b, std::size_t at) {
  return (static_cast<std::uint32_t>(b[at]) << 16) | (static_cast<std::uint32_t>(b[at + 1]) << 8) |
         b[at + 2];
}

inline std::uint32_t get_u32(std::span<const std::uint8_t> b, std::size_t at) {
  return (static_cast<std::uint32_t>(b[at]) << 24) | get_u24(b, at + 1);
}

inline void put_u16(std::span<std::uint8_t> b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<std::uint8_t>(v >> 8);
  b[at + 1] = static_cast<std::uint8_t>(v);
}

inline void put_u24(std::span<std::uint8_t> b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<std::uint8_t>(v >> 16);
  b[at + 1] = static_cast<std::uint8_t>(v >> 8);
  b[at + 2] = static_cast<std::uint8_t>(v);
}

inline void put_u32(std::span<std::uint8_t> b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<std::uint8_t>(v >> 24);
  put_u24(b, at + 1, v);
}

// Rounds half away from zero (as the vendor formulas' round()) and saturates to [0, max]; NaN -> 0.
// Producers of reports (the simulated rig) want a valid raw value whatever the physics says.
inline std::uint32_t round_saturated(double value, std::uint32_t max) {
  if (!(value > 0.0)) return 0;  // also catches NaN
  const double r = std::round(value);
  if (r >= static_cast<double>(max)) return max;
  return static_cast<std::uint32_t>(r);
}

}  // namespace furuta::bridge::wire
