#pragma once
// How the control loop reaches one board: take every report that has arrived, write one report.
// Two ways to read, one interface:
//  - DirectBoardLink polls the transport on the loop thread. For the simulated rig and replay,
//  whose
//    reports carry their arrival time already.
//  - ThreadedBoardLink keeps a reader thread blocked in read_report, so each report is stamped when
//  it
//    arrives (the 1047's loss detection needs arrival times), and hands reports to the loop through
//    a lock-free queue. For hardware.

#include <atomic>
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
  virtual const bridge::DeviceInfo& device_info() const noexcept = 0;
};

class DirectBoardLink final : public BoardLink {
 public:
  explicit DirectBoardLink(bridge::Transport& transport) : transport_(transport) {}
  bridge::TransportStatus drain(BoardReports& out) override;
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override;
  const bridge::DeviceInfo& device_info() const noexcept override {
    return transport_.device_info();
  }

 private:
  bridge::Transport& transport_;
};

class ThreadedBoardLink final : public BoardLink {
 public:
  // Starts the reader thread; the transport must be open and outlive the link.
  explicit ThreadedBoardLink(bridge::Transport& transport);
  ~ThreadedBoardLink() override;  // stops and joins the reader
  ThreadedBoardLink(const ThreadedBoardLink&) = delete;
  ThreadedBoardLink& operator=(const ThreadedBoardLink&) = delete;

  bridge::TransportStatus drain(BoardReports& out) noexcept override;  // the queue cannot throw
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override;
  const bridge::DeviceInfo& device_info() const noexcept override {
    return transport_.device_info();
  }

 private:
  void read_forever();

  class Queue;
  bridge::Transport& transport_;
  std::unique_ptr<Queue> queue_;
  std::atomic<bool> stop_{false};
  std::atomic<bridge::TransportStatus> failure_{bridge::TransportStatus::ok};
  std::thread reader_;
};

}  // namespace furuta::daemon
