#pragma once
// The simulated rig as the tests that design a balance controller for it and run it need it: the
// truth of config/rig.toml's [simulation], its motor and supply, the encoders' counts at the
// joints.

#include <numbers>

#include "furuta/config/rig_config.hpp"
#include "furuta/model/model.hpp"

namespace furuta::testing {

struct SimulatedRig {
  model::Parameters<double> truth;
  model::MotorData motor;
  double supply_v = 12;
  double arm_count_rad = 0;       // 1024 per motor-shaft turn, before the gears
  double pendulum_count_rad = 0;  // 4096 per turn
};

inline SimulatedRig simulated_rig() {
  const config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  constexpr double kTurn = 2 * std::numbers::pi;
  return {rig.simulation.parameters, rig.simulation.motor, rig.simulation.supply_voltage_v,
          kTurn / (1024.0 * rig.simulation.motor.total_ratio()), kTurn / 4096.0};
}

}  // namespace furuta::testing
