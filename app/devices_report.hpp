#pragma once
// Inside `furuta devices`: the report printed for one discovery result, separate from the USB scan
// so tests can show it every case (boards listed, none, permissions, no USB) without hardware.

#include <iosfwd>

#include "furuta/firmware_bridge/usb_backends.hpp"

namespace furuta::app {

// Prints `found` and returns run_devices_command's code (0 every board listed, 1
// some listed and some denied, 2 none listed: none found, all denied or USB unreadable).
int report_discovery(const bridge::DiscoveryResult& found, std::ostream& out, std::ostream& err);

}  // namespace furuta::app
