// `furuta devices`: what is plugged in, and, when nothing usable is, what to do about it.

#include <ostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "devices_report.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/simulated_rig.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"

namespace furuta::app {

namespace {

constexpr int kListed = 0;
constexpr int kNoneListed = 1;
constexpr int kUsbUnreadable = 2;

constexpr const char* kUdevRule = "systemd/70-furuta-phidgets.rules";

// HID boards go through hidraw (hidapi), which leaves the kernel driver in place; a vendor-class
// interface (1047 firmware 2xx) has no hidraw node, so only libusb reaches it.
std::string backend_for(const bridge::DeviceInfo& device) {
  return device.vendor_class_interface ? "libusb (vendor-class interface)" : "hidapi (HID)";
}

void print_device(std::ostream& out, const bridge::DeviceInfo& device, const std::string& backend) {
  out << "  " << device.product_name << "  serial " << (device.serial.empty() ? "?" : device.serial)
      << "  firmware " << device.firmware_version << "  " << device.path << "  backend " << backend
      << "\n";
}

int list_simulated(std::ostream& out) {
  bridge::VirtualClock clock;
  const bridge::SimulatedRig rig(bridge::SimulatedRigConfig{}, clock);
  const std::vector<bridge::DeviceInfo> devices = rig.devices();
  if (devices.empty()) {
    out << "the simulated rig has no boards connected\n";
    return kNoneListed;
  }
  out << "simulated Phidget boards:\n";
  for (const bridge::DeviceInfo& device : devices) print_device(out, device, "simulated");
  return kListed;
}

void explain_access_denied(const std::vector<std::string>& denied, std::ostream& err) {
  err << "permission denied opening " << denied.size() << " Phidget board(s):\n";
  for (const std::string& name : denied) err << "  " << name << "\n";
  err << "install the udev rule " << kUdevRule << " and give your user the group 'furuta':\n"
      << "  sudo cp " << kUdevRule << " /etc/udev/rules.d/\n"
      << "  sudo udevadm control --reload\n"
      << "  sudo groupadd -f furuta && sudo usermod -aG furuta $USER   (log in again)\n"
      << "then unplug and replug the boards.\n";
}

}  // namespace

int report_discovery(const bridge::DiscoveryResult& found, std::ostream& out, std::ostream& err) {
  if (!found.error.empty()) {
    err << "cannot read the USB bus: libusb could not start (" << found.error << ").\n"
        << "Is this a container or machine without /dev/bus/usb? Pass the USB devices through, or "
           "use --simulated.\n";
    return kUsbUnreadable;
  }

  if (!found.devices.empty()) {
    out << "Phidget boards on USB:\n";
    for (const bridge::DeviceInfo& device : found.devices) {
      print_device(out, device, backend_for(device));
    }
  }
  if (!found.access_denied.empty()) explain_access_denied(found.access_denied, err);

  if (found.devices.empty() && found.access_denied.empty()) {
    out << "no Phidget boards found (vendor 06c2).\n"
        << "Check that the boards are powered and their USB cables plugged in (`lsusb -d 06c2:` "
           "should list them).\n";
  }
  return found.devices.empty() ? kNoneListed : kListed;
}

int run_devices_command(const DevicesOptions& options, std::ostream& out, std::ostream& err) {
  if (options.simulated) return list_simulated(out);
  return report_discovery(bridge::discover_phidgets(), out, err);
}

}  // namespace furuta::app
