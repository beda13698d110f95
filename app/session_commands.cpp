// `furuta start|stop|estop|status` (a running daemon, over LCM), `furuta run` (one session without
// a daemon), `furuta log info|export-csv`, `furuta replay`.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <ostream>
#include <random>
#include <sstream>
#include <thread>

#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

namespace {

using namespace std::chrono_literals;

const char* state_name(std::int8_t state) {
  switch (state) {
    case furuta::rig_status_t::STATE_IDLE:
      return "idle";
    case furuta::rig_status_t::STATE_RUNNING:
      return "running";
    case furuta::rig_status_t::STATE_FAULT:
      return "fault";
    case furuta::rig_status_t::STATE_DISCONNECTED:
      return "disconnected";
    default:
      return "unknown";
  }
}

void print_status(const furuta::rig_status_t& s, std::ostream& out) {
  out << "state " << state_name(s.state);
  if (!s.session.empty()) out << ", session " << s.session;
  out << "; cycles " << s.cycles << ", overruns " << s.overruns << ", lost reports 1065 "
      << s.motor_lost_reports << " / 1047 " << s.encoder_lost_reports;
  out << std::fixed << std::setprecision(1) << "; wake-up latency mean " << s.jitter_mean_us
      << " us, p99 " << s.jitter_p99_us << " us, max " << s.jitter_max_us << " us";
  if (!s.last_fault.empty()) out << "; last fault: " << s.last_fault;
  out << "\n";
}

struct ReplyWaiter {
  std::int64_t request_id = 0;
  std::optional<furuta::rig_status_t> reply;
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_status_t* m) {
    if (m->reply_to_request_id == request_id) reply = *m;
  }
};

void fill_start_command(const StartOptions& start, const config::ExcitationConfig& defaults,
                        furuta::rig_command_t& command) {
  command.profile = start.profile.value_or(defaults.profile);
  command.amplitude_duty = start.amplitude_duty.value_or(defaults.amplitude_duty);
  command.duration_s = start.duration_s.value_or(defaults.duration_s);
  command.seed = start.seed.value_or(defaults.seed);
  command.label = start.label;
}

std::string lcm_url_for(const RemoteOptions& remote) {
  if (!remote.lcm_url.empty()) return remote.lcm_url;
  return config::load_rig_config(remote.config_path).daemon.lcm_url;
}

// The last command written to the 1065 as the log recorded it: on every way a session ends it must
// be the zero command, so this is what to look at after a fault.
std::string last_motor_command(const session_log::SessionLog& log) {
  const furuta::rig_usb_report_t* last = nullptr;
  for (const auto& r : log.usb_reports) {
    if (r.board == furuta::rig_usb_report_t::BOARD_MOTOR_1065 &&
        (r.kind == furuta::rig_usb_report_t::KIND_OUTPUT ||
         r.kind == furuta::rig_usb_report_t::KIND_ERROR)) {
      last = &r;
    }
  }
  if (!last) return "no command logged";
  bridge::MotorOutput1065 output;
  if (bridge::decode_output_1065(last->bytes, output) != bridge::CodecStatus::ok) {
    return "last command undecodable (" + std::to_string(last->bytes.size()) + " bytes)";
  }
  std::ostringstream text;
  text << "last command duty " << output.duty_cycle() << ", braking " << output.braking_fraction();
  if (last->kind == furuta::rig_usb_report_t::KIND_ERROR)
    text << " (write failed: " << last->status << ")";
  return text.str();
}

}  // namespace

int run_remote_command(RemoteKind kind, const RemoteOptions& remote, const StartOptions& start,
                       std::ostream& out, std::ostream& err) {
  const std::string url = lcm_url_for(remote);
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    err << "furuta: cannot open LCM at " << url << "\n";
    return 2;
  }
  ReplyWaiter waiter;
  std::random_device entropy;
  waiter.request_id = static_cast<std::int64_t>(entropy() >> 1) + 1;
  lcm::Subscription* sub =
      lcm.subscribe(session_log::kChannelStatus, &ReplyWaiter::on_status, &waiter);

  furuta::rig_command_t command{};
  command.request_id = waiter.request_id;
  switch (kind) {
    case RemoteKind::start:
      command.kind = furuta::rig_command_t::KIND_START_SESSION;
      fill_start_command(start, config::load_rig_config(remote.config_path).excitation, command);
      break;
    case RemoteKind::stop:
      command.kind = furuta::rig_command_t::KIND_STOP;
      break;
    case RemoteKind::estop:
      command.kind = furuta::rig_command_t::KIND_ESTOP;
      break;
    case RemoteKind::status:
      command.kind = furuta::rig_command_t::KIND_STATUS_REQUEST;
      break;
  }
  lcm.publish(session_log::kChannelCommand, &command);
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(std::llround(remote.reply_timeout_s * 1000));
  while (!waiter.reply && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);
  lcm.unsubscribe(sub);
  if (!waiter.reply) {
    err << "furuta: no answer from furutad on " << url << " within " << remote.reply_timeout_s
        << " s (is it running? `systemctl status furutad`)\n";
    return 2;
  }
  if (!waiter.reply->request_accepted) {
    err << "furuta: refused: " << waiter.reply->request_reason << "\n";
    return 1;
  }
  print_status(*waiter.reply, out);
  return 0;
}

int run_session_command(const RunOptions& options, std::ostream& out, std::ostream& err) {
  const config::RigConfig rig = config::load_rig_config(options.config_path);
  daemon::DaemonSettings settings = daemon::daemon_settings_from_config(rig);
  if (!options.logs_dir.empty()) settings.recorder.logs_dir = options.logs_dir;
  for (const auto& recovered : session_log::recover_partial_logs(settings.recorder.logs_dir)) {
    err << "furuta run: "
        << (recovered.discarded ? "removed an empty log: " : "recovered a session cut short: ")
        << recovered.path.string() << "\n";
  }
  daemon::ConnectOptions connect;
  if (options.simulated) connect.backend = daemon::BackendChoice::simulated;
  connect.virtual_time = options.virtual_time;
  daemon::RigConnection rig_io = daemon::connect_rig(rig, connect);
  for (const std::string& warning : rig_io.warnings) err << "furuta run: " << warning << "\n";
  settings.recorder.motor_device = bridge::format_trace_device_line(rig_io.motor->device_info());
  settings.recorder.encoder_device =
      bridge::format_trace_device_line(rig_io.encoder->device_info());
  settings.loop.wait_when_queue_full = options.virtual_time;
  // A one-shot run waits for the pendulum to settle instead of refusing at once.
  settings.loop.rest_wait_s = 120.0;

  const std::string url = options.lcm_url.empty() ? rig.daemon.lcm_url : options.lcm_url;
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    err << "furuta run: cannot open LCM at " << url << " (try --lcm-url memq://)\n";
    return 2;
  }
  daemon::Daemon daemon(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, lcm);
  furuta::rig_command_t command{};
  command.kind = furuta::rig_command_t::KIND_START_SESSION;
  fill_start_command(options.session, rig.excitation, command);
  const furuta::rig_status_t reply = daemon.handle_command(command);
  if (!reply.request_accepted) {
    err << "furuta run: refused: " << reply.request_reason << "\n";
    return 1;
  }
  daemon.loop().exit_when_idle();
  daemon.start();
  daemon.wait();
  const daemon::StopReason stop = daemon.loop().counters().last_stop.load();
  const auto& log = daemon.recorder().last_log();
  out << "session ended: " << daemon::to_string(stop);
  if (log) out << "; log " << log->string();
  out << "\n";
  if (!log) {
    err << "furuta run: no log was written"
        << (daemon.recorder().last_fault().empty() ? "" : ": " + daemon.recorder().last_fault())
        << "\n";
    return 1;
  }
  return daemon::is_fault(stop) ? 1 : 0;
}

int run_log_info_command(const std::filesystem::path& path, std::ostream& out, std::ostream&) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  out << path.string() << "\n";
  if (log.start) {
    const auto& s = *log.start;
    out << "  session   " << s.session << (s.label.empty() ? "" : " (" + s.label + ")") << "\n";
    out << "  profile   " << s.profile << ", amplitude " << s.amplitude_duty << ", duration "
        << s.duration_s << " s, seed " << s.seed << ", period " << s.period_ns / 1000 << " us\n";
    out << "  software  " << s.software_version << "\n";
  } else {
    out << "  no session start record\n";
  }
  out << "  samples   " << log.samples.size();
  const auto missing = log.missing_sequence_numbers();
  if (!missing.empty()) out << " (" << missing.size() << " sequence numbers missing)";
  out << "\n  usb       " << log.usb_reports.size() << " raw reports\n";
  out << "  faults    " << log.faults.size();
  for (const auto& f : log.faults) {
    if (f.fatal) out << "; fatal: " << f.reason << (f.detail.empty() ? "" : " (" + f.detail + ")");
  }
  out << "\n  motor     " << last_motor_command(log);
  out << "\n  end       "
      << (log.end ? log.end->end_reason + ", " + std::to_string(log.end->samples) + " samples"
                  : std::string("missing: the session was cut short"))
      << "\n";
  const auto& st = log.read_stats;
  out << "  file      " << st.events << " events";
  if (st.damaged_regions > 0) {
    out << ", " << st.damaged_regions << " damaged regions (" << st.bytes_skipped
        << " bytes skipped)";
  }
  if (st.truncated_tail) out << ", truncated tail";
  if (log.undecodable_events > 0) out << ", " << log.undecodable_events << " undecodable";
  out << "\n";
  return log.complete() ? 0 : 1;
}

int run_log_export_csv_command(const std::filesystem::path& path,
                               const std::filesystem::path& csv_path, std::ostream& out,
                               std::ostream& err) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  std::ofstream csv(csv_path);
  if (!csv) {
    err << "furuta log export-csv: cannot write " << csv_path.string() << "\n";
    return 2;
  }
  csv << "seq,t_s,arm_counts,pendulum_counts,q1_rad,q2_rad,commanded_duty,applied_duty,"
         "current_a,supply_v,motor_flags,encoder_flags,motor_lost,encoder_lost,overruns,flags\n";
  csv << std::setprecision(10);
  const std::int64_t t0 = log.samples.empty() ? 0 : log.samples.front().monotonic_ns;
  for (const auto& s : log.samples) {
    csv << s.seq << ',' << static_cast<double>(s.monotonic_ns - t0) * 1e-9 << ',' << s.arm_counts
        << ',' << s.pendulum_counts << ',' << s.arm_angle_rad << ',' << s.pendulum_angle_rad << ','
        << s.commanded_duty << ',' << s.applied_duty << ',' << s.motor_current_a << ','
        << s.supply_voltage_v << ',' << s.motor_status_flags << ',' << s.encoder_flags << ','
        << s.motor_lost_reports << ',' << s.encoder_lost_reports << ',' << s.overruns << ','
        << s.flags << '\n';
  }
  csv.close();
  if (!csv) {
    err << "furuta log export-csv: error writing " << csv_path.string() << "\n";
    return 2;
  }
  out << "wrote " << log.samples.size() << " samples to " << csv_path.string() << "\n";
  return 0;
}

int run_replay_command(const std::filesystem::path& path, const std::filesystem::path& config_path,
                       std::ostream& out, std::ostream& err) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  if (!log.start) {
    err << "furuta replay: " << path.string() << " has no session start record\n";
    return 2;
  }
  // The log carries the configuration it ran with; a given file overrides it.
  const config::RigConfig rig =
      config_path.empty()
          ? config::parse_rig_config(log.start->rig_config_toml, path.string() + " (rig config)")
          : config::load_rig_config(config_path);
  daemon::DaemonSettings settings = daemon::daemon_settings_from_config(rig);
  const auto temp =
      std::filesystem::temp_directory_path() / ("furuta-replay-" + std::to_string(::getpid()));
  settings.recorder.logs_dir = temp;
  settings.loop.wait_when_queue_full = true;
  // The loop's first cycle falls on the recorded session's first deadline and the session starts
  // there: the original already passed the rest check (the replayed traffic starts with the
  // session).
  settings.loop.rest_check_s = 0.0;
  daemon::ConnectOptions connect{daemon::BackendChoice::replay, path, true,
                                 log.start->monotonic_ns - log.start->period_ns};
  daemon::RigConnection rig_io = daemon::connect_rig(rig, connect);
  settings.recorder.motor_device = log.start->motor_device;
  settings.recorder.encoder_device = log.start->encoder_device;
  lcm::LCM lcm("memq://");
  std::optional<std::filesystem::path> replay_log;
  {
    daemon::Daemon daemon(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, lcm);
    daemon.start_replayed_session(*log.start);
    daemon.loop().exit_when_idle();
    daemon.start();
    daemon.wait();
    replay_log = daemon.recorder().last_log();
  }
  if (!replay_log) {
    err << "furuta replay: the replayed session wrote no log\n";
    std::filesystem::remove_all(temp);
    return 2;
  }
  const session_log::SessionLog again = session_log::load_session_log(*replay_log);
  std::filesystem::remove_all(temp);
  std::size_t differing = 0;
  std::int64_t first_difference = -1;
  const std::size_t n = std::min(log.samples.size(), again.samples.size());
  for (std::size_t i = 0; i < n; ++i) {
    const auto& a = log.samples[i];
    const auto& b = again.samples[i];
    const bool same = a.seq == b.seq && a.monotonic_ns == b.monotonic_ns &&
                      a.arm_counts == b.arm_counts && a.pendulum_counts == b.pendulum_counts &&
                      a.commanded_duty == b.commanded_duty && a.applied_duty == b.applied_duty &&
                      a.motor_report_host_ns == b.motor_report_host_ns &&
                      a.encoder_delta_counts == b.encoder_delta_counts && a.flags == b.flags;
    if (!same) {
      ++differing;
      if (first_difference < 0) first_difference = a.seq;
    }
  }
  out << "replayed " << again.samples.size() << " of " << log.samples.size() << " samples";
  if (differing == 0 && again.samples.size() == log.samples.size()) {
    out << ": identical\n";
    return 0;
  }
  out << ": " << differing << " differ (first at seq " << first_difference << ")\n";
  return 1;
}

}  // namespace furuta::app
