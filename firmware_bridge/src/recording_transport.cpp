#include <utility>

#include "furuta/firmware_bridge/replay_transport.hpp"

namespace furuta::bridge {

RecordingTransport::RecordingTransport(std::unique_ptr<Transport> inner, Clock& clock)
    : inner_(std::move(inner)), clock_(clock) {}

TransportStatus RecordingTransport::open(const DeviceMatch& match) {
  if (!inner_) return TransportStatus::not_found;
  const TransportStatus status = inner_->open(match);
  // A reopen after a disconnect finds the same device; the latest description wins.
  if (status == TransportStatus::ok) trace_.device = inner_->device_info();
  return status;
}

// An input is stamped with the report's host_time_ns (when it arrived), everything else with
// clock_.now_ns() when the call returned. Replay delivers an input at once when its time has passed
// and otherwise sleeps until it, so this reproduces both what the consumer sees (the same
// host_time_ns, which the 1047 loss tracker and the session log depend on) and when each read
// returns: a read that waited for the report returned at its arrival, a late poll returns late in
// replay too. Stamping inputs with the return time instead would replace per-report arrival times
// (the simulated rig's) by the batch's read time. This assumes the inner transport stamps
// host_time_ns on this same clock, as every backend does (the hardware ones use CLOCK_MONOTONIC, as
// MonotonicClock does).
TransportStatus RecordingTransport::read_report(UsbReport& report,
                                                std::chrono::nanoseconds timeout) {
  if (!inner_) return TransportStatus::not_open;
  const TransportStatus status = inner_->read_report(report, timeout);
  if (status == TransportStatus::ok || status == TransportStatus::short_report) {
    // A short report keeps its bytes as an input: replay gives short_report again from its length,
    // and the bytes that did arrive are not lost from the recording.
    const auto bytes = report.view();
    trace_.events.push_back(
        TraceEvent{report.host_time_ns, TraceEventKind::input, {bytes.begin(), bytes.end()}, {}});
  } else if (status != TransportStatus::timeout) {
    // Timeouts are not events: replay re-creates them from the gaps between recorded times.
    trace_.events.push_back(TraceEvent{clock_.now_ns(), TraceEventKind::error, {}, status});
  }
  return status;
}

// Failed writes are not recorded: the format's ERR events belong to the read stream, and replay
// cannot make a write fail.
TransportStatus RecordingTransport::write_report(std::span<const std::uint8_t> report) {
  if (!inner_) return TransportStatus::not_open;
  const TransportStatus status = inner_->write_report(report);
  if (status == TransportStatus::ok) {
    trace_.events.push_back(
        TraceEvent{clock_.now_ns(), TraceEventKind::output, {report.begin(), report.end()}, {}});
  }
  return status;
}

void RecordingTransport::close() {
  if (inner_) inner_->close();
  trace_.events.push_back(TraceEvent{clock_.now_ns(), TraceEventKind::end, {}, {}});
}

bool RecordingTransport::is_open() const {
  return inner_ && inner_->is_open();
}

const DeviceInfo& RecordingTransport::device_info() const {
  return inner_ ? inner_->device_info() : trace_.device;
}

}  // namespace furuta::bridge
