// What is plugged in: every device with the Phidgets vendor id, through a UsbBus (libusb on
// hardware), which sees HID and vendor-class boards alike (hidapi would miss a 1047 with firmware
// 2xx).

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "furuta/firmware_bridge/usb_backends.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"

namespace furuta::bridge {

DiscoveryResult discover_phidgets(UsbBus& bus) {
  DiscoveryResult result;
  std::vector<UsbDeviceDescription> devices;
  if (bus.list(kPhidgetsVendorId, devices, result.error) != TransportStatus::ok) {
    if (result.error.empty()) result.error = "the USB bus could not be read";
    return result;
  }
  for (const UsbDeviceDescription& d : devices) {
    DeviceInfo info;
    info.vendor_id = d.vendor_id;
    info.product_id = d.product_id;
    info.product_name = std::string(phidget_product_name(d.product_id));
    info.vendor_class_interface = d.interface_class == kUsbClassVendorSpecific;
    info.firmware_version = firmware_version_from_bcd(d.bcd_device, info.vendor_class_interface);
    info.path = d.path;
    info.serial = d.serial;
    // Report lengths stay 0: they need the interface claimed, which discovery must not do to a
    // board another process may be using.
    if (d.access_denied) {
      result.access_denied.push_back(info.product_name + " at " + info.path);
      continue;
    }
    result.devices.push_back(std::move(info));
  }
  return result;
}

DiscoveryResult discover_phidgets() {
  const std::unique_ptr<UsbBus> bus = make_libusb_bus();
  return discover_phidgets(*bus);
}

}  // namespace furuta::bridge
