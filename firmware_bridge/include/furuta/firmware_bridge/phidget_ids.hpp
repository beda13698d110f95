#pragma once
// USB identities of the Phidget boards, their firmware versions as the vendor reads them, and the
// firmware versions whose report layouts the codecs implement (docs/phidget-protocol.md).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace furuta::bridge {

inline constexpr std::uint16_t kPhidgetsVendorId = 0x06C2;
inline constexpr std::uint16_t kProductMotorControl1065 = 0x003E;
inline constexpr std::uint16_t kProductEncoder1047 = 0x004F;
inline constexpr std::uint16_t kProductEncoder1057 = 0x0080;
inline constexpr std::uint16_t kProductMotorControl1064 = 0x0059;
inline constexpr std::uint16_t kProductMotorControl1060 = 0x0058;

// The 1065 and the 1047 each send an input report every 8 ms.
inline constexpr std::int64_t kReportPeriodNs = 8'000'000;

// "1065 MotorControl 1-Motor", ..., or "unknown Phidget" for other product ids.
std::string_view phidget_product_name(std::uint16_t product_id);

// The firmware version of a HID board as libphidget21 reads bcdDevice: major * 100 + minor, the
// minor byte taken as binary (0x0105 is 105, 0x0210 would be 216), and a bcdDevice below 0x100
// multiplied by 100 (0x0001 is 100).
constexpr int firmware_version_hid(std::uint16_t bcd_device) {
  if (bcd_device < 0x100) return bcd_device * 100;
  return (bcd_device >> 8) * 100 + (bcd_device & 0xFF);
}

// The firmware version of a vendor-class board (1047 firmware 2xx) as libphidget22 reads
// bcdDevice: binary-coded decimal, four digits (0x0210 is 210).
constexpr int firmware_version_vendor_class(std::uint16_t bcd_device) {
  return ((bcd_device >> 12) & 0xF) * 1000 + ((bcd_device >> 8) & 0xF) * 100 +
         ((bcd_device >> 4) & 0xF) * 10 + (bcd_device & 0xF);
}

constexpr int firmware_version_from_bcd(std::uint16_t bcd_device, bool vendor_class_interface) {
  return vendor_class_interface ? firmware_version_vendor_class(bcd_device)
                                : firmware_version_hid(bcd_device);
}

// The inverse, for the simulated rig's descriptors: the bcdDevice a board of that version reports.
constexpr std::uint16_t bcd_device_from_firmware(int version, bool vendor_class_interface) {
  if (vendor_class_interface) {
    return static_cast<std::uint16_t>((version / 1000 % 10) << 12 | (version / 100 % 10) << 8 |
                                      (version / 10 % 10) << 4 | (version % 10));
  }
  return static_cast<std::uint16_t>((version / 100) << 8 | (version % 100));
}

// The firmware versions whose layout the codecs implement, per board and interface class, as the
// vendor library drives them: the 1065 on 100-199; the 1047 on 100-199 as HID and 200-299 as a
// vendor-class device. Anything else (a 1047_2 with firmware 3xx adds fields we have not seen) is
// outside what the codecs know.
struct FirmwareRange {
  int first = 0;
  int last = 0;
};
std::optional<FirmwareRange> known_firmware(std::uint16_t product_id, bool vendor_class_interface);
bool firmware_known(std::uint16_t product_id, bool vendor_class_interface, int version);

// The shortest input report whose fields the codec reads (1065: 25 bytes, 1047: 40); 0 for a
// product without a codec here.
std::size_t minimum_input_report_bytes(std::uint16_t product_id);

}  // namespace furuta::bridge
