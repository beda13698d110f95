// What a board link does when its transport throws: the exception must reach the control loop
// (which writes the zero command and ends the session) or become a USB failure; it must never end
// the process through std::terminate with the motor still driven.
#include "furuta/daemon/board_link.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace furuta::daemon {
namespace {

using bridge::TransportStatus;

class ThrowingTransport final : public bridge::Transport {
 public:
  TransportStatus open(const bridge::DeviceMatch&) override { return TransportStatus::ok; }
  TransportStatus read_report(bridge::UsbReport&, std::chrono::nanoseconds) override {
    throw std::runtime_error("read failed");
  }
  TransportStatus write_report(std::span<const std::uint8_t>) override {
    throw std::runtime_error("write failed");
  }
  void close() override {}
  bool is_open() const override { return true; }
  const bridge::DeviceInfo& device_info() const override { return info_; }

 private:
  bridge::DeviceInfo info_;
};

TEST(BoardLink, DirectLinkLetsATransportExceptionReachTheLoop) {
  ThrowingTransport transport;
  DirectBoardLink link(transport);
  BoardReports reports;
  EXPECT_THROW(link.drain(reports), std::runtime_error);
  const std::uint8_t bytes[4] = {};
  EXPECT_THROW(link.write(bytes), std::runtime_error);
}

TEST(BoardLink, ThreadedLinkTurnsAReaderExceptionIntoAnIoError) {
  ThrowingTransport transport;
  ThreadedBoardLink link(transport);
  BoardReports reports;
  // The reader thread meets the exception on its first read; wait for it to be reported (a hang
  // guard, not a timing check).
  TransportStatus status = TransportStatus::ok;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (status == TransportStatus::ok && std::chrono::steady_clock::now() < give_up) {
    status = link.drain(reports);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(status, TransportStatus::io_error);
  EXPECT_EQ(reports.count, 0);
  // The reader reopens the transport after each failure (it opens at once here); a write while it
  // does is refused as disconnected without touching the transport. Otherwise the write's own
  // exception reaches the caller.
  const std::uint8_t bytes[4] = {};
  // Until the reader has reopened it: a hang guard again, not a count of attempts (a count ran
  // out under ThreadSanitizer on a loaded machine).
  bool threw = false;
  const auto reopen_give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!threw && std::chrono::steady_clock::now() < reopen_give_up) {
    try {
      EXPECT_EQ(link.write(bytes), TransportStatus::disconnected);
      std::this_thread::yield();
    } catch (const std::runtime_error&) {
      threw = true;
    }
  }
  EXPECT_TRUE(threw);
}

}  // namespace
}  // namespace furuta::daemon
