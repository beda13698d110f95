// `furuta start|stop|estop|status` (a running daemon, over LCM) and `furuta run` (one session
// without a daemon).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <fstream>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <ostream>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "balance_text.hpp"
#include "commands.hpp"
#include "daemon_channel.hpp"
#include "furuta/command_auth/command_auth.hpp"
#include "furuta/command_auth/status_signature.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
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

std::string utc_time(std::int64_t wall_ns) {
  const auto seconds = static_cast<std::time_t>(wall_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", &utc);
  return stamp;
}

// duration_reached and stop_command end a session as asked; every other end is a fault.
bool ended_as_asked(const std::string& end_reason) {
  const std::string reason = end_reason.substr(0, end_reason.find(':'));
  return reason == "duration_reached" || reason == "stop_command";
}

class LcmChannel final : public DaemonChannel {
 public:
  explicit LcmChannel(std::string url) : url_(std::move(url)), lcm_(url_) {
    if (lcm_.good()) {
      subscription_ = lcm_.subscribe(session_log::kChannelStatus, &LcmChannel::on_status, this);
      // Statuses pile up here only while this process is busy elsewhere; the newest matter.
      subscription_->setQueueCapacity(256);
    }
  }
  ~LcmChannel() override {
    if (subscription_) lcm_.unsubscribe(subscription_);
  }
  bool good() { return lcm_.good(); }
  void send(const furuta::rig_command_t& command) override {
    lcm_.publish(session_log::kChannelCommand, &command);
  }
  void send_signed(const furuta::rig_signed_command_t& command) override {
    lcm_.publish(session_log::kChannelSignedCommand, &command);
  }
  std::optional<furuta::rig_status_t> receive(std::chrono::milliseconds wait) override {
    const auto deadline = std::chrono::steady_clock::now() + wait;
    while (received_.empty()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      lcm_.handleTimeout(static_cast<int>(std::max<std::int64_t>(1, left.count())));
    }
    furuta::rig_status_t first = std::move(received_.front());
    received_.pop_front();
    return first;
  }
  std::string where() const override { return url_; }

 private:
  // Raw: a message larger than any status the daemon sends is dropped unread, and one that does
  // not decode is dropped without LCM's message on stderr.
  void on_status(const lcm::ReceiveBuffer* buffer, const std::string&) {
    furuta::rig_status_t status{};
    if (decode_status(buffer->data, buffer->data_size, status)) {
      received_.push_back(std::move(status));
    }
  }
  std::string url_;
  lcm::LCM lcm_;
  lcm::Subscription* subscription_ = nullptr;
  std::deque<furuta::rig_status_t> received_;
};

// Random and non-zero: zero means "not a reply", and two `furuta` at once must not share one.
std::int64_t new_request_id() {
  std::random_device entropy;
  return static_cast<std::int64_t>(((std::uint64_t{entropy()} << 31) ^ entropy()) >> 1) + 1;
}

std::chrono::milliseconds millis(double seconds) {
  return std::chrono::milliseconds(std::llround(seconds * 1000));
}

// Which answers count: those signed under the daemon's public key. Without a readable public key
// nothing can be checked, and every answer is taken as it is (the caller says so once).
class AnswerCheck {
 public:
  explicit AnswerCheck(std::optional<command_auth::DaemonPublicKey> key) : key_(key) {}
  bool verifying() const { return key_.has_value(); }
  bool trusted(const furuta::rig_status_t& status) {
    if (!key_) return true;
    switch (command_auth::check_status(status, *key_)) {
      case command_auth::StatusAuthenticity::signed_by_daemon:
        return true;
      case command_auth::StatusAuthenticity::unsigned_status:
        ++unsigned_;
        return false;
      case command_auth::StatusAuthenticity::wrongly_signed:
        ++wrongly_signed_;
        return false;
    }
    return false;
  }
  // "" when nothing was ignored, else what and why, for the message that nothing answered.
  std::string ignored() const {
    if (unsigned_ == 0 && wrongly_signed_ == 0) return {};
    return "; " + std::to_string(unsigned_) + " unsigned and " + std::to_string(wrongly_signed_) +
           " wrongly signed answer(s) were ignored: a furutad without its daemon key, or someone "
           "on the LCM group forging the daemon's answers (docs/security.md)";
  }
  // Said once at the end of a command that got its signed answer all the same.
  void warn_if_ignored(const std::string& name, std::ostream& err) const {
    if (const std::string what = ignored(); !what.empty()) {
      err << name << ": WARNING: " << what.substr(2) << "\n";  // past the "; "
    }
  }

 private:
  std::optional<command_auth::DaemonPublicKey> key_;
  std::int64_t unsigned_ = 0;
  std::int64_t wrongly_signed_ = 0;
};

// The first status for which `done` holds, within `limit`, among the trusted answers to this
// tool's own status requests (each a fresh random id, so no old answer can be played back as
// one). A request goes out now and every 250 ms.
template <class Done>
std::optional<furuta::rig_status_t> poll_status(DaemonChannel& channel, AnswerCheck& check,
                                                std::chrono::milliseconds limit, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  auto next_request = std::chrono::steady_clock::now();
  std::set<std::int64_t> asked;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return std::nullopt;
    if (now >= next_request) {
      furuta::rig_command_t ask{};
      ask.request_id = new_request_id();
      ask.kind = furuta::rig_command_t::KIND_STATUS_REQUEST;
      asked.insert(ask.request_id);
      channel.send(ask);
      next_request = now + std::chrono::milliseconds(250);
    }
    const auto wait = std::min(next_request, deadline) - now;
    auto s = channel.receive(std::chrono::duration_cast<std::chrono::milliseconds>(wait) +
                             std::chrono::milliseconds(1));
    if (s && asked.count(s->reply_to_request_id) != 0 && check.trusted(*s) && done(*s)) return s;
  }
}

const char* command_name(RemoteKind kind) {
  switch (kind) {
    case RemoteKind::start:
      return "start";
    case RemoteKind::stop:
      return "stop";
    case RemoteKind::estop:
      return "estop";
    case RemoteKind::status:
      return "status";
  }
  return "?";
}

// False, said on `err`, when the controller file of a balance start does not read: nothing is
// sent or started.
bool fill_start_command(const StartOptions& start, const config::ExcitationConfig& defaults,
                        furuta::rig_command_t& command, const std::string& name,
                        std::ostream& err) {
  command.profile = start.profile.value_or(defaults.profile);
  command.amplitude_duty = start.amplitude_duty.value_or(defaults.amplitude_duty);
  command.duration_s = start.duration_s.value_or(defaults.duration_s);
  command.seed = start.seed.value_or(defaults.seed);
  command.label = start.label;
  if (start.balance) {
    // Read and checked here, before anything is sent: a bad file is refused without motion. The
    // daemon reads it again and takes it only if its bytes are still the ones hashed here.
    config::ControllerFile controller;
    try {
      controller = config::load_controller_file(*start.balance);
    } catch (const config::ConfigError& e) {
      err << name << ": " << e.what() << "; nothing was started\n";
      return false;
    }
    command.profile = std::string(daemon::kBalanceProfile);
    command.amplitude_duty = controller.spec.max_duty;
    command.controller_path = std::filesystem::absolute(*start.balance).lexically_normal().string();
    command.controller_sha256 = controller.sha256;
  }
  return true;
}

// A session value the configuration's [limits] can never accept (an amplitude above
// max_amplitude_duty, NaN, a label that cannot be a file name) is bad usage, like one that is not
// a number: said with the field, the limit's key and the file, before anything else happens.
// The values the configuration filled in are its own and pass its check.
bool session_values_usable(const std::string& name, const furuta::rig_command_t& command,
                           const config::RigConfig& rig, const std::filesystem::path& config_path,
                           std::ostream& err) {
  const std::string problem = daemon::start_session_problem(
      command, daemon::daemon_settings_from_config(rig).command_limits);
  if (problem.empty()) return true;
  err << name << ": " << problem << " (the limits are [limits] max_amplitude_duty, "
      << "max_duration_s and max_label_chars of " << config_path.string() << ")\n";
  return false;
}

// The daemon's public key, or nothing (said on `err`: its answers are then taken unverified).
std::optional<command_auth::DaemonPublicKey> daemon_public_key(const RemoteOptions& remote,
                                                               const std::string& name,
                                                               std::ostream& err) {
  std::filesystem::path path = remote.daemon_public_key;
  if (path.empty()) {
    try {
      path = config::load_rig_config(remote.config_path).daemon.daemon_public_key_file;
    } catch (const std::exception& e) {
      err << name << ": WARNING: the daemon's answers are taken unverified: " << e.what() << "\n";
      return std::nullopt;
    }
  }
  command_auth::PublicKeyFile file = command_auth::read_daemon_public_key(path);
  if (!file.key) {
    err << name << ": WARNING: the daemon's answers are taken unverified: " << file.problem << "\n";
  }
  return file.key;
}

std::string lcm_url_for(const RemoteOptions& remote) {
  if (!remote.lcm_url.empty()) return remote.lcm_url;
  return config::load_rig_config(remote.config_path).daemon.lcm_url;
}

std::string describe_rig(const config::RigConfig& rig, const RunOptions& options,
                         const daemon::RigConnection& rig_io) {
  const bridge::DeviceInfo& motor = rig_io.motor->device_info();
  const bridge::DeviceInfo& encoder = rig_io.encoder->device_info();
  std::ostringstream text;
  if (options.simulated) {
    text << "simulated (--sim)";
  } else if (rig.backend == config::UsbBackend::simulated) {
    text << "simulated ([rig] backend = \"simulated\" in " << options.config_path.string()
         << "; set hidapi or libusb for the USB boards)";
  } else {
    text << "USB boards through " << rig_io.description;
  }
  text << ": motor board " << rig.motor_board.model << " serial " << motor.serial << " (firmware "
       << motor.firmware_version << "), encoder board " << rig.encoder_board.model << " serial "
       << encoder.serial << " (firmware " << encoder.firmware_version << ")";
  if (options.virtual_time) text << ", virtual time";
  return text.str();
}

}  // namespace

bool decode_status(const void* data, std::size_t size, furuta::rig_status_t& status) {
  return size <= command_auth::kMaxStatusBytes &&
         status.decode(data, 0, static_cast<int>(size)) >= 0;
}

// Counts that have no data yet say so rather than showing a zero.
void print_status(const furuta::rig_status_t& status, std::ostream& out) {
  // Every text of a status may quote a stranger's bytes: bounded and escaped before printing.
  furuta::rig_status_t s = status;
  command_auth::bound_status_text(s);
  out << "state " << state_name(s.state);
  if (!s.session.empty()) out << ", session " << s.session;
  if (s.cycles == 0) {
    out << "; cycles 0: the loop has not run yet, no reports";
  } else {
    out << "; cycles " << s.cycles << ", overruns " << s.overruns << ", lost reports motor board "
        << s.motor_lost_reports << " / encoder board " << s.encoder_lost_reports;
  }
  out << "; wake-up latency ";
  if (s.latency_samples == 0) {
    out << "no data yet (figures are per session)";
  } else {
    out << (s.session.empty() ? "of the last session" : "of this session") << " ("
        << s.latency_samples << " cycles) " << std::fixed << std::setprecision(1) << "mean "
        << s.jitter_mean_us << " us, p99 " << s.jitter_p99_us << " us, max " << s.jitter_max_us
        << " us";
    out.unsetf(std::ios::floatfield);
  }
  if (s.session.empty() && !s.last_session.empty()) {
    out << "; last session " << s.last_session << " ended " << s.last_session_end;
  }
  if (s.last_fault.empty()) {
    out << "; no fault since start-up";
  } else {
    out << "; last fault: " << s.last_fault << " (" << utc_time(s.last_fault_wall_ns)
        << (s.last_fault_session.empty() ? ", no session running"
                                         : ", in session " + s.last_fault_session)
        << "), " << s.sessions_since_fault << " session(s) ended well since";
  }
  if (!s.logs_problem.empty()) out << "; starts refused: cannot log a session: " << s.logs_problem;
  if (s.refused_unauthenticated > 0) {
    out << "; " << s.refused_unauthenticated
        << " command(s) refused for their signature since start-up, the latest: "
        << s.unauthenticated_reason;
  }
  std::string counts;
  for (const auto& [n, what] :
       {std::pair{s.refused_unsigned, "unsigned"},
        std::pair{s.refused_bad_signature, "bad signature"},
        std::pair{s.refused_malformed, "malformed"},
        std::pair{s.refused_out_of_time, "out of time"}, std::pair{s.refused_replayed, "replayed"},
        std::pair{s.refused_start_budget, "over the start budget"},
        std::pair{s.refused_stop_budget, "over the stop budget"},
        std::pair{s.refused_status_budget, "over the status budget"},
        std::pair{s.refused_invalid, "invalid"},
        std::pair{s.replies_withheld, "not answered (reply budget)"}}) {
    if (n > 0) counts += (counts.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  }
  if (!counts.empty()) out << "; refusals since start-up: " << counts;
  out << "\n";
}

int run_remote_command(RemoteKind kind, const RemoteOptions& remote, const StartOptions& start,
                       std::ostream& out, std::ostream& err) {
  const std::string url = lcm_url_for(remote);
  LcmChannel channel(url);
  if (!channel.good()) {
    err << "furuta " << command_name(kind) << ": cannot open LCM at " << url
        << " (check [daemon] lcm_url or --lcm-url)\n";
    return 2;
  }
  return run_remote_command(kind, channel, remote, start, out, err);
}

int run_remote_command(RemoteKind kind, DaemonChannel& channel, const RemoteOptions& remote,
                       const StartOptions& start, std::ostream& out, std::ostream& err) {
  const std::string name = std::string("furuta ") + command_name(kind);
  furuta::rig_command_t command{};
  command.request_id = new_request_id();
  const std::int64_t id = command.request_id;
  std::optional<command_auth::CommandKey> key;
  switch (kind) {
    case RemoteKind::start: {
      const config::RigConfig rig = config::load_rig_config(remote.config_path);
      command.kind = furuta::rig_command_t::KIND_START_SESSION;
      if (!fill_start_command(start, rig.excitation, command, name, err) ||
          !session_values_usable(name, command, rig, remote.config_path, err)) {
        return kExitNotDone;
      }
      const std::filesystem::path key_path =
          remote.command_key.empty() ? std::filesystem::path(rig.daemon.command_key_file)
                                     : remote.command_key;
      command_auth::KeyFile key_file = command_auth::read_command_key(key_path);
      if (!key_file.key) {
        err << name << ": " << (key_file.permission_denied ? "not in group furuta: " : "")
            << "cannot start sessions; stop/estop/status still work (" << key_file.problem << ")\n";
        return kExitNotPermitted;
      }
      key = key_file.key;
      break;
    }
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
  AnswerCheck check(daemon_public_key(remote, name, err));
  // A start is sent once (its signature is taken once); the others again until answered, an
  // e-stop most often, so one lost in a flood is soon followed by the next.
  const std::chrono::milliseconds resend = kind == RemoteKind::start ? std::chrono::hours(1)
                                           : kind == RemoteKind::estop
                                               ? std::chrono::milliseconds(20)
                                               : std::chrono::milliseconds(250);
  std::optional<furuta::rig_status_t> reply;
  const auto deadline = std::chrono::steady_clock::now() + millis(remote.reply_timeout_s);
  auto next_send = std::chrono::steady_clock::now();
  while (!reply && std::chrono::steady_clock::now() < deadline) {
    if (std::chrono::steady_clock::now() >= next_send) {
      if (key) {
        channel.send_signed(
            command_auth::sign_command_now(command, *key, command_auth::this_sender()));
      } else {
        channel.send(command);
      }
      next_send = std::chrono::steady_clock::now() + resend;
    }
    const auto wait = std::min(std::chrono::duration_cast<std::chrono::milliseconds>(
                                   next_send - std::chrono::steady_clock::now()),
                               std::chrono::milliseconds(50));
    auto s = channel.receive(std::max(wait, std::chrono::milliseconds(1)));
    if (s && s->reply_to_request_id == id && check.trusted(*s)) reply = std::move(s);
  }
  // Whatever follows, forged answers ignored on the way are said at the end.
  struct SayIgnored {
    const AnswerCheck& check;
    const std::string& name;
    std::ostream& err;
    ~SayIgnored() { check.warn_if_ignored(name, err); }
  };
  if (!reply) {
    err << name << ": no answer from furutad on " << channel.where() << " within "
        << remote.reply_timeout_s
        << " s (is it running? `systemctl status furutad`; a furutad of another version does not "
           "understand this furuta)"
        << check.ignored() << "\n";
    return 2;
  }
  const SayIgnored say_ignored{check, name, err};
  if (!reply->request_accepted) {
    err << name << ": refused: " << reply->request_reason << "\n";
    print_status(*reply, out);
    return 1;
  }
  if (kind == RemoteKind::status) {
    print_status(*reply, out);
    return 0;
  }

  if (kind == RemoteKind::start) {
    if (!remote.wait) {
      out << name << ": accepted (request " << id
          << "); not waiting for it to run: `furuta status` shows whether it does\n";
      print_status(*reply, out);
      return 0;
    }
    // The reply says the command was valid and queued; the loop decides (the pendulum must hang
    // still first) and the status names the request either way.
    const auto verdict = poll_status(channel, check, millis(remote.wait_s), [&](const auto& s) {
      return s.last_session_request_id == id || s.refused_request_id == id;
    });
    if (!verdict) {
      err << name << ": accepted (request " << id << "), but within " << remote.wait_s
          << " s the session neither ran nor was refused; `furuta status` shows what the daemon "
             "does\n";
      return 2;
    }
    if (verdict->refused_request_id == id) {
      err << name << ": refused: " << verdict->refused_reason << "\n";
      print_status(*verdict, out);
      return 1;
    }
    if (verdict->last_session_end.empty()) {
      out << name << ": session " << verdict->last_session << " running\n";
      print_status(*verdict, out);
      return 0;
    }
    const bool as_asked = ended_as_asked(verdict->last_session_end);
    (as_asked ? out : err) << name << ": session " << verdict->last_session
                           << " ran and has already ended: " << verdict->last_session_end << "\n";
    print_status(*verdict, out);
    return as_asked ? 0 : 1;
  }

  // stop, estop: the reply's state is from before the loop acted on it. Its session name may lag
  // the loop's state by a moment (the I/O thread names it): then the session is the first one
  // after the reply's last_session.
  const char* done =
      kind == RemoteKind::estop ? "e-stop: motor commanded to zero, braked" : "stop requested";
  if (reply->state != furuta::rig_status_t::STATE_RUNNING) {
    out << name << ": " << done << "; no session was running"
        << (kind == RemoteKind::stop ? ": nothing to stop" : "") << "\n";
    print_status(*reply, out);
    return 0;
  }
  const std::string session = reply->session;
  const std::string before = reply->last_session;
  const std::string which = session.empty() ? "the running session" : "session " + session;
  if (!remote.wait) {
    out << name << ": " << done << "; not waiting for " << which << " to end\n";
    return 0;
  }
  const auto ended = poll_status(channel, check, millis(remote.wait_s), [&](const auto& s) {
    if (s.last_session_end.empty()) return false;
    return session.empty() ? !s.last_session.empty() && s.last_session != before
                           : s.last_session == session;
  });
  if (!ended) {
    err << name << ": " << done << ", but " << which << " still ran after " << remote.wait_s
        << " s; `furuta status` (and `furuta estop`)\n";
    return 2;
  }
  out << name << ": " << done << "; session " << ended->last_session
      << " ended: " << ended->last_session_end << "\n";
  print_status(*ended, out);
  return 0;
}

int run_session_command(const RunOptions& options, std::ostream& out, std::ostream& err) {
  const config::RigConfig rig = config::load_rig_config(options.config_path);
  // Made once, before anything runs: the controller file is read here, not again.
  furuta::rig_command_t command{};
  command.kind = furuta::rig_command_t::KIND_START_SESSION;
  if (!fill_start_command(options.session, rig.excitation, command, "furuta run", err) ||
      !session_values_usable("furuta run", command, rig, options.config_path, err)) {
    return kExitNotDone;
  }
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
  // Before anything moves: which rig, and why that one (a configuration left at its default
  // backend drives the simulated rig, which must not pass for the real one).
  out << "furuta run: configuration " << options.config_path.string() << "\n";
  out << "furuta run: rig: " << describe_rig(rig, options, rig_io) << "\n";
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
  if (log && options.session.balance) {
    if (const auto balance = pipeline::summarize_balance(session_log::load_session_log(*log))) {
      out << balance_text(*balance);
    }
  }
  if (!log) {
    err << "furuta run: no log was written"
        << (daemon.recorder().last_fault().empty() ? "" : ": " + daemon.recorder().last_fault())
        << "\n";
    return 1;
  }
  // A fall is a balance session's outcome, not a fault of the rig; it is still not done.
  return daemon::is_fault(stop) || stop == daemon::StopReason::pendulum_fell ? 1 : 0;
}

}  // namespace furuta::app
