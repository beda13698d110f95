// The machine's timing floor: wake-up latency of a bare clock_nanosleep(TIMER_ABSTIME) loop, with
// or without the daemon's real-time set-up. Figures, never pass/fail.
//   build/release/bench/loop_latency --period-us 1000 --seconds 60 --fifo --json floor.json
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "latency_probe.hpp"

namespace {

void print_table(const furuta::bench::LoopFigures& f, bool fifo_asked) {
  const auto& h = f.latency;
  std::printf("bare clock_nanosleep loop: period %.0f us, %.0f s, SCHED_FIFO %s%s\n",
              static_cast<double>(f.period_ns) / 1000.0, static_cast<double>(f.duration_ns) / 1e9,
              f.fifo_in_force ? "in force" : "not in force",
              fifo_asked && !f.fifo_in_force ? " (asked for, refused)" : "");
  std::printf("  %-26s %9.1f us\n", "wake-up latency p50", h.quantile_us(0.5));
  std::printf("  %-26s %9.1f us\n", "wake-up latency p99", h.quantile_us(0.99));
  std::printf("  %-26s %9.1f us\n", "wake-up latency p99.9", h.quantile_us(0.999));
  std::printf("  %-26s %9.1f us\n", "wake-up latency max", h.max_us());
  std::printf("  %-26s %9.1f us\n", "wake-up latency mean", h.mean_us());
  std::printf("  %-26s %9llu\n", "cycles", static_cast<unsigned long long>(f.cycles));
  std::printf("  %-26s %9llu (%llu deadlines skipped)\n", "overruns",
              static_cast<unsigned long long>(f.overruns),
              static_cast<unsigned long long>(f.missed_deadlines));
  std::printf("  %-26s %9.2f us\n", "CPU time per cycle", f.cpu_us_per_cycle);
  std::printf("  %-26s %9ld / %ld\n", "context switches vol/invol", f.voluntary_switches,
              f.involuntary_switches);
  if (f.steal_ms >= 0.0) std::printf("  %-26s %9.0f ms\n", "vCPU steal (all CPUs)", f.steal_ms);
  if (fifo_asked) {
    std::printf("  %-26s %s\n", "CPU affinity", f.realtime.affinity ? "pinned" : "not pinned");
    std::printf("  %-26s %s\n", "timer slack", f.realtime.timer_slack ? "set" : "not set");
    std::printf("  %-26s %s\n", "mlockall",
                !f.memory_lock_asked            ? "not asked"
                : f.memory_lock_refused.empty() ? "locked"
                                                : f.memory_lock_refused.c_str());
    for (const auto& line : f.realtime.refused) std::printf("  refused: %s\n", line.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Wake-up latency of a bare clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) loop"};
  std::int64_t period_us = 16'000;
  double seconds = 60.0;
  bool fifo = false;
  int priority = 80;
  int cpu = -1;
  bool no_mlock = false;
  std::string json_path;
  app.add_option("--period-us", period_us, "loop period in microseconds")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{10'000'000}));
  app.add_option("--seconds", seconds, "how long to run")->check(CLI::Range(0.001, 86'400.0));
  auto* fifo_flag = app.add_flag("--fifo", fifo,
                                 "the daemon's real-time set-up: SCHED_FIFO, timer slack 1 ns, "
                                 "mlockall, and --cpu if given");
  app.add_option("--priority", priority, "SCHED_FIFO priority with --fifo")
      ->check(CLI::Range(1, 99))
      ->needs(fifo_flag);
  app.add_option("--cpu", cpu, "pin the loop thread to this CPU (with --fifo)")
      ->check(CLI::NonNegativeNumber)
      ->needs(fifo_flag);
  app.add_flag("--no-mlock", no_mlock, "with --fifo, leave memory unlocked")->needs(fifo_flag);
  app.add_option("--json", json_path, "also write the figures as one JSON object to this file");
  CLI11_PARSE(app, argc, argv);

  furuta::daemon::RealtimeOptions options;
  options.enabled = fifo;
  options.fifo_priority = priority;
  options.cpu = cpu;
  options.lock_memory = !no_mlock;

  const auto figures = furuta::bench::measure_bare_loop(
      period_us * 1000, static_cast<std::int64_t>(seconds * 1e9), options);
  print_table(figures, fifo);

  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << furuta::bench::to_json(figures) << "\n";
    if (!out) {
      std::cerr << "loop_latency: cannot write " << json_path << "\n";
      return 1;
    }
  }
  return 0;
}
