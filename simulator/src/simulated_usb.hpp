#pragma once
// Private to the simulator: the simulated rig as a UsbBus (SimulatedRig::make_usb_bus).

#include <memory>

#include "furuta/firmware_bridge/usb_device.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::sim {

std::unique_ptr<bridge::UsbBus> make_simulated_usb_bus(SimulatedRig& rig);

}  // namespace furuta::sim
