#include "furuta/daemon/board_link.hpp"

#include <algorithm>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>

namespace furuta::daemon {

using bridge::TransportStatus;

namespace {

void store(RawReport& to, const bridge::UsbReport& from, TransportStatus status) noexcept {
  to.time_ns = from.host_time_ns;
  to.status = status;
  to.length = static_cast<std::uint8_t>(std::min(from.length, from.bytes.size()));
  std::copy_n(from.bytes.begin(), to.length, to.bytes.begin());
}

bool is_report(TransportStatus status) {
  return status == TransportStatus::ok || status == TransportStatus::short_report;
}

}  // namespace

TransportStatus DirectBoardLink::drain(BoardReports& out) {
  bridge::UsbReport report;
  while (out.count < out.reports.size()) {
    const TransportStatus status = transport_.read_report(report, std::chrono::nanoseconds(0));
    if (status == TransportStatus::timeout) return TransportStatus::ok;
    if (!is_report(status)) return status;
    store(out.reports[out.count++], report, status);
  }
  return TransportStatus::ok;
}

TransportStatus DirectBoardLink::write(std::span<const std::uint8_t> report) {
  return transport_.write_report(report);
}

// A report and how it was read, as the reader thread hands it over.
struct ReadResult {
  bridge::UsbReport report;
  TransportStatus status = TransportStatus::ok;
};

// Two seconds of reports at 8 ms; more only if the loop stalls for longer, and then the oldest
// survive and the reader records the overflow as a failure rather than dropping silently.
class ThreadedBoardLink::Queue
    : public boost::lockfree::spsc_queue<ReadResult, boost::lockfree::capacity<256>> {};

ThreadedBoardLink::ThreadedBoardLink(bridge::Transport& transport)
    : transport_(transport), queue_(std::make_unique<Queue>()) {
  reader_ = std::thread([this] { read_forever(); });
}

ThreadedBoardLink::~ThreadedBoardLink() {
  stop_.store(true);
  if (reader_.joinable()) reader_.join();
}

void ThreadedBoardLink::read_forever() {
  // The read blocks until a report arrives, so host_time_ns is its arrival time. The timeout only
  // bounds how long a stop request waits.
  constexpr auto kReadTimeout = std::chrono::milliseconds(50);
  ReadResult result;
  while (!stop_.load()) {
    try {
      result.status = transport_.read_report(result.report, kReadTimeout);
    } catch (...) {
      // Escaping this thread would be std::terminate with the motor still driven; as a failed
      // read, the loop stops the session with the motor at zero.
      result.status = TransportStatus::io_error;
    }
    if (result.status == TransportStatus::timeout) continue;
    if (!is_report(result.status)) {
      failure_.store(result.status);
      // A dead device answers at once; don't spin on it.
      std::this_thread::sleep_for(kReadTimeout);
      continue;
    }
    if (!queue_->push(result)) failure_.store(TransportStatus::io_error);
  }
}

TransportStatus ThreadedBoardLink::drain(BoardReports& out) noexcept {
  ReadResult result;
  while (out.count < out.reports.size() && queue_->pop(result)) {
    store(out.reports[out.count++], result.report, result.status);
  }
  return failure_.load();
}

TransportStatus ThreadedBoardLink::write(std::span<const std::uint8_t> report) {
  return transport_.write_report(report);
}

}  // namespace furuta::daemon
