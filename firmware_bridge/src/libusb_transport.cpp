// Any Phidget board through libusb: the only way to reach a 1047 with vendor-class firmware 2xx,
// and an alternative to hidraw for the HID boards. The interface is claimed exclusively (usbhid
// detached while we hold it, re-attached on close).

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"
#include "libusb_support.hpp"

namespace furuta::bridge {

namespace {

using usb_detail::ConfigPtr;
using usb_detail::ContextPtr;
using usb_detail::DeviceList;
using usb_detail::HandlePtr;

constexpr int kInterface = 0;
constexpr std::uint8_t kEndpointIn = 0x81;
constexpr std::uint8_t kEndpointOut = 0x01;

// Writes are on the control loop's path (one per 16 ms cycle), so they may not block for the vendor
// library's 500 ms. 10 ms covers a full-speed interrupt OUT endpoint polled every 8 frames plus a
// frame of slack (the boards' bInterval is not documented: *inferred*), and a control transfer,
// which completes within a frame or two, with room to spare.
constexpr unsigned int kWriteTimeoutMs = 10;
// Descriptor requests during open(), off the control path: generous.
constexpr unsigned int kSetupTimeoutMs = 1000;

// HID class requests and descriptors (HID 1.11, sections 7.1 and 7.2).
constexpr std::uint8_t kHidDescriptorType = 0x21;
constexpr std::uint8_t kReportDescriptorType = 0x22;
constexpr std::uint8_t kGetDescriptorRequestType = 0x81;  // device-to-host, standard, interface
constexpr std::uint8_t kGetDescriptorRequest = 0x06;
constexpr std::uint16_t kReportDescriptorValue = kReportDescriptorType << 8;  // 0x2200, index 0
constexpr std::uint8_t kSetReportRequestType = 0x21;  // host-to-device, class, interface
constexpr std::uint8_t kSetReportRequest = 0x09;
constexpr std::uint16_t kSetReportOutputValue = 0x0200;  // report type Output (2), report id 0
// Used when the interface's HID descriptor does not give the report descriptor's length.
constexpr std::uint16_t kDefaultReportDescriptorBytes = 256;
constexpr std::uint16_t kMaxReportDescriptorBytes = 4096;  // the kernel's limit too

// The vendor-class 1047 (firmware 2xx) takes its output report as a vendor "device write" control
// transfer: host-to-device, vendor, device recipient; request 0x02 with packet type 0x01 in
// wValue's high byte (from the vendor library's notes). The low byte of wValue and wIndex were not
// found stated: *inferred* as 0, to be checked on hardware.
constexpr std::uint8_t kVendorWriteRequestType = 0x40;
constexpr std::uint8_t kVendorWriteRequest = 0x02;
constexpr std::uint8_t kVendorWritePacketType = 0x01;
constexpr std::uint8_t kVendorWriteValueLow = 0x00;  // *inferred*
constexpr std::uint16_t kVendorWriteIndex = 0x0000;  // *inferred*
constexpr std::uint16_t kVendorWriteValue =
    static_cast<std::uint16_t>(kVendorWritePacketType << 8 | kVendorWriteValueLow);
// The vendor-class output report: one byte, the bitmask of channels to enable.
constexpr std::size_t kVendorOutputReportBytes = 1;

// The length of the report descriptor as the interface's HID class descriptor states it (it sits in
// the interface descriptor's `extra` bytes: bLength, 0x21, bcdHID(2), bCountryCode,
// bNumDescriptors, then {bDescriptorType, wDescriptorLength(2)} per descriptor).
std::uint16_t report_descriptor_length(const libusb_interface_descriptor& interface) {
  const std::size_t size = interface.extra_length > 0 ? interface.extra_length : 0;
  const unsigned char* extra = interface.extra;
  std::size_t pos = 0;
  while (extra != nullptr && pos + 2 <= size) {
    const std::size_t length = extra[pos];
    if (length < 2 || pos + length > size) break;
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

TransportStatus status_from_libusb(int error) {
  switch (error) {
    case LIBUSB_SUCCESS:
      return TransportStatus::ok;
    case LIBUSB_ERROR_TIMEOUT:
      return TransportStatus::timeout;
    case LIBUSB_ERROR_ACCESS:
      return TransportStatus::access_denied;
    case LIBUSB_ERROR_BUSY:
      return TransportStatus::busy;
    case LIBUSB_ERROR_NO_DEVICE:
      return TransportStatus::disconnected;
    case LIBUSB_ERROR_NOT_FOUND:
      return TransportStatus::not_found;
    case LIBUSB_ERROR_INVALID_PARAM:
      return TransportStatus::invalid_argument;
    // A signal interrupted the wait: nothing arrived, the caller reads again.
    case LIBUSB_ERROR_INTERRUPTED:
      return TransportStatus::timeout;
    default:
      return TransportStatus::io_error;
  }
}

class LibusbTransport final : public Transport {
 public:
  ~LibusbTransport() override { close(); }

  TransportStatus open(const DeviceMatch& match) override;
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override;
  TransportStatus write_report(std::span<const std::uint8_t> report) override;
  void close() override;
  bool is_open() const override { return handle_ != nullptr; }
  const DeviceInfo& device_info() const override { return info_; }

 private:
  // Claims the interface of an opened device and learns its endpoints and report lengths. On
  // failure the caller's close() undoes whatever was done.
  TransportStatus set_up(libusb_device* device, const libusb_device_descriptor& descriptor,
                         std::string serial);
  TransportStatus read_hid_report_lengths(const libusb_interface_descriptor& interface);

  ContextPtr context_;  // declared first: outlives handle_
  HandlePtr handle_;
  DeviceInfo info_;
  bool detached_kernel_driver_ = false;
  bool claimed_ = false;
  bool has_out_endpoint_ = false;
};

TransportStatus LibusbTransport::open(const DeviceMatch& match) {
  close();
  if (!context_) {
    int error = 0;
    context_ = usb_detail::make_context(error);
    if (!context_) return TransportStatus::io_error;  // no usbfs here: nothing can be opened
  }
  const DeviceList list(context_.get());
  if (list.error() != LIBUSB_SUCCESS) return TransportStatus::io_error;

  // Several boards of one product may be plugged in: the serial, read from each, tells them apart.
  // A board we may not open could be the one asked for, so denial outranks "not found".
  bool saw_denied = false;
  bool saw_failure = false;
  for (libusb_device* device : list) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
    if (descriptor.idVendor != match.vendor_id || descriptor.idProduct != match.product_id)
      continue;

    libusb_device_handle* raw = nullptr;
    const int opened = libusb_open(device, &raw);
    if (opened == LIBUSB_ERROR_ACCESS) {
      saw_denied = true;
      continue;
    }
    if (opened != LIBUSB_SUCCESS) {
      saw_failure = true;
      continue;
    }
    HandlePtr handle(raw);
    std::string serial = usb_detail::read_serial(handle.get(), descriptor.iSerialNumber);
    if (match.serial && serial != *match.serial) continue;

    handle_ = std::move(handle);
    const TransportStatus status = set_up(device, descriptor, std::move(serial));
    if (status != TransportStatus::ok) close();
    return status;
  }
  if (saw_denied) return TransportStatus::access_denied;
  if (saw_failure) return TransportStatus::io_error;
  return TransportStatus::not_found;
}

TransportStatus LibusbTransport::set_up(libusb_device* device,
                                        const libusb_device_descriptor& descriptor,
                                        std::string serial) {
  libusb_device_handle* handle = handle_.get();

  // usbhid binds the HID boards; the interface cannot be claimed while it does.
  if (libusb_kernel_driver_active(handle, kInterface) == 1) {
    const int detached = libusb_detach_kernel_driver(handle, kInterface);
    if (detached != LIBUSB_SUCCESS) return status_from_libusb(detached);
    detached_kernel_driver_ = true;
  }
  const int claimed = libusb_claim_interface(handle, kInterface);
  if (claimed != LIBUSB_SUCCESS) return status_from_libusb(claimed);
  claimed_ = true;

  libusb_config_descriptor* raw_config = nullptr;
  const int got_config = libusb_get_active_config_descriptor(device, &raw_config);
  if (got_config != LIBUSB_SUCCESS) return status_from_libusb(got_config);
  const ConfigPtr config(raw_config);
  if (config->bNumInterfaces <= kInterface || config->interface[kInterface].num_altsetting < 1) {
    return TransportStatus::io_error;
  }
  const libusb_interface_descriptor& interface = config->interface[kInterface].altsetting[0];

  std::optional<std::uint16_t> in_packet_bytes;
  for (int i = 0; i < interface.bNumEndpoints; ++i) {
    const libusb_endpoint_descriptor& endpoint = interface.endpoint[i];
    if (endpoint.bEndpointAddress == kEndpointIn) in_packet_bytes = endpoint.wMaxPacketSize;
    if (endpoint.bEndpointAddress == kEndpointOut) has_out_endpoint_ = true;
  }
  if (!in_packet_bytes) return TransportStatus::io_error;  // not a board we know how to read

  info_.vendor_class_interface = interface.bInterfaceClass == LIBUSB_CLASS_VENDOR_SPEC;
  if (info_.vendor_class_interface) {
    // No report descriptor: one report per interrupt packet, taken to fill the packet (the vendor
    // library's reading). Should the 2xx firmware send shorter packets (its 4 x 10 bytes of data in
    // a 64-byte endpoint), every read would come back short_report: to check on hardware.
    info_.input_report_bytes = *in_packet_bytes & 0x07FF;  // bits 11-12: extra transactions
    info_.output_report_bytes = kVendorOutputReportBytes;
  } else {
    const TransportStatus lengths = read_hid_report_lengths(interface);
    if (lengths != TransportStatus::ok) return lengths;
  }
  if (info_.input_report_bytes == 0 || info_.input_report_bytes > kMaxReportBytes ||
      info_.output_report_bytes > kMaxReportBytes) {
    return TransportStatus::io_error;
  }

  info_.vendor_id = descriptor.idVendor;
  info_.product_id = descriptor.idProduct;
  info_.serial = std::move(serial);
  info_.firmware_version = firmware_version_from_bcd(descriptor.bcdDevice);
  info_.product_name = std::string(phidget_product_name(descriptor.idProduct));
  info_.path = usb_detail::bus_path(device);
  return TransportStatus::ok;
}

TransportStatus LibusbTransport::read_hid_report_lengths(
    const libusb_interface_descriptor& interface) {
  std::vector<std::uint8_t> descriptor(report_descriptor_length(interface));
  const int received = libusb_control_transfer(
      handle_.get(), kGetDescriptorRequestType, kGetDescriptorRequest, kReportDescriptorValue,
      static_cast<std::uint16_t>(interface.bInterfaceNumber), descriptor.data(),
      static_cast<std::uint16_t>(descriptor.size()), kSetupTimeoutMs);
  if (received < 0) return status_from_libusb(received);
  descriptor.resize(static_cast<std::size_t>(received));
  // Without the lengths a short (lossy) report could not be told from a whole one: refuse.
  const HidReportLengths lengths = parse_hid_report_lengths(descriptor);
  if (lengths.input_bytes == 0) return TransportStatus::io_error;
  info_.input_report_bytes = lengths.input_bytes;
  info_.output_report_bytes = lengths.output_bytes;
  return TransportStatus::ok;
}

TransportStatus LibusbTransport::read_report(UsbReport& report, std::chrono::nanoseconds timeout) {
  report.length = 0;
  if (!handle_) return TransportStatus::not_open;

  // Ask for exactly one report: were we to ask for more and the report fill whole packets, the
  // transfer would wait on and merge the next report. libusb reads timeout 0 as "forever", so a
  // poll waits at most 1 ms (usb_detail::timeout_ms_at_least_one).
  // A packet longer than asked for fails with LIBUSB_ERROR_OVERFLOW (io_error): the descriptor's
  // length would then be wrong. (Our code allocates nothing here; libusb's synchronous call
  // allocates its transfer internally.)
  int transferred = 0;
  const int result = libusb_interrupt_transfer(
      handle_.get(), kEndpointIn, report.bytes.data(), static_cast<int>(info_.input_report_bytes),
      &transferred, usb_detail::timeout_ms_at_least_one(timeout));
  report.host_time_ns = MonotonicClock{}.now_ns();
  report.length = transferred > 0 ? static_cast<std::size_t>(transferred) : 0;

  if (result == LIBUSB_SUCCESS) {
    return report.length < info_.input_report_bytes ? TransportStatus::short_report
                                                    : TransportStatus::ok;
  }
  // Part of a report arrived before the timeout: the rest is lost, say so.
  if (result == LIBUSB_ERROR_TIMEOUT && report.length > 0) return TransportStatus::short_report;
  return status_from_libusb(result);
}

TransportStatus LibusbTransport::write_report(std::span<const std::uint8_t> report) {
  if (!handle_) return TransportStatus::not_open;
  const std::size_t length = info_.output_report_bytes;
  if (report.empty() || report.size() > length) return TransportStatus::invalid_argument;

  // Zero-padded to the report length, as the boards expect; no report-id byte on the wire.
  std::array<std::uint8_t, kMaxReportBytes> buffer{};
  std::copy(report.begin(), report.end(), buffer.begin());

  int sent = 0;
  if (has_out_endpoint_) {
    const int result = libusb_interrupt_transfer(handle_.get(), kEndpointOut, buffer.data(),
                                                 static_cast<int>(length), &sent, kWriteTimeoutMs);
    if (result != LIBUSB_SUCCESS) return status_from_libusb(result);
  } else if (info_.vendor_class_interface) {
    sent = libusb_control_transfer(handle_.get(), kVendorWriteRequestType, kVendorWriteRequest,
                                   kVendorWriteValue, kVendorWriteIndex, buffer.data(),
                                   static_cast<std::uint16_t>(length), kWriteTimeoutMs);
  } else {
    sent =
        libusb_control_transfer(handle_.get(), kSetReportRequestType, kSetReportRequest,
                                kSetReportOutputValue, static_cast<std::uint16_t>(kInterface),
                                buffer.data(), static_cast<std::uint16_t>(length), kWriteTimeoutMs);
  }
  if (sent < 0) return status_from_libusb(sent);
  return static_cast<std::size_t>(sent) == length ? TransportStatus::ok : TransportStatus::io_error;
}

void LibusbTransport::close() {
  if (handle_) {
    // Give the board back as we found it, so hidraw tools (and our hidapi backend) see it again.
    if (claimed_) libusb_release_interface(handle_.get(), kInterface);
    if (detached_kernel_driver_) libusb_attach_kernel_driver(handle_.get(), kInterface);
    handle_.reset();
  }
  claimed_ = false;
  detached_kernel_driver_ = false;
  has_out_endpoint_ = false;
  info_ = DeviceInfo{};
}

}  // namespace

std::unique_ptr<Transport> make_libusb_transport() {
  return std::make_unique<LibusbTransport>();
}

}  // namespace furuta::bridge
