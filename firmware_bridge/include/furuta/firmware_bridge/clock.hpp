#pragma once
// Time as a dependency: the control loop, the simulated rig and replay all read and sleep on a
// Clock, so tests run in virtual time (fast, deterministic) and the rig in real time, with the same
// code.

#include <cstdint>

namespace furuta::bridge {

class Clock {
 public:
  virtual ~Clock() = default;
  // Monotonic nanoseconds; only differences are meaningful.
  virtual std::int64_t now_ns() const = 0;
  // Returns at or after deadline_ns (immediately when it has passed).
  virtual void sleep_until_ns(std::int64_t deadline_ns) = 0;
};

// CLOCK_MONOTONIC with absolute-deadline sleeps (clock_nanosleep TIMER_ABSTIME), retried on EINTR.
class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const override;
  void sleep_until_ns(std::int64_t deadline_ns) override;
};

// Time that moves only when someone sleeps on it or advances it. Single-threaded use.
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(std::int64_t start_ns = 0) : now_ns_(start_ns) {}
  std::int64_t now_ns() const override { return now_ns_; }
  void sleep_until_ns(std::int64_t deadline_ns) override {
    if (deadline_ns > now_ns_) now_ns_ = deadline_ns;
  }
  void advance_ns(std::int64_t delta_ns) {
    if (delta_ns > 0) now_ns_ += delta_ns;
  }

 private:
  std::int64_t now_ns_;
};

// Another clock shifted by a fixed offset: replays a recording in real time on the recording's own
// time base.
class OffsetClock final : public Clock {
 public:
  OffsetClock(Clock& base, std::int64_t offset_ns) : base_(base), offset_ns_(offset_ns) {}
  std::int64_t now_ns() const override { return base_.now_ns() + offset_ns_; }
  void sleep_until_ns(std::int64_t deadline_ns) override {
    base_.sleep_until_ns(deadline_ns - offset_ns_);
  }

 private:
  Clock& base_;
  std::int64_t offset_ns_;
};

}  // namespace furuta::bridge
