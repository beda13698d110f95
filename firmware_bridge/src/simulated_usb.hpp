#pragma once
// Private to the firmware bridge: the simulated rig as a UsbBus (SimulatedRig::make_usb_bus).

#include <memory>

#include "furuta/firmware_bridge/simulated_rig.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"

namespace furuta::bridge {

std::unique_ptr<UsbBus> make_simulated_usb_bus(SimulatedRig& rig);

}  // namespace furuta::bridge
