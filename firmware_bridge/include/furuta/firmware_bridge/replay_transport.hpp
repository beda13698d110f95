#pragma once
// Replays a recorded trace as a device: input reports arrive at their recorded times on the given
// Clock, recorded errors recur, reads between the last input and the recording's END time out, and
// each output report written is checked against the recording (or, in record mode, appended to a
// new trace). Also a recorder that wraps any live transport.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/transport.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::bridge {

struct ReplayMismatch {
  std::int64_t time_ns = 0;
  std::size_t output_index = 0;        // which written report (0-based)
  std::vector<std::uint8_t> expected;  // empty when the recording had no more outputs
  std::vector<std::uint8_t> actual;
};

class ReplayTransport final : public Transport {
 public:
  enum class OutputMode : std::uint8_t { check, record };

  ReplayTransport(UsbTrace trace, Clock& clock, OutputMode mode = OutputMode::check);

  TransportStatus open(const DeviceMatch& match) override;  // matches the trace's device
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override;
  TransportStatus write_report(std::span<const std::uint8_t> report) override;
  void close() override;
  bool is_open() const override;
  const DeviceInfo& device_info() const override;

  const std::vector<ReplayMismatch>& mismatches() const { return mismatches_; }
  // Outputs written (record mode: the new recording of them).
  const std::vector<TraceEvent>& written_outputs() const { return written_; }
  bool finished() const;  // every recorded input delivered

 private:
  UsbTrace trace_;
  Clock& clock_;
  OutputMode mode_;
  bool open_ = false;
  std::size_t next_event_ = 0;               // next input or error event to play
  std::size_t next_output_ = 0;              // next recorded output to compare against
  std::optional<std::int64_t> end_time_ns_;  // when the recording stopped, if it says
  std::vector<ReplayMismatch> mismatches_;
  std::vector<TraceEvent> written_;
};

// Passes every call through to `inner` and records it, with the clock's time, into a trace;
// close() records END so a replay knows how long the device was there.
class RecordingTransport final : public Transport {
 public:
  RecordingTransport(std::unique_ptr<Transport> inner, Clock& clock);

  TransportStatus open(const DeviceMatch& match) override;
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override;
  TransportStatus write_report(std::span<const std::uint8_t> report) override;
  void close() override;
  bool is_open() const override;
  const DeviceInfo& device_info() const override;

  const UsbTrace& trace() const { return trace_; }

 private:
  std::unique_ptr<Transport> inner_;
  Clock& clock_;
  UsbTrace trace_;
};

}  // namespace furuta::bridge
