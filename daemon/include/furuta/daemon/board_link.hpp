#pragma once
// How the control loop reaches one board: take every report that has arrived, write one report.
// Two ways to read, one interface:
//  - DirectBoardLink polls the transport on the loop thread. For the simulated rig and replay,
//    whose reports carry their arrival time already.
//  - ThreadedBoardLink keeps a reader thread blocked in read_report, so each report is stamped
//    when it arrives (the encoder board's loss detection, in its adapter, needs arrival times),
//    and hands reports to the loop through a lock-free queue. For hardware.

#include <atomic>
#include <chrono>
#include <memory>
#include <span>
#include <thread>

#include "furuta/daemon/loop_events.hpp"
#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::daemon {

class BoardLink {
 public:
  virtual ~BoardLink() = default;
  // Appends every report that has arrived to `out` (until it is full; the rest wait for the next
  // call). Returns ok, or the failure that stopped reading (disconnected, io_error, ...). Short
  // reports are kept, with status short_report.
  // Neither is noexcept: whatever a transport throws must reach the loop, which answers it with a
  // zero command and ends the session (reason exception); noexcept would turn it into
  // std::terminate with the motor still driven.
  virtual bridge::TransportStatus drain(BoardReports& out) = 0;
  virtual bridge::TransportStatus write(std::span<const std::uint8_t> report) = 0;
  // After drain or write has failed (disconnected, io_error, ...): one step towards having the
  // board open again by the same identity (vendor, product, serial). Returns ok once it is open;
  // the caller then initialises it as at start-up (the board may have been power-cycled). Any
  // other status: not yet, ask again later. Never blocks for long: DirectBoardLink closes and
  // opens the transport right here (simulated rig and replay only: quick, but it may allocate);
  // ThreadedBoardLink leaves the reopening to its reader thread and only asks for it.
  virtual bridge::TransportStatus reconnect() = 0;
  virtual const bridge::DeviceInfo& device_info() const noexcept = 0;
};

// The identity a board is reopened by: vendor, product and serial of the device first opened
// (the bus path may change when it is plugged in again; the serial does not).
bridge::DeviceMatch identity_of(const bridge::DeviceInfo& info);

class DirectBoardLink final : public BoardLink {
 public:
  // The transport must be open.
  explicit DirectBoardLink(bridge::Transport& transport)
      : transport_(transport), identity_(identity_of(transport.device_info())) {}
  bridge::TransportStatus drain(BoardReports& out) override;
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override;
  bridge::TransportStatus reconnect() override;
  const bridge::DeviceInfo& device_info() const noexcept override {
    return transport_.device_info();
  }

 private:
  bridge::Transport& transport_;
  bridge::DeviceMatch identity_;
};

class ThreadedBoardLink final : public BoardLink {
 public:
  // Starts the reader thread; the transport must be open and outlive the link. After a failure the
  // reader closes the transport and tries to open it again every `reopen_interval`.
  explicit ThreadedBoardLink(bridge::Transport& transport,
                             std::chrono::milliseconds reopen_interval = kDefaultReopenInterval);
  ~ThreadedBoardLink() override;  // stops and joins the reader
  ThreadedBoardLink(const ThreadedBoardLink&) = delete;
  ThreadedBoardLink& operator=(const ThreadedBoardLink&) = delete;

  bridge::TransportStatus drain(BoardReports& out) noexcept override;  // the queue cannot throw
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override;
  // Lock-free: the first call asks the reader thread to reopen; later ones say whether it has.
  bridge::TransportStatus reconnect() noexcept override;
  // The device as first opened: the reader thread rewrites the transport's own copy when it
  // reopens, which the loop thread must not read meanwhile.
  const bridge::DeviceInfo& device_info() const noexcept override { return info_; }

  static constexpr std::chrono::milliseconds kDefaultReopenInterval{200};

 private:
  void read_forever();
  void reopen();  // reader thread: close, open by identity, until it works or the link stops

  class Queue;
  bridge::Transport& transport_;
  const bridge::DeviceInfo info_;
  const bridge::DeviceMatch identity_;
  const std::chrono::milliseconds reopen_interval_;
  std::unique_ptr<Queue> queue_;
  std::atomic<bool> stop_{false};
  std::atomic<bridge::TransportStatus> failure_{bridge::TransportStatus::ok};
  // Set by the reader when a read fails, or by the loop when a write did: the transport is to be
  // reopened, and writes are refused until it has been. Cleared by the reader once it is open.
  std::atomic<bool> down_{false};
  // The loop is inside write_report: the reader must not close the transport under it. With
  // down_, a Dekker-style handshake (both sequentially consistent): the writer raises writing_
  // then looks at down_; the reader raises down_ then waits for writing_ to fall.
  std::atomic<bool> writing_{false};
  std::atomic<std::uint64_t> reopens_{0};  // successful reopens by the reader
  // The loop's side of reconnect(): it has asked, and the reader's count when it did.
  bool reopen_asked_ = false;
  std::uint64_t reopens_when_asked_ = 0;
  std::thread reader_;
};

}  // namespace furuta::daemon
