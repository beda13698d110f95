#pragma once
// The USB layer beneath the libusb transport: a bus that lists the devices of a vendor with their
// descriptors and opens one, and an opened device's control and interrupt transfers. libusb
// implements it for hardware (make_libusb_bus); the simulated rig (simulator/) implements it too,
// so the transport's choices (which request, which endpoint, which lengths, which firmware version)
// meet the boards' byte protocol in tests, as libfranka's transport meets its mock server.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::bridge {

inline constexpr std::uint8_t kUsbClassHid = 0x03;
inline constexpr std::uint8_t kUsbClassVendorSpecific = 0xFF;

struct UsbEndpointDescription {
  std::uint8_t address = 0;            // bit 7 set: IN
  std::uint16_t max_packet_bytes = 0;  // wMaxPacketSize as the descriptor gives it
};

// What the descriptors say of one device and its interface 0 (the boards have one configuration
// and one interface).
struct UsbDeviceDescription {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::uint16_t bcd_device = 0;
  std::string serial;          // iSerialNumber; empty when unreadable
  bool access_denied = false;  // listed, but we may not open it (so the serial is unknown)
  std::string path;            // "bus 1 port 3": where to plug, and how open() finds it again
  std::uint8_t interface_class = 0;
  // The class-specific descriptors that follow interface 0's descriptor (a HID board's HID
  // descriptor, which gives the report descriptor's length).
  std::vector<std::uint8_t> interface_extra;
  std::vector<UsbEndpointDescription> endpoints;
};

struct UsbSetup {
  std::uint8_t request_type = 0;  // bmRequestType
  std::uint8_t request = 0;       // bRequest
  std::uint16_t value = 0;        // wValue
  std::uint16_t index = 0;        // wIndex
};

// An opened device with interface 0 claimed; destroying it releases the interface (and gives a
// detached kernel driver back). Transfers return a status and the bytes moved; a timeout may have
// moved some.
class UsbDevice {
 public:
  virtual ~UsbDevice() = default;
  UsbDevice() = default;
  UsbDevice(const UsbDevice&) = delete;
  UsbDevice& operator=(const UsbDevice&) = delete;

  // `data` is the data stage: filled for a device-to-host request (bit 7 of request_type), sent
  // otherwise. A request the device does not answer (a stall) is io_error.
  virtual TransportStatus control_transfer(const UsbSetup& setup, std::span<std::uint8_t> data,
                                           std::size_t& transferred,
                                           std::chrono::milliseconds timeout) = 0;
  // One transfer on an interrupt endpoint; for IN, a packet longer than `data` is io_error (an
  // overflow).
  virtual TransportStatus interrupt_transfer(std::uint8_t endpoint, std::span<std::uint8_t> data,
                                             std::size_t& transferred,
                                             std::chrono::milliseconds timeout) = 0;
};

class UsbBus {
 public:
  virtual ~UsbBus() = default;
  UsbBus() = default;
  UsbBus(const UsbBus&) = delete;
  UsbBus& operator=(const UsbBus&) = delete;

  // Every device of `vendor_id`. io_error when the bus cannot be read, with `error` saying why.
  virtual TransportStatus list(std::uint16_t vendor_id, std::vector<UsbDeviceDescription>& out,
                               std::string& error) = 0;
  // Opens a listed device and claims its interface 0 (detaching a kernel driver that holds it).
  virtual TransportStatus open(const UsbDeviceDescription& device,
                               std::unique_ptr<UsbDevice>& out) = 0;
  // The time a report is stamped with on arrival (CLOCK_MONOTONIC on hardware).
  virtual std::int64_t now_ns() const = 0;
};

// The hardware bus. Creating it never fails; a machine without usbfs fails at list().
std::unique_ptr<UsbBus> make_libusb_bus();

// Any Phidget board over a UsbBus: claims interface 0, reads interrupt IN 0x81, writes interrupt
// OUT 0x01 when the interface has it, else HID SET_REPORT, or for a vendor-class interface (1047
// firmware 2xx) the vendor "device write" request. Report lengths come from the HID report
// descriptor; a vendor-class board has none, and its reports are taken as the packets come
// (docs/phidget-protocol.md).
std::unique_ptr<Transport> make_usb_transport(std::unique_ptr<UsbBus> bus);

}  // namespace furuta::bridge
