#pragma once
// A session log as typed messages: what the daemon writes and the identification reads.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/rig_control_t.hpp"
#include "furuta/rig_controller_t.hpp"
#include "furuta/rig_fault_t.hpp"
#include "furuta/rig_log_seal_t.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/rig_signed_command_t.hpp"
#include "furuta/rig_usb_report_t.hpp"
#include "furuta/session_log/lcm_log.hpp"

namespace furuta::session_log {

inline constexpr const char* kChannelSample = "RIG_SAMPLE";
inline constexpr const char* kChannelSession = "RIG_SESSION";
inline constexpr const char* kChannelStatus = "RIG_STATUS";
inline constexpr const char* kChannelCommand = "RIG_COMMAND";
// Commands that move the motor, signed (docs/security.md); a log keeps the one that started it.
inline constexpr const char* kChannelSignedCommand = "RIG_COMMAND_SIGNED";
inline constexpr const char* kChannelUsb = "RIG_USB";
inline constexpr const char* kChannelFault = "RIG_FAULT";
// Balance sessions: the controller's cycle beside each sample, and the controller file it ran.
inline constexpr const char* kChannelControl = "RIG_CONTROL";
inline constexpr const char* kChannelController = "RIG_CONTROLLER";
// A log's last event, never published: what the log held when written (rig_log_seal_t).
inline constexpr const char* kChannelSeal = "RIG_LOG_SEAL";

struct SessionLog {
  std::filesystem::path path;
  std::optional<furuta::rig_session_t> start;  // the first event
  std::optional<furuta::rig_session_t> end;    // absent when the session was cut short
  // The signed command that started the session, tag and all (absent: started in-process, by a
  // replay, or logged before commands were signed).
  std::optional<furuta::rig_signed_command_t> start_command;
  std::vector<furuta::rig_sample_t> samples;
  std::vector<furuta::rig_usb_report_t> usb_reports;
  std::vector<furuta::rig_fault_t> faults;
  // A balance session's: the controller's cycles, and the controller file (the first record).
  std::vector<furuta::rig_control_t> control;
  std::optional<furuta::rig_controller_t> controller;
  LogReadStats read_stats;
  std::uint64_t undecodable_events = 0;  // intact on disk but not a message of its channel's type
  std::uint64_t unknown_channel_events = 0;
  // Indices i (ascending) such that the reader skipped a damaged region between samples[i - 1] and
  // samples[i]: the samples on either side are not contiguous in time even when no sequence
  // number is missing (the region may have held USB reports only).
  std::vector<std::size_t> damage_before_sample;

  // The seal (the first RIG_LOG_SEAL event; absent in logs written before logs were sealed, and
  // in logs cut short) and what the reader found against it.
  std::optional<furuta::rig_log_seal_t> seal;
  // SHA-256 (hex) over the events before the seal, or over every event when there is none: the
  // log's identity, the same for two copies of one log whatever their file names.
  std::string digest_hex;
  std::uint64_t digested_events = 0;   // the events digest_hex covers
  std::uint64_t digested_samples = 0;  // RIG_SAMPLE events among them
  bool seal_digest_matches = false;    // the seal's digest is digest_hex
  // The seal event's header as read: its number is the events before it, its time theirs.
  bool seal_header_matches = false;
  std::uint64_t events_after_seal = 0;
  std::uint64_t start_records = 0;  // more than one: sessions joined into one file
  std::uint64_t end_records = 0;
  // Samples whose session is not the start record's (another session's samples joined in).
  std::uint64_t foreign_samples = 0;

  bool complete() const { return start.has_value() && end.has_value(); }
  // Sample sequence numbers not present between 0 (a session's first) and the last (each should be
  // explained by a fault record).
  std::vector<std::int64_t> missing_sequence_numbers() const;
};

// Throws std::runtime_error only when the file cannot be opened; damage is counted, not thrown.
SessionLog load_session_log(const std::filesystem::path& path);

// Where a replayed log's data came from, for its seal.
struct SealSource {
  std::string source;     // "PATH sha256:HEX" of the log replayed; empty for a session on the rig
  std::string integrity;  // that log's verdict: "intact" or its problems
};
// Writes the log's seal: its last event, after the end record, carrying the session, the events
// and samples written so far and their digest (LcmLogWriter::digest). The seal's own event is
// numbered `events` and timed as the event before it, so that its header is fixed too.
LogWriteStatus write_seal(LcmLogWriter& log, const std::string& session, std::int64_t samples,
                          const SealSource& source = {});

// A command the host wrote to the motor board (an OUTPUT report of the log), read by the board's
// adapter: the board ramps its applied duty towards `duty` at `acceleration_pct_per_s` (never 0)
// from `time_ns` (the write's host time).
struct MotorCommandWrite {
  std::int64_t time_ns = 0;
  double duty = 0.0;  // [-1, 1], n/255
  double acceleration_pct_per_s = 0.0;
  double braking_fraction = 0.0;  // [0, 1], what duty 0 does
};

// Every command written to the motor board that the transport accepted, in time order, read by
// the adapter named `motor_board` (the configuration's [boards.motor] model); reports it cannot
// read are skipped.
std::vector<MotorCommandWrite> motor_command_writes(const SessionLog& log,
                                                    std::string_view motor_board);

// A report the motor board sent (an INPUT report of the log), read by its adapter: what the board
// measured when it made the report, received by the host at `time_ns`.
struct MotorInputReport {
  std::int64_t time_ns = 0;
  std::int32_t encoder_position = 0;  // the board's count; an i32 that wraps
  double applied_duty = 0.0;          // [-1, 1], n/255
  double supply_v = 0.0;
};

// Every report of the motor board its adapter can read, in time order (reports of equal time in
// the log's order).
std::vector<MotorInputReport> motor_input_reports(const SessionLog& log,
                                                  std::string_view motor_board);

// Each report's time on its board's own clock, fed the samples' reports in log order: the motor
// board's 8-bit report counter unwrapped (in reports), the encoder board's packet ticks
// accumulated (in ticks; the first report's are left out: they cover time before the host
// listened). A lost encoder board report takes its ticks with it, so after one the encoder
// board's times no longer keep time.
class BoardTimeline {
 public:
  double motor_report(std::int16_t packet_counter);
  double encoder_report(std::int32_t packet_ticks);

 private:
  std::optional<std::uint8_t> last_counter_;
  double reports_ = 0;
  std::optional<double> ticks_;
};

// The raw USB reports of one board, as a trace the replay backend can play (the device line from
// the session start record).
bridge::UsbTrace usb_trace_from_log(const SessionLog& log, std::int8_t board);

}  // namespace furuta::session_log
