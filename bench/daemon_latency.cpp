// The daemon's loop in real time against the simulated rig, with the machine's floor (a bare
// clock_nanosleep loop) measured in the same run, just before it, under the same real-time set-up.
//
//   daemon_latency --period-us 16000 --seconds 60 [--session bang-bang|balance|both]
//                  [--balance CONTROLLER.toml] [--fifo] [--cpu C] [--lcm-url URL] [--json FILE]
//                  [--samples-csv PREFIX]
//
// Each session runs in a daemon of its own on a fresh simulated rig (at rest, as it starts), with
// the same settings, one after the other: a bang-bang excitation, or a balance session (swing-up,
// catch, balance) that runs the controller file named by --balance, designed for this rig and
// period (`furuta controller design`). Reports, for the floor and for each session, wake-up
// latency p50/p99/p99.9/max, overruns and CPU time per cycle; for a balance session the control
// law's own time per cycle (RigSample::control.law_time_ns); and the sample-to-subscriber latency
// over LCM (a subscriber on its own LCM instance and thread): the time it receives a sample minus
// the time the loop queued it (the hand-off and the transport), and minus the sample's cycle
// deadline (the loop's wake-up and its cycle's work too).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "furuta/config/controller_file.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/control/balance_law.hpp"
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

enum class SessionKind { bang_bang, balance };

std::string_view to_string(SessionKind kind) {
  return kind == SessionKind::balance ? "balance" : "bang_bang";
}

constexpr std::size_t kModes = 4;  // control::BalanceMode: swing_up, catching, balance, fallen

// Exact quantiles of the law's times (a few thousand values: sorted once at the end).
struct LawTimes {
  std::vector<std::int64_t> ns;  // sorted by finish()
  void finish() { std::sort(ns.begin(), ns.end()); }
  double quantile(double q) const {
    if (ns.empty()) return 0;
    const auto i = static_cast<std::size_t>(q * static_cast<double>(ns.size() - 1) + 0.5);
    return static_cast<double>(ns[std::min(i, ns.size() - 1)]);
  }
  double max() const { return ns.empty() ? 0 : static_cast<double>(ns.back()); }
  double mean() const {
    double sum = 0;
    for (const std::int64_t v : ns) sum += static_cast<double>(v);
    return ns.empty() ? 0 : sum / static_cast<double>(ns.size());
  }
};

struct SessionFigures {
  SessionKind kind = SessionKind::bang_bang;
  // The session's own cycles, from its samples: the whole lateness, the missed periods included.
  daemon::LatencyHistogram wake;
  std::vector<std::int64_t> wake_ns;  // the same, for pooling sessions of a kind
  // The loop's over its whole run: the rest check before the session and the cycle after it too.
  daemon::LatencyHistogram loop_wake;
  std::int64_t overruns = 0, cycles = 0, cpu_ns = 0, samples_logged = 0;
  std::string stop_reason;
  std::unique_ptr<SubscriberLatency> subscriber;
  // Balance sessions: the law's time per cycle, over all the session's cycles and by mode, the
  // cycles in each mode, and the first balanced sample's time from the session's start.
  LawTimes law;
  std::array<LawTimes, kModes> law_by_mode;
  std::array<std::int64_t, kModes> mode_cycles{};
  double balanced_from_s = -1;
  // Per sample, for --samples-csv: what explains a tail (when the late cycles came, in which mode).
  struct Sample {
    std::int64_t seq, wake_ns;
    std::int32_t overruns;
    int mode;  // -1 outside balance sessions
    std::int64_t law_ns;
    double arm_rad, pendulum_rad, duty;
  };
  std::vector<Sample> samples;
};

struct Setup {
  config::RigConfig rig;
  daemon::DaemonSettings settings;
  std::string lcm_url;
  double seconds = 0;
  std::int64_t period_ns = 0;
  bool fifo = false;
  int cpu = -1;
  std::filesystem::path controller_path;  // absolute
  std::string controller_sha256;
  bool keep_samples = false;
};

// One session in a daemon of its own; nullopt (said on stderr) when the daemon refuses the start.
std::optional<SessionFigures> run_session(const Setup& setup, SessionKind kind) {
  SessionFigures f;
  f.kind = kind;
  daemon::DaemonSettings settings = setup.settings;
  const auto logs =
      std::filesystem::temp_directory_path() /
      ("furuta-bench-" + std::to_string(::getpid()) + "-" + std::string(to_string(kind)));
  settings.recorder.logs_dir = logs;
  daemon::RigConnection rig_io =
      daemon::connect_rig(setup.rig, {daemon::BackendChoice::simulated, {}});
  settings.recorder.motor_device = bridge::format_trace_device_line(rig_io.motor->device_info());
  settings.recorder.encoder_device =
      bridge::format_trace_device_line(rig_io.encoder->device_info());

  lcm::LCM daemon_lcm(setup.lcm_url);
  const bool separate_subscriber = setup.lcm_url.rfind("memq", 0) != 0;
  lcm::LCM subscriber_lcm(separate_subscriber ? setup.lcm_url : "memq://");
  lcm::LCM& sub_lcm = separate_subscriber ? subscriber_lcm : daemon_lcm;
  // One slot per cycle the session can have, with room for the cycles around it.
  const auto slots = static_cast<std::size_t>(static_cast<double>(setup.seconds) * 1e9 /
                                              static_cast<double>(setup.period_ns)) +
                     64;
  f.subscriber = std::make_unique<SubscriberLatency>(slots);
  SubscriberLatency& subscriber = *f.subscriber;
  f.law.ns.reserve(slots);
  f.wake_ns.reserve(slots);
  if (setup.keep_samples) f.samples.reserve(slots);
  for (LawTimes& m : f.law_by_mode) m.ns.reserve(slots);
  sub_lcm.subscribe(session_log::kChannelSample, &SubscriberLatency::on_sample, &subscriber);
  std::atomic<bool> stop_subscriber{false};
  std::thread subscriber_thread;
  if (separate_subscriber) {
    subscriber_thread = std::thread([&] {
      if (setup.fifo) daemon::keep_off_cpu(setup.cpu);
      while (!stop_subscriber.load()) sub_lcm.handleTimeout(50);
    });
  }

  bool refused = false;
  std::int32_t overruns_before = 0;  // the observer's, on the I/O thread
  {
    daemon::Daemon d(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, daemon_lcm);
    // On the I/O thread, before each sample is published; read here after the daemon has gone.
    const std::int64_t period_ns = setup.period_ns;
    d.recorder().on_publish(
        [&f, &subscriber, &overruns_before, period_ns](const daemon::RigSample& s) {
          // A late cycle's sample carries its lateness past the newest deadline it skipped to; the
          // periods it skipped are in the session's overrun count.
          const std::int64_t missed = s.overruns - overruns_before;
          overruns_before = s.overruns;
          f.wake.record(s.wake_latency_ns + missed * period_ns);
          if (f.wake_ns.size() < f.wake_ns.capacity()) {
            f.wake_ns.push_back(s.wake_latency_ns + missed * period_ns);
          }
          if (f.samples.size() < f.samples.capacity()) {
            f.samples.push_back({s.seq, s.wake_latency_ns + missed * period_ns, s.overruns,
                                 s.control.present ? static_cast<int>(s.control.mode) : -1,
                                 s.control.present ? s.control.law_time_ns : 0, s.arm_angle_rad,
                                 s.pendulum_angle_rad, s.commanded_duty});
          }
          if (s.control.present) {
            f.law.ns.push_back(s.control.law_time_ns);
            const std::size_t mode = std::min<std::size_t>(s.control.mode, kModes - 1);
            f.law_by_mode[mode].ns.push_back(s.control.law_time_ns);
            ++f.mode_cycles[mode];
            if (f.balanced_from_s < 0 &&
                s.control.mode == static_cast<std::uint8_t>(control::BalanceMode::balance)) {
              f.balanced_from_s = static_cast<double>(s.seq * period_ns) * 1e-9;
            }
          }
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
    if (kind == SessionKind::balance) {
      // As `furuta start --balance` sends it: the daemon reads the file, checks its hash, rig and
      // period, and takes the law's duty limit as the session's amplitude.
      start.profile = std::string(daemon::kBalanceProfile);
      start.controller_path = setup.controller_path.string();
      start.controller_sha256 = setup.controller_sha256;
    }
    start.duration_s = setup.seconds;
    start.label = "bench";
    const auto reply = d.handle_command(start);
    if (!reply.request_accepted) {
      std::cerr << "daemon_latency: " << to_string(kind)
                << " session refused: " << reply.request_reason << "\n";
      refused = true;
    } else {
      d.loop().exit_when_idle();
      const daemon::RealtimeResult r = d.start();
      for (const auto& refusal : r.refused) std::cerr << "real-time refused: " << refusal << "\n";
      d.wait();
      const auto& c = d.loop().counters();
      f.overruns = c.overruns.load();
      f.cycles = c.cycles.load();
      f.cpu_ns = c.loop_cpu_time_ns.load();
      f.loop_wake = d.loop().wake_latency();
      f.stop_reason = std::string(daemon::to_string(c.last_stop.load()));
      f.samples_logged = d.recorder().samples_published();
    }
  }
  // With memq the subscriber ran on the daemon's LCM thread; drain what it left.
  if (!separate_subscriber) {
    while (daemon_lcm.handleTimeout(0) > 0) {
    }
  }
  stop_subscriber.store(true);
  if (subscriber_thread.joinable()) subscriber_thread.join();
  std::filesystem::remove_all(logs);
  if (refused) return std::nullopt;
  f.law.finish();
  for (LawTimes& m : f.law_by_mode) m.finish();
  return f;
}

struct Row {
  std::string what;
  double p50, p99, p999, max, mean;
  std::int64_t overruns;
  double cpu_us;
};

Row row(std::string what, const daemon::LatencyHistogram& h, std::int64_t overruns, double cpu_us) {
  return {std::move(what),
          h.quantile_us(0.5),
          h.quantile_us(0.99),
          h.quantile_us(0.999),
          h.max_us(),
          h.mean_us(),
          overruns,
          cpu_us};
}

void print_row(const Row& r) {
  std::cout << std::left << std::setw(30) << r.what << std::right << std::fixed
            << std::setprecision(0) << std::setw(8) << r.p50 << std::setw(8) << r.p99
            << std::setw(9) << r.p999 << std::setw(9) << r.max << std::setw(8) << r.mean
            << std::setw(10) << r.overruns << std::setprecision(1) << std::setw(10) << r.cpu_us
            << "\n";
}

double cpu_us_per_cycle(const SessionFigures& f) {
  return f.cycles > 0 ? static_cast<double>(f.cpu_ns) / 1000.0 / static_cast<double>(f.cycles)
                      : 0.0;
}

std::string quantiles(const daemon::LatencyHistogram& h) {
  std::ostringstream q;
  q << std::fixed << std::setprecision(0) << "p50 " << h.quantile_us(0.5) << ", p99 "
    << h.quantile_us(0.99) << ", p99.9 " << h.quantile_us(0.999) << ", max " << h.max_us();
  return q.str();
}

std::string law_quantiles(const LawTimes& t) {
  std::ostringstream q;
  q << std::fixed << std::setprecision(0) << "p50 " << t.quantile(0.5) << ", p99 "
    << t.quantile(0.99) << ", max " << t.max() << ", mean " << t.mean() << " (" << t.ns.size()
    << " cycles)";
  return q.str();
}

std::string histogram_json(const daemon::LatencyHistogram& h) {
  std::ostringstream j;
  j << "{\"p50_us\":" << h.quantile_us(0.5) << ",\"p99_us\":" << h.quantile_us(0.99)
    << ",\"p999_us\":" << h.quantile_us(0.999) << ",\"max_us\":" << h.max_us()
    << ",\"mean_us\":" << h.mean_us() << ",\"count\":" << h.count() << "}";
  return j.str();
}

std::string law_json(const LawTimes& t) {
  std::ostringstream j;
  j << "{\"p50_ns\":" << t.quantile(0.5) << ",\"p99_ns\":" << t.quantile(0.99)
    << ",\"max_ns\":" << t.max() << ",\"mean_ns\":" << t.mean() << ",\"cycles\":" << t.ns.size()
    << "}";
  return j.str();
}

std::string session_json(const SessionFigures& f) {
  const SubscriberLatency& s = *f.subscriber;
  std::ostringstream j;
  j << "{\"kind\":\"" << to_string(f.kind) << "\",\"session\":" << histogram_json(f.wake)
    << ",\"loop\":" << histogram_json(f.loop_wake) << ",\"overruns\":" << f.overruns
    << ",\"cpu_us_per_cycle\":" << cpu_us_per_cycle(f) << ",\"cycles\":" << f.cycles
    << ",\"stop\":\"" << f.stop_reason << "\"";
  if (f.kind == SessionKind::balance) {
    j << ",\"law\":" << law_json(f.law) << ",\"law_by_mode\":{";
    for (std::size_t m = 0; m < kModes; ++m) {
      j << (m ? "," : "") << "\"" << control::to_string(static_cast<control::BalanceMode>(m))
        << "\":" << law_json(f.law_by_mode[m]);
    }
    j << "},\"balanced_from_s\":" << f.balanced_from_s;
  }
  j << ",\"subscriber\":{\"p50_us\":" << s.histogram.quantile_us(0.5)
    << ",\"p99_us\":" << s.histogram.quantile_us(0.99)
    << ",\"p999_us\":" << s.histogram.quantile_us(0.999) << ",\"max_us\":" << s.histogram.max_us()
    << ",\"from_deadline_p50_us\":" << s.from_deadline.quantile_us(0.5)
    << ",\"from_deadline_p99_us\":" << s.from_deadline.quantile_us(0.99)
    << ",\"to_publisher_p99_us\":" << s.to_publisher.quantile_us(0.99)
    << ",\"from_publisher_p99_us\":" << s.from_publisher.quantile_us(0.99)
    << ",\"received\":" << s.received << ",\"published\":" << f.samples_logged << "}}";
  return j.str();
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
  std::string samples_csv;
  std::string config_path = config::default_rig_config_path().string();
  std::vector<std::string> session_names{"bang-bang"};
  std::string balance_path;
  app.add_option("--period-us", period_us)->check(CLI::Range(100.0, 1e6));
  app.add_option("--seconds", seconds, "Each loop's length: the floor's and each session's")
      ->check(CLI::Range(1.0, 3600.0));
  app.add_option("--session", session_names,
                 "Sessions to run, in order, each in a daemon of its own: bang-bang, balance, "
                 "both (bang-bang then balance); comma-separated or repeated")
      ->delimiter(',')
      ->check(CLI::IsMember({"bang-bang", "balance", "both"}));
  app.add_option("--balance", balance_path,
                 "The controller file a balance session runs (furuta controller design), "
                 "designed for --config's rig and for --period-us")
      ->check(CLI::ExistingFile);
  app.add_flag("--fifo", fifo, "SCHED_FIFO (+ mlockall) for every loop");
  app.add_option("--cpu", cpu, "Pin every loop to this CPU");
  app.add_option("--lcm-url", lcm_url,
                 "LCM for samples; udpm needs a multicast route (see bench/README.md)");
  app.add_option("--json", json_path, "Write the figures as JSON");
  app.add_option("--samples-csv", samples_csv,
                 "Write each session's samples (wake-up latency, mode, law time, angles, duty) "
                 "to PREFIX-<session>-<n>.csv");
  app.add_option("--config", config_path)->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);

  std::vector<SessionKind> kinds;
  for (const std::string& name : session_names) {
    if (name != "balance") kinds.push_back(SessionKind::bang_bang);
    if (name != "bang-bang") kinds.push_back(SessionKind::balance);
  }
  const bool any_balance = std::ranges::count(kinds, SessionKind::balance) > 0;
  if (any_balance && balance_path.empty()) {
    std::cerr << "daemon_latency: a balance session needs --balance CONTROLLER.toml (design one "
                 "with `furuta controller design RESULTS.json -o CONTROLLER.toml`)\n";
    return 2;
  }

  Setup setup;
  setup.keep_samples = !samples_csv.empty();
  setup.period_ns = static_cast<std::int64_t>(period_us * 1000);
  setup.seconds = seconds;
  setup.fifo = fifo;
  setup.cpu = cpu;
  setup.lcm_url = lcm_url;
  setup.rig = config::load_rig_config(config_path);
  setup.rig.simulation.record_truth = false;
  if (any_balance) {
    // Checked before the floor's run, so that a file the daemon would refuse costs no minute; the
    // daemon reads and checks it again when the session starts.
    config::ControllerFile controller;
    try {
      controller = config::load_controller_file(balance_path);
    } catch (const std::exception& e) {
      std::cerr << "daemon_latency: " << e.what() << "\n";
      return 2;
    }
    if (controller.period_ns != setup.period_ns || controller.rig != setup.rig.name) {
      std::cerr << "daemon_latency: " << balance_path << " was designed for rig '" << controller.rig
                << "' at " << controller.period_ns << " ns; this run is rig '" << setup.rig.name
                << "' at " << setup.period_ns << " ns\n";
      return 2;
    }
    setup.controller_path = std::filesystem::absolute(balance_path).lexically_normal();
    setup.controller_sha256 = controller.sha256;
  }

  const auto duration_ns = static_cast<std::int64_t>(seconds * 1e9);
  daemon::RealtimeOptions rt;
  rt.enabled = fifo;
  rt.cpu = cpu;

  daemon::DaemonSettings& settings = setup.settings;
  settings = daemon::daemon_settings_from_config(setup.rig);
  settings.loop.period_ns = setup.period_ns;
  // Staleness counts cycles; keep it at 32 ms of silence whatever the period.
  settings.loop.safety.stale_report_cycles = std::max<int>(
      settings.loop.safety.stale_report_cycles, static_cast<int>(32'000'000 / setup.period_ns) + 1);
  // Every session waits out the configuration's rest check, as a balance session must: the start
  // is queued before the loop runs, so without a wait it would be refused at once.
  settings.loop.rest_wait_s = settings.loop.rest_check_s + 1.0;
  settings.realtime = rt;
  settings.queue_capacity = 8192;

  std::cerr << "floor: bare loop, " << period_us << " us, " << seconds << " s ...\n";
  const bench::LoopFigures floor = bench::measure_bare_loop(setup.period_ns, duration_ns, rt);

  std::vector<SessionFigures> sessions;
  for (const SessionKind kind : kinds) {
    std::cerr << "daemon: loop + simulated rig in real time, " << to_string(kind)
              << " session ...\n";
    std::optional<SessionFigures> f = run_session(setup, kind);
    if (!f) return 1;
    if (!samples_csv.empty()) {
      const std::string path = samples_csv + "-" + std::string(to_string(kind)) + "-" +
                               std::to_string(sessions.size()) + ".csv";
      std::ofstream csv(path);
      csv << "seq,t_s,wake_latency_us,overruns,mode,law_time_ns,arm_rad,pendulum_rad,duty\n";
      for (const auto& x : f->samples) {
        csv << x.seq << "," << static_cast<double>(x.seq * setup.period_ns) * 1e-9 << ","
            << static_cast<double>(x.wake_ns) * 1e-3 << "," << x.overruns << "," << x.mode << ","
            << x.law_ns << "," << x.arm_rad << "," << x.pendulum_rad << "," << x.duty << "\n";
      }
    }
    sessions.push_back(std::move(*f));
  }

  const Row floor_row{"bare clock_nanosleep loop",
                      floor.latency.quantile_us(0.5),
                      floor.latency.quantile_us(0.99),
                      floor.latency.quantile_us(0.999),
                      floor.latency.max_us(),
                      floor.latency.mean_us(),
                      static_cast<std::int64_t>(floor.overruns),
                      floor.cpu_us_per_cycle};
  std::cout << "period " << period_us << " us, " << seconds << " s per loop, SCHED_FIFO "
            << (fifo ? (floor.fifo_in_force ? "in force" : "asked, refused") : "off")
            << (cpu >= 0 ? ", pinned to CPU " + std::to_string(cpu) : std::string()) << ", LCM "
            << lcm_url << "\n";
  std::cout << std::left << std::setw(30) << "wake-up latency [us]" << std::right << std::setw(8)
            << "p50" << std::setw(8) << "p99" << std::setw(9) << "p99.9" << std::setw(9) << "max"
            << std::setw(8) << "mean" << std::setw(10) << "overruns" << std::setw(10) << "cpu/cyc"
            << "\n";
  print_row(floor_row);
  for (const SessionFigures& f : sessions) {
    print_row(row("daemon, " + std::string(to_string(f.kind)) + " session", f.wake, f.overruns,
                  cpu_us_per_cycle(f)));
  }
  std::cout << "(a session's row: its own cycles; overruns and cpu/cyc: the loop's whole run, the "
               "rest check before the session included)\n";
  std::cout << std::fixed << std::setprecision(2);
  for (const SessionFigures& f : sessions) {
    std::cout << "ratio " << to_string(f.kind) << "/floor: p50 "
              << f.wake.quantile_us(0.5) / std::max(floor_row.p50, 1.0) << ", p99 "
              << f.wake.quantile_us(0.99) / std::max(floor_row.p99, 1.0) << "\n";
  }
  // Each kind's sessions together: a run that alternates them (bang-bang,balance,balance,bang-bang)
  // compares the two kinds under the same drift of the machine's load.
  struct Pooled {
    daemon::LatencyHistogram wake;
    LawTimes law;
    int sessions = 0;
  };
  std::array<Pooled, 2> pooled;  // by SessionKind
  for (const SessionFigures& f : sessions) {
    Pooled& p = pooled[static_cast<std::size_t>(f.kind)];
    ++p.sessions;
    for (const std::int64_t w : f.wake_ns) p.wake.record(w);
    p.law.ns.insert(p.law.ns.end(), f.law.ns.begin(), f.law.ns.end());
  }
  for (Pooled& p : pooled) p.law.finish();
  const Pooled& bang = pooled[static_cast<std::size_t>(SessionKind::bang_bang)];
  const Pooled& balance = pooled[static_cast<std::size_t>(SessionKind::balance)];
  for (const SessionKind kind : {SessionKind::bang_bang, SessionKind::balance}) {
    const Pooled& p = pooled[static_cast<std::size_t>(kind)];
    if (p.sessions < 2) continue;
    std::cout << "all " << p.sessions << " " << to_string(kind)
              << " sessions: " << std::setprecision(0) << quantiles(p.wake) << ", mean "
              << p.wake.mean_us() << std::setprecision(2) << "\n";
  }
  if (bang.sessions > 0 && balance.sessions > 0) {
    const auto ratio = [&](double q) {
      return balance.wake.quantile_us(q) / std::max(bang.wake.quantile_us(q), 1.0);
    };
    std::cout << "ratio balance/bang_bang" << (bang.sessions + balance.sessions > 2 ? " (all)" : "")
              << ": p50 " << ratio(0.5) << ", p99 " << ratio(0.99) << ", p99.9 " << ratio(0.999)
              << ", max " << balance.wake.max_us() / std::max(bang.wake.max_us(), 1.0) << "\n";
  }
  if (balance.sessions > 1) {
    std::cout << std::setprecision(0) << "balance law per cycle [ns], all " << balance.sessions
              << " balance sessions: " << law_quantiles(balance.law) << "\n";
  }
  for (const SessionFigures& f : sessions) {
    std::cout << std::fixed << std::setprecision(0);
    const std::string name(to_string(f.kind));
    if (f.kind == SessionKind::balance) {
      std::cout << "balance law per cycle [ns]: " << law_quantiles(f.law) << "\n";
      for (std::size_t m = 0; m < kModes; ++m) {
        if (f.law_by_mode[m].ns.empty()) continue;
        std::cout << "  " << control::to_string(static_cast<control::BalanceMode>(m)) << ": "
                  << law_quantiles(f.law_by_mode[m]) << "\n";
      }
      if (f.balanced_from_s >= 0) {
        std::cout << std::setprecision(2) << "  balanced from t = " << f.balanced_from_s << " s\n";
      } else {
        std::cout << "  never balanced\n";
      }
    }
    const SubscriberLatency& s = *f.subscriber;
    std::cout << name
              << " sample -> subscriber [us], from the loop queueing it: " << quantiles(s.histogram)
              << "\n"
              << name << " sample -> subscriber [us], from its cycle's deadline: "
              << quantiles(s.from_deadline) << " (" << s.received << " of " << f.samples_logged
              << " samples received)\n"
              << "  of which queued -> publisher: " << quantiles(s.to_publisher)
              << "; publisher -> subscriber: " << quantiles(s.from_publisher) << "\n";
    std::cout << name << " session ended: " << f.stop_reason << "\n";
  }

  if (!json_path.empty()) {
    std::ofstream json(json_path);
    json << "{\"period_us\":" << period_us << ",\"seconds\":" << seconds
         << ",\"fifo\":" << (fifo ? "true" : "false") << ",\"cpu\":" << cpu
         << ",\"floor\":" << bench::to_json(floor) << ",\"sessions\":[";
    for (std::size_t i = 0; i < sessions.size(); ++i) {
      json << (i ? "," : "") << session_json(sessions[i]);
    }
    json << "],\"pooled\":{\"bang_bang\":" << histogram_json(bang.wake)
         << ",\"balance\":" << histogram_json(balance.wake)
         << ",\"balance_law\":" << law_json(balance.law) << "}}\n";
  }
  return 0;
}
