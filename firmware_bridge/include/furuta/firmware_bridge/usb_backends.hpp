#pragma once
// The real-hardware backends and device discovery.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::bridge {

// HID boards through hidraw (hidapi). Report lengths come from the HID report descriptor.
std::unique_ptr<Transport> make_hidapi_transport();

// Any board through libusb: detaches the kernel driver, claims interface 0, reads interrupt IN 0x81,
// writes interrupt OUT 0x01 when the interface has it, else HID SET_REPORT (or, for the vendor-class
// 1047 firmware 2xx, the vendor "device write" control transfer).
std::unique_ptr<Transport> make_libusb_transport();

// Report Count of the items preceding the first Input (0x81) and Output (0x91) main items, times
// Report Size / 8, as the vendor libraries read them. Zero where the descriptor has no such item.
struct HidReportLengths {
  std::size_t input_bytes = 0;
  std::size_t output_bytes = 0;
};
HidReportLengths parse_hid_report_lengths(std::span<const std::uint8_t> descriptor);

struct DiscoveryResult {
  std::vector<DeviceInfo> devices;  // every device with vendor id 0x06C2
  // Devices seen but not readable (serial unknown): permissions. Each names its bus path.
  std::vector<std::string> access_denied;
  std::string error;  // libusb could not even start (no USB in this machine/container)
};
DiscoveryResult discover_phidgets();

}  // namespace furuta::bridge
