// The simulated rig as a USB bus: each board with the descriptors a real one shows (bcdDevice as
// the vendor encodes its firmware version, HID or vendor-class interface 0, an IN endpoint, a HID
// report descriptor) and the control requests it answers. Behind the endpoints are the rig's own
// report queues, so the USB transport runs its real code path against the boards' protocol.

#include "simulated_usb.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "furuta/firmware_bridge/phidget_ids.hpp"

namespace furuta::sim {

using namespace bridge;  // NOLINT(google-build-using-namespace): the boards' types and codecs

namespace {

constexpr std::uint8_t kEndpointIn = 0x81;

bool is_vendor_class(const DeviceInfo& info) {
  return info.vendor_class_interface;
}

// A vendor-defined HID report descriptor with one input and one output report of 8-bit fields, the
// shape parse_hid_report_lengths reads as the vendor libraries do.
std::vector<std::uint8_t> hid_report_descriptor(std::size_t input_bytes, std::size_t output_bytes) {
  return {
      0x06, 0x00,
      0xFF,        // Usage Page (vendor defined)
      0x09, 0x01,  // Usage (1)
      0xA1, 0x01,  // Collection (Application)
      0x15, 0x00,  // Logical Minimum (0)
      0x26, 0xFF,
      0x00,                                          // Logical Maximum (255)
      0x75, 0x08,                                    // Report Size (8)
      0x95, static_cast<std::uint8_t>(input_bytes),  // Report Count
      0x09, 0x01,
      0x81, 0x02,                                     // Usage, Input (Data, Var, Abs)
      0x95, static_cast<std::uint8_t>(output_bytes),  // Report Count
      0x09, 0x01,
      0x91, 0x02,  // Usage, Output (Data, Var, Abs)
      0xC0,        // End Collection
  };
}

// The HID class descriptor that follows a HID interface's descriptor: bLength 9, type 0x21, HID
// 1.11, no country, one report descriptor of `length` bytes.
std::vector<std::uint8_t> hid_class_descriptor(std::size_t length) {
  return {0x09,
          0x21,
          0x11,
          0x01,
          0x00,
          0x01,
          0x22,
          static_cast<std::uint8_t>(length & 0xFF),
          static_cast<std::uint8_t>(length >> 8)};
}

UsbDeviceDescription describe(const DeviceInfo& info, const SimulatedRigConfig& config) {
  UsbDeviceDescription d;
  d.vendor_id = info.vendor_id;
  d.product_id = info.product_id;
  d.serial = info.serial;
  d.path = info.product_id == kProductMotorControl1065 ? "simulated bus 1 port 1"
                                                       : "simulated bus 1 port 2";
  d.bcd_device = bcd_device_from_firmware(info.firmware_version, is_vendor_class(info));
  if (is_vendor_class(info)) {
    d.interface_class = kUsbClassVendorSpecific;
    d.endpoints.push_back({kEndpointIn, config.usb_packet_bytes_1047});
  } else {
    d.interface_class = kUsbClassHid;
    const std::vector<std::uint8_t> report =
        hid_report_descriptor(info.input_report_bytes, info.output_report_bytes);
    d.interface_extra = hid_class_descriptor(report.size());
    d.endpoints.push_back({kEndpointIn, static_cast<std::uint16_t>(info.input_report_bytes)});
  }
  return d;
}

bool same(const UsbSetup& a, const UsbSetup& b) {
  return a.request_type == b.request_type && a.request == b.request && a.value == b.value &&
         a.index == b.index;
}

class SimulatedUsbDevice final : public UsbDevice {
 public:
  SimulatedUsbDevice(std::unique_ptr<Transport> board, const DeviceInfo& info)
      : board_(std::move(board)), vendor_class_(is_vendor_class(info)) {
    if (!vendor_class_) {
      report_descriptor_ = hid_report_descriptor(info.input_report_bytes, info.output_report_bytes);
    }
  }

  TransportStatus control_transfer(const UsbSetup& setup, std::span<std::uint8_t> data,
                                   std::size_t& transferred,
                                   std::chrono::milliseconds /*timeout*/) override {
    transferred = 0;
    // HID 1.11 7.1.1 GET_DESCRIPTOR (report), 7.2.2 SET_REPORT (output, id 0), on interface 0.
    static constexpr UsbSetup kGetReportDescriptor{0x81, 0x06, 0x2200, 0};
    static constexpr UsbSetup kSetOutputReport{0x21, 0x09, 0x0200, 0};
    // The vendor's "device write" to a vendor-class board: interface recipient (libphidget22 1.10
    // usblinux.c:278-281). Nothing else reaches the board's enable mask.
    static constexpr UsbSetup kVendorDeviceWrite{0x41, 0x02, 0x0100, 0};
    if (!vendor_class_ && same(setup, kGetReportDescriptor)) {
      transferred = std::min(data.size(), report_descriptor_.size());
      std::copy_n(report_descriptor_.begin(), transferred, data.begin());
      return TransportStatus::ok;
    }
    const bool write =
        vendor_class_ ? same(setup, kVendorDeviceWrite) : same(setup, kSetOutputReport);
    if (!write) return TransportStatus::io_error;  // a stall: the board does not know the request
    const TransportStatus status = board_->write_report(data);
    if (status == TransportStatus::ok) transferred = data.size();
    return status == TransportStatus::invalid_argument ? TransportStatus::io_error : status;
  }

  TransportStatus interrupt_transfer(std::uint8_t endpoint, std::span<std::uint8_t> data,
                                     std::size_t& transferred,
                                     std::chrono::milliseconds timeout) override {
    transferred = 0;
    if (endpoint != kEndpointIn) return TransportStatus::io_error;  // no OUT endpoint here
    UsbReport report;
    const TransportStatus status = board_->read_report(report, timeout);
    // On the wire a truncated report is just a shorter packet: the transport judges its length.
    if (status != TransportStatus::ok && status != TransportStatus::short_report) return status;
    if (report.length > data.size()) return TransportStatus::io_error;  // LIBUSB_ERROR_OVERFLOW
    std::copy_n(report.bytes.begin(), report.length, data.begin());
    transferred = report.length;
    return TransportStatus::ok;
  }

 private:
  std::unique_ptr<Transport> board_;
  bool vendor_class_ = false;
  std::vector<std::uint8_t> report_descriptor_;
};

class SimulatedUsbBus final : public UsbBus {
 public:
  explicit SimulatedUsbBus(SimulatedRig& rig) : rig_(rig) {}

  TransportStatus list(std::uint16_t vendor_id, std::vector<UsbDeviceDescription>& out,
                       std::string& /*error*/) override {
    out.clear();
    for (const DeviceInfo& info : rig_.devices()) {
      if (info.vendor_id == vendor_id) out.push_back(describe(info, rig_.config()));
    }
    return TransportStatus::ok;
  }

  TransportStatus open(const UsbDeviceDescription& device,
                       std::unique_ptr<UsbDevice>& out) override {
    out.reset();
    std::unique_ptr<Transport> board = rig_.make_transport();
    const TransportStatus status =
        board->open({device.vendor_id, device.product_id, device.serial});
    if (status != TransportStatus::ok) return status;
    const DeviceInfo info = board->device_info();
    out = std::make_unique<SimulatedUsbDevice>(std::move(board), info);
    return TransportStatus::ok;
  }

  std::int64_t now_ns() const override { return rig_.now_ns(); }

 private:
  SimulatedRig& rig_;
};

}  // namespace

std::unique_ptr<UsbBus> make_simulated_usb_bus(SimulatedRig& rig) {
  return std::make_unique<SimulatedUsbBus>(rig);
}

}  // namespace furuta::sim
