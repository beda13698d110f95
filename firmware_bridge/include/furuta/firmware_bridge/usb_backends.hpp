#pragma once
// The real-hardware backends and device discovery.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/transport.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"

namespace furuta::bridge {

// HID boards through hidraw (hidapi). Report lengths come from the HID report descriptor.
std::unique_ptr<Transport> make_hidapi_transport();

// Any board through libusb: make_usb_transport(make_libusb_bus()).
std::unique_ptr<Transport> make_libusb_transport();

// Lengths in bytes of the first input and first output report: Report Count * Report Size summed
// over the Input (0x81) / Output (0x91) main items of that report, rounded up to bytes. For a
// descriptor with one Input and one Output item (the Phidgets') this is the vendor libraries'
// reading (the Report Count preceding each item); several items in one report are summed. Zero
// where the descriptor has no such item. Never reads outside `descriptor`: a truncated item ends
// the walk.
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
// Lists the bus without claiming anything (a board another process uses is listed too); report
// lengths stay 0. The firmware version is read as the vendor reads it for the interface's class.
DiscoveryResult discover_phidgets(UsbBus& bus);
DiscoveryResult discover_phidgets();  // on make_libusb_bus()

}  // namespace furuta::bridge
