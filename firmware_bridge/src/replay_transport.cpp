#include "furuta/firmware_bridge/replay_transport.hpp"

#include <algorithm>
#include <limits>

namespace furuta::bridge {

namespace {

bool is_read_event(const TraceEvent& e) {
  return e.kind == TraceEventKind::input || e.kind == TraceEventKind::error;
}

// now + timeout without overflow: callers pass nanoseconds::max() to mean "wait for ever".
std::int64_t deadline_after(std::int64_t now_ns, std::chrono::nanoseconds timeout) {
  const std::int64_t t = std::max<std::int64_t>(timeout.count(), 0);
  if (now_ns > std::numeric_limits<std::int64_t>::max() - t) {
    return std::numeric_limits<std::int64_t>::max();
  }
  return now_ns + t;
}

}  // namespace

ReplayTransport::ReplayTransport(UsbTrace trace, Clock& clock, OutputMode mode)
    : trace_(std::move(trace)), clock_(clock), mode_(mode) {
  // The last END marks when the recording stopped; earlier ones are closes before a reopen.
  for (const TraceEvent& e : trace_.events) {
    if (e.kind == TraceEventKind::end) end_time_ns_ = e.time_ns;
  }
}

// Opening again after close() (as the loop does after a recorded disconnect) continues where the
// replay stood: the recording went on across the reconnect too.
TransportStatus ReplayTransport::open(const DeviceMatch& match) {
  const DeviceInfo& d = trace_.device;
  if (match.vendor_id != d.vendor_id || match.product_id != d.product_id) {
    return TransportStatus::not_found;
  }
  if (match.serial && *match.serial != d.serial) return TransportStatus::not_found;
  open_ = true;
  return TransportStatus::ok;
}

TransportStatus ReplayTransport::read_report(UsbReport& report, std::chrono::nanoseconds timeout) {
  if (!open_) return TransportStatus::not_open;
  // Outputs are consumed by write_report, in their own order; reads only see inputs and errors.
  while (next_event_ < trace_.events.size() && !is_read_event(trace_.events[next_event_])) {
    ++next_event_;
  }
  const std::int64_t now = clock_.now_ns();
  if (next_event_ >= trace_.events.size()) {
    // Past the last input the recorded device was still there, and quiet, until the recording
    // stopped: reads that end by then time out as they did live; only later ones are exhausted.
    const std::int64_t deadline = deadline_after(now, timeout);
    if (end_time_ns_ && deadline <= *end_time_ns_) {
      clock_.sleep_until_ns(deadline);
      return TransportStatus::timeout;
    }
    return TransportStatus::replay_exhausted;
  }

  const TraceEvent& event = trace_.events[next_event_];
  if (event.time_ns > now) {
    const std::int64_t deadline = deadline_after(now, timeout);
    if (event.time_ns > deadline) {
      // Nothing would have arrived within the timeout: wait it out like a device would.
      clock_.sleep_until_ns(deadline);
      return TransportStatus::timeout;
    }
    clock_.sleep_until_ns(event.time_ns);
  }
  ++next_event_;
  report.host_time_ns = event.time_ns;

  if (event.kind == TraceEventKind::error) {
    report.length = 0;
    return event.status;
  }
  const std::size_t n = std::min(event.bytes.size(), report.bytes.size());
  std::copy_n(event.bytes.begin(), n, report.bytes.begin());
  report.length = n;
  // Only a hand-built trace can hold more than a report buffer; the parser refuses such lines.
  if (event.bytes.size() > report.bytes.size()) return TransportStatus::io_error;
  if (n < trace_.device.input_report_bytes) return TransportStatus::short_report;
  return TransportStatus::ok;
}

TransportStatus ReplayTransport::write_report(std::span<const std::uint8_t> report) {
  if (!open_) return TransportStatus::not_open;
  const std::int64_t now = clock_.now_ns();
  const std::size_t output_index = written_.size();
  written_.push_back(TraceEvent{now, TraceEventKind::output, {report.begin(), report.end()}, {}});
  if (mode_ == OutputMode::record) return TransportStatus::ok;

  while (next_output_ < trace_.events.size() &&
         trace_.events[next_output_].kind != TraceEventKind::output) {
    ++next_output_;
  }
  if (next_output_ >= trace_.events.size()) {
    mismatches_.push_back(ReplayMismatch{now, output_index, {}, {report.begin(), report.end()}});
    return TransportStatus::replay_mismatch;
  }
  // Consumed either way, so one wrong report does not shift every later comparison.
  const std::vector<std::uint8_t>& expected = trace_.events[next_output_++].bytes;
  if (!std::equal(expected.begin(), expected.end(), report.begin(), report.end())) {
    mismatches_.push_back(
        ReplayMismatch{now, output_index, expected, {report.begin(), report.end()}});
    return TransportStatus::replay_mismatch;
  }
  return TransportStatus::ok;
}

void ReplayTransport::close() {
  open_ = false;
}

bool ReplayTransport::is_open() const {
  return open_;
}

const DeviceInfo& ReplayTransport::device_info() const {
  return trace_.device;
}

bool ReplayTransport::finished() const {
  return std::none_of(trace_.events.begin() + static_cast<std::ptrdiff_t>(next_event_),
                      trace_.events.end(), is_read_event);
}

}  // namespace furuta::bridge
