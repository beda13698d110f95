// The daemon's loop in real time against the simulated rig, with the machine's floor (a bare
// clock_nanosleep loop) measured in the same run, just before it, under the same real-time set-up.
//
//   daemon_latency --period-us 16000 --seconds 60 [--fifo] [--cpu C] [--lcm-url URL] [--json FILE]
//
// Reports wake-up latency p50/p99/p99.9/max, overruns and CPU time per cycle for both loops, and
// the sample-to-subscriber latency over LCM (a subscriber on its own LCM instance and thread): the
// time it receives a sample minus the time the loop queued it (the hand-off and the transport),
// and minus the sample's cycle deadline (the loop's wake-up and its cycle's work too).
#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/session_log/session_log.hpp"
#include "latency_probe.hpp"

namespace {

using namespace furuta;

struct SubscriberLatency {
  explicit SubscriberLatency(std::size_t samples) : queued_ns(samples), published_ns(samples) {}
  daemon::LatencyHistogram histogram;      // from the loop's queueing of the sample
  daemon::LatencyHistogram from_deadline;  // from the sample's cycle deadline
  // The two hops: queued -> the publisher has it (the I/O thread's hand-off), and the publisher
  // has it -> the subscriber has it (encoding, UDP, the subscriber's wake-up).
  daemon::LatencyHistogram to_publisher, from_publisher;
  std::vector<std::atomic<std::int64_t>> queued_ns;     // by seq, from the recorder's probe
  std::vector<std::atomic<std::int64_t>> published_ns;  // by seq, when the probe ran
  std::int64_t received = 0;
  void on_sample(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_sample_t* m) {
    const std::int64_t now = bridge::MonotonicClock{}.now_ns();
    from_deadline.record(now - m->monotonic_ns);
    const auto seq = static_cast<std::size_t>(m->seq);
    if (seq < queued_ns.size() && queued_ns[seq].load() != 0) {
      histogram.record(now - queued_ns[seq].load());
      from_publisher.record(now - published_ns[seq].load());
    }
    ++received;
  }
};

struct Row {
  std::string what;
  double p50, p99, p999, max, mean;
  std::int64_t overruns;
  double cpu_us;
};

void print_row(const Row& r) {
  std::cout << std::left << std::setw(26) << r.what << std::right << std::fixed
            << std::setprecision(0) << std::setw(8) << r.p50 << std::setw(8) << r.p99
            << std::setw(9) << r.p999 << std::setw(9) << r.max << std::setw(8) << r.mean
            << std::setw(10) << r.overruns << std::setprecision(1) << std::setw(10) << r.cpu_us
            << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "daemon_latency: the daemon's loop against the simulated rig, beside the bare floor"};
  double period_us = 16000;
  double seconds = 60;
  bool fifo = false;
  int cpu = -1;
  std::string lcm_url = "memq://";
  std::string json_path;
  std::string config_path = config::default_rig_config_path().string();
  app.add_option("--period-us", period_us)->check(CLI::Range(100.0, 1e6));
  app.add_option("--seconds", seconds)->check(CLI::Range(1.0, 3600.0));
  app.add_flag("--fifo", fifo, "SCHED_FIFO (+ mlockall) for both loops");
  app.add_option("--cpu", cpu, "Pin both loops to this CPU");
  app.add_option("--lcm-url", lcm_url,
                 "LCM for samples; udpm needs a multicast route (see bench/README.md)");
  app.add_option("--json", json_path, "Write the figures as JSON");
  app.add_option("--config", config_path)->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);

  const auto period_ns = static_cast<std::int64_t>(period_us * 1000);
  const auto duration_ns = static_cast<std::int64_t>(seconds * 1e9);
  daemon::RealtimeOptions rt;
  rt.enabled = fifo;
  rt.cpu = cpu;

  std::cerr << "floor: bare loop, " << period_us << " us, " << seconds << " s ...\n";
  const bench::LoopFigures floor = bench::measure_bare_loop(period_ns, duration_ns, rt);

  std::cerr << "daemon: loop + simulated rig in real time ...\n";
  config::RigConfig rig = config::load_rig_config(config_path);
  rig.simulation.record_truth = false;
  daemon::DaemonSettings settings = daemon::daemon_settings_from_config(rig);
  settings.loop.period_ns = period_ns;
  // Staleness counts cycles; keep it at 32 ms of silence whatever the period.
  settings.loop.safety.stale_report_cycles = std::max<int>(
      settings.loop.safety.stale_report_cycles, static_cast<int>(32'000'000 / period_ns) + 1);
  settings.loop.rest_check_s = 0.0;
  settings.realtime = rt;
  settings.queue_capacity = 8192;
  const auto logs =
      std::filesystem::temp_directory_path() / ("furuta-bench-" + std::to_string(::getpid()));
  settings.recorder.logs_dir = logs;
  daemon::RigConnection rig_io = daemon::connect_rig(rig, {daemon::BackendChoice::simulated, {}});
  settings.recorder.motor_device = bridge::format_trace_device_line(rig_io.motor->device_info());
  settings.recorder.encoder_device =
      bridge::format_trace_device_line(rig_io.encoder->device_info());

  lcm::LCM daemon_lcm(lcm_url);
  const bool separate_subscriber = lcm_url.rfind("memq", 0) != 0;
  lcm::LCM subscriber_lcm(separate_subscriber ? lcm_url : "memq://");
  lcm::LCM& sub_lcm = separate_subscriber ? subscriber_lcm : daemon_lcm;
  // One slot per cycle the session can have, with room for the cycles around it.
  SubscriberLatency subscriber(static_cast<std::size_t>(seconds * 1e6 / period_us) + 64);
  sub_lcm.subscribe(session_log::kChannelSample, &SubscriberLatency::on_sample, &subscriber);
  std::atomic<bool> stop_subscriber{false};
  std::thread subscriber_thread;
  if (separate_subscriber) {
    subscriber_thread = std::thread([&] {
      if (fifo) daemon::keep_off_cpu(cpu);
      while (!stop_subscriber.load()) sub_lcm.handleTimeout(50);
    });
  }

  std::int64_t overruns = 0, cycles = 0, samples_logged = 0, cpu_ns = 0;
  daemon::LatencyHistogram wake;
  std::string stop_reason;
  {
    daemon::Daemon d(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, daemon_lcm);
    d.recorder().on_publish([&subscriber](const daemon::RigSample& s) {
      const auto seq = static_cast<std::size_t>(s.seq);
      if (seq >= subscriber.queued_ns.size()) return;
      const std::int64_t now = bridge::MonotonicClock{}.now_ns();
      subscriber.to_publisher.record(now - s.queued_ns);
      subscriber.published_ns[seq].store(now);
      subscriber.queued_ns[seq].store(s.queued_ns);
    });
    furuta::rig_command_t start{};
    start.kind = furuta::rig_command_t::KIND_START_SESSION;
    start.profile = "bang_bang";
    start.amplitude_duty = 0.3;
    start.duration_s = seconds;
    start.label = "bench";
    const auto reply = d.handle_command(start);
    if (!reply.request_accepted) {
      std::cerr << "daemon_latency: session refused: " << reply.request_reason << "\n";
      return 1;
    }
    d.loop().exit_when_idle();
    const daemon::RealtimeResult r = d.start();
    for (const auto& refusal : r.refused) std::cerr << "real-time refused: " << refusal << "\n";
    d.wait();
    const auto& c = d.loop().counters();
    overruns = c.overruns.load();
    cycles = c.cycles.load();
    cpu_ns = c.loop_cpu_time_ns.load();
    wake = d.loop().wake_latency();
    stop_reason = std::string(daemon::to_string(c.last_stop.load()));
    samples_logged = d.recorder().samples_published();
  }
  // With memq the subscriber ran on the daemon's LCM thread; drain what it left.
  if (!separate_subscriber) {
    while (daemon_lcm.handleTimeout(0) > 0) {
    }
  }
  stop_subscriber.store(true);
  if (subscriber_thread.joinable()) subscriber_thread.join();
  std::filesystem::remove_all(logs);

  const Row floor_row{"bare clock_nanosleep loop",
                      floor.latency.quantile_us(0.5),
                      floor.latency.quantile_us(0.99),
                      floor.latency.quantile_us(0.999),
                      floor.latency.max_us(),
                      floor.latency.mean_us(),
                      static_cast<std::int64_t>(floor.overruns),
                      floor.cpu_us_per_cycle};
  const Row daemon_row{
      "daemon loop + simulated rig",
      wake.quantile_us(0.5),
      wake.quantile_us(0.99),
      wake.quantile_us(0.999),
      wake.max_us(),
      wake.mean_us(),
      overruns,
      cycles > 0 ? static_cast<double>(cpu_ns) / 1000.0 / static_cast<double>(cycles) : 0.0};
  std::cout << "period " << period_us << " us, " << seconds << " s, SCHED_FIFO "
            << (fifo ? (floor.fifo_in_force ? "in force" : "asked, refused") : "off")
            << (cpu >= 0 ? ", pinned to CPU " + std::to_string(cpu) : std::string()) << ", LCM "
            << lcm_url << "\n";
  std::cout << std::left << std::setw(26) << "wake-up latency [us]" << std::right << std::setw(8)
            << "p50" << std::setw(8) << "p99" << std::setw(9) << "p99.9" << std::setw(9) << "max"
            << std::setw(8) << "mean" << std::setw(10) << "overruns" << std::setw(10) << "cpu/cyc"
            << "\n";
  print_row(floor_row);
  print_row(daemon_row);
  std::cout << std::fixed << std::setprecision(2) << "ratio daemon/floor: p50 "
            << daemon_row.p50 / std::max(floor_row.p50, 1.0) << ", p99 "
            << daemon_row.p99 / std::max(floor_row.p99, 1.0) << "\n";
  const auto quantiles = [](const daemon::LatencyHistogram& h) {
    std::ostringstream q;
    q << std::fixed << std::setprecision(0) << "p50 " << h.quantile_us(0.5) << ", p99 "
      << h.quantile_us(0.99) << ", p99.9 " << h.quantile_us(0.999) << ", max " << h.max_us();
    return q.str();
  };
  std::cout << "sample -> subscriber [us], from the loop queueing it: "
            << quantiles(subscriber.histogram) << "\n"
            << "sample -> subscriber [us], from its cycle's deadline: "
            << quantiles(subscriber.from_deadline) << " (" << subscriber.received << " of "
            << samples_logged << " samples received)\n"
            << "  of which queued -> publisher: " << quantiles(subscriber.to_publisher)
            << "; publisher -> subscriber: " << quantiles(subscriber.from_publisher) << "\n";
  std::cout << "session ended: " << stop_reason << "\n";

  if (!json_path.empty()) {
    std::ofstream json(json_path);
    json << "{\"period_us\":" << period_us << ",\"seconds\":" << seconds
         << ",\"fifo\":" << (fifo ? "true" : "false") << ",\"cpu\":" << cpu
         << ",\"floor\":" << bench::to_json(floor) << ",\"daemon\":{\"p50_us\":" << daemon_row.p50
         << ",\"p99_us\":" << daemon_row.p99 << ",\"p999_us\":" << daemon_row.p999
         << ",\"max_us\":" << daemon_row.max << ",\"mean_us\":" << daemon_row.mean
         << ",\"overruns\":" << overruns << ",\"cpu_us_per_cycle\":" << daemon_row.cpu_us
         << ",\"cycles\":" << cycles << ",\"stop\":\"" << stop_reason
         << "\"},\"subscriber\":{\"p50_us\":" << subscriber.histogram.quantile_us(0.5)
         << ",\"p99_us\":" << subscriber.histogram.quantile_us(0.99)
         << ",\"p999_us\":" << subscriber.histogram.quantile_us(0.999)
         << ",\"max_us\":" << subscriber.histogram.max_us()
         << ",\"from_deadline_p50_us\":" << subscriber.from_deadline.quantile_us(0.5)
         << ",\"from_deadline_p99_us\":" << subscriber.from_deadline.quantile_us(0.99)
         << ",\"to_publisher_p99_us\":" << subscriber.to_publisher.quantile_us(0.99)
         << ",\"from_publisher_p99_us\":" << subscriber.from_publisher.quantile_us(0.99)
         << ",\"received\":" << subscriber.received << ",\"published\":" << samples_logged
         << "}}\n";
  }
  return 0;
}
