#pragma once
// USB identities of the Phidget boards (see shared/reference/phidget-usb-protocol.md).

#include <cstdint>
#include <string_view>

namespace furuta::bridge {

inline constexpr std::uint16_t kPhidgetsVendorId = 0x06C2;
inline constexpr std::uint16_t kProductMotorControl1065 = 0x003E;
inline constexpr std::uint16_t kProductEncoder1047 = 0x004F;
inline constexpr std::uint16_t kProductEncoder1057 = 0x0080;
inline constexpr std::uint16_t kProductMotorControl1064 = 0x0059;
inline constexpr std::uint16_t kProductMotorControl1060 = 0x0058;

// "1065 MotorControl 1-Motor", ..., or "unknown Phidget" for other product ids.
std::string_view phidget_product_name(std::uint16_t product_id);

// Firmware version as the vendor libraries print it: (bcdDevice >> 8) * 100 + (bcdDevice & 0xFF).
constexpr int firmware_version_from_bcd(std::uint16_t bcd_device) {
  return (bcd_device >> 8) * 100 + (bcd_device & 0xFF);
}

}  // namespace furuta::bridge
