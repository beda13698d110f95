#pragma once
// The machine's timing floor: a loop that does nothing but sleep to absolute deadlines on
// CLOCK_MONOTONIC, measured the way the daemon's loop is measured. Anything the daemon adds on top
// of this is the daemon's own cost; anything here is the kernel's and the VM's.

#include <cstdint>
#include <string>

#include "furuta/daemon/realtime.hpp"

namespace furuta::bench {

struct LoopFigures {
  std::int64_t period_ns = 0;
  std::int64_t duration_ns = 0;
  std::uint64_t cycles = 0;            // wake-ups measured
  std::uint64_t overruns = 0;          // wake-ups at or past the following deadline
  std::uint64_t missed_deadlines = 0;  // deadlines skipped because of those overruns
  daemon::LatencyHistogram latency;    // actual wake - deadline
  double cpu_us_per_cycle = 0.0;       // the loop thread's CPU time over the run / cycles
  long voluntary_switches = 0;         // of the loop thread over the run
  long involuntary_switches = 0;       // preempted while runnable
  // Time the hypervisor ran something else on this VM's vCPUs during the run (all CPUs, from
  // /proc/stat; -1 when unreadable): a SCHED_FIFO thread cannot wake while its vCPU is not running.
  double steal_ms = -1.0;
  daemon::RealtimeResult realtime;  // what the set-up achieved on the loop thread
  bool fifo_in_force = false;       // the loop thread's policy as read back at the end
  bool memory_lock_asked = false;
  std::string memory_lock_refused;  // empty when locked (or not asked)
};

// Runs the loop on a thread of its own for duration_ns, with the real-time set-up of options
// applied to that thread only (and mlockall process-wide when options.enabled &&
// options.lock_memory: it stays in force afterwards, as it would in the daemon). Missed deadlines
// are skipped, never caught up in a burst. Blocks for the duration.
LoopFigures measure_bare_loop(std::int64_t period_ns, std::int64_t duration_ns,
                              const daemon::RealtimeOptions& options);

// One JSON object with the figures (microseconds for latencies), for putting beside other figures.
std::string to_json(const LoopFigures& figures);

}  // namespace furuta::bench
