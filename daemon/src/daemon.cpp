#include "furuta/daemon/daemon.hpp"

#include <algorithm>
#include <cctype>
#include <ctime>
#include <future>
#include <optional>
#include <thread>

#include "furuta/common/wire_text.hpp"
#include "furuta/config/controller_file.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::daemon {

namespace {

// The longest the publisher/logger sleeps without an event: the bound on how late a due status or
// log sync may be (the loop's events wake it at once).
constexpr std::chrono::milliseconds kIoIdleWait{20};
// How long before the next sample is due the publisher stops sleeping and watches the queue, and
// how long after it watches before it sleeps again: a thread woken from an idle CPU starts late
// (on a VM by far more than the loop's own cycle), and a sample should reach its subscribers as
// soon as the loop made it. Watching costs this share of a CPU per period.
constexpr std::chrono::microseconds kWatchBeforeSample{400};
constexpr std::chrono::microseconds kWatchAfterSample{600};

void copy_to(std::array<char, kNameChars>& to, const std::string& from) {
  copy_text(to, from.c_str());
}

}  // namespace

std::string session_name(std::int64_t wall_time_ns, const std::string& label) {
  const std::time_t seconds = static_cast<std::time_t>(wall_time_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H-%M-%SZ", &utc);
  std::string name = stamp;
  std::string safe;
  for (char c : label) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
    safe += ok ? c : '_';
  }
  while (!safe.empty() && safe.front() == '.') safe.erase(safe.begin());
  if (!safe.empty()) name += "_" + safe.substr(0, 48);
  return name;
}

std::string unique_session_name(const std::string& name, const std::filesystem::path& logs_dir) {
  namespace fs = std::filesystem;
  const auto taken = [&](const std::string& candidate) {
    // .partial: a session being written now, in this process or another.
    for (const fs::path& dir :
         {logs_dir, logs_dir / "done", logs_dir / "failed", logs_dir / ".partial"}) {
      std::error_code ec;
      for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string leaf = it->path().filename().string();
        if (leaf.size() > candidate.size() && leaf.compare(0, candidate.size(), candidate) == 0 &&
            leaf[candidate.size()] == '.') {
          return true;
        }
      }
    }
    return false;
  };
  std::string candidate = name;
  for (int n = 2; taken(candidate); ++n) candidate = name + "-" + std::to_string(n);
  return candidate;
}

Daemon::Daemon(DaemonSettings settings, BoardLink& motor, BoardLink& encoder, bridge::Clock& clock,
               lcm::LCM& lcm)
    : settings_(std::move(settings)),
      lcm_(lcm),
      events_(settings_.queue_capacity),
      validator_(settings_.command_limits),
      verifier_(settings_.command_key, settings_.command_key_problem, settings_.command_auth,
                wall_now_ns(), monotonic_now_ns()) {
  if (settings_.daemon_key) signer_.emplace(*settings_.daemon_key);
  loop_ = std::make_unique<ControlLoop>(settings_.loop, motor, encoder, clock, events_);
  recorder_ = std::make_unique<SessionRecorder>(
      settings_.recorder, &lcm_,
      [this](const std::string&) { loop_->request_stop(StopReason::log_error); });
  recorder_->on_session_logged([this](const std::filesystem::path& path) {
    sessions_logged_.fetch_add(1);
    if (on_logged_) on_logged_(path);
  });
  if (const std::optional<UdpmAddress> group = parse_udpm_url(settings_.command_url)) {
    intake_ = std::make_unique<MulticastReceiver>(*group, settings_.command_socket_buffer_bytes);
    return;
  }
  subscription_ = lcm_.subscribe(session_log::kChannelCommand, &Daemon::on_command, this);
  signed_subscription_ =
      lcm_.subscribe(session_log::kChannelSignedCommand, &Daemon::on_signed_command, this);
  // A flood must not pile up in LCM's queue behind the e-stop that ends it: the kernel's socket
  // buffer holds what waits.
  subscription_->setQueueCapacity(64);
  signed_subscription_->setQueueCapacity(64);
}

std::int64_t Daemon::monotonic_now_ns() const {
  if (settings_.monotonic_clock_ns) return settings_.monotonic_clock_ns();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::int64_t Daemon::wall_now_ns() const {
  if (settings_.wall_clock_ns) return settings_.wall_clock_ns();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Daemon::~Daemon() {
  stop(StopReason::signal);
  try {
    wait();
  } catch (...) {
    // The loop already wrote the zero command; a destructor cannot report more.
  }
  if (subscription_) lcm_.unsubscribe(subscription_);
  if (signed_subscription_) lcm_.unsubscribe(signed_subscription_);
}

void Daemon::on_session_logged(std::function<void(const std::filesystem::path&)> callback) {
  on_logged_ = std::move(callback);
}

std::string Daemon::logs_problem() const {
  std::lock_guard lock(snapshot_mutex_);
  return snapshot_.logs_problem;
}

RealtimeResult Daemon::start() {
  check_logs_dir();  // before the first command can ask
  io_thread_ = std::thread([this] { io_thread_main(); });
  lcm_thread_ = std::thread([this] { lcm_thread_main(); });
  std::promise<RealtimeResult> rt_result;
  auto rt_future = rt_result.get_future();
  loop_thread_ = std::thread([this, &rt_result] {
    rt_result.set_value(apply_realtime_to_this_thread(settings_.realtime));
    try {
      loop_->run();
    } catch (...) {
      loop_error_ = std::current_exception();
    }
  });
  RealtimeResult result = rt_future.get();
  if (settings_.realtime.enabled && settings_.realtime.lock_memory) {
    // Every thread exists now, so their stacks are locked too.
    if (std::string why = lock_process_memory(); !why.empty()) {
      result.refused.push_back("mlockall: " + why);
    }
  }
  return result;
}

void Daemon::stop(StopReason reason) {
  loop_->request_stop(reason);
  loop_->request_exit();
}

void Daemon::wait() {
  if (loop_thread_.joinable()) loop_thread_.join();
  io_stop_.store(true);
  events_.notify();
  if (io_thread_.joinable()) io_thread_.join();
  lcm_stop_.store(true);
  if (lcm_thread_.joinable()) lcm_thread_.join();
  if (loop_error_) std::rethrow_exception(std::exchange(loop_error_, nullptr));
}

void Daemon::refresh_snapshot() {
  const LatencyHistogram& h = recorder_->session_wake_latency();
  std::lock_guard lock(snapshot_mutex_);
  snapshot_.session = recorder_->current_session();
  snapshot_.last_fault = recorder_->last_fault();
  snapshot_.history = recorder_->history();
  snapshot_.latency_samples = static_cast<std::int64_t>(h.count());
  snapshot_.jitter_mean_us = h.mean_us();
  snapshot_.jitter_p99_us = h.quantile_us(0.99);
  snapshot_.jitter_max_us = h.max_us();
}

furuta::rig_status_t Daemon::status_message() {
  furuta::rig_status_t m{};
  m.monotonic_ns = loop_->counters().clock_ns.load();
  const LoopCounters& c = loop_->counters();
  switch (c.state.load()) {
    case LoopState::running:
      m.state = furuta::rig_status_t::STATE_RUNNING;
      break;
    case LoopState::fault:
      m.state = furuta::rig_status_t::STATE_FAULT;
      break;
    default:
      m.state = furuta::rig_status_t::STATE_IDLE;
      break;
  }
  m.cycles = c.cycles.load();
  m.overruns = c.overruns.load();
  m.motor_lost_reports = c.motor_lost_reports.load();
  m.encoder_lost_reports = c.encoder_lost_reports.load();
  std::lock_guard lock(snapshot_mutex_);
  m.session = snapshot_.session;
  m.last_fault = snapshot_.last_fault;
  m.jitter_mean_us = snapshot_.jitter_mean_us;
  m.jitter_p99_us = snapshot_.jitter_p99_us;
  m.jitter_max_us = snapshot_.jitter_max_us;
  m.latency_samples = snapshot_.latency_samples;
  const SessionRecorder::History& h = snapshot_.history;
  m.last_fault_wall_ns = m.last_fault.empty() ? 0 : h.last_fault_wall_ns;
  m.last_fault_session = h.last_fault_session;
  m.sessions_since_fault = h.sessions_since_fault;
  m.last_session = h.last_session;
  m.last_session_request_id = h.last_session_request_id;
  m.last_session_end = h.last_session_end;
  m.refused_request_id = h.refused_request_id;
  m.refused_reason = h.refused_reason;
  m.logs_problem = snapshot_.logs_problem;
  m.unauthenticated_reason = unauthenticated_reason_;
  const RefusalCounts& r = refusals_;
  m.refused_unsigned = r.unsigned_motor_commands.load();
  m.refused_bad_signature = r.bad_signature.load();
  m.refused_malformed = r.malformed.load();
  m.refused_out_of_time = r.out_of_time.load();
  m.refused_replayed = r.replayed.load();
  m.refused_unauthenticated = m.refused_unsigned + m.refused_bad_signature + m.refused_malformed +
                              m.refused_out_of_time + m.refused_replayed;
  m.refused_start_budget = r.start_budget.load();
  m.refused_stop_budget = r.stop_budget.load();
  m.refused_status_budget = r.status_budget.load();
  m.refused_invalid = r.invalid.load();
  m.replies_withheld = r.replies_withheld.load();
  return m;
}

void Daemon::check_logs_dir() {
  if (settings_.recorder.logs_dir.empty()) return;  // a daemon without logs (tests)
  std::string problem = session_log::logs_dir_problem(settings_.recorder.logs_dir,
                                                      settings_.recorder.min_free_bytes_to_start);
  std::lock_guard lock(snapshot_mutex_);
  snapshot_.logs_problem = std::move(problem);
}

void Daemon::io_thread_main() {
  if (settings_.realtime.enabled) keep_off_cpu(settings_.realtime.cpu);
  LoopEvent event;
  auto next_status = std::chrono::steady_clock::now();
  auto publish_status = [&] {
    check_logs_dir();
    refresh_snapshot();
    publish(status_message());
  };
  // When the next sample is due, on this thread's clock.
  const auto period = std::chrono::nanoseconds(settings_.loop.period_ns);
  std::optional<std::chrono::steady_clock::time_point> next_sample;
  for (;;) {
    bool any = false;
    while (events_.pop(event)) {
      if (event.kind == LoopEvent::Kind::sample) {
        // The loop's samples keep its period: one seen later than due (this thread was late) was
        // still due then, and the next is a period after that; one seen early, or far off the
        // schedule (a new session), sets it.
        const auto seen = std::chrono::steady_clock::now();
        const bool on_schedule =
            next_sample && seen > *next_sample && seen - *next_sample < period / 2;
        next_sample = (on_schedule ? *next_sample : seen) + period;
      }
      recorder_->handle(event);
      any = true;
      // A status reply names the session and the last fault from the snapshot: bring it up to date
      // as they change, not only once a second.
      if (event.kind != LoopEvent::Kind::sample) refresh_snapshot();
    }
    const auto now = std::chrono::steady_clock::now();
    recorder_->sync_if_due(now);
    if (now >= next_status) {
      publish_status();
      next_status = now + settings_.status_interval;
    }
    // Ready once the loop cycles and a decodable report from each board has come in.
    if (!ready_.load() && loop_->counters().cycles.load() > 0 &&
        loop_->counters().motor_reports_seen.load() &&
        loop_->counters().encoder_reports_seen.load()) {
      ready_.store(true);
    }
    if (io_stop_.load() && events_.read_available() == 0) break;
    // Until the loop queues an event (it wakes this thread), or the next status or sync is due;
    // close to the next sample, watching the queue instead of sleeping.
    if (!any) wait_for_event(next_sample);
  }
  publish_status();
}

void Daemon::wait_for_event(std::optional<std::chrono::steady_clock::time_point> next_sample) {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::nanoseconds(settings_.loop.period_ns);
  // A bounded share of each period: at short periods the publisher is rarely asleep long anyway.
  const auto before = std::min<std::chrono::nanoseconds>(kWatchBeforeSample, period / 20);
  const auto after = std::min<std::chrono::nanoseconds>(kWatchAfterSample, period / 20);
  const auto now = Clock::now();
  if (!next_sample || now >= *next_sample + after) {
    events_.wait_for(kIoIdleWait);
  } else if (now < *next_sample - before) {
    events_.wait_for(std::min<std::chrono::nanoseconds>(kIoIdleWait, *next_sample - before - now));
  } else {
    while (events_.read_available() == 0 && !io_stop_.load() &&
           Clock::now() < *next_sample + after) {
      std::this_thread::yield();
    }
  }
}

void Daemon::lcm_thread_main() {
  if (settings_.realtime.enabled) keep_off_cpu(settings_.realtime.cpu);
  while (!lcm_stop_.load()) {
    if (intake_) {
      take_datagrams(intake_->receive(50));
    } else {
      lcm_.handleTimeout(50);
    }
  }
}

void Daemon::take_datagrams(std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    const std::optional<LcmDatagram> datagram = parse_lcm_datagram(intake_->datagram(i));
    if (!datagram) continue;  // not a one-datagram LCM message: no command is a fragment
    const bool command = datagram->channel == session_log::kChannelCommand;
    const bool signed_command = datagram->channel == session_log::kChannelSignedCommand;
    if (!command && !signed_command) continue;
    if (intake_->oversized(i)) {
      refusals_.malformed.fetch_add(1);
    } else if (command) {
      take_command(datagram->message);
    } else {
      take_signed_command(datagram->message);
    }
  }
}

namespace {

// Larger than any command or signed command the tools send (the verifier's limits are below it):
// anything bigger is not decoded at all.
constexpr std::size_t kMaxCommandMessageBytes = 2048;

constexpr char kUnsignedReason[] =
    "unsigned: a command that moves the motor must be signed with the rig's command key (furuta "
    "start signs it when it may read the key; docs/security.md)";

}  // namespace

void Daemon::on_command(const lcm::ReceiveBuffer* buffer, const std::string&) {
  take_command({static_cast<const std::uint8_t*>(buffer->data), buffer->data_size});
}

void Daemon::on_signed_command(const lcm::ReceiveBuffer* buffer, const std::string&) {
  take_signed_command({static_cast<const std::uint8_t*>(buffer->data), buffer->data_size});
}

void Daemon::take_command(std::span<const std::uint8_t> bytes) {
  furuta::rig_command_t command{};
  if (bytes.size() > kMaxCommandMessageBytes ||
      command.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
    refusals_.malformed.fetch_add(1);
    return;  // nothing to address a reply to
  }
  if (command_auth::moves_motor(command)) {
    note_unauthenticated(command_auth::Refusal::unsigned_command, kUnsignedReason);
    if (reply_allowed(false, false)) publish(refusal_reply(command.request_id, kUnsignedReason));
    return;
  }
  const CommandDecision decision = decide(command);
  if (reply_allowed(decision.accepted, command.kind == furuta::rig_command_t::KIND_ESTOP)) {
    publish(reply_for(command.request_id, decision));
  }
}

void Daemon::take_signed_command(std::span<const std::uint8_t> bytes) {
  furuta::rig_signed_command_t message{};
  if (bytes.size() > kMaxCommandMessageBytes ||
      message.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
    refusals_.malformed.fetch_add(1);
    return;
  }
  const command_auth::Verdict verdict = verify(message);
  if (!verdict.accepted) {
    note_unauthenticated(verdict.refusal, verdict.reason);
    if (reply_allowed(false, false)) {
      publish(refusal_reply(unverified_request_id(message), verdict.reason));
    }
    return;
  }
  const CommandDecision decision = take_signed(message, verdict.command);
  if (reply_allowed(decision.accepted, verdict.command.kind == furuta::rig_command_t::KIND_ESTOP)) {
    publish(reply_for(verdict.command.request_id, decision));
  }
}

void Daemon::publish(furuta::rig_status_t status) {
  command_auth::bound_status_text(status);
  if (signer_) signer_->sign(status);
  lcm_.publish(session_log::kChannelStatus, &status);
}

bool Daemon::reply_allowed(bool accepted, bool estop) {
  // The loop's time, as for the command budgets: exact in virtual time.
  const std::int64_t now = loop_->counters().clock_ns.load();
  const CommandLimits& limits = settings_.command_limits;
  const bool allowed =
      !accepted ? refusal_replies_.take(std::max(0, limits.max_refusal_replies_per_s), now)
      : estop   ? estop_replies_.take(std::max(0, limits.max_estop_replies_per_s), now)
                : true;
  if (!allowed) refusals_.replies_withheld.fetch_add(1);
  return allowed;
}

void Daemon::count(CommandRefusal refusal) {
  switch (refusal) {
    case CommandRefusal::none:
      break;
    case CommandRefusal::start_budget:
      refusals_.start_budget.fetch_add(1);
      break;
    case CommandRefusal::stop_budget:
      refusals_.stop_budget.fetch_add(1);
      break;
    case CommandRefusal::status_budget:
      refusals_.status_budget.fetch_add(1);
      break;
    case CommandRefusal::invalid:
      refusals_.invalid.fetch_add(1);
      break;
  }
}

void Daemon::note_unauthenticated(command_auth::Refusal refusal, const std::string& reason) {
  using command_auth::Refusal;
  switch (refusal) {
    case Refusal::bad_signature:
      refusals_.bad_signature.fetch_add(1);
      break;
    case Refusal::malformed:
      refusals_.malformed.fetch_add(1);
      break;
    case Refusal::out_of_time:
      refusals_.out_of_time.fetch_add(1);
      break;
    case Refusal::replayed:
      refusals_.replayed.fetch_add(1);
      break;
    case Refusal::unsigned_command:
      refusals_.unsigned_motor_commands.fetch_add(1);
      break;
    case Refusal::none:
    case Refusal::no_key:
    case Refusal::memory_full:
    case Refusal::not_recorded:
      refusals_.invalid.fetch_add(1);  // a start this daemon cannot take now
      break;
  }
  std::lock_guard lock(snapshot_mutex_);
  unauthenticated_reason_ = text::printable_text(reason, 512);
}

furuta::rig_status_t Daemon::refusal_reply(std::int64_t request_id, const std::string& reason) {
  return reply_for(request_id, CommandDecision{false, reason});
}

furuta::rig_status_t Daemon::reply_for(std::int64_t request_id, const CommandDecision& decision) {
  furuta::rig_status_t reply = status_message();
  reply.reply_to_request_id = request_id;
  reply.request_accepted = decision.accepted;
  reply.request_reason = decision.reason;
  return reply;
}

std::int64_t Daemon::unverified_request_id(const furuta::rig_signed_command_t& message) {
  // The request id only addresses the reply; nothing else of an unverified command is used.
  furuta::rig_command_t unverified{};
  const bool decodable =
      !message.command.empty() &&
      unverified.decode(message.command.data(), 0, static_cast<int>(message.command.size())) > 0;
  return decodable ? unverified.request_id : 0;
}

command_auth::Verdict Daemon::verify(const furuta::rig_signed_command_t& message) {
  std::lock_guard lock(command_mutex_);
  return verifier_.verify(message, wall_now_ns(), monotonic_now_ns());
}

CommandDecision Daemon::take_signed(const furuta::rig_signed_command_t& message,
                                    const furuta::rig_command_t& command) {
  if (command.kind == furuta::rig_command_t::KIND_START_SESSION) {
    std::vector<std::uint8_t> encoded(static_cast<std::size_t>(message.getEncodedSize()));
    message.encode(encoded.data(), 0, static_cast<int>(encoded.size()));
    recorder_->note_signed_start(command.request_id, std::move(encoded));
  }
  return decide(command);
}

furuta::rig_status_t Daemon::handle_unsigned_command(const furuta::rig_command_t& command) {
  if (command_auth::moves_motor(command)) {
    note_unauthenticated(command_auth::Refusal::unsigned_command, kUnsignedReason);
    return refusal_reply(command.request_id, kUnsignedReason);
  }
  return handle_command(command);
}

furuta::rig_status_t Daemon::handle_signed_command(const furuta::rig_signed_command_t& message) {
  const command_auth::Verdict verdict = verify(message);
  if (!verdict.accepted) {
    note_unauthenticated(verdict.refusal, verdict.reason);
    return refusal_reply(unverified_request_id(message), verdict.reason);
  }
  return reply_for(verdict.command.request_id, take_signed(message, verdict.command));
}

bool Daemon::start_replayed_session(const furuta::rig_session_t& start,
                                    const furuta::rig_controller_t* controller) {
  ExcitationSpec spec = settings_.default_excitation;
  spec.kind = parse_profile_kind(start.profile).value_or(spec.kind);
  spec.amplitude_duty = start.amplitude_duty;
  spec.duration_s = start.duration_s;
  spec.seed = static_cast<std::uint64_t>(start.seed);
  SessionRequest request;
  if (start.profile == kBalanceProfile) {
    // The law the session ran, from the log's own record of its controller file.
    if (!controller) return false;
    try {
      const config::ControllerFile file =
          config::parse_controller_file(controller->controller_toml, controller->path);
      request.balance_law = control::BalanceLaw(file.spec);
    } catch (const std::exception&) {
      return false;
    }
    request.balance = true;
    spec.kind = ProfileKind::free_decay;
    recorder_->note_controller(0,
                               {controller->path, controller->sha256, controller->controller_toml});
  }
  request.excitation = Excitation(spec);
  copy_to(request.session, start.session + "_replay");
  copy_to(request.label, start.label);
  request.has_arm_zero = true;
  request.arm_zero_counts = start.arm_zero_counts;
  std::lock_guard lock(command_mutex_);  // the request queue has a single producer at a time
  return loop_->request_session(request);
}

std::string Daemon::prepare_balance(const furuta::rig_command_t& command, ExcitationSpec& spec,
                                    SessionRequest& request) {
  // Everything is checked before anything moves: a file that does not read, is not the one
  // signed, or was designed for another rig or period is refused with the motor at rest.
  config::ControllerFile file;
  try {
    file = config::load_controller_file(command.controller_path);
  } catch (const std::exception& e) {
    return std::string("controller: ") + e.what();
  }
  if (file.sha256 != command.controller_sha256) {
    return "controller: " + command.controller_path + " has SHA-256 " + file.sha256 + ", not the " +
           command.controller_sha256 + " the command was signed with";
  }
  if (file.rig != settings_.rig_name) {
    return "controller: " + command.controller_path + " was designed for rig '" + file.rig +
           "', this is '" + settings_.rig_name + "'";
  }
  if (file.period_ns != settings_.loop.period_ns) {
    return "controller: " + command.controller_path + " was designed for a period of " +
           std::to_string(file.period_ns) + " ns, the loop's is " +
           std::to_string(settings_.loop.period_ns) + " ns";
  }
  if (!(file.spec.max_duty <= settings_.loop.safety.max_duty)) {
    return "controller: " + command.controller_path + " may ask for a duty of " +
           std::to_string(file.spec.max_duty) + ", above the safety limit " +
           std::to_string(settings_.loop.safety.max_duty);
  }
  try {
    request.balance_law = control::BalanceLaw(file.spec);
  } catch (const std::exception& e) {
    return "controller: " + command.controller_path + ": " + e.what();
  }
  request.balance = true;
  // The session's amplitude is the law's limit, checked against the command limits next.
  spec.amplitude_duty = file.spec.max_duty;
  recorder_->note_controller(command.request_id,
                             {command.controller_path, file.sha256, std::move(file.text)});
  return {};
}

furuta::rig_status_t Daemon::handle_command(const furuta::rig_command_t& command) {
  return reply_for(command.request_id, decide(command));
}

CommandDecision Daemon::decide(const furuta::rig_command_t& command) {
  CommandDecision decision;
  {
    // Held until the request is queued too: the loop's request queue is single-producer, and
    // commands come from the LCM thread and from callers of handle_command alike.
    std::lock_guard lock(command_mutex_);
    // The loop's time, not the clock's: this runs on the LCM thread. Rate limiting on the time
    // of the loop's last wake-up is at most a period behind, and exact in virtual time.
    decision = validator_.validate(command, loop_->counters().clock_ns.load());
    if (decision.accepted) decision = carry_out(command);
  }
  count(decision.refusal);
  return decision;
}

CommandDecision Daemon::carry_out(const furuta::rig_command_t& command) {
  CommandDecision decision{true, {}};
  switch (command.kind) {
    case furuta::rig_command_t::KIND_START_SESSION: {
      // Decided here when it can be, so the reply is the verdict; the loop still checks (a
      // session may begin between this and its turn) and refuses by the request's id.
      if (loop_->counters().state.load() == LoopState::running) {
        std::lock_guard lock(snapshot_mutex_);
        decision = {false,
                    "a session is already running" +
                        (snapshot_.session.empty() ? "" : ": " + snapshot_.session) +
                        " (furuta stop ends it)",
                    CommandRefusal::invalid};
        break;
      }
      SessionRequest request;
      request.request_id = command.request_id;
      try {
        ExcitationSpec spec = spec_from_command(command, settings_.default_excitation);
        if (command.profile == kBalanceProfile) {
          if (std::string why = prepare_balance(command, spec, request); !why.empty()) {
            decision = {false, why, CommandRefusal::invalid};
            break;
          }
        }
        if (std::string why = check_spec_limits(spec, settings_.command_limits); !why.empty()) {
          decision = {false, why, CommandRefusal::invalid};
          break;
        }
        request.excitation = Excitation(spec);
      } catch (const std::exception& e) {
        decision = {false, e.what(), CommandRefusal::invalid};
        break;
      }
      // Before the loop takes it: a session whose log cannot even be created would drive the
      // motor only to be stopped with log_error a few cycles later.
      if (!settings_.recorder.logs_dir.empty()) {
        if (std::string why = session_log::logs_dir_problem(
                settings_.recorder.logs_dir, settings_.recorder.min_free_bytes_to_start);
            !why.empty()) {
          decision = {false, "cannot log a session: " + why, CommandRefusal::invalid};
          break;
        }
      }
      const auto wall = std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count();
      copy_to(request.session,
              unique_session_name(session_name(wall, command.label), settings_.recorder.logs_dir));
      copy_to(request.label, command.label);
      if (!loop_->request_session(request)) {
        decision = {false, "a start request is already waiting", CommandRefusal::invalid};
      }
      break;
    }
    case furuta::rig_command_t::KIND_STOP:
      loop_->request_stop(StopReason::stop_command);
      break;
    case furuta::rig_command_t::KIND_ESTOP:
      loop_->request_stop(StopReason::estop_command);
      break;
    default:
      break;  // status request: the reply is the answer
  }
  return decision;
}

}  // namespace furuta::daemon
