#pragma once
// The whole model (docs/model.md): parameters, dynamics, motor torque, regressor.

#include "furuta/model/dynamics.hpp"    // IWYU pragma: export
#include "furuta/model/motor.hpp"       // IWYU pragma: export
#include "furuta/model/parameters.hpp"  // IWYU pragma: export
#include "furuta/model/regressor.hpp"   // IWYU pragma: export
