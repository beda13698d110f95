#pragma once
// What the real-time loop hands to the publisher/logger thread, through a lock-free single-producer
// queue: fixed-size plain structs, so producing one never allocates.

#include <array>
#include <cstdint>

#include "furuta/daemon/excitation.hpp"
#include "furuta/daemon/safety.hpp"
#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/firmware_bridge/transport.hpp"
#include "furuta/rig_sample_t.hpp"

namespace furuta::daemon {

// At 16 ms each board sends two reports a cycle; after a stall the backlog is drained this many at
// a time (the rest stay queued in the transport for the next cycle, so none is lost).
inline constexpr std::size_t kMaxReportsPerCycle = 24;
inline constexpr std::size_t kNameChars = 96;
inline constexpr std::size_t kDetailChars = 160;

// One USB report as it crossed the wire.
struct RawReport {
  std::int64_t time_ns = 0;  // arrival (input) or write (output) time, on the loop's clock
  bridge::TransportStatus status = bridge::TransportStatus::ok;  // ok or short_report for inputs
  std::uint8_t length = 0;
  std::array<std::uint8_t, bridge::kMaxReportBytes> bytes{};
};

struct BoardReports {
  std::uint8_t count = 0;
  std::array<RawReport, kMaxReportsPerCycle> reports{};
};

// The reports of one cycle that decoded, each read once by the board's adapter where it arrived.
template <typename Reading>
struct BoardReadings {
  std::uint8_t count = 0;
  std::array<Reading, kMaxReportsPerCycle> readings{};
};

// The sample's flags are the message's (rig_sample_t.lcm): one definition.
inline constexpr std::int32_t kSampleMotorStale = furuta::rig_sample_t::FLAG_MOTOR_STALE;
inline constexpr std::int32_t kSampleEncoderStale = furuta::rig_sample_t::FLAG_ENCODER_STALE;
inline constexpr std::int32_t kSampleMotorLost = furuta::rig_sample_t::FLAG_MOTOR_LOST;
inline constexpr std::int32_t kSampleEncoderLost = furuta::rig_sample_t::FLAG_ENCODER_LOST;
inline constexpr std::int32_t kSampleOverrun = furuta::rig_sample_t::FLAG_OVERRUN;

// The balance controller's cycle (rig_control_t), beside the sample of a balance session.
struct ControlFigures {
  bool present = false;   // false outside balance sessions
  std::uint8_t mode = 0;  // rig_control_t::MODE_*, in control::BalanceMode's order
  double upright_error_rad = 0;
  double arm_rate_rad_s = 0;
  double pendulum_rate_rad_s = 0;
  double energy_ratio = 0;
  double law_duty = 0;
  std::int64_t law_time_ns = 0;
};

struct RigSample {
  std::int64_t seq = 0;
  std::int64_t monotonic_ns = 0;  // the cycle's deadline (its wake-up is monotonic_ns + latency)
  std::int64_t wake_latency_ns = 0;
  std::int64_t queued_ns = 0;  // when the loop queued it for the publisher, on the loop's clock
  std::int64_t wall_time_ns = 0;
  std::int32_t arm_counts = 0;       // relative to the session start
  std::int64_t pendulum_counts = 0;  // relative to the zero (hanging at rest at the start)
  double arm_angle_rad = 0;
  double pendulum_angle_rad = 0;
  double commanded_duty = 0;
  double applied_duty = 0;
  double motor_current_a = 0;
  double supply_voltage_v = 0;
  std::uint8_t motor_status_flags = 0;
  std::uint8_t encoder_flags = 0;
  BoardReports motor_in;  // as they crossed the wire, for the log's bit-exact replay
  BoardReports encoder_in;
  BoardReadings<bridge::MotorReading> motor;  // the same reports, read
  BoardReadings<bridge::EncoderReading> encoder;
  RawReport motor_out;                    // the command written this cycle
  std::int32_t motor_lost_reports = 0;    // cumulative in the session
  std::int32_t encoder_lost_reports = 0;  // cumulative in the session
  std::int32_t overruns = 0;              // cumulative missed cycles in the session
  std::int32_t flags = 0;                 // kSample*
  ControlFigures control;
};

struct SessionStartEvent {
  std::array<char, kNameChars> session{};
  std::array<char, kNameChars> label{};
  std::int64_t request_id = 0;  // the start command's (0: a replay)
  ExcitationSpec excitation;
  bool balance = false;  // the balance controller, not the excitation, drives the motor
  std::int64_t period_ns = 0;
  std::int64_t monotonic_ns = 0;
  std::int64_t wall_time_ns = 0;
  std::int64_t arm_zero_counts = 0;       // the motor board's position taken as q1 = 0
  std::int64_t pendulum_zero_counts = 0;  // the encoder board's accumulated counts taken as q2 = 0
};

struct SessionEndEvent {
  std::array<char, kNameChars> session{};
  StopReason reason = StopReason::none;
  std::array<char, kDetailChars> detail{};
  std::int64_t samples = 0;
  std::int64_t monotonic_ns = 0;
  std::int64_t wall_time_ns = 0;
  // The zero command that ended it, when written outside a sample's cycle (duration reached, stop,
  // e-stop, signal); length 0 when the last sample carries it.
  RawReport final_command;
};

struct FaultEvent {
  StopReason reason = StopReason::none;  // for non-fatal events: none, with a kind in `what`
  std::array<char, 32> what{};           // machine-readable: lost_reports, overrun, usb_error, ...
  std::array<char, kDetailChars> detail{};
  std::int64_t seq = 0;  // the sample it concerns
  std::int64_t monotonic_ns = 0;
  bool fatal = false;
  std::int64_t request_id = 0;  // start_refused, start_cancelled: the start command's
};

struct LoopEvent {
  enum class Kind : std::uint8_t { sample, session_start, session_end, fault };
  Kind kind = Kind::sample;
  RigSample sample;
  SessionStartEvent start;
  SessionEndEvent end;
  FaultEvent fault;
};

// Copies a string into a fixed char array, truncated and always terminated.
template <std::size_t N>
void copy_text(std::array<char, N>& to, const char* from) noexcept {
  std::size_t i = 0;
  for (; from && from[i] != '\0' && i + 1 < N; ++i) to[i] = from[i];
  to[i] = '\0';
}

}  // namespace furuta::daemon
