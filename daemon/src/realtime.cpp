#include "furuta/daemon/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/sysinfo.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace furuta::daemon {
namespace {

std::string errno_text(int error) {
  return std::strerror(error);
}

// Pinning before raising the priority: the thread then never migrates while it runs as SCHED_FIFO.
bool pin_to_cpu(int cpu, std::vector<std::string>& refused) {
  const std::string step = "CPU affinity " + std::to_string(cpu) + ": ";
  const int configured = get_nprocs_conf();
  // CPU_SET past CPU_SETSIZE writes outside the set, so an impossible CPU is refused before it.
  if (cpu >= CPU_SETSIZE || cpu >= configured) {
    refused.push_back(step + "no such CPU (this machine has " + std::to_string(configured) + ")");
    return false;
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int error = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
  if (error != 0) {
    // EINVAL here usually means the CPU exists but is outside this process's cpuset (container).
    refused.push_back(step + errno_text(error));
    return false;
  }
  return true;
}

}  // namespace

void keep_off_cpu(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (pthread_getaffinity_np(pthread_self(), sizeof(set), &set) != 0) return;
  CPU_CLR(cpu, &set);
  if (CPU_COUNT(&set) == 0) return;  // nowhere else to go: stay where we are
  pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
}

namespace {

bool make_fifo(int priority, std::vector<std::string>& refused) {
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error != 0) {
    refused.push_back("SCHED_FIFO priority " + std::to_string(priority) + ": " + errno_text(error));
    return false;
  }
  return true;
}

bool set_timer_slack(std::int64_t slack_ns, std::vector<std::string>& refused) {
  const std::string step = "timer slack " + std::to_string(slack_ns) + " ns: ";
  if (prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(slack_ns), 0, 0, 0) != 0) {
    refused.push_back(step + errno_text(errno));
    return false;
  }
  // Recent kernels give SCHED_FIFO threads zero slack and silently ignore the request, so success
  // is judged by what the thread now has: no more slack than asked for.
  const int got = prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0);
  if (got < 0) {
    refused.push_back(step + "reading it back: " + errno_text(errno));
    return false;
  }
  if (got > slack_ns) {
    refused.push_back(step + "the thread still has " + std::to_string(got) + " ns");
    return false;
  }
  return true;
}

// Buckets hold (lower, upper] so that "fraction of samples <= upper edge" is exact for quantiles.
constexpr std::int64_t kFineWidthNs = 1'000;
constexpr std::int64_t kCoarseWidthNs = 100'000;
constexpr std::int64_t kFineEndNs = 1'000'000;
constexpr std::int64_t kCoarseEndNs = 100'000'000;

}  // namespace

bool RealtimeResult::complete(const RealtimeOptions& options) const {
  if (!options.enabled) return true;
  if (!refused.empty() || !fifo) return false;
  if (options.cpu >= 0 && !affinity) return false;
  if (options.timer_slack_ns > 0 && !timer_slack) return false;
  return true;
}

RealtimeResult apply_realtime_to_this_thread(const RealtimeOptions& options) {
  RealtimeResult result;
  if (!options.enabled) return result;
  if (options.cpu >= 0) result.affinity = pin_to_cpu(options.cpu, result.refused);
  result.fifo = make_fifo(options.fifo_priority, result.refused);
  // Zero would reset the slack to the process default rather than remove it, so it means "leave
  // it".
  if (options.timer_slack_ns > 0)
    result.timer_slack = set_timer_slack(options.timer_slack_ns, result.refused);
  return result;
}

std::string lock_process_memory() {
  // Only the reason: callers name the step themselves, as in RealtimeResult::refused.
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return errno_text(errno);
  return {};
}

void LatencyHistogram::record(std::int64_t latency_ns) noexcept {
  std::size_t index = 0;
  if (latency_ns <= 0) {
    index = 0;  // woke at or before the deadline
  } else if (latency_ns <= kFineEndNs) {
    index = static_cast<std::size_t>((latency_ns - 1) / kFineWidthNs);
  } else if (latency_ns <= kCoarseEndNs) {
    index = kFineBuckets + static_cast<std::size_t>((latency_ns - kFineEndNs - 1) / kCoarseWidthNs);
  } else {
    index = kFineBuckets + kCoarseBuckets;
  }
  ++buckets_[index];
  max_ns_ = count_ == 0 ? latency_ns : std::max(max_ns_, latency_ns);
  ++count_;
  sum_ns_ += static_cast<double>(latency_ns);
}

void LatencyHistogram::reset() noexcept {
  buckets_.fill(0);
  count_ = 0;
  sum_ns_ = 0.0;
  max_ns_ = 0;
}

double LatencyHistogram::mean_us() const noexcept {
  if (count_ == 0) return 0.0;
  return sum_ns_ / static_cast<double>(count_) / 1000.0;
}

// The smallest bucket edge e with (samples <= e) >= q * count, capped at the exact max (so a
// quantile never reads above the max, and the overflow bucket, which has no edge, reports the max).
double LatencyHistogram::quantile_us(double q) const noexcept {
  if (count_ == 0) return 0.0;
  if (!(q > 0.0)) q = 0.0;  // also catches NaN
  if (q > 1.0) q = 1.0;
  const auto n = static_cast<double>(count_);
  // The rank of the sample holding the quantile, 1-based; the epsilon keeps 0.999 * 1000 at 999
  // despite rounding.
  const double rank_real = std::ceil(q * n - 1e-6);
  const std::uint64_t rank =
      rank_real < 1.0 ? 1 : std::min(count_, static_cast<std::uint64_t>(rank_real));
  std::uint64_t cumulative = 0;
  std::size_t index = 0;
  for (; index < buckets_.size(); ++index) {
    cumulative += buckets_[index];
    if (cumulative >= rank) break;
  }
  std::int64_t edge_ns = max_ns_;
  if (index < kFineBuckets) {
    edge_ns = static_cast<std::int64_t>(index + 1) * kFineWidthNs;
  } else if (index < kFineBuckets + kCoarseBuckets) {
    edge_ns = kFineEndNs + static_cast<std::int64_t>(index - kFineBuckets + 1) * kCoarseWidthNs;
  }
  return static_cast<double>(std::min(edge_ns, max_ns_)) / 1000.0;
}

}  // namespace furuta::daemon
