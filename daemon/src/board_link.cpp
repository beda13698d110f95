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

bridge::DeviceMatch identity_of(const bridge::DeviceInfo& info) {
  bridge::DeviceMatch match;
  match.vendor_id = info.vendor_id;
  match.product_id = info.product_id;
  if (!info.serial.empty()) match.serial = info.serial;
  return match;
}

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

TransportStatus DirectBoardLink::reconnect() {
  // A handle onto a device that went away stays dead: only a fresh open finds it again.
  transport_.close();
  return transport_.open(identity_);
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

ThreadedBoardLink::ThreadedBoardLink(bridge::Transport& transport,
                                     std::chrono::milliseconds reopen_interval)
    : transport_(transport),
      info_(transport.device_info()),
      identity_(identity_of(info_)),
      reopen_interval_(reopen_interval),
      queue_(std::make_unique<Queue>()) {
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
    if (down_.load()) {
      reopen();
      continue;
    }
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
      down_.store(true);  // the next turn reopens it
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

void ThreadedBoardLink::reopen() {
  // Until the loop is out of write_report, the transport is still in use.
  while (writing_.load()) std::this_thread::yield();
  while (!stop_.load()) {
    transport_.close();
    // Hardware backends may block here (enumeration, claiming the interface): this thread may.
    TransportStatus status = TransportStatus::io_error;
    try {
      status = transport_.open(identity_);
    } catch (...) {
      status = TransportStatus::io_error;
    }
    if (status == TransportStatus::ok) {
      reopens_.fetch_add(1);
      failure_.store(TransportStatus::ok);
      down_.store(false);
      return;
    }
    // A device that is gone answers at once; don't spin on it.
    const auto until = std::chrono::steady_clock::now() + reopen_interval_;
    while (!stop_.load() && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(
          std::min<std::chrono::nanoseconds>(reopen_interval_, std::chrono::milliseconds(20)));
    }
  }
}

TransportStatus ThreadedBoardLink::write(std::span<const std::uint8_t> report) {
  writing_.store(true);
  if (down_.load()) {
    writing_.store(false);
    return TransportStatus::disconnected;
  }
  TransportStatus status = TransportStatus::io_error;
  try {
    status = transport_.write_report(report);
  } catch (...) {
    writing_.store(false);
    throw;
  }
  writing_.store(false);
  return status;
}

TransportStatus ThreadedBoardLink::reconnect() noexcept {
  if (!reopen_asked_) {
    // Ask for a reopen of our own even when the reader has already done one: a failed write is
    // news to it (its reads may still succeed), and one reopen too many costs nothing.
    reopen_asked_ = true;
    reopens_when_asked_ = reopens_.load();
    down_.store(true);
    return TransportStatus::disconnected;
  }
  if (down_.load() || reopens_.load() == reopens_when_asked_) {
    const TransportStatus failure = failure_.load();
    return failure == TransportStatus::ok ? TransportStatus::disconnected : failure;
  }
  reopen_asked_ = false;
  // Reopened. What was queued before belongs to the board as it was; the loop starts afresh.
  ReadResult stale;
  while (queue_->pop(stale)) {
  }
  return TransportStatus::ok;
}

}  // namespace furuta::daemon
