// What is plugged in: every device with the Phidgets vendor id, through libusb, which sees HID and
// vendor-class boards alike (hidapi would miss a 1047 with firmware 2xx).

#include <libusb.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "furuta/firmware_bridge/usb_backends.hpp"
#include "libusb_support.hpp"

namespace furuta::bridge {

DiscoveryResult discover_phidgets() {
  DiscoveryResult result;
  int error = 0;
  const usb_detail::ContextPtr context = usb_detail::make_context(error);
  if (!context) {
    result.error = std::string("libusb_init failed: ") + libusb_strerror(error);
    return result;
  }
  const usb_detail::DeviceList list(context.get());
  if (list.error() != LIBUSB_SUCCESS) {
    result.error = std::string("cannot list USB devices: ") + libusb_strerror(list.error());
    return result;
  }

  for (libusb_device* device : list) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(device, &descriptor) != LIBUSB_SUCCESS) continue;
    if (descriptor.idVendor != kPhidgetsVendorId) continue;

    DeviceInfo info;
    info.vendor_id = descriptor.idVendor;
    info.product_id = descriptor.idProduct;
    info.product_name = std::string(phidget_product_name(descriptor.idProduct));
    info.firmware_version = firmware_version_from_bcd(descriptor.bcdDevice);
    info.path = usb_detail::bus_path(device);
    info.vendor_class_interface = usb_detail::interface0_class(device) ==
                                  std::optional<std::uint8_t>(LIBUSB_CLASS_VENDOR_SPEC);
    // Report lengths stay 0: they need the interface claimed, which discovery must not do to a
    // board another process may be using.

    // The serial is a string descriptor, fetched from the device: that needs it opened, which is
    // where missing permissions show.
    libusb_device_handle* raw = nullptr;
    const int opened = libusb_open(device, &raw);
    if (opened == LIBUSB_ERROR_ACCESS) {
      result.access_denied.push_back(info.product_name + " at " + info.path);
      continue;
    }
    if (opened == LIBUSB_SUCCESS) {
      const usb_detail::HandlePtr handle(raw);
      info.serial = usb_detail::read_serial(handle.get(), descriptor.iSerialNumber);
    }
    // Other failures (unplugged mid-scan, ...) still list the board, serial unknown.
    result.devices.push_back(std::move(info));
  }
  return result;
}

}  // namespace furuta::bridge
