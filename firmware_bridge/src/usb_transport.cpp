// A Phidget board over a UsbBus: which endpoint to read, which request to write with, how long a
// report is and which firmware version the board has. The bus is libusb on hardware and the
// simulated rig's in tests, so every choice made here is checked against the boards' protocol.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "furuta/firmware_bridge/usb_backends.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"

namespace furuta::bridge {

namespace {

constexpr std::uint16_t kInterface = 0;
constexpr std::uint8_t kEndpointIn = 0x81;
constexpr std::uint8_t kEndpointOut = 0x01;
// wMaxPacketSize bits 11-12 count extra transactions per frame (high speed); the size is below.
constexpr std::uint16_t kPacketSizeMask = 0x07FF;

// Writes are on the control loop's path (one per 16 ms cycle), so they may not block for the vendor
// library's 500 ms. 10 ms covers a full-speed interrupt OUT endpoint polled every 8 frames plus a
// frame of slack (the boards' bInterval is not documented: *inferred*), and a control transfer,
// which completes within a frame or two, with room to spare.
constexpr std::chrono::milliseconds kWriteTimeout{10};
// Descriptor requests during open(), off the control path: generous.
constexpr std::chrono::milliseconds kSetupTimeout{1000};

// HID class requests and descriptors (HID 1.11, sections 7.1 and 7.2).
constexpr std::uint8_t kHidDescriptorType = 0x21;
constexpr std::uint8_t kReportDescriptorType = 0x22;
constexpr UsbSetup kGetReportDescriptor{0x81, 0x06, kReportDescriptorType << 8, kInterface};
constexpr UsbSetup kSetOutputReport{0x21, 0x09, 0x0200, kInterface};  // report type Output, id 0
// Used when the interface's HID descriptor does not give the report descriptor's length.
constexpr std::uint16_t kDefaultReportDescriptorBytes = 256;
constexpr std::uint16_t kMaxReportDescriptorBytes = 4096;  // the kernel's limit too

// The vendor-class 1047 (firmware 2xx) takes its output report as the vendor's "device write":
// host-to-device, vendor, *interface* recipient (0x41), request 0x02, packet type 0x01 in wValue's
// high byte, wIndex the interface (libphidget22 1.10 usblinux.c:278-281). A device-recipient
// request (0x40) may go unanswered.
constexpr UsbSetup kVendorDeviceWrite{0x41, 0x02, 0x0100, kInterface};
// The vendor-class output report: one byte, the bitmask of channels to enable.
constexpr std::size_t kVendorOutputReportBytes = 1;

// The length of the report descriptor as the interface's HID class descriptor states it (it sits in
// the interface descriptor's `extra` bytes: bLength, 0x21, bcdHID(2), bCountryCode,
// bNumDescriptors, then {bDescriptorType, wDescriptorLength(2)} per descriptor).
std::uint16_t report_descriptor_length(std::span<const std::uint8_t> extra) {
  std::size_t pos = 0;
  while (pos + 2 <= extra.size()) {
    const std::size_t length = extra[pos];
    if (length < 2 || pos + length > extra.size()) break;
    if (extra[pos + 1] == kHidDescriptorType && length >= 6) {
      const std::size_t count = extra[pos + 5];
      for (std::size_t i = 0; i < count && pos + 9 + 3 * i <= pos + length; ++i) {
        const std::size_t at = pos + 6 + 3 * i;
        if (extra[at] == kReportDescriptorType) {
          const auto bytes = static_cast<std::uint16_t>(extra[at + 1] | extra[at + 2] << 8);
          return std::min(bytes, kMaxReportDescriptorBytes);
        }
      }
    }
    pos += length;
  }
  return kDefaultReportDescriptorBytes;
}

class UsbTransport final : public Transport {
 public:
  explicit UsbTransport(std::unique_ptr<UsbBus> bus) : bus_(std::move(bus)) {}
  ~UsbTransport() override { close(); }

  TransportStatus open(const DeviceMatch& match) override;
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override;
  TransportStatus write_report(std::span<const std::uint8_t> report) override;
  void close() override;
  bool is_open() const override { return device_ != nullptr; }
  const DeviceInfo& device_info() const override { return info_; }

 private:
  TransportStatus set_up(const UsbDeviceDescription& description);
  TransportStatus read_hid_report_lengths(const UsbDeviceDescription& description);

  std::unique_ptr<UsbBus> bus_;        // declared first: outlives device_
  std::unique_ptr<UsbDevice> device_;  // open and claimed
  DeviceInfo info_;
  std::size_t read_request_bytes_ = 0;  // what one interrupt IN transfer asks for
  bool has_out_endpoint_ = false;
};

TransportStatus UsbTransport::open(const DeviceMatch& match) {
  close();
  std::vector<UsbDeviceDescription> devices;
  std::string error;
  const TransportStatus listed = bus_->list(match.vendor_id, devices, error);
  if (listed != TransportStatus::ok) return listed;

  // Several boards of one product may be plugged in: the serial, read from each, tells them apart.
  // A board we may not open could be the one asked for, so denial outranks "not found".
  bool saw_denied = false;
  bool saw_busy = false;  // claimed by another process
  bool saw_failure = false;
  for (const UsbDeviceDescription& d : devices) {
    if (d.product_id != match.product_id) continue;
    if (d.access_denied) {
      saw_denied = true;
      continue;
    }
    if (match.serial && d.serial != *match.serial) continue;
    const TransportStatus opened = bus_->open(d, device_);
    if (opened == TransportStatus::access_denied) {
      saw_denied = true;
      continue;
    }
    if (opened != TransportStatus::ok) {
      (opened == TransportStatus::busy ? saw_busy : saw_failure) = true;
      continue;
    }
    const TransportStatus status = set_up(d);
    if (status != TransportStatus::ok) close();
    return status;
  }
  if (saw_denied) return TransportStatus::access_denied;
  if (saw_busy) return TransportStatus::busy;
  if (saw_failure) return TransportStatus::io_error;
  return TransportStatus::not_found;
}

TransportStatus UsbTransport::set_up(const UsbDeviceDescription& d) {
  std::optional<std::uint16_t> in_packet_bytes;
  for (const UsbEndpointDescription& endpoint : d.endpoints) {
    if (endpoint.address == kEndpointIn)
      in_packet_bytes = endpoint.max_packet_bytes & kPacketSizeMask;
    if (endpoint.address == kEndpointOut) has_out_endpoint_ = true;
  }
  if (!in_packet_bytes || *in_packet_bytes == 0) return TransportStatus::io_error;

  info_.vendor_class_interface = d.interface_class == kUsbClassVendorSpecific;
  if (info_.vendor_class_interface) {
    // No report descriptor. The vendor library takes the report's length from a Phidget-specific
    // descriptor (type 0x42) whose layout we have not seen, and accepts what it reads: a 2xx 1047
    // may send its 40 bytes in a 64-byte endpoint. So ask for a whole packet, and call a report
    // short only when it lacks what the codec reads (docs/phidget-protocol.md).
    const std::size_t needed = minimum_input_report_bytes(d.product_id);
    info_.input_report_bytes = needed > 0 ? needed : *in_packet_bytes;
    info_.output_report_bytes = kVendorOutputReportBytes;
    read_request_bytes_ = *in_packet_bytes;
    if (info_.input_report_bytes > *in_packet_bytes) return TransportStatus::io_error;
  } else {
    const TransportStatus lengths = read_hid_report_lengths(d);
    if (lengths != TransportStatus::ok) return lengths;
    // Ask for exactly one report: were we to ask for more and the report fill whole packets, the
    // transfer would wait on and merge the next report.
    read_request_bytes_ = info_.input_report_bytes;
  }
  if (info_.input_report_bytes == 0 || read_request_bytes_ > kMaxReportBytes ||
      info_.output_report_bytes > kMaxReportBytes) {
    return TransportStatus::io_error;
  }

  info_.vendor_id = d.vendor_id;
  info_.product_id = d.product_id;
  info_.serial = d.serial;
  info_.firmware_version = firmware_version_from_bcd(d.bcd_device, info_.vendor_class_interface);
  info_.product_name = std::string(phidget_product_name(d.product_id));
  info_.path = d.path;
  return TransportStatus::ok;
}

TransportStatus UsbTransport::read_hid_report_lengths(const UsbDeviceDescription& d) {
  std::vector<std::uint8_t> descriptor(report_descriptor_length(d.interface_extra));
  std::size_t received = 0;
  const TransportStatus status =
      device_->control_transfer(kGetReportDescriptor, descriptor, received, kSetupTimeout);
  if (status != TransportStatus::ok) return status;
  descriptor.resize(received);
  // Without the lengths a short (lossy) report could not be told from a whole one: refuse.
  const HidReportLengths lengths = parse_hid_report_lengths(descriptor);
  if (lengths.input_bytes == 0) return TransportStatus::io_error;
  info_.input_report_bytes = lengths.input_bytes;
  info_.output_report_bytes = lengths.output_bytes;
  return TransportStatus::ok;
}

TransportStatus UsbTransport::read_report(UsbReport& report, std::chrono::nanoseconds timeout) {
  report.length = 0;
  if (!device_) return TransportStatus::not_open;
  // A bus counts milliseconds (libusb reads 0 as "forever"), so a poll waits at most 1 ms.
  const auto wait =
      std::max(std::chrono::ceil<std::chrono::milliseconds>(timeout), std::chrono::milliseconds{1});
  std::size_t transferred = 0;
  const TransportStatus status = device_->interrupt_transfer(
      kEndpointIn, std::span(report.bytes.data(), read_request_bytes_), transferred, wait);
  report.host_time_ns = bus_->now_ns();
  report.length = transferred;

  if (status == TransportStatus::ok) {
    return report.length < info_.input_report_bytes ? TransportStatus::short_report
                                                    : TransportStatus::ok;
  }
  // Part of a report arrived before the timeout: the rest is lost, say so.
  if (status == TransportStatus::timeout && report.length > 0) return TransportStatus::short_report;
  report.length = 0;
  return status;
}

TransportStatus UsbTransport::write_report(std::span<const std::uint8_t> report) {
  if (!device_) return TransportStatus::not_open;
  const std::size_t length = info_.output_report_bytes;
  if (report.empty() || report.size() > length) return TransportStatus::invalid_argument;

  // Zero-padded to the report length, as the boards expect; no report-id byte on the wire.
  std::array<std::uint8_t, kMaxReportBytes> buffer{};
  std::copy(report.begin(), report.end(), buffer.begin());
  const std::span<std::uint8_t> data(buffer.data(), length);

  std::size_t sent = 0;
  TransportStatus status = TransportStatus::io_error;
  if (has_out_endpoint_) {
    status = device_->interrupt_transfer(kEndpointOut, data, sent, kWriteTimeout);
  } else if (info_.vendor_class_interface) {
    status = device_->control_transfer(kVendorDeviceWrite, data, sent, kWriteTimeout);
  } else {
    status = device_->control_transfer(kSetOutputReport, data, sent, kWriteTimeout);
  }
  if (status != TransportStatus::ok) return status;
  return sent == length ? TransportStatus::ok : TransportStatus::io_error;
}

void UsbTransport::close() {
  device_.reset();  // releases the interface, gives a detached kernel driver back
  has_out_endpoint_ = false;
  read_request_bytes_ = 0;
  info_ = DeviceInfo{};
}

}  // namespace

std::unique_ptr<Transport> make_usb_transport(std::unique_ptr<UsbBus> bus) {
  return std::make_unique<UsbTransport>(std::move(bus));
}

std::unique_ptr<Transport> make_libusb_transport() {
  return make_usb_transport(make_libusb_bus());
}

}  // namespace furuta::bridge
