// The hardware UsbBus: libusb. It lists and opens devices and moves bytes; which request and which
// lengths a board wants is the transport's business (usb_transport.cpp), so that part is tested
// against the simulated rig's bus as well.

#include <libusb.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"
#include "libusb_support.hpp"

namespace furuta::bridge {

namespace {

using detail::ConfigPtr;
using detail::ContextPtr;
using detail::DeviceList;
using detail::HandlePtr;

constexpr int kClaimedInterface = 0;

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
    default:  // PIPE (a stall: the request was not understood), OVERFLOW, IO, ...
      return TransportStatus::io_error;
  }
}

unsigned int timeout_ms(std::chrono::milliseconds timeout) {
  return detail::timeout_ms_at_least_one(timeout);
}

// Interface 0's descriptors, from the active configuration (index 0 when none is active yet).
void describe_interface(libusb_device* device, UsbDeviceDescription& d) {
  libusb_config_descriptor* raw = nullptr;
  if (libusb_get_active_config_descriptor(device, &raw) != LIBUSB_SUCCESS &&
      libusb_get_config_descriptor(device, 0, &raw) != LIBUSB_SUCCESS) {
    return;
  }
  const ConfigPtr config(raw);
  if (config->bNumInterfaces <= kClaimedInterface ||
      config->interface[kClaimedInterface].num_altsetting < 1) {
    return;
  }
  const libusb_interface_descriptor& interface = config->interface[kClaimedInterface].altsetting[0];
  d.interface_class = interface.bInterfaceClass;
  if (interface.extra != nullptr && interface.extra_length > 0) {
    d.interface_extra.assign(interface.extra, interface.extra + interface.extra_length);
  }
  for (int i = 0; i < interface.bNumEndpoints; ++i) {
    const libusb_endpoint_descriptor& endpoint = interface.endpoint[i];
    d.endpoints.push_back({endpoint.bEndpointAddress, endpoint.wMaxPacketSize});
  }
}

class LibusbDevice final : public UsbDevice {
 public:
  LibusbDevice(HandlePtr handle, bool detached_kernel_driver)
      : handle_(std::move(handle)), detached_kernel_driver_(detached_kernel_driver) {}
  ~LibusbDevice() override {
    // Give the board back as we found it, so hidraw tools (and our hidapi backend) see it again.
    libusb_release_interface(handle_.get(), kClaimedInterface);
    if (detached_kernel_driver_) libusb_attach_kernel_driver(handle_.get(), kClaimedInterface);
  }

  TransportStatus control_transfer(const UsbSetup& setup, std::span<std::uint8_t> data,
                                   std::size_t& transferred,
                                   std::chrono::milliseconds timeout) override {
    transferred = 0;
    const int result = libusb_control_transfer(
        handle_.get(), setup.request_type, setup.request, setup.value, setup.index, data.data(),
        static_cast<std::uint16_t>(std::min<std::size_t>(data.size(), 0xFFFF)),
        timeout_ms(timeout));
    if (result < 0) return status_from_libusb(result);
    transferred = static_cast<std::size_t>(result);
    return TransportStatus::ok;
  }

  TransportStatus interrupt_transfer(std::uint8_t endpoint, std::span<std::uint8_t> data,
                                     std::size_t& transferred,
                                     std::chrono::milliseconds timeout) override {
    // Our code allocates nothing here; libusb's synchronous call allocates its transfer.
    int moved = 0;
    const int result =
        libusb_interrupt_transfer(handle_.get(), endpoint, data.data(),
                                  static_cast<int>(data.size()), &moved, timeout_ms(timeout));
    transferred = moved > 0 ? static_cast<std::size_t>(moved) : 0;
    return status_from_libusb(result);
  }

 private:
  HandlePtr handle_;
  bool detached_kernel_driver_ = false;
};

class LibusbBus final : public UsbBus {
 public:
  TransportStatus list(std::uint16_t vendor_id, std::vector<UsbDeviceDescription>& out,
                       std::string& error) override {
    out.clear();
    if (!start(error)) return TransportStatus::io_error;
    const DeviceList list(context_.get());
    if (list.error() != LIBUSB_SUCCESS) {
      error = std::string("cannot list USB devices: ") + libusb_strerror(list.error());
      return TransportStatus::io_error;
    }
    for (libusb_device* device : list) {
      libusb_device_descriptor descriptor{};
      if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
      if (descriptor.idVendor != vendor_id) continue;
      UsbDeviceDescription d;
      d.vendor_id = descriptor.idVendor;
      d.product_id = descriptor.idProduct;
      d.bcd_device = descriptor.bcdDevice;
      d.path = detail::bus_path(device);
      describe_interface(device, d);
      // The serial is a string descriptor, fetched from the device: that needs it opened, which
      // is where missing permissions show. Other failures (unplugged mid-scan) list it anyway.
      libusb_device_handle* raw = nullptr;
      const int opened = libusb_open(device, &raw);
      if (opened == LIBUSB_ERROR_ACCESS) d.access_denied = true;
      if (opened == LIBUSB_SUCCESS) {
        const HandlePtr handle(raw);
        d.serial = detail::read_serial(handle.get(), descriptor.iSerialNumber);
      }
      out.push_back(std::move(d));
    }
    return TransportStatus::ok;
  }

  TransportStatus open(const UsbDeviceDescription& wanted,
                       std::unique_ptr<UsbDevice>& out) override {
    out.reset();
    std::string error;
    if (!start(error)) return TransportStatus::io_error;
    const DeviceList list(context_.get());
    if (list.error() != LIBUSB_SUCCESS) return TransportStatus::io_error;
    for (libusb_device* device : list) {
      libusb_device_descriptor descriptor{};
      if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
      if (descriptor.idVendor != wanted.vendor_id || descriptor.idProduct != wanted.product_id ||
          detail::bus_path(device) != wanted.path) {
        continue;
      }
      libusb_device_handle* raw = nullptr;
      const int opened = libusb_open(device, &raw);
      if (opened != LIBUSB_SUCCESS) return status_from_libusb(opened);
      HandlePtr handle(raw);
      // usbhid binds the HID boards; the interface cannot be claimed while it does.
      bool detached = false;
      if (libusb_kernel_driver_active(handle.get(), kClaimedInterface) == 1) {
        const int result = libusb_detach_kernel_driver(handle.get(), kClaimedInterface);
        if (result != LIBUSB_SUCCESS) return status_from_libusb(result);
        detached = true;
      }
      const int claimed = libusb_claim_interface(handle.get(), kClaimedInterface);
      if (claimed != LIBUSB_SUCCESS) {
        if (detached) libusb_attach_kernel_driver(handle.get(), kClaimedInterface);
        return status_from_libusb(claimed);
      }
      out = std::make_unique<LibusbDevice>(std::move(handle), detached);
      return TransportStatus::ok;
    }
    return TransportStatus::not_found;  // unplugged since it was listed
  }

  std::int64_t now_ns() const override { return MonotonicClock{}.now_ns(); }

 private:
  // One context for the bus's life, started on first use: a machine without usbfs fails here.
  bool start(std::string& error) {
    if (context_) return true;
    int code = 0;
    context_ = detail::make_context(code);
    if (!context_) error = std::string("libusb_init failed: ") + libusb_strerror(code);
    return context_ != nullptr;
  }

  ContextPtr context_;
};

}  // namespace

std::unique_ptr<UsbBus> make_libusb_bus() {
  return std::make_unique<LibusbBus>();
}

}  // namespace furuta::bridge
