#pragma once
// The rig's boards by role. The loop drives a motor board and reads an encoder board; what it
// needs of them is below, in units, with each board's own time. A board model is an adapter behind
// these interfaces (its codec and its loss detection), made by its configuration name: nothing
// above this module names a board model except as a configuration value.
//
// An adapter decodes each input report exactly once, where it arrives; the loop's sample, the log's
// typed records and everything downstream take the reading, never the bytes again. The bytes stay
// beside it for bit-exact replay only.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::bridge {

// One motor-board input report.
struct MotorReading {
  std::int64_t host_ns = 0;          // arrival, on the loop's clock
  std::int64_t position_counts = 0;  // the motor shaft encoder's count as the board keeps it
  double applied_duty = 0.0;         // [-1, 1], what the board applies now
  double current_a = 0.0;
  double supply_v = 0.0;
  bool over_temperature = false;     // the board's protection tripped (or a short)
  bool under_voltage = false;        // the board's supply lock-out
  std::uint8_t status_flags = 0;     // the board's own status bits, logged as they came
  std::uint32_t report_counter = 0;  // how the board numbers its reports (wraps at its width)
  std::uint32_t board_time = 0;      // the board's clock at the report, in its own units
  int lost_before = 0;               // reports the board sent that never arrived, before this one
};

// One encoder-board input report, for the channel the pendulum is on.
struct EncoderReading {
  std::int64_t host_ns = 0;
  std::int32_t delta_counts = 0;  // counts since the board's previous report
  std::uint32_t board_ticks = 0;  // board time this report covers, in the board's ticks
  std::uint8_t flags = 0;         // the channel's own bits, logged as they came
  int lost_before = 0;            // reports found lost at this one (their counts are gone)
};

// The steps a motor board's readings move in: what its wire can say.
struct MotorResolution {
  double duty_step = 0.0;      // the applied duty's, as the board echoes it
  double supply_step_v = 0.0;  // the supply reading's
};

// What the loop asks of the motor.
struct MotorCommand {
  double duty = 0.0;              // [-1, 1]
  double braking_fraction = 0.0;  // [0, 1]
};

// What a written output report commands, as the board takes it: it ramps its applied duty towards
// `duty` at `acceleration_pct_per_s` (% of full duty per s, never 0) from the moment it arrives.
struct MotorWrite {
  double duty = 0.0;
  double acceleration_pct_per_s = 0.0;
  double braking_fraction = 0.0;  // what duty 0 does
};

class MotorBoard {
 public:
  virtual ~MotorBoard() = default;
  // The reading in `report`, or nothing when it is not a whole report of this board (the bytes
  // are still logged; nothing is taken from them).
  virtual std::optional<MotorReading> read(std::span<const std::uint8_t> report,
                                           std::int64_t host_ns) noexcept = 0;
  // `command` as the output report, into `report` (the device's output report length): false when
  // the length is not this board's or the command is not finite. The duty never goes out above
  // the adapter's limit, whatever the wire's rounding.
  virtual bool write(const MotorCommand& command,
                     std::span<std::uint8_t> report) const noexcept = 0;
  // What an output report written to this board commands (a log's record of the writes).
  virtual std::optional<MotorWrite> read_write(
      std::span<const std::uint8_t> report) const noexcept = 0;
  // The board is new as far as the host knows (a reconnect): loss detection starts again.
  virtual void restart() noexcept = 0;
  virtual MotorResolution resolution() const noexcept = 0;
};

class EncoderBoard {
 public:
  virtual ~EncoderBoard() = default;
  virtual std::optional<EncoderReading> read(std::span<const std::uint8_t> report,
                                             std::int64_t host_ns) noexcept = 0;
  // The output report that makes the board report the pendulum's channel; its length (0: none).
  virtual std::size_t enable(std::span<std::uint8_t> report) const noexcept = 0;
  virtual void restart() noexcept = 0;
};

struct MotorBoardSettings {
  double max_duty = 1.0;              // never written above this
  double acceleration_pct_per_s = 0;  // the duty's ramp, % of full duty per s; 0: the fastest
};

using MotorBoardMaker = std::unique_ptr<MotorBoard> (*)(const DeviceInfo& device,
                                                        const MotorBoardSettings& settings);
using EncoderBoardMaker = std::unique_ptr<EncoderBoard> (*)(const DeviceInfo& device, int channel);

// Where the host finds a board on the bus.
struct UsbIdentity {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
};

// A motor board model as the host knows it before one is opened: its adapter, where it is found,
// and the duty ramps it can be set to (% of full duty per s).
struct MotorBoardKind {
  MotorBoardMaker make = nullptr;
  UsbIdentity usb;
  double min_acceleration_pct_per_s = 0;
  double max_acceleration_pct_per_s = 0;
};
struct EncoderBoardKind {
  EncoderBoardMaker make = nullptr;
  UsbIdentity usb;
};

// The board models the project ships adapters for, as configuration values name them.
inline constexpr std::string_view kShippedMotorBoard = "1065";
inline constexpr std::string_view kShippedEncoderBoard = "1047";

// The kind registered under `kind` (a configuration value); std::invalid_argument naming the
// kinds there are for an unknown one.
MotorBoardKind motor_board_kind(std::string_view kind);
EncoderBoardKind encoder_board_kind(std::string_view kind);
// The adapter of `kind` for the opened device (throws as motor_board_kind does).
std::unique_ptr<MotorBoard> make_motor_board(std::string_view kind, const DeviceInfo& device,
                                             const MotorBoardSettings& settings);
std::unique_ptr<EncoderBoard> make_encoder_board(std::string_view kind, const DeviceInfo& device,
                                                 int channel);
// A new board is a kind registered under its configuration name before the rig is opened;
// false when the name is taken.
bool register_motor_board(std::string_view kind, const MotorBoardKind& board);
bool register_encoder_board(std::string_view kind, const EncoderBoardKind& board);
std::vector<std::string> motor_board_kinds();
std::vector<std::string> encoder_board_kinds();

}  // namespace furuta::bridge
