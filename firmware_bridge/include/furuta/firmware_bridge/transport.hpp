#pragma once
// One USB device, one handle: open, read an input report, write an output report, close.
// Every call returns a status; nothing on this path throws or allocates.

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "furuta/firmware_bridge/phidget_ids.hpp"

namespace furuta::bridge {

enum class TransportStatus : std::uint8_t {
  ok,
  timeout,        // no report within the timeout: not an error by itself
  not_found,      // no device matches
  access_denied,  // permissions (udev rule missing)
  busy,           // claimed by another process
  disconnected,   // the device went away; close and open again
  short_report,   // fewer bytes than the report length: data lost
  io_error,
  not_open,
  invalid_argument,
  replay_mismatch,   // replay: the written report differs from the recorded one
  replay_exhausted,  // replay: no more recorded input
};

std::string_view to_string(TransportStatus status);

struct DeviceMatch {
  std::uint16_t vendor_id = kPhidgetsVendorId;
  std::uint16_t product_id = 0;
  std::optional<std::string> serial;  // decimal ASCII, as in iSerialNumber
};

struct DeviceInfo {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;
  int firmware_version = 0;  // e.g. 105 for bcdDevice 0x0105
  std::string product_name;
  std::string path;  // bus path or hidraw node, for messages
  std::size_t input_report_bytes = 0;
  std::size_t output_report_bytes = 0;
  bool vendor_class_interface = false;  // 1047 firmware 2xx: libusb only
};

inline constexpr std::size_t kMaxReportBytes = 64;

// An input report as received, in a fixed buffer so reading never allocates.
struct UsbReport {
  std::array<std::uint8_t, kMaxReportBytes> bytes{};
  std::size_t length = 0;
  // When the report arrived, on the transport's Clock (CLOCK_MONOTONIC for hardware). The hardware
  // backends stamp it when read_report returns, so it is the arrival time only for a reader that is
  // blocked in read_report when the report comes (a reader thread per board), not for one that
  // drains a backlog; the 1047 loss detection needs arrival times.
  std::int64_t host_time_ns = 0;

  std::span<const std::uint8_t> view() const { return {bytes.data(), length}; }
};

class Transport {
 public:
  virtual ~Transport() = default;
  Transport() = default;
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  virtual TransportStatus open(const DeviceMatch& match) = 0;
  // Waits up to `timeout` for one input report; zero polls. A report shorter than the device's
  // input report length is returned with short_report (its bytes in `report`), never padded
  // silently.
  virtual TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) = 0;
  // `report` without any HID report-id prefix; the backend adds what its API needs.
  virtual TransportStatus write_report(std::span<const std::uint8_t> report) = 0;
  virtual void close() = 0;
  virtual bool is_open() const = 0;
  // Valid after a successful open.
  virtual const DeviceInfo& device_info() const = 0;
};

}  // namespace furuta::bridge
