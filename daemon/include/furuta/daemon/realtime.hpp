#pragma once
// Real-time set-up of the loop thread, and the loop's timing statistics.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace furuta::daemon {

struct RealtimeOptions {
  bool enabled = false;             // try at all
  int fifo_priority = 80;           // SCHED_FIFO priority of the loop thread (1..99)
  int cpu = -1;                     // pin the loop thread to this CPU; -1: leave it
  bool lock_memory = true;          // mlockall(MCL_CURRENT | MCL_FUTURE), once threads exist
  std::int64_t timer_slack_ns = 1;  // PR_SET_TIMERSLACK of the loop thread
};

struct RealtimeResult {
  bool fifo = false;
  bool affinity = false;
  bool timer_slack = false;
  std::vector<std::string> refused;  // one line per step that was refused, with the errno text
  bool complete(const RealtimeOptions& options) const;  // every step asked for succeeded
};

// Applies SCHED_FIFO, affinity and timer slack to the calling thread only.
RealtimeResult apply_realtime_to_this_thread(const RealtimeOptions& options);
// mlockall; call after every thread has started (their stacks are then locked too). Empty on
// success, else why not.
std::string lock_process_memory();
// Keeps the calling (non-real-time) thread off `cpu`, so its system calls never hold up the loop
// pinned there: on a kernel without full preemption a SCHED_FIFO thread still waits for another
// thread's kernel work on its CPU. No effect when cpu < 0 or no other CPU is allowed.
void keep_off_cpu(int cpu);

// Wake-up latency (actual wake - deadline) histogram: fixed buckets, so recording never allocates.
// Buckets are 1 us wide up to 1 ms, then 100 us wide up to 100 ms; beyond that, one overflow bucket
// (the max is still exact).
class LatencyHistogram {
 public:
  void record(std::int64_t latency_ns) noexcept;
  void reset() noexcept;
  std::uint64_t count() const noexcept { return count_; }
  double mean_us() const noexcept;
  double max_us() const noexcept { return static_cast<double>(max_ns_) / 1000.0; }
  // Upper edge of the bucket holding the q-quantile (q in [0, 1]), in microseconds.
  double quantile_us(double q) const noexcept;

 private:
  static constexpr std::size_t kFineBuckets = 1000;   // 0..1 ms in 1 us
  static constexpr std::size_t kCoarseBuckets = 990;  // 1..100 ms in 100 us
  std::array<std::uint64_t, kFineBuckets + kCoarseBuckets + 1> buckets_{};
  std::uint64_t count_ = 0;
  double sum_ns_ = 0.0;
  std::int64_t max_ns_ = 0;
};

}  // namespace furuta::daemon
