// The `furuta` session and log subcommands, as a user runs them (simulated rig, virtual time).
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "daemon_channel.hpp"
#include "furuta/command_auth/command_auth.hpp"
#include "furuta/command_auth/status_signature.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/session_log.hpp"
#include "furuta/simulator/simulated_rig.hpp"
#include "stepped_clock.hpp"
#include "temp_dir.hpp"

namespace furuta::app {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

fs::path only_log_in(const fs::path& dir) {
  fs::path found;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".lcmlog") found = entry.path();
  }
  return found;
}

// A `furuta run --sim --virtual-time` of `duration_s` with the configuration at `config`.
RunOptions simulated_run(const fs::path& config, const fs::path& logs, double duration_s) {
  RunOptions options;
  options.config_path = config;
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = logs;
  options.lcm_url = "memq://";
  options.session.duration_s = duration_s;
  options.session.label = "cli";
  return options;
}

fs::path run_simulated_session(const fs::path& logs, double duration_s) {
  const RunOptions options = simulated_run(FURUTA_SOURCE_DIR "/config/rig.toml", logs, duration_s);
  std::ostringstream out, err;
  EXPECT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  EXPECT_NE(out.str().find("session ended: duration_reached"), std::string::npos) << out.str();
  return only_log_in(logs);
}

TEST(RunCommand, OptionsLeftOutComeFromTheConfigurationFieldByField) {
  // Giving only --amplitude and --seed must not fall back to the configuration for them (nor for
  // the duration to a built-in default).
  TempDir dir;
  RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = dir.path();
  options.lcm_url = "memq://";
  options.session.amplitude_duty = 0.125;
  options.session.seed = 7;
  options.session.duration_s = 1.0;
  std::ostringstream out, err;
  ASSERT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  const session_log::SessionLog log = session_log::load_session_log(only_log_in(dir.path()));
  ASSERT_TRUE(log.start.has_value());
  EXPECT_EQ(log.start->amplitude_duty, 0.125);
  EXPECT_EQ(log.start->seed, 7);
  EXPECT_EQ(log.start->duration_s, 1.0);
  EXPECT_EQ(log.start->profile, "bang_bang");  // the configuration's
}

TEST(RunCommand, ASimulatedSessionLeavesALogThatInfoExportAndReplayRead) {
  TempDir dir;
  const fs::path log = run_simulated_session(dir.path(), 4.0);
  ASSERT_FALSE(log.empty());

  std::ostringstream out, err;
  EXPECT_EQ(run_log_info_command(log, out, err), 0) << out.str();
  EXPECT_NE(out.str().find("samples   250"), std::string::npos) << out.str();  // 4 s / 16 ms
  EXPECT_NE(out.str().find("duration_reached"), std::string::npos);
  // The session ended with the zero, braking command written last.
  EXPECT_NE(out.str().find("motor     last command duty 0, braking 1\n"), std::string::npos)
      << out.str();

  const fs::path csv = dir.path() / "samples.csv";
  EXPECT_EQ(run_log_export_csv_command(log, csv, out, err), 0);
  std::ifstream in(csv);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, 251);  // header + samples

  std::ostringstream replay_out;
  EXPECT_EQ(run_replay_command(log, {}, replay_out, err), 0) << replay_out.str() << err.str();
  EXPECT_NE(replay_out.str().find("replayed 250 of 250 samples: identical"), std::string::npos)
      << replay_out.str();
}

TEST(RunCommand, InfoOnALogCutShortSaysSoAndFails) {
  TempDir dir;
  const fs::path log = run_simulated_session(dir.path(), 2.0);
  const fs::path cut = dir.path() / "cut.lcmlog";
  fs::copy_file(log, cut);
  // As if power failed mid-session: inside an event two thirds in (a cut at a plain byte count
  // could fall between two events, and there would be no torn tail to report).
  std::vector<std::uint64_t> offsets;
  {
    session_log::LcmLogReader reader(log);
    for (session_log::LogEvent e; reader.next(e);) offsets.push_back(e.file_offset);
  }
  ASSERT_GT(offsets.size(), 3u);
  fs::resize_file(cut, offsets[offsets.size() * 2 / 3] + 10);
  std::ostringstream out, err;
  EXPECT_EQ(run_log_info_command(cut, out, err), 1);
  EXPECT_NE(out.str().find("missing: the session was cut short"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("truncated tail"), std::string::npos) << out.str();
}

TEST(RemoteCommand, WithNoDaemonListeningItSaysSoAndReturns2) {
  RemoteOptions remote;
  remote.lcm_url = "memq://";  // nobody else is in this process's memq
  remote.reply_timeout_s = 0.2;
  std::ostringstream out, err;
  EXPECT_EQ(run_remote_command(RemoteKind::status, remote, {}, out, err), 2);
  EXPECT_NE(err.str().find("no answer from furutad"), std::string::npos) << err.str();
}

// A daemon of the simulated rig in this process, in stepped time, behind the channel `furuta
// start|stop|estop|status` use: each command sent moves the loop one cycle (so time moves only as
// the command polls), and every status the daemon publishes comes back through LCM (memq://).
class SteppedDaemon final : public DaemonChannel {
 public:
  SteppedDaemon() {
    sim_ = std::make_unique<sim::SimulatedRig>(config_.simulation, clock_);
    motor_usb_ = sim_->make_transport();
    encoder_usb_ = sim_->make_transport();
    EXPECT_EQ(motor_usb_->open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}}),
              bridge::TransportStatus::ok);
    EXPECT_EQ(encoder_usb_->open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}}),
              bridge::TransportStatus::ok);
    motor_ = std::make_unique<daemon::DirectBoardLink>(*motor_usb_);
    encoder_ = std::make_unique<daemon::DirectBoardLink>(*encoder_usb_);
    settings_ = daemon::daemon_settings_from_config(config_);
    settings_.recorder.motor_device = bridge::format_trace_device_line(motor_usb_->device_info());
    settings_.recorder.encoder_device =
        bridge::format_trace_device_line(encoder_usb_->device_info());
    settings_.recorder.logs_dir = logs_.path();
    settings_.loop.wait_when_queue_full = true;
    settings_.command_limits.max_commands_per_s = 1000;  // the polls are not under test
    EXPECT_EQ(command_auth::ensure_command_key(key_path(), "").problem, "");
    settings_.command_key = command_auth::read_command_key(key_path()).key;
    // The daemon signs its answers; `furuta` checks them with the public half.
    EXPECT_EQ(command_auth::ensure_command_key(key_dir_.path() / "daemon.key", "").problem, "");
    settings_.daemon_key = command_auth::read_command_key(key_dir_.path() / "daemon.key").key;
    EXPECT_EQ(command_auth::write_daemon_public_key(
                  public_key_path(), command_auth::daemon_public_key(*settings_.daemon_key)),
              "");
    subscription_ = lcm_.subscribe(session_log::kChannelStatus, &SteppedDaemon::on_status, this);
    daemon_ = std::make_unique<daemon::Daemon>(settings_, *motor_, *encoder_, clock_, lcm_);
    daemon_->start();
  }
  ~SteppedDaemon() override {
    clock_.run_free();
    daemon_.reset();
    lcm_.unsubscribe(subscription_);
  }

  // The loop's cycles, each on time (the pendulum hangs still: the rest check passes at 63).
  void step_cycles(int n) {
    const auto& cycles = daemon_->loop().counters().cycles;
    for (int i = 0; i < n; ++i) {
      const std::int64_t target = cycles.load() + 1;
      ASSERT_TRUE(clock_.wake_sleeper_on_time()) << "the loop stopped sleeping";
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (cycles.load() < target) {
        ASSERT_LT(std::chrono::steady_clock::now(), give_up) << "the loop stopped cycling";
        std::this_thread::yield();
      }
    }
  }
  void keep_time_still() { steps_per_command_ = 0; }

  void send(const furuta::rig_command_t& command) override {
    ++sent_[static_cast<std::uint8_t>(command.kind)];
    if (command.kind == lost_kind_ && to_lose_ > 0) {
      --to_lose_;
    } else {
      lcm_.publish(session_log::kChannelCommand, &command);
    }
    step_cycles(steps_per_command_);
  }
  void send_signed(const furuta::rig_signed_command_t& command) override {
    if (on_signed_) on_signed_(command);
    lcm_.publish(session_log::kChannelSignedCommand, &command);
    step_cycles(steps_per_command_);
  }
  // Called with each signed command before the daemon sees it (a forger watching the group).
  void watch_signed(std::function<void(const furuta::rig_signed_command_t&)> forger) {
    on_signed_ = std::move(forger);
  }
  // The key this daemon checks starts with (furuta start signs with it).
  fs::path key_path() const { return key_dir_.path() / "command.key"; }
  // The public half of the key this daemon signs its answers with.
  fs::path public_key_path() const { return key_dir_.path() / "daemon.pub"; }
  std::optional<furuta::rig_status_t> receive(std::chrono::milliseconds wait) override {
    std::unique_lock lock(mutex_);
    if (!arrived_.wait_for(lock, wait, [&] { return !statuses_.empty(); })) return std::nullopt;
    furuta::rig_status_t first = statuses_.front();
    statuses_.pop_front();
    return first;
  }
  // A status as if published by someone on the group, before what the daemon says next.
  void inject(const furuta::rig_status_t& status) {
    std::lock_guard lock(mutex_);
    statuses_.push_front(status);
  }
  // Commands of these kinds reach no daemon (lost in a flood) until `n` of them were sent.
  void lose_first(std::int8_t kind, int n) {
    lost_kind_ = kind;
    to_lose_ = n;
  }
  int sent(std::int8_t kind) const { return sent_[static_cast<std::uint8_t>(kind)]; }
  daemon::Daemon& daemon() { return *daemon_; }
  const daemon::DaemonSettings& settings() const { return settings_; }
  void publish_signed(const furuta::rig_signed_command_t& command) {
    lcm_.publish(session_log::kChannelSignedCommand, &command);
  }
  std::string where() const override { return "memq:// (a test daemon)"; }

 private:
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_status_t* m) {
    {
      std::lock_guard lock(mutex_);
      statuses_.push_back(*m);
    }
    arrived_.notify_all();
  }

  TempDir logs_{"furuta-remote"};
  TempDir key_dir_{"furuta-key"};
  config::RigConfig config_ = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  furuta::testing::SteppedClock clock_{1'000'000'000};
  std::unique_ptr<sim::SimulatedRig> sim_;
  std::unique_ptr<bridge::Transport> motor_usb_, encoder_usb_;
  std::unique_ptr<daemon::DirectBoardLink> motor_, encoder_;
  daemon::DaemonSettings settings_;
  lcm::LCM lcm_{"memq://"};
  lcm::Subscription* subscription_ = nullptr;
  std::unique_ptr<daemon::Daemon> daemon_;
  int steps_per_command_ = 1;
  std::int8_t lost_kind_ = -1;
  int to_lose_ = 0;
  std::array<int, 256> sent_{};
  std::function<void(const furuta::rig_signed_command_t&)> on_signed_;
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<furuta::rig_status_t> statuses_;
};

struct Said {
  int code = -1;
  std::string out, err;
  bool has(const std::string& part) const {
    return out.find(part) != std::string::npos || err.find(part) != std::string::npos;
  }
};

Said remote(SteppedDaemon& daemon, RemoteKind kind, StartOptions start = {},
            RemoteOptions options = {}) {
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  if (options.command_key.empty()) options.command_key = daemon.key_path();
  if (options.daemon_public_key.empty()) options.daemon_public_key = daemon.public_key_path();
  std::ostringstream out, err;
  Said said;
  said.code = run_remote_command(kind, daemon, options, start, out, err);
  said.out = out.str();
  said.err = err.str();
  return said;
}

StartOptions session_of(const std::string& profile, double duration_s, const std::string& label) {
  StartOptions start;
  start.profile = profile;
  start.amplitude_duty = 0.1;
  start.duration_s = duration_s;
  start.label = label;
  return start;
}

TEST(RemoteCommand, StartWaitsUntilTheSessionRunsAndStopUntilItHasEnded) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);  // past the one-second rest check
  const Said started = remote(daemon, RemoteKind::start, session_of("free_decay", 30, "first"));
  EXPECT_EQ(started.code, 0) << started.out << started.err;
  EXPECT_TRUE(started.has("furuta start: session ")) << started.out;
  EXPECT_TRUE(started.has("_first running")) << started.out;
  EXPECT_TRUE(started.has("state running, session ")) << started.out;

  // Another start while it runs: refused, exit 1, saying which session runs.
  const Said second = remote(daemon, RemoteKind::start, session_of("free_decay", 30, "second"));
  EXPECT_EQ(second.code, 1) << second.out << second.err;
  EXPECT_TRUE(second.has("furuta start: refused: a session is already running: ")) << second.err;
  EXPECT_TRUE(second.has("_first")) << second.err;

  // stop prints the state after it took effect, not before.
  const Said stopped = remote(daemon, RemoteKind::stop);
  EXPECT_EQ(stopped.code, 0) << stopped.out << stopped.err;
  EXPECT_TRUE(stopped.has("furuta stop: stop requested; session ")) << stopped.out;
  EXPECT_TRUE(stopped.has("_first ended: stop_command")) << stopped.out;
  EXPECT_TRUE(stopped.has("\nstate idle;")) << stopped.out;

  // Nothing to stop: said, and no failure.
  const Said again = remote(daemon, RemoteKind::stop);
  EXPECT_EQ(again.code, 0) << again.out << again.err;
  EXPECT_TRUE(again.has("no session was running: nothing to stop")) << again.out;
}

// A start the configuration can never accept is bad usage (2), said with the field and the
// configuration's limit, and never sent: before, NaN went to the daemon and came back refused (1).
TEST(RemoteCommand, AStartOutsideTheConfigurationsLimitsIsBadUsageAndNotSent) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);
  for (const double amplitude : {0.9, std::numeric_limits<double>::quiet_NaN(), -0.2}) {
    StartOptions start = session_of("free_decay", 30, "too-much");
    start.amplitude_duty = amplitude;
    const Said said = remote(daemon, RemoteKind::start, start);
    EXPECT_EQ(said.code, 2) << said.out << said.err;
    EXPECT_TRUE(said.has("furuta start: amplitude_duty: ")) << said.err;
    EXPECT_TRUE(said.has("[limits] max_amplitude_duty")) << said.err;
  }
  EXPECT_EQ(daemon.sent(furuta::rig_command_t::KIND_START_SESSION), 0);
  StartOptions long_one = session_of("free_decay", 1e6, "too-long");
  const Said said = remote(daemon, RemoteKind::start, long_one);
  EXPECT_EQ(said.code, 2) << said.out << said.err;
  EXPECT_TRUE(said.has("duration_s: 1e+06 above the limit 600")) << said.err;
}

// The loop refuses a start the command thread accepted (the pendulum has not hung still for the
// rest check yet): `furuta start` waits for that verdict and exits 1 with it.
TEST(RemoteCommand, AStartTheLoopRefusesExits1WithTheReason) {
  SteppedDaemon daemon;
  daemon.step_cycles(20);
  const Said said = remote(daemon, RemoteKind::start, session_of("bang_bang", 30, "early"));
  EXPECT_EQ(said.code, 1) << said.out << said.err;
  EXPECT_TRUE(said.has("furuta start: refused: the pendulum is not at rest")) << said.err;
  EXPECT_TRUE(said.has("state idle")) << said.out;
}

// Accepted, then no verdict within --wait (here the loop is held still): exit 2, and says so.
// --no-wait returns at the acceptance.
TEST(RemoteCommand, AStartWithNoVerdictInTimeExits2AndNoWaitReturnsAtTheAcceptance) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);
  daemon.keep_time_still();
  RemoteOptions quick;
  quick.wait_s = 0.3;
  const Said waited = remote(daemon, RemoteKind::start, session_of("bang_bang", 30, "held"), quick);
  EXPECT_EQ(waited.code, 2) << waited.out << waited.err;
  EXPECT_TRUE(waited.has("the session neither ran nor was refused")) << waited.err;

  RemoteOptions no_wait;
  no_wait.wait = false;
  SteppedDaemon other;
  other.step_cycles(70);
  const Said said =
      remote(other, RemoteKind::start, session_of("bang_bang", 30, "nowait"), no_wait);
  EXPECT_EQ(said.code, 0) << said.out << said.err;
  EXPECT_TRUE(said.has("furuta start: accepted (request ")) << said.out;
  EXPECT_TRUE(said.has("not waiting for it to run")) << said.out;
}

// The refusal a forger on the group sends first, unsigned or signed with a key of its own,
// answering a genuine signed start: ignored, and the daemon's own answer is the one believed.
TEST(RemoteCommand, AForgedAnswerIsIgnoredAndTheDaemonsOwnBelieved) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);
  const command_auth::StatusSigner forger_key(command_auth::CommandKey{7, 7, 7});
  int forged = 0;
  daemon.watch_signed([&](const furuta::rig_signed_command_t& m) {
    furuta::rig_command_t command{};
    ASSERT_GT(command.decode(m.command.data(), 0, static_cast<int>(m.command.size())), 0);
    furuta::rig_status_t lie{};
    lie.reply_to_request_id = command.request_id;
    lie.request_accepted = false;
    lie.request_reason = "the command key was revoked; no session started";
    daemon.inject(lie);  // unsigned
    forger_key.sign(lie);
    daemon.inject(lie);  // signed, but not by the daemon
    forged += 2;
  });
  const Said started = remote(daemon, RemoteKind::start, session_of("free_decay", 30, "real"));
  EXPECT_EQ(forged, 2);
  EXPECT_EQ(started.code, 0) << started.out << started.err;
  EXPECT_FALSE(started.has("revoked")) << started.out << started.err;
  // Believed only the daemon, and said that someone answered in its name.
  EXPECT_TRUE(
      started.has("furuta start: WARNING: 1 unsigned and 1 wrongly signed answer(s) were "
                  "ignored"))
      << started.err;
  EXPECT_TRUE(started.has("_real running")) << started.out;
  EXPECT_EQ(daemon.daemon().loop().counters().state.load(), daemon::LoopState::running);
}

// Nothing but forged answers: no answer is believed, and the tool says what it ignored.
TEST(RemoteCommand, OnlyForgedAnswersAreNoAnswerAndSaySo) {
  SteppedDaemon daemon;
  RemoteOptions options;
  options.reply_timeout_s = 1.0;
  // Checked against a key the daemon does not have: every answer is "wrongly signed".
  TempDir other;
  ASSERT_EQ(
      command_auth::write_daemon_public_key(
          other.path() / "other.pub", command_auth::daemon_public_key(command_auth::CommandKey{9})),
      "");
  options.daemon_public_key = other.path() / "other.pub";
  const Said said = remote(daemon, RemoteKind::status, {}, options);
  EXPECT_EQ(said.code, 2) << said.out << said.err;
  EXPECT_TRUE(said.has("no answer from furutad")) << said.err;
  EXPECT_TRUE(said.has("wrongly signed answer(s) were ignored")) << said.err;
  EXPECT_TRUE(said.has("forging the daemon's answers")) << said.err;

  // Without a readable public key the answers are taken, and the tool says they are unverified.
  RemoteOptions unverified;
  unverified.daemon_public_key = other.path() / "none.pub";
  const Said taken = remote(daemon, RemoteKind::status, {}, unverified);
  EXPECT_EQ(taken.code, 0) << taken.out << taken.err;
  EXPECT_TRUE(taken.has("WARNING: the daemon's answers are taken unverified")) << taken.err;
  EXPECT_TRUE(taken.has("state idle")) << taken.out;
}

// What a stranger's sender did to the status reaches the terminal escaped, never raw.
TEST(RemoteCommand, StatusPrintsAStrangersTextEscaped) {
  SteppedDaemon daemon;
  furuta::rig_command_t start{};
  start.request_id = 55;
  start.kind = furuta::rig_command_t::KIND_START_SESSION;
  daemon.publish_signed(command_auth::sign_command(start, command_auth::CommandKey{1},
                                                   "\x1b]0;pwned\a\x1b[2J", 0, 1));
  const Said said = remote(daemon, RemoteKind::status);
  EXPECT_EQ(said.code, 0) << said.err;
  EXPECT_TRUE(said.has("1 bad signature")) << said.out;
  EXPECT_TRUE(said.has("\\x1b]0;pwned\\x07")) << said.out;
  EXPECT_EQ(said.out.find('\x1b'), std::string::npos) << said.out;
  EXPECT_EQ(said.out.find('\a'), std::string::npos) << said.out;
}

// An e-stop lost on the way (a flood, a full socket buffer) is sent again until answered.
TEST(RemoteCommand, AnEstopIsSentAgainUntilAnswered) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);
  ASSERT_EQ(remote(daemon, RemoteKind::start, session_of("free_decay", 30, "lost")).code, 0);
  daemon.lose_first(furuta::rig_command_t::KIND_ESTOP, 3);
  const Said halted = remote(daemon, RemoteKind::estop);
  EXPECT_EQ(halted.code, 0) << halted.out << halted.err;
  EXPECT_TRUE(halted.has("_lost ended: estop_command")) << halted.out;
  EXPECT_GE(daemon.sent(furuta::rig_command_t::KIND_ESTOP), 4);
}

// A balance start is signed like any other and carries the controller file's SHA-256: the daemon
// reads the file and runs it only while its bytes are the ones signed. Stop and e-stop during the
// balance end it with the zero written last, as for every session.
TEST(RemoteCommand, ABalanceStartCarriesTheControllersHashAndStopsLikeAnyOther) {
  TempDir dir("furuta-remote-balance");
  ControllerDesignOptions design;
  design.results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
  design.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  design.output = dir.path() / "controller.toml";
  std::ostringstream design_out, design_err;
  ASSERT_EQ(run_controller_design_command(design, design_out, design_err), 0) << design_err.str();
  StartOptions start;
  start.balance = design.output;
  start.duration_s = 60;
  start.label = "upright";

  for (const RemoteKind how : {RemoteKind::stop, RemoteKind::estop}) {
    SteppedDaemon daemon;
    daemon.step_cycles(70);  // past the rest check
    const Said started = remote(daemon, RemoteKind::start, start);
    ASSERT_EQ(started.code, 0) << started.out << started.err;
    EXPECT_TRUE(started.has("_upright running")) << started.out;
    daemon.step_cycles(250);  // 4 s: swung up and caught
    const Said ended = remote(daemon, how);
    const std::string reason = how == RemoteKind::stop ? "stop_command" : "estop_command";
    EXPECT_EQ(ended.code, 0) << ended.out << ended.err;
    EXPECT_TRUE(ended.has("_upright ended: " + reason)) << ended.out;

    const auto path = daemon.daemon().recorder().last_log();
    ASSERT_TRUE(path.has_value());
    const session_log::SessionLog log = session_log::load_session_log(*path);
    ASSERT_TRUE(log.start.has_value());
    EXPECT_EQ(log.start->profile, "balance");
    ASSERT_TRUE(log.start_command.has_value());  // who started it, signed
    ASSERT_TRUE(log.controller.has_value());
    EXPECT_EQ(log.controller->path, fs::absolute(design.output).lexically_normal().string());
    bool balanced = false;
    for (const auto& c : log.control) {
      balanced = balanced || c.mode == furuta::rig_control_t::MODE_BALANCE;
    }
    EXPECT_TRUE(balanced) << "never reached balance before the " << reason;
    ASSERT_TRUE(log.end.has_value());
    EXPECT_EQ(log.end->end_reason.rfind(reason, 0), 0u) << log.end->end_reason;
    const auto writes = session_log::motor_command_writes(log, "1065");
    ASSERT_FALSE(writes.empty());
    EXPECT_EQ(writes.back().duty, 0.0);

    if (how == RemoteKind::estop) {
      // The file changes between signing and the daemon's reading: refused, nothing moves.
      daemon.watch_signed([&](const furuta::rig_signed_command_t&) {
        std::ofstream(design.output, std::ios::app) << "# edited after it was hashed\n";
      });
      const Said refused = remote(daemon, RemoteKind::start, start);
      EXPECT_EQ(refused.code, 1) << refused.out << refused.err;
      EXPECT_TRUE(refused.has("the command was signed with")) << refused.err;
      EXPECT_EQ(daemon.daemon().recorder().last_log(), path);  // no new session
    }
  }
}

// status: no latency figures before any session ("no data yet", not 0.0), no fault since start-up;
// after an e-stop and a later good session, the fault with its time and session, and that one
// session ended well since.
TEST(RemoteCommand, StatusSaysWhatHasNoDataAndWhenTheLastFaultHappened) {
  SteppedDaemon daemon;
  daemon.step_cycles(70);
  const Said idle = remote(daemon, RemoteKind::status);
  EXPECT_EQ(idle.code, 0) << idle.err;
  EXPECT_TRUE(idle.has("wake-up latency no data yet")) << idle.out;
  EXPECT_FALSE(idle.has("mean 0.0")) << idle.out;
  EXPECT_TRUE(idle.has("no fault since start-up")) << idle.out;

  ASSERT_EQ(remote(daemon, RemoteKind::start, session_of("free_decay", 30, "halted")).code, 0);
  const Said halted = remote(daemon, RemoteKind::estop);
  EXPECT_EQ(halted.code, 0) << halted.out << halted.err;
  EXPECT_TRUE(halted.has("furuta estop: e-stop: motor commanded to zero, braked; session "))
      << halted.out;
  EXPECT_TRUE(halted.has("_halted ended: estop_command")) << halted.out;

  daemon.step_cycles(70);
  ASSERT_EQ(remote(daemon, RemoteKind::start, session_of("free_decay", 30, "fine")).code, 0);
  ASSERT_EQ(remote(daemon, RemoteKind::stop).code, 0);
  const Said later = remote(daemon, RemoteKind::status);
  EXPECT_TRUE(later.has("last fault: estop_command (20")) << later.out;
  EXPECT_TRUE(later.has(" UTC, in session ")) << later.out;
  EXPECT_TRUE(later.has("_halted), 1 session(s) ended well since")) << later.out;
  EXPECT_TRUE(later.has("last session ")) << later.out;
  EXPECT_TRUE(later.has("_fine ended stop_command")) << later.out;
  EXPECT_TRUE(later.has("wake-up latency of the last session (")) << later.out;
}

// `furuta run` says which rig it drives and why, and which configuration it read, before the
// session starts: the configuration's default backend is the simulated rig.
TEST(RunCommand, SaysWhichRigAndWhichConfigurationItUses) {
  TempDir dir;
  const fs::path config = dir.path() / "rig.toml";
  fs::copy_file(FURUTA_SOURCE_DIR "/config/rig.toml", config);
  RunOptions options = simulated_run(config, dir.path() / "logs", 0.5);
  std::ostringstream out, err;
  ASSERT_EQ(run_session_command(options, out, err), 0) << out.str() << err.str();
  EXPECT_NE(out.str().find("furuta run: configuration " + config.string() + "\n"),
            std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("furuta run: rig: simulated (--sim): motor board 1065 serial "),
            std::string::npos)
      << out.str();
  EXPECT_LT(out.str().find("furuta run: rig:"), out.str().find("session ended"));

  options.simulated = false;  // the configuration says simulated
  std::ostringstream out2, err2;
  ASSERT_EQ(run_session_command(options, out2, err2), 0) << out2.str() << err2.str();
  EXPECT_NE(out2.str().find("furuta run: rig: simulated ([rig] backend = \"simulated\" in " +
                            config.string()),
            std::string::npos)
      << out2.str();
}

TEST(RunCommand, ABadConfigurationNamesFileLineAndField) {
  TempDir dir;
  const fs::path config = dir.path() / "rig.toml";
  std::ofstream(config) << "[safety]\nmax_duty = 2\n";
  RunOptions options;
  options.config_path = config;
  options.simulated = true;
  std::ostringstream out, err;
  try {
    run_session_command(options, out, err);
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("rig.toml:2: safety.max_duty: must be in (0, 1]"),
              std::string::npos)
        << e.what();
  }
}

// The shipped rig.toml with `from` replaced by `to` (each must occur), written into `dir`.
fs::path edited_config(const fs::path& dir,
                       const std::vector<std::pair<std::string, std::string>>& edits) {
  std::ifstream in(FURUTA_SOURCE_DIR "/config/rig.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  for (const auto& [from, to] : edits) {
    const auto at = toml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) toml.replace(at, from.size(), to);
  }
  const fs::path path = dir / "rig.toml";
  std::ofstream(path) << toml;
  return path;
}

// A 1047_2 (vendor class, firmware 2xx, 6 MHz ticks) runs a whole session like the HID board: its
// report timing is read with its own tick, so no report counts as lost, and the log replays.
TEST(RunCommand, ASessionOnAVendorClass1047WithFirmware210) {
  TempDir dir;
  const fs::path config =
      edited_config(dir.path(), {{"firmware_1047 = 101", "firmware_1047 = 210"}});
  std::ostringstream out, err;
  ASSERT_EQ(run_session_command(simulated_run(config, dir.path() / "logs", 2.0), out, err), 0)
      << out.str() << err.str();
  EXPECT_NE(out.str().find("session ended: duration_reached"), std::string::npos) << out.str();
  const fs::path log = only_log_in(dir.path() / "logs");
  const session_log::SessionLog loaded = session_log::load_session_log(log);
  ASSERT_TRUE(loaded.start.has_value());
  ASSERT_EQ(loaded.samples.size(), 125u);  // 2 s / 16 ms
  EXPECT_EQ(loaded.samples.back().encoder_lost_reports, 0);
  EXPECT_EQ(loaded.samples.back().motor_lost_reports, 0);
  EXPECT_NE(loaded.start->encoder_device.find("firmware=210"), std::string::npos)
      << loaded.start->encoder_device;
  std::ostringstream replay_out;
  EXPECT_EQ(run_replay_command(log, {}, replay_out, err), 0) << replay_out.str() << err.str();
  EXPECT_NE(replay_out.str().find("identical"), std::string::npos) << replay_out.str();
}

// A 1047 with firmware 3xx (the 1047_2's later firmware adds a field whose layout is not known) is
// refused before the motor moves, naming the board, its serial, its firmware and the way out.
TEST(RunCommand, AnUntestedFirmwareIsRefusedUnlessTheConfigurationAllowsIt) {
  TempDir dir;
  const fs::path refused =
      edited_config(dir.path(), {{"firmware_1047 = 101", "firmware_1047 = 310"}});
  std::ostringstream out, err;
  try {
    run_session_command(simulated_run(refused, dir.path() / "logs", 1.0), out, err);
    FAIL() << "a board with firmware 310 was opened: " << out.str();
  } catch (const std::exception& e) {
    const std::string message = e.what();
    for (const char* part : {"encoder board", "1047", "serial 300002", "firmware 310", "200-299",
                             "[boards.encoder] allow_untested_firmware = true"}) {
      EXPECT_NE(message.find(part), std::string::npos) << part << " in: " << message;
    }
  }
  EXPECT_FALSE(fs::exists(dir.path() / "logs") && !fs::is_empty(dir.path() / "logs"));

  TempDir allowed_dir;
  const fs::path allowed = edited_config(
      allowed_dir.path(),
      {{"firmware_1047 = 101", "firmware_1047 = 310"},
       {"allow_untested_firmware = false  # known", "allow_untested_firmware = true  # known"}});
  std::ostringstream out2, err2;
  EXPECT_EQ(
      run_session_command(simulated_run(allowed, allowed_dir.path() / "logs", 1.0), out2, err2), 0)
      << out2.str() << err2.str();
  EXPECT_NE(err2.str().find("firmware 310"), std::string::npos) << err2.str();
  EXPECT_NE(err2.str().find("opened anyway"), std::string::npos) << err2.str();
}

}  // namespace
}  // namespace furuta::app
