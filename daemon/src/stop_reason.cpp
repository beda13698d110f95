#include "furuta/daemon/safety.hpp"

namespace furuta::daemon {

std::string_view to_string(StopReason reason) {
  switch (reason) {
    case StopReason::none:
      return "none";
    case StopReason::duration_reached:
      return "duration_reached";
    case StopReason::stop_command:
      return "stop_command";
    case StopReason::estop_command:
      return "estop_command";
    case StopReason::signal:
      return "signal";
    case StopReason::arm_angle_limit:
      return "arm_angle_limit";
    case StopReason::duty_limit:
      return "duty_limit";
    case StopReason::stale_motor_reports:
      return "stale_motor_reports";
    case StopReason::stale_encoder_reports:
      return "stale_encoder_reports";
    case StopReason::usb_error:
      return "usb_error";
    case StopReason::under_voltage:
      return "under_voltage";
    case StopReason::over_temperature:
      return "over_temperature";
    case StopReason::supply_out_of_range:
      return "supply_out_of_range";
    case StopReason::arm_encoder_stuck:
      return "arm_encoder_stuck";
    case StopReason::pendulum_encoder_stuck:
      return "pendulum_encoder_stuck";
    case StopReason::log_error:
      return "log_error";
    case StopReason::exception:
      return "exception";
    case StopReason::pendulum_fell:
      return "pendulum_fell";
  }
  return "unknown";
}

bool is_fault(StopReason reason) {
  // A fall ends a balance session as its outcome, not as a fault of the rig.
  return reason != StopReason::none && reason != StopReason::duration_reached &&
         reason != StopReason::stop_command && reason != StopReason::pendulum_fell;
}

}  // namespace furuta::daemon
