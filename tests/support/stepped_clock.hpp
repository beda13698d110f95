#pragma once
// A clock for the daemon's tests: time moves only when the test says so, one sleep of the loop at
// a time, so every cycle is on time and every count exact. Safe to read from any thread, unlike
// VirtualClock (the daemon's LCM and I/O threads read the loop's time).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <limits>
#include <mutex>

#include "furuta/firmware_bridge/clock.hpp"

namespace furuta::testing {

// Time that moves when the test says so; a sleeper waits for it. Thread-safe, unlike VirtualClock.
class SteppedClock final : public furuta::bridge::Clock {
 public:
  explicit SteppedClock(std::int64_t start_ns) : now_(start_ns) {}
  std::int64_t now_ns() const override { return now_.load(); }
  void sleep_until_ns(std::int64_t deadline_ns) override {
    std::unique_lock lock(mutex_);
    sleeping_until_ = deadline_ns;
    changed_.notify_all();
    changed_.wait(lock, [&] { return free_ || now_.load() >= deadline_ns; });
    sleeping_until_ = kNobody;
    if (free_ && now_.load() < deadline_ns) now_.store(deadline_ns);
  }
  // Waits until the sleeper is blocked, then moves time to its deadline: it wakes exactly on time.
  // False if nobody came to sleep (a hang guard).
  bool wake_sleeper_on_time() {
    std::unique_lock lock(mutex_);
    const bool blocked = changed_.wait_for(lock, std::chrono::seconds(20), [&] {
      return sleeping_until_ != kNobody && sleeping_until_ > now_.load();
    });
    if (!blocked) return false;
    now_.store(sleeping_until_);
    changed_.notify_all();
    return true;
  }
  // From here on, a sleep returns at once with the time moved to its deadline (for shutdown).
  void run_free() {
    {
      std::lock_guard lock(mutex_);
      free_ = true;
    }
    changed_.notify_all();
  }
  // Back to stepping, once the sleeper run_free let go is gone (a daemon restarted in a test).
  void stop_running_free() {
    std::lock_guard lock(mutex_);
    free_ = false;
  }

 private:
  static constexpr std::int64_t kNobody = std::numeric_limits<std::int64_t>::min();
  std::atomic<std::int64_t> now_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::int64_t sleeping_until_ = kNobody;
  bool free_ = false;
};

}  // namespace furuta::testing
