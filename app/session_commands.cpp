// `furuta start|stop|estop|status` (a running daemon, over LCM) and `furuta run` (one session
// without a daemon).
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

}  // namespace furuta::app
