#include "latency_probe.hpp"

#include <sched.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "furuta/firmware_bridge/clock.hpp"

namespace furuta::bench {
namespace {

std::int64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

rusage thread_usage() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return usage;
}

void run_loop(std::int64_t period_ns, std::int64_t duration_ns,
              const daemon::RealtimeOptions& options, LoopFigures& figures) {
  figures.realtime = daemon::apply_realtime_to_this_thread(options);
  if (options.enabled && options.lock_memory) {
    figures.memory_lock_asked = true;
    figures.memory_lock_refused = daemon::lock_process_memory();
  }
  // The daemon's own clock, so the floor is measured through the same sleep the loop uses.
  bridge::MonotonicClock clock;
  const rusage usage_before = thread_usage();
  const std::int64_t cpu_before = thread_cpu_ns();
  const std::int64_t start = clock.now_ns();
  const std::int64_t end = start + duration_ns;
  std::int64_t deadline = start + period_ns;
  while (deadline <= end) {
    clock.sleep_until_ns(deadline);
    const std::int64_t woke = clock.now_ns();
    figures.latency.record(woke - deadline);
    ++figures.cycles;
    deadline += period_ns;
    if (woke >= deadline) {
      // Sleeping to a deadline already past would return at once: a burst. Skip to the next one
      // still ahead instead, and count what was skipped.
      const std::int64_t skipped = (woke - deadline) / period_ns + 1;
      ++figures.overruns;
      figures.missed_deadlines += static_cast<std::uint64_t>(skipped);
      deadline += skipped * period_ns;
    }
  }
  const std::int64_t cpu_ns = thread_cpu_ns() - cpu_before;
  const rusage usage_after = thread_usage();
  figures.fifo_in_force = sched_getscheduler(0) == SCHED_FIFO;
  if (figures.cycles > 0)
    figures.cpu_us_per_cycle =
        static_cast<double>(cpu_ns) / static_cast<double>(figures.cycles) / 1000.0;
  figures.voluntary_switches = usage_after.ru_nvcsw - usage_before.ru_nvcsw;
  figures.involuntary_switches = usage_after.ru_nivcsw - usage_before.ru_nivcsw;
}

// Steal time of all CPUs in clock ticks (the eighth figure of the "cpu" line), or -1.
long long steal_ticks() {
  std::ifstream stat("/proc/stat");
  std::string line;
  if (!std::getline(stat, line)) return -1;
  std::istringstream fields(line);
  std::string name;
  long long value = 0;
  fields >> name;
  for (int i = 0; i < 8; ++i) {
    if (!(fields >> value)) return -1;
  }
  return name == "cpu" ? value : -1;
}

// A JSON string literal (quotes, backslashes and control characters escaped).
std::string quoted(const std::string& text) {
  return nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", value);
  return text;
}

}  // namespace

LoopFigures measure_bare_loop(std::int64_t period_ns, std::int64_t duration_ns,
                              const daemon::RealtimeOptions& options) {
  LoopFigures figures;
  figures.period_ns = period_ns;
  figures.duration_ns = duration_ns;
  if (period_ns <= 0 || duration_ns <= 0) return figures;
  // A thread of its own so that SCHED_FIFO and the pinning end with it, not with the caller.
  const long long steal_before = steal_ticks();
  std::thread loop([&] { run_loop(period_ns, duration_ns, options, figures); });
  loop.join();
  const long long steal_after = steal_ticks();
  const long ticks_per_s = sysconf(_SC_CLK_TCK);
  if (steal_before >= 0 && steal_after >= steal_before && ticks_per_s > 0)
    figures.steal_ms =
        static_cast<double>(steal_after - steal_before) * 1000.0 / static_cast<double>(ticks_per_s);
  return figures;
}

std::string to_json(const LoopFigures& f) {
  std::string refused = "[";
  for (std::size_t i = 0; i < f.realtime.refused.size(); ++i)
    refused += (i ? ", " : "") + quoted(f.realtime.refused[i]);
  refused += "]";
  const auto& h = f.latency;
  std::string out = "{";
  out += "\"what\": \"bare clock_nanosleep loop\"";
  out += ", \"period_us\": " + number(static_cast<double>(f.period_ns) / 1000.0);
  out += ", \"duration_s\": " + number(static_cast<double>(f.duration_ns) / 1e9);
  out += ", \"cycles\": " + std::to_string(f.cycles);
  out += ", \"overruns\": " + std::to_string(f.overruns);
  out += ", \"missed_deadlines\": " + std::to_string(f.missed_deadlines);
  out += ", \"latency_us\": {\"p50\": " + number(h.quantile_us(0.5)) +
         ", \"p99\": " + number(h.quantile_us(0.99)) +
         ", \"p99_9\": " + number(h.quantile_us(0.999)) + ", \"max\": " + number(h.max_us()) +
         ", \"mean\": " + number(h.mean_us()) + "}";
  out += ", \"cpu_us_per_cycle\": " + number(f.cpu_us_per_cycle);
  out += ", \"voluntary_switches\": " + std::to_string(f.voluntary_switches);
  out += ", \"involuntary_switches\": " + std::to_string(f.involuntary_switches);
  out += ", \"steal_ms\": " + number(f.steal_ms);
  out += ", \"fifo_in_force\": " + std::string(f.fifo_in_force ? "true" : "false");
  out += ", \"affinity\": " + std::string(f.realtime.affinity ? "true" : "false");
  out += ", \"timer_slack\": " + std::string(f.realtime.timer_slack ? "true" : "false");
  out += ", \"memory_locked\": " +
         std::string(f.memory_lock_asked && f.memory_lock_refused.empty() ? "true" : "false");
  out += ", \"refused\": " + refused;
  if (!f.memory_lock_refused.empty())
    out += ", \"memory_lock_refused\": " + quoted(f.memory_lock_refused);
  out += "}";
  return out;
}

}  // namespace furuta::bench
