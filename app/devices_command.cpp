// `furuta devices`: what is plugged in, and, when nothing usable is, what to do about it.

#include <exception>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "devices_report.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::app {

namespace {

// The README's rule: every board found was listed (0); some were and some could not be opened,
// said which (1, done in part); no board answered, whether none is plugged in, none may be opened
// or the bus cannot be read (2: a rig with no board to talk to is as unusable as no daemon).
constexpr int kListed = kExitDone;
constexpr int kSomeDenied = kExitPartOrRefused;
constexpr int kNoneListed = kExitNotDone;
constexpr int kUsbUnreadable = kExitNotDone;

constexpr const char* kUdevRule = "systemd/70-furuta-phidgets.rules";

// HID boards go through hidraw (hidapi), which leaves the kernel driver in place; a vendor-class
// interface (the encoder board's at firmware 2xx, per its adapter) has no hidraw node, so only
// libusb reaches it.
std::string backend_for(const bridge::DeviceInfo& device) {
  return device.vendor_class_interface ? "libusb (vendor-class interface)" : "hidapi (HID)";
}

// The firmware as the vendor library reports it, and a word when the codecs do not know it: the
// daemon refuses such a board unless the configuration allows it.
std::string firmware_text(const bridge::DeviceInfo& device) {
  std::string text = std::to_string(device.firmware_version);
  const bool known = bridge::firmware_known(device.product_id, device.vendor_class_interface,
                                            device.firmware_version);
  const auto range = bridge::known_firmware(device.product_id, device.vendor_class_interface);
  if (!known && range) {
    text += " (untested: furuta knows " + std::to_string(range->first) + "-" +
            std::to_string(range->last) + " for this board)";
  }
  return text;
}

void print_device(std::ostream& out, const bridge::DeviceInfo& device, const std::string& backend) {
  out << "  " << device.product_name << "  serial " << (device.serial.empty() ? "?" : device.serial)
      << "  firmware " << firmware_text(device) << "  " << device.path << "  backend " << backend
      << "\n";
}

// The simulated rig is listed as the USB scan lists hardware: from its boards' descriptors, so the
// firmware is read from bcdDevice as the vendor reads it.
int list_simulated(const DevicesOptions& options, std::ostream& out, std::ostream& err) {
  sim::SimulatedRigConfig rig_config;
  if (!options.config_path.empty()) {
    try {
      rig_config = config::load_rig_config(options.config_path).simulation;
    } catch (const std::exception& e) {
      err << e.what() << "\n";
      return kUsbUnreadable;
    }
  }
  bridge::VirtualClock clock;
  sim::SimulatedRig rig(rig_config, clock);
  const std::unique_ptr<bridge::UsbBus> bus = rig.make_usb_bus();
  const bridge::DiscoveryResult found = bridge::discover_phidgets(*bus);
  if (found.devices.empty()) {
    out << "the simulated rig has no boards connected\n";
    return kNoneListed;
  }
  out << "simulated Phidget boards:\n";
  for (const bridge::DeviceInfo& device : found.devices) {
    print_device(out, device, "simulated " + backend_for(device));
  }
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
           "use --sim.\n";
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
  if (found.devices.empty()) return kNoneListed;
  return found.access_denied.empty() ? kListed : kSomeDenied;
}

int run_devices_command(const DevicesOptions& options, std::ostream& out, std::ostream& err) {
  if (options.simulated) return list_simulated(options, out, err);
  return report_discovery(bridge::discover_phidgets(), out, err);
}

}  // namespace furuta::app
