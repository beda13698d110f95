#pragma once
// A minimal bang-bang session driven straight through the firmware bridge: the simulated-rig demo
// and the replay tests use it. (The daemon's real-time loop supersedes it for real sessions.)

#include <cstdint>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/encoder_geometry.hpp"
#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::app {

struct BridgeSessionSpec {
  std::int64_t period_ns = 16'000'000;
  double duration_s = 10.0;
  double amplitude_duty = 0.3;
  double switch_period_s = 0.5;  // the duty's sign flips every switch period
  int pendulum_channel = 0;
  bridge::EncoderGeometry arm_encoder;
  bridge::EncoderGeometry pendulum_encoder;
};

// One cycle's decoded view of both boards (the newest report of each).
struct BridgeSample {
  std::int64_t time_ns = 0;  // cycle wake-up on the session clock
  std::int32_t arm_counts = 0;
  std::int64_t pendulum_counts = 0;  // running sum of 1047 deltas
  double arm_angle_rad = 0;
  double pendulum_angle_rad = 0;
  double commanded_duty = 0;
  double applied_duty = 0;
  double motor_current_a = 0;
  double supply_voltage_v = 0;
  std::uint8_t motor_status_flags = 0;
  int motor_reports = 0;  // reports drained this cycle
  int encoder_reports = 0;
  std::int64_t motor_lost_total = 0;
  std::int64_t encoder_lost_total = 0;
  std::int64_t motor_report_host_ns = 0;  // newest report's receive time
  std::int64_t encoder_report_host_ns = 0;

  bool operator==(const BridgeSample&) const = default;
};

struct BridgeSessionResult {
  std::vector<BridgeSample> samples;
  int transport_errors = 0;  // reads or writes that failed (the session stops at the first)
  std::string stop_reason;   // "duration reached" or the failure
};

// Opens nothing: `motor` (1065) and `encoder` (1047) must be open. Enables the pendulum channel,
// runs the session, and always ends by commanding zero duty.
BridgeSessionResult run_bridge_session(bridge::Transport& motor, bridge::Transport& encoder,
                                       bridge::Clock& clock, const BridgeSessionSpec& spec);

}  // namespace furuta::app
