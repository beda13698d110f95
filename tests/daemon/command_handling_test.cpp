// Commands over LCM (memq://), through the daemon's own LCM thread: a rejected command is answered
// with a status saying which field is wrong, a flood is rate-limited (and told so), an e-stop
// always gets through, a status request gets the state and the counts.
//
// The loop runs on a clock the test steps one period at a time (safe to read from any thread), so
// the rate limiter's notion of time, and every count, is exact.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "daemon_test_support.hpp"
#include "furuta/command_auth/command_auth.hpp"
#include "furuta/command_auth/status_signature.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/simulator/simulated_rig.hpp"
#include "lcm_datagram.hpp"
#include "stepped_clock.hpp"
#include "temp_dir.hpp"

namespace furuta::daemon {
namespace {

namespace fs = std::filesystem;

using furuta::rig_command_t;
using furuta::rig_status_t;

// Status replies (those answering a request) as the daemon's LCM thread delivers them.
class Inbox {
 public:
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const rig_status_t* m) {
    if (m->reply_to_request_id == 0) return;  // the periodic status, not a reply
    {
      std::lock_guard lock(mutex_);
      replies_.push_back(*m);
    }
    arrived_.notify_all();
  }
  std::size_t count() {
    std::lock_guard lock(mutex_);
    return replies_.size();
  }
  // The reply to `request_id`; fails the test if none comes within a generous time (a hang guard,
  // not a timing assertion).
  rig_status_t reply_to(std::int64_t request_id) {
    std::unique_lock lock(mutex_);
    const rig_status_t* found = nullptr;
    const bool got = arrived_.wait_for(lock, std::chrono::seconds(20), [&] {
      for (const auto& r : replies_) {
        if (r.reply_to_request_id == request_id) found = &r;
      }
      return found != nullptr;
    });
    if (!got) {
      ADD_FAILURE() << "no reply to request " << request_id;
      return {};
    }
    return *found;
  }

 private:
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<rig_status_t> replies_;
};

struct CommandRig {
  config::RigConfig config = testing::quiet_rig();
  furuta::testing::SteppedClock clock{1'000'000'000};
  std::unique_ptr<sim::SimulatedRig> sim;
  std::unique_ptr<bridge::Transport> motor_usb;
  std::unique_ptr<bridge::Transport> encoder_usb;
  std::unique_ptr<DirectBoardLink> motor;
  std::unique_ptr<DirectBoardLink> encoder;
  DaemonSettings settings;
  lcm::LCM lcm{"memq://"};
  Inbox inbox;
  lcm::Subscription* subscription = nullptr;
  std::unique_ptr<Daemon> daemon;
  std::int64_t next_id = 1000;
  // The rig's command key, and the wall clock signed commands are checked against (the test's).
  command_auth::CommandKey key = key_filled_with(0x5a);
  std::atomic<std::int64_t> wall_ns{1'800'000'000'000'000'000};
  std::int64_t next_nonce = 1;

  static command_auth::CommandKey key_filled_with(std::uint8_t value) {
    command_auth::CommandKey k{};
    k.fill(value);
    return k;
  }

  CommandRig() {
    sim = std::make_unique<sim::SimulatedRig>(config.simulation, clock);
    motor_usb = sim->make_transport();
    encoder_usb = sim->make_transport();
    const bool opened =
        motor_usb->open({bridge::kPhidgetsVendorId, bridge::kProductMotorControl1065, {}}) ==
            bridge::TransportStatus::ok &&
        encoder_usb->open({bridge::kPhidgetsVendorId, bridge::kProductEncoder1047, {}}) ==
            bridge::TransportStatus::ok;
    EXPECT_TRUE(opened);
    motor = std::make_unique<DirectBoardLink>(*motor_usb);
    encoder = std::make_unique<DirectBoardLink>(*encoder_usb);
    settings = daemon_settings_from_config(config);
    settings.recorder.motor_device = bridge::format_trace_device_line(motor_usb->device_info());
    settings.recorder.encoder_device = bridge::format_trace_device_line(encoder_usb->device_info());
    settings.loop.wait_when_queue_full = true;
    settings.command_key = key;
    settings.wall_clock_ns = [this] { return wall_ns.load(); };
    subscription = lcm.subscribe(session_log::kChannelStatus, &Inbox::on_status, &inbox);
  }
  ~CommandRig() {
    clock.run_free();  // the loop may be asleep waiting for time that the test no longer gives
    daemon.reset();
    lcm.unsubscribe(subscription);
  }

  void start(const fs::path& logs_dir) {
    settings.recorder.logs_dir = logs_dir;
    daemon = std::make_unique<Daemon>(settings, *motor, *encoder, clock, lcm);
    daemon->start();
  }

  // One cycle at a time: time moves to the deadline the loop sleeps for, and the cycle it then
  // runs is waited for. No cycle is ever late.
  void step_cycles(int n) {
    const auto& cycles = daemon->loop().counters().cycles;
    for (int i = 0; i < n; ++i) {
      // The count only moves after a wake-up, and the previous one has been counted already.
      const std::int64_t target = cycles.load() + 1;
      ASSERT_TRUE(clock.wake_sleeper_on_time()) << "the loop stopped sleeping";
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (cycles.load() < target) {
        ASSERT_LT(std::chrono::steady_clock::now(), give_up) << "the loop stopped cycling";
        std::this_thread::yield();
      }
    }
  }

  // Publishes a command as `furuta` would (the daemon's LCM thread takes it): signed with the
  // rig's key on RIG_COMMAND_SIGNED when it moves the motor, else on RIG_COMMAND. Returns its id.
  std::int64_t send(rig_command_t command) {
    if (command_auth::moves_motor(command)) return send_signed(command, key);
    return send_unsigned(command);
  }
  std::int64_t send_unsigned(rig_command_t command) {
    command.request_id = next_id++;
    lcm.publish(session_log::kChannelCommand, &command);
    return command.request_id;
  }
  std::int64_t send_signed(rig_command_t command, const command_auth::CommandKey& with) {
    command.request_id = next_id++;
    const auto m =
        command_auth::sign_command(command, with, "test@rig", wall_ns.load(), next_nonce++);
    lcm.publish(session_log::kChannelSignedCommand, &m);
    return command.request_id;
  }
  // The log of the one session the daemon has finished ("" if it has not, within a hang guard).
  fs::path only_log(const fs::path& logs_dir) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (daemon->sessions_logged() < 1 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    fs::path found;
    if (daemon->sessions_logged() != 1) return found;
    for (const auto& entry : fs::directory_iterator(logs_dir)) {
      if (entry.path().extension() == ".lcmlog") found = entry.path();
    }
    return found;
  }
  // A signed message as given (a capture sent again, one changed on the way).
  void send_message(const furuta::rig_signed_command_t& m) {
    lcm.publish(session_log::kChannelSignedCommand, &m);
  }
  rig_status_t ask(const rig_command_t& command) { return inbox.reply_to(send(command)); }
};

rig_command_t status_request() {
  return testing::simple_command(rig_command_t::KIND_STATUS_REQUEST);
}

// Asks for the status until `ready` holds: the io thread fills some of its fields (the session
// name, how the last session ended) a moment after the loop's event. The loop's clock stands
// still meanwhile and the daemon answers a limited number of status requests per second of that
// clock, so the asks are spaced out (at most about 200); a hang guard of 20 s in all, not a
// timing check.
template <class Ready>
rig_status_t ask_until(CommandRig& rig, Ready ready) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  auto pause = std::chrono::milliseconds(1);
  rig_status_t status;
  do {
    status = rig.ask(status_request());
    if (ready(status)) return status;
    std::this_thread::sleep_for(pause);
    pause = std::min(2 * pause, std::chrono::milliseconds(100));
  } while (std::chrono::steady_clock::now() < give_up);
  ADD_FAILURE() << "the status did not show what the test waits for within 20 s";
  return status;
}

TEST(CommandHandling, RejectedCommandsAreAnsweredWithTheFieldAtFault) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;  // the rate limit is another test
  rig.start(dir.path());

  struct Case {
    const char* what;
    rig_command_t command;
    const char* field;
  };
  std::vector<Case> cases;
  cases.push_back(
      {"amplitude too high", testing::start_command("bang_bang", 0.9, 10.0), "amplitude_duty: "});
  cases.push_back(
      {"amplitude NaN",
       testing::start_command("bang_bang", std::numeric_limits<double>::quiet_NaN(), 10.0),
       "amplitude_duty: "});
  cases.push_back({"unknown profile", testing::start_command("sawtooth", 0.3, 10.0), "profile: "});
  cases.push_back(
      {"NaN duration",
       testing::start_command("bang_bang", 0.3, std::numeric_limits<double>::quiet_NaN()),
       "duration_s: "});
  cases.push_back(
      {"duration too long", testing::start_command("bang_bang", 0.3, 1e6), "duration_s: "});
  cases.push_back(
      {"label with a path", testing::start_command("bang_bang", 0.3, 10.0, "../up"), "label: "});
  cases.push_back({"label too long",
                   testing::start_command("bang_bang", 0.3, 10.0, std::string(200, 'a')),
                   "label: "});
  rig_command_t negative_seed = testing::start_command("bang_bang", 0.3, 10.0);
  negative_seed.seed = -1;
  cases.push_back({"negative seed", negative_seed, "seed: "});
  cases.push_back({"unknown kind", testing::simple_command(42), "kind: "});

  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const rig_status_t reply = rig.ask(c.command);
    EXPECT_FALSE(reply.request_accepted);
    EXPECT_EQ(reply.request_reason.rfind(c.field, 0), 0u) << reply.request_reason;
    EXPECT_EQ(reply.state, +rig_status_t::STATE_IDLE);
  }
  // None of them started anything; a valid command is accepted (the channel itself works).
  rig.step_cycles(3);
  EXPECT_EQ(rig.daemon->loop().counters().sessions_completed.load(), 0);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::idle);
  const rig_status_t ok = rig.ask(status_request());
  EXPECT_TRUE(ok.request_accepted) << ok.request_reason;
  EXPECT_TRUE(ok.request_reason.empty());
}

TEST(CommandHandling, AFloodIsRateLimitedAndAnEstopAlwaysGetsThrough) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  ASSERT_EQ(rig.settings.command_limits.max_commands_per_s, 5);
  rig.start(dir.path());
  // The pendulum has hung still for the rest check (one second): a start is accepted and runs.
  rig.step_cycles(70);
  const rig_status_t started = rig.ask(testing::start_command("bang_bang", 0.3, 30.0));
  ASSERT_TRUE(started.request_accepted) << started.request_reason;
  rig.step_cycles(2);
  ASSERT_EQ(rig.daemon->loop().counters().state.load(), LoopState::running);

  // Time stands still: the bucket (5 commands, one spent on the start) does not refill. The flood
  // is of bad start commands: the first four are looked at (and refused for their profile), the
  // rest are refused unread.
  furuta::rig_command_t bad_start = testing::start_command("bang_bang", 0.3, 30.0);
  bad_start.profile = "square";
  std::vector<std::int64_t> flood;
  for (int i = 0; i < 6; ++i) flood.push_back(rig.send(bad_start));
  const std::int64_t estop = rig.send(testing::simple_command(rig_command_t::KIND_ESTOP));
  for (int i = 0; i < 6; ++i) flood.push_back(rig.send(bad_start));

  int looked_at = 0;
  for (const std::int64_t id : flood) {
    const rig_status_t reply = rig.inbox.reply_to(id);
    EXPECT_FALSE(reply.request_accepted);
    if (reply.request_reason.rfind("profile", 0) == 0) {
      ++looked_at;
      continue;
    }
    EXPECT_EQ(reply.request_reason, "rate limit: more than 5 starts per second");
  }
  EXPECT_EQ(looked_at, 4);
  const rig_status_t estop_reply = rig.inbox.reply_to(estop);
  EXPECT_TRUE(estop_reply.request_accepted) << estop_reply.request_reason;

  // The e-stop took effect at the next cycle.
  rig.step_cycles(1);
  EXPECT_EQ(rig.daemon->loop().counters().last_stop.load(), StopReason::estop_command);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::fault);

  // A second later the bucket has refilled: commands are taken again.
  rig.step_cycles(static_cast<int>(1'000'000'000 / rig.settings.loop.period_ns) + 1);
  const rig_status_t later = rig.ask(status_request());
  EXPECT_TRUE(later.request_accepted) << later.request_reason;
}

// Hostile input on RIG_COMMAND (issue 8): bytes that are no rig_command_t at all, then a flood of
// about 5000 bad start commands a second in virtual time while a session runs at the largest
// amplitude a command may ask for. The daemon keeps answering, refuses each with a reason, accepts
// no more than the token bucket allows, lets the e-stop through, and the motor is never written a
// duty beyond the configured limits.
TEST(CommandHandling, HostileBytesAndAFloodNeverMoveTheMotorBeyondTheLimits) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_refusal_replies_per_s = 1'000'000'000;  // every one answered
  rig.start(dir.path());

  // Malformed messages (found by fuzz_command_decode): a string length of 0 used to throw out of
  // LCM's dispatch and end the process; INT32_MIN read past the buffer.
  furuta::rig_command_t valid = testing::start_command("bang_bang", 0.3, 10.0);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(valid.getEncodedSize()));
  valid.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  for (std::uint32_t length : {0u, 0x80000000u, 0xFFFFFFFFu}) {
    std::vector<std::uint8_t> bad = bytes;
    for (int i = 0; i < 4; ++i) bad[17 + i] = static_cast<std::uint8_t>(length >> (24 - 8 * i));
    rig.lcm.publish(session_log::kChannelCommand, bad.data(), static_cast<unsigned>(bad.size()));
  }
  const std::vector<std::uint8_t> junk(3, 0xEE);
  rig.lcm.publish(session_log::kChannelCommand, junk.data(), static_cast<unsigned>(junk.size()));
  // Larger than any command: dropped undecoded, like the junk, and counted.
  const rig_command_t oversized = testing::start_command(std::string(100000, 'p'), 0.2, 10.0);
  rig.lcm.publish(session_log::kChannelCommand, &oversized);
  const rig_status_t alive = rig.ask(status_request());
  EXPECT_TRUE(alive.request_accepted) << alive.request_reason;
  EXPECT_EQ(alive.refused_malformed, 5);

  rig.step_cycles(70);  // past the rest check
  const double limit = rig.settings.command_limits.max_amplitude_duty;
  const rig_status_t started = rig.ask(testing::start_command("bang_bang", limit, 30.0, "max"));
  ASSERT_TRUE(started.request_accepted) << started.request_reason;

  std::vector<rig_command_t> hostile;
  for (double amplitude :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -0.5,
        1e308, std::nextafter(limit, 1.0), 2.0}) {
    hostile.push_back(testing::start_command("bang_bang", amplitude, 10.0));
  }
  for (double duration : {-1.0, 0.0, 1e308, std::numeric_limits<double>::infinity(),
                          std::numeric_limits<double>::quiet_NaN()}) {
    hostile.push_back(testing::start_command("chirp", 0.2, duration));
  }
  hostile.push_back(testing::start_command(std::string(500, 'p'), 0.2, 10.0));
  hostile.push_back(testing::start_command("bang_bang\n", 0.2, 10.0));
  hostile.push_back(testing::start_command("prbs", 0.2, 10.0, std::string(500, 'l')));
  rig_command_t seed = testing::start_command("step", 0.2, 10.0);
  seed.seed = std::numeric_limits<std::int64_t>::min();
  hostile.push_back(seed);
  hostile.push_back(testing::simple_command(std::numeric_limits<std::int8_t>::min()));

  // Issue 21: starts that are valid but unsigned, or signed with another key, go in the flood
  // too. They are refused for their signature before any check that spends the token bucket.
  const command_auth::CommandKey wrong_key = CommandRig::key_filled_with(0x33);
  const rig_command_t plausible = testing::start_command("bang_bang", 0.2, 10.0, "intruder");
  const int kinds = static_cast<int>(hostile.size()) + 2;
  auto send_kind = [&](int k) {
    if (k < static_cast<int>(hostile.size())) return rig.send(hostile[k]);
    if (k == static_cast<int>(hostile.size())) return rig.send_unsigned(plausible);
    return rig.send_signed(plausible, wrong_key);
  };

  // 63 cycles of 16 ms (about a second), 80 commands each: about 5000 a second.
  const int cycles = 63, per_cycle = 80;
  int accepted = 0, rate_limited = 0, refused_with_field = 0, refused_unauthenticated = 0;
  std::vector<std::int64_t> ids;
  for (int c = 0; c < cycles; ++c) {
    ids.clear();
    for (int i = 0; i < per_cycle; ++i) ids.push_back(send_kind((c * per_cycle + i) % kinds));
    for (const std::int64_t id : ids) {
      const rig_status_t reply = rig.inbox.reply_to(id);
      if (reply.request_accepted) {
        ++accepted;
        continue;
      }
      ASSERT_FALSE(reply.request_reason.empty());
      ASSERT_LT(reply.request_reason.size(), 300u) << reply.request_reason;
      if (reply.request_reason.rfind("rate limit: ", 0) == 0) {
        ++rate_limited;
      } else if (reply.request_reason.rfind("unsigned: ", 0) == 0 ||
                 reply.request_reason.rfind("bad signature from ", 0) == 0) {
        ++refused_unauthenticated;
      } else {
        ++refused_with_field;
      }
    }
    rig.step_cycles(1);
  }
  EXPECT_EQ(accepted, 0);  // every one of them is bad
  // The bucket: 5 at once (one spent on the start), then 5 a second.
  const double seconds = cycles * rig.settings.loop.period_ns * 1e-9;
  EXPECT_LE(refused_with_field, 4 + static_cast<int>(seconds * 5) + 1);
  EXPECT_GE(refused_with_field, 4);
  EXPECT_EQ(rate_limited + refused_with_field + refused_unauthenticated, cycles * per_cycle);
  int unauthenticated_sent = 0;
  for (int n = 0; n < cycles * per_cycle; ++n) unauthenticated_sent += n % kinds >= kinds - 2;
  EXPECT_EQ(refused_unauthenticated, unauthenticated_sent);
  // The status counts the malformed messages sent first among them.
  EXPECT_EQ(rig.ask(status_request()).refused_unauthenticated, unauthenticated_sent + 5);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::running);

  const rig_status_t estop = rig.ask(testing::simple_command(rig_command_t::KIND_ESTOP));
  EXPECT_TRUE(estop.request_accepted) << estop.request_reason;
  rig.step_cycles(1);
  EXPECT_EQ(rig.daemon->loop().counters().last_stop.load(), StopReason::estop_command);

  // Every write to the 1065 during the session, from its log.
  const fs::path log_path = rig.only_log(dir.path());
  ASSERT_FALSE(log_path.empty());
  const session_log::SessionLog log = session_log::load_session_log(log_path);
  const int max_raw = static_cast<int>(std::floor(rig.config.safety.max_duty * 255 + 1e-9));
  const int amplitude_raw = static_cast<int>(std::lround(limit * 255));
  int writes = 0, peak = 0;
  for (const auto& r : log.usb_reports) {
    if (r.board != furuta::rig_usb_report_t::BOARD_MOTOR ||
        r.kind != furuta::rig_usb_report_t::KIND_OUTPUT) {
      continue;
    }
    ++writes;
    peak = std::max(peak, testing::duty_raw_of(r.bytes));
  }
  EXPECT_GT(writes, cycles);
  EXPECT_EQ(peak, amplitude_raw);  // the session drove the motor at its amplitude, no further
  EXPECT_LE(peak, max_raw);
}

// Issue 21: only a start signed with the rig's key, fresh and not seen before, moves the motor.
// Each other one is refused with its reason and counted, and the loop never sees it; stop and
// e-stop need no signature. The log keeps the signed start, so it shows who started it.
TEST(CommandHandling, OnlyAStartSignedWithTheRigsKeyMovesTheMotor) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(dir.path());
  rig.step_cycles(70);             // past the rest check
  rig.wall_ns += 120'000'000'000;  // the daemon has run for two minutes
  const rig_command_t start = testing::start_command("bang_bang", 0.2, 30.0, "signed");
  auto refused = [&](std::int64_t id, const std::string& reason_start) {
    const rig_status_t reply = rig.inbox.reply_to(id);
    EXPECT_FALSE(reply.request_accepted);
    EXPECT_EQ(reply.request_reason.rfind(reason_start, 0), 0u) << reply.request_reason;
    rig.step_cycles(2);
    EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::idle);
    return reply;
  };
  refused(rig.send_unsigned(start), "unsigned: a command that moves the motor must be signed");
  refused(rig.send_signed(start, CommandRig::key_filled_with(0x33)),
          "bad signature from \"test@rig\"");

  // A signed start for 0.2 whose amplitude was raised to 0.6 on the way, its tag kept.
  rig_command_t quiet = start;
  quiet.request_id = 7001;
  rig_command_t loud = quiet;
  loud.amplitude_duty = 0.6;
  auto tampered = command_auth::sign_command(quiet, rig.key, "test@rig", rig.wall_ns.load(), 77);
  tampered.command =
      command_auth::sign_command(loud, rig.key, "test@rig", rig.wall_ns.load(), 77).command;
  rig.send_message(tampered);
  refused(7001, "bad signature from");

  // One signed a minute ago (captured then, sent now).
  rig_command_t stale = start;
  stale.request_id = 7002;
  rig.send_message(command_auth::sign_command(stale, rig.key, "test@rig",
                                              rig.wall_ns.load() - 60'000'000'000, 78));
  refused(7002, "signed 60 s ago");

  // The genuine one runs.
  rig_command_t genuine = start;
  genuine.request_id = 7003;
  const auto captured =
      command_auth::sign_command(genuine, rig.key, "ana@workstation", rig.wall_ns.load(), 79);
  rig.send_message(captured);
  const rig_status_t accepted = rig.inbox.reply_to(7003);
  ASSERT_TRUE(accepted.request_accepted) << accepted.request_reason;
  rig.step_cycles(3);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::running);

  // Stop needs no signature; the captured start sent again afterwards is a replay.
  const rig_status_t stop = rig.ask(testing::simple_command(rig_command_t::KIND_STOP));
  EXPECT_TRUE(stop.request_accepted) << stop.request_reason;
  rig.step_cycles(2);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::idle);
  rig.wall_ns += 5'000'000'000;
  rig.send_message(captured);  // its reply has the id the first answer had: wait for the count
  const rig_status_t status =
      ask_until(rig, [](const rig_status_t& s) { return s.refused_unauthenticated == 5; });
  rig.step_cycles(2);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::idle);
  const rig_status_t estop = rig.ask(testing::simple_command(rig_command_t::KIND_ESTOP));
  EXPECT_TRUE(estop.request_accepted) << estop.request_reason;

  EXPECT_EQ(status.refused_unauthenticated, 5);
  EXPECT_EQ(status.unauthenticated_reason, "replayed: this signed command was taken already");

  // The one session's log holds the signed start: sender, tag and all, and the tag checks out.
  const fs::path log_path = rig.only_log(dir.path());
  ASSERT_FALSE(log_path.empty());
  const session_log::SessionLog log = session_log::load_session_log(log_path);
  ASSERT_TRUE(log.start_command.has_value());
  EXPECT_EQ(log.start_command->sender, "ana@workstation");
  EXPECT_EQ(log.start_command->nonce, 79);
  const command_auth::CommandTag tag = command_auth::command_tag(rig.key, *log.start_command);
  EXPECT_TRUE(std::equal(tag.begin(), tag.end(), log.start_command->tag));
  EXPECT_EQ(log.unknown_channel_events, 0u);
}

// A signed command with a megabyte of sender, no key needed: refused by its size, and neither the
// reply nor any status after it quotes it, so every answer stays small enough to receive.
TEST(CommandHandling, AMegabyteSenderNeitherBlindsTheStatusNorIsEchoed) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.start(dir.path());
  rig_command_t start = testing::start_command("bang_bang", 0.2, 10.0, "x");
  start.request_id = 8001;
  rig.send_message(command_auth::sign_command(start, CommandRig::key_filled_with(0x33),
                                              std::string(1'000'000, '\x1b'), rig.wall_ns.load(),
                                              1));
  const rig_status_t after = rig.ask(status_request());
  EXPECT_LE(static_cast<std::size_t>(after.getEncodedSize()), command_auth::kMaxStatusBytes);
  EXPECT_EQ(after.refused_malformed, 1);  // over the size any command has: not even decoded
  EXPECT_EQ(rig.inbox.count(), 1u);       // nothing answered it

  // Over the sender's limit, within the message's: refused by its size, the reply short.
  start.request_id = 8002;
  rig.send_message(command_auth::sign_command(start, CommandRig::key_filled_with(0x33),
                                              std::string(1000, 'A'), rig.wall_ns.load(), 2));
  const rig_status_t reply = rig.inbox.reply_to(8002);
  EXPECT_FALSE(reply.request_accepted);
  EXPECT_EQ(reply.request_reason, "sender: 1000 bytes, above the limit of 128");
  EXPECT_LE(static_cast<std::size_t>(reply.getEncodedSize()), command_auth::kMaxStatusBytes);
  const rig_status_t counted = rig.ask(status_request());
  EXPECT_EQ(counted.refused_malformed, 2);
  EXPECT_EQ(counted.refused_unauthenticated, 2);
  EXPECT_EQ(counted.unauthenticated_reason, reply.request_reason);

  // Within the size, a sender of escape sequences is quoted escaped.
  start.request_id = 8003;
  rig.send_message(command_auth::sign_command(start, CommandRig::key_filled_with(0x33),
                                              "\x1b[2J\x1b]0;pwned\a", rig.wall_ns.load(), 3));
  const rig_status_t escaped = rig.inbox.reply_to(8003);
  EXPECT_EQ(escaped.request_reason.find('\x1b'), std::string::npos) << escaped.request_reason;
  EXPECT_NE(escaped.request_reason.find("\\x1b[2J"), std::string::npos) << escaped.request_reason;
}

// With a udpm:// URL the daemon reads commands from the group's port itself, in batches: what LCM
// would deliver is taken the same way, oversized command datagrams are counted as malformed, other
// channels and fragments are passed over. Sent to the port on loopback, as the group's would come.
TEST(CommandHandling, CommandsOnTheGroupAreReadByTheDaemonsOwnSocket) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(furuta::testing::free_loopback_udp_port());
  rig.settings.command_url =
      "udpm://239.255.201.18:" + std::to_string(ntohs(address.sin_port)) + "?ttl=0";
  try {
    rig.start(dir.path());
  } catch (const std::system_error& e) {
    GTEST_SKIP() << "no multicast here: " << e.what();
  }
  // The daemon no longer handles this memq LCM (it reads the socket): its answers are handled here.
  std::atomic<bool> done{false};
  std::thread answers([&] {
    while (!done.load()) rig.lcm.handleTimeout(10);
  });
  const int sender = ::socket(AF_INET, SOCK_DGRAM, 0);
  const auto send = [&](const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    const std::vector<std::uint8_t> datagram = furuta::testing::lcm_datagram(channel, bytes, 1);
    ASSERT_EQ(::sendto(sender, datagram.data(), datagram.size(), 0,
                       reinterpret_cast<const sockaddr*>(&address), sizeof address),
              static_cast<ssize_t>(datagram.size()));
  };
  const auto encoded = [](const auto& message) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
    message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    return bytes;
  };

  send(session_log::kChannelCommand, std::vector<std::uint8_t>(5000, 0));  // oversized
  send("RIG_SAMPLE", std::vector<std::uint8_t>(5000, 0));                  // not a command
  send(session_log::kChannelSignedCommand, {1, 2, 3});                     // undecodable
  rig_command_t start = testing::start_command("bang_bang", 0.2, 10.0, "x");
  start.request_id = 9001;
  send(session_log::kChannelSignedCommand,
       encoded(command_auth::sign_command(start, rig.key, "test@rig", rig.wall_ns.load(), 1)));
  rig_command_t ask = status_request();
  ask.request_id = 9002;
  send(session_log::kChannelCommand, encoded(ask));

  const rig_status_t started = rig.inbox.reply_to(9001);
  EXPECT_TRUE(started.request_accepted) << started.request_reason;
  const rig_status_t status = rig.inbox.reply_to(9002);
  EXPECT_EQ(status.refused_malformed, 2);
  rig_command_t stop = testing::simple_command(rig_command_t::KIND_ESTOP);
  stop.request_id = 9003;
  send(session_log::kChannelCommand, encoded(stop));
  EXPECT_TRUE(rig.inbox.reply_to(9003).request_accepted);
  ::close(sender);
  done.store(true);
  answers.join();
}

// Stops, e-stops and status requests have budgets of their own: a flood of unsigned stops does not
// keep a genuine signed start out, and every refusal is counted under its reason.
TEST(CommandHandling, AStopFloodDoesNotSpendTheStartBudget) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_refusal_replies_per_s = 1'000'000'000;
  rig.start(dir.path());
  rig.step_cycles(70);  // past the rest check
  // Time stands still: 100 stops and 100 status requests at once, then the start.
  std::vector<std::int64_t> stops;
  for (int i = 0; i < 100; ++i) {
    stops.push_back(rig.send(testing::simple_command(rig_command_t::KIND_STOP)));
    rig.send(status_request());
  }
  // Every stop answered, then the loop takes them (a stop cancels a start that waits with it).
  int stops_refused = 0;
  for (std::int64_t id : stops) stops_refused += !rig.inbox.reply_to(id).request_accepted;
  EXPECT_EQ(stops_refused, 100 - rig.settings.command_limits.max_stops_per_s);
  rig.step_cycles(1);
  const rig_status_t start = rig.ask(testing::start_command("bang_bang", 0.2, 30.0, "through"));
  EXPECT_TRUE(start.request_accepted) << start.request_reason;
  rig.step_cycles(3);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::running);
  // The e-stop needs no budget at all.
  EXPECT_TRUE(rig.ask(testing::simple_command(rig_command_t::KIND_ESTOP)).request_accepted);
  rig.step_cycles(1);
  EXPECT_EQ(rig.daemon->loop().counters().last_stop.load(), StopReason::estop_command);
  rig.step_cycles(70);  // the budgets refill
  const rig_status_t counts = rig.ask(status_request());
  EXPECT_EQ(counts.refused_stop_budget, 80);
  EXPECT_EQ(counts.refused_status_budget, 80);
  EXPECT_EQ(counts.refused_start_budget, 0);
  EXPECT_EQ(counts.refused_unauthenticated, 0);
}

// A flood of wrongly signed commands is counted, but only answered within the refusal reply
// budget: the daemon does not echo a flood onto the group. Accepted commands are always answered.
TEST(CommandHandling, RefusalsAreAnsweredWithinTheirBudgetAndAllCounted) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.start(dir.path());
  const rig_command_t start = testing::start_command("bang_bang", 0.2, 30.0, "flood");
  for (int i = 0; i < 500; ++i) rig.send_signed(start, CommandRig::key_filled_with(0x33));
  const rig_status_t status = rig.ask(status_request());
  EXPECT_TRUE(status.request_accepted);
  EXPECT_EQ(status.refused_bad_signature, 500);
  EXPECT_EQ(status.replies_withheld, 500 - rig.settings.command_limits.max_refusal_replies_per_s);
  EXPECT_EQ(rig.inbox.count(),
            static_cast<std::size_t>(rig.settings.command_limits.max_refusal_replies_per_s + 1));
}

// With a daemon key every answer carries the daemon's signature; the public half checks it.
TEST(CommandHandling, EveryAnswerIsSignedWithTheDaemonKey) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.daemon_key = CommandRig::key_filled_with(0x77);
  rig.start(dir.path());
  const auto public_key = command_auth::daemon_public_key(*rig.settings.daemon_key);
  const rig_status_t status = rig.ask(status_request());
  EXPECT_EQ(command_auth::check_status(status, public_key),
            command_auth::StatusAuthenticity::signed_by_daemon);
  const rig_status_t refused = rig.ask(testing::start_command("square", 0.2, 1.0));
  EXPECT_FALSE(refused.request_accepted);
  EXPECT_EQ(command_auth::check_status(refused, public_key),
            command_auth::StatusAuthenticity::signed_by_daemon);
  EXPECT_EQ(command_auth::check_status(
                refused, command_auth::daemon_public_key(CommandRig::key_filled_with(0x78))),
            command_auth::StatusAuthenticity::wrongly_signed);
}

// A start dated ahead of the daemon's clock (within the skew) is taken; the daemon restarts with
// the same replay state file; the same bytes are refused.
TEST(CommandHandling, AStartTakenBeforeARestartIsRefusedAfterIt) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_auth.state_file = dir.path() / "command-replay.state";
  rig.start(dir.path());
  rig.step_cycles(70);
  rig_command_t start = testing::start_command("free_decay", 0.1, 30.0, "once");
  start.request_id = 9001;
  const auto captured =
      command_auth::sign_command(start, rig.key, "ana@rig", rig.wall_ns.load() + 1'500'000'000, 5);
  rig.send_message(captured);
  ASSERT_TRUE(rig.inbox.reply_to(9001).request_accepted);
  rig.step_cycles(3);
  ASSERT_TRUE(rig.ask(testing::simple_command(rig_command_t::KIND_STOP)).request_accepted);
  rig.step_cycles(3);

  rig.clock.run_free();
  rig.daemon.reset();
  rig.clock.stop_running_free();
  rig.wall_ns += 500'000'000;  // restarted half a second later
  rig.start(dir.path());
  rig.step_cycles(70);
  rig.send_message(captured);
  const rig_status_t replay =
      ask_until(rig, [](const rig_status_t& s) { return s.refused_out_of_time == 1; });
  EXPECT_EQ(replay.refused_out_of_time, 1);
  EXPECT_NE(replay.unauthenticated_reason.find("replay floor"), std::string::npos)
      << replay.unauthenticated_reason;
  rig.step_cycles(3);
  EXPECT_EQ(rig.daemon->loop().counters().state.load(), LoopState::idle);
}

TEST(CommandHandling, AStatusRequestGetsTheStateAndTheCounts) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(dir.path());
  rig.step_cycles(20);
  const rig_status_t idle = rig.ask(status_request());
  EXPECT_TRUE(idle.request_accepted);
  EXPECT_EQ(idle.state, +rig_status_t::STATE_IDLE);
  EXPECT_EQ(idle.cycles, 20);
  EXPECT_EQ(idle.overruns, 0);
  EXPECT_EQ(idle.motor_lost_reports, 0);
  EXPECT_EQ(idle.encoder_lost_reports, 0);
  EXPECT_TRUE(idle.session.empty()) << idle.session;
  EXPECT_EQ(idle.monotonic_ns, 1'000'000'000 + 20 * rig.settings.loop.period_ns);

  rig.step_cycles(50);  // 70 cycles: past the one-second rest check
  ASSERT_TRUE(rig.ask(testing::start_command("bang_bang", 0.3, 30.0, "status")).request_accepted);
  rig.step_cycles(5);
  const rig_status_t running =
      ask_until(rig, [](const rig_status_t& s) { return !s.session.empty(); });
  EXPECT_EQ(running.state, +rig_status_t::STATE_RUNNING);
  EXPECT_EQ(running.cycles, 75);
  EXPECT_NE(running.session.find("_status"), std::string::npos) << running.session;

  // Lost reports show in the counts: three 1065 reports dropped.
  rig.step_cycles(1);
  rig.sim->drop_reports(sim::RigBoard::motor_1065, 3);
  rig.step_cycles(4);
  const rig_status_t lost = rig.ask(status_request());
  EXPECT_EQ(lost.motor_lost_reports, 3);
  EXPECT_EQ(lost.state, +rig_status_t::STATE_RUNNING);

  // After a stop the state is idle again.
  ASSERT_TRUE(rig.ask(testing::simple_command(rig_command_t::KIND_STOP)).request_accepted);
  rig.step_cycles(1);
  const rig_status_t stopped = rig.ask(status_request());
  EXPECT_EQ(stopped.state, +rig_status_t::STATE_IDLE);
  EXPECT_EQ(stopped.cycles, 81);
}

// The command thread accepts a start it cannot judge; the loop then refuses it when the pendulum
// has not hung still for the rest check. The status must say so under the start's request id (the
// verdict `furuta start` waits for), or the user sees "accepted" and a rig that never starts. A
// refused start is no fault of the rig: the last fault stays empty.
TEST(CommandHandling, AStartTheLoopRefusesSaysWhyInTheStatus) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(dir.path());
  rig.step_cycles(20);  // a third of the one-second rest check
  const std::int64_t id = rig.send(testing::start_command("bang_bang", 0.3, 30.0, "early"));
  ASSERT_TRUE(rig.inbox.reply_to(id).request_accepted);
  rig.step_cycles(2);
  const rig_status_t after =
      ask_until(rig, [&](const rig_status_t& s) { return s.refused_request_id == id; });
  EXPECT_EQ(after.refused_request_id, id);
  EXPECT_EQ(after.refused_reason.rfind("the pendulum is not at rest", 0), 0u)
      << after.refused_reason;
  EXPECT_EQ(after.state, +rig_status_t::STATE_IDLE);
  EXPECT_TRUE(after.session.empty()) << after.session;
  EXPECT_TRUE(after.last_session.empty()) << after.last_session;
  EXPECT_TRUE(after.last_fault.empty()) << after.last_fault;
}

// A start while a session runs: the command thread knows, so the reply itself is the refusal.
TEST(CommandHandling, AStartWhileASessionRunsIsRefusedInTheReply) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(dir.path());
  rig.step_cycles(70);
  const std::int64_t first = rig.send(testing::start_command("bang_bang", 0.3, 30.0, "first"));
  ASSERT_TRUE(rig.inbox.reply_to(first).request_accepted);
  rig.step_cycles(2);
  const rig_status_t running =
      ask_until(rig, [](const rig_status_t& s) { return !s.session.empty(); });
  EXPECT_EQ(running.last_session, running.session);
  EXPECT_EQ(running.last_session_request_id, first);
  EXPECT_TRUE(running.last_session_end.empty()) << running.last_session_end;

  const rig_status_t second = rig.ask(testing::start_command("bang_bang", 0.3, 30.0, "second"));
  EXPECT_FALSE(second.request_accepted);
  EXPECT_EQ(second.request_reason.rfind("a session is already running: " + running.session, 0), 0u)
      << second.request_reason;
}

// The last fault says when and where it happened and how many sessions ended well since; the
// latest session, how it ended and the request it came from stay after it ended; an idle daemon
// that has run no session has no latency figures (not zeros).
TEST(CommandHandling, TheStatusSaysWhenTheLastFaultHappenedAndWhatRanSince) {
  testing::TempDir dir("furuta-commands");
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(dir.path());
  rig.step_cycles(70);
  const rig_status_t idle = rig.ask(status_request());
  EXPECT_EQ(idle.latency_samples, 0);
  EXPECT_TRUE(idle.last_fault.empty());
  EXPECT_EQ(idle.last_fault_wall_ns, 0);
  EXPECT_TRUE(idle.last_session.empty());
  EXPECT_TRUE(idle.logs_problem.empty()) << idle.logs_problem;

  const auto wall_now = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  const std::int64_t before = wall_now();
  // A free decay (zero duty) keeps the pendulum still for the next session's rest check.
  ASSERT_TRUE(
      rig.ask(testing::start_command("free_decay", 0.1, 30.0, "estopped")).request_accepted);
  rig.step_cycles(5);
  const rig_status_t first =
      ask_until(rig, [](const rig_status_t& s) { return !s.session.empty(); });
  ASSERT_TRUE(rig.ask(testing::simple_command(rig_command_t::KIND_ESTOP)).request_accepted);
  rig.step_cycles(2);
  const rig_status_t faulted =
      ask_until(rig, [](const rig_status_t& s) { return !s.last_session_end.empty(); });
  const std::int64_t after = wall_now();
  EXPECT_EQ(faulted.last_fault.rfind("estop_command", 0), 0u) << faulted.last_fault;
  EXPECT_GE(faulted.last_fault_wall_ns, before);
  EXPECT_LE(faulted.last_fault_wall_ns, after);
  EXPECT_EQ(faulted.last_fault_session, first.session);
  EXPECT_EQ(faulted.sessions_since_fault, 0);
  EXPECT_EQ(faulted.last_session, first.session);
  EXPECT_EQ(faulted.last_session_end, "estop_command");
  EXPECT_GT(faulted.latency_samples, 0);  // the session's cycles

  rig.step_cycles(70);  // the rest check again
  const std::int64_t id = rig.send(testing::start_command("free_decay", 0.1, 30.0, "fine"));
  ASSERT_TRUE(rig.inbox.reply_to(id).request_accepted);
  rig.step_cycles(3);
  ask_until(rig, [&](const rig_status_t& s) { return s.last_session_request_id == id; });
  ASSERT_TRUE(rig.ask(testing::simple_command(rig_command_t::KIND_STOP)).request_accepted);
  rig.step_cycles(2);
  const rig_status_t later = ask_until(rig, [&](const rig_status_t& s) {
    return s.last_session_request_id == id && !s.last_session_end.empty();
  });
  EXPECT_EQ(later.last_session_end, "stop_command");
  EXPECT_EQ(later.sessions_since_fault, 1);
  EXPECT_EQ(later.last_fault, faulted.last_fault);  // still the e-stop, with its time and session
  EXPECT_EQ(later.last_fault_wall_ns, faulted.last_fault_wall_ns);
  EXPECT_EQ(later.last_fault_session, first.session);
}

// A logs directory that cannot be written (here under a regular file, which stops root too) is in
// the status from the daemon's start, and every start is refused with it.
TEST(CommandHandling, ALogsDirectoryThatCannotBeWrittenIsInTheStatusAndStartsAreRefused) {
  testing::TempDir dir("furuta-commands");
  std::ofstream(dir.path() / "file") << "not a directory";
  const fs::path logs = dir.path() / "file" / "logs";
  CommandRig rig;
  rig.settings.command_limits.max_commands_per_s = 1000;
  rig.start(logs);
  const rig_status_t status = rig.ask(status_request());
  EXPECT_NE(status.logs_problem.find(logs.string()), std::string::npos) << status.logs_problem;
  EXPECT_NE(status.logs_problem.find("Not a directory"), std::string::npos) << status.logs_problem;
  rig.step_cycles(70);
  const rig_status_t start = rig.ask(testing::start_command("bang_bang", 0.3, 30.0));
  EXPECT_FALSE(start.request_accepted);
  EXPECT_NE(start.request_reason.find("cannot log a session"), std::string::npos)
      << start.request_reason;
  EXPECT_NE(start.request_reason.find("Not a directory"), std::string::npos)
      << start.request_reason;
}

}  // namespace
}  // namespace furuta::daemon

namespace furuta::daemon {
namespace {

TEST(SessionNames, ASecondSessionInTheSameSecondGetsItsOwnName) {
  furuta::testing::TempDir dir;
  const std::string base = session_name(1'800'000'000'000'000'000, "bang");
  EXPECT_EQ(unique_session_name(base, dir.path()), base);
  std::ofstream(dir.path() / (base + ".lcmlog")) << "x";
  EXPECT_EQ(unique_session_name(base, dir.path()), base + "-2");
  std::filesystem::create_directories(dir.path() / "done");
  std::ofstream(dir.path() / "done" / (base + "-2.lcmlog")) << "x";
  std::ofstream(dir.path() / (base + "-3.lcmlog.part")) << "x";
  EXPECT_EQ(unique_session_name(base, dir.path()), base + "-4");
  // A longer name that merely starts with the same stamp does not count as taken.
  std::ofstream(dir.path() / (base + "x.lcmlog")) << "x";
  EXPECT_EQ(unique_session_name(base + "x", dir.path()), base + "x-2");
  EXPECT_EQ(unique_session_name(base + "y", dir.path()), base + "y");
}

}  // namespace
}  // namespace furuta::daemon
