// Every way a session can end writes a zero command to the motor last: each exit path of the
// issue's safety supervisor, triggered mid-session in virtual time on the simulated rig, checked
// four ways: the loop's end reason, the motor link's own record of what was written, the session
// log (complete, consecutive, its last motor output the zero) and the wire (what the simulated
// 1065 applies afterwards).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "../session_log/child_process.hpp"
#include "daemon_test_support.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::daemon {
namespace {

namespace fs = std::filesystem;
using sim::RigBoard;
using testing::HookedLink;
using testing::TempDir;

// The fault is injected this many session cycles in (0.8 s): the motor is being driven by then.
constexpr int kFaultCycle = 50;

// One daemon on the simulated rig in virtual time, with hooked board links.
struct Rig {
  TempDir dir;
  config::RigConfig config = testing::quiet_rig();
  RigConnection io;
  std::unique_ptr<HookedLink> motor;
  std::unique_ptr<HookedLink> encoder;
  DaemonSettings settings;
  lcm::LCM lcm{"memq://"};
  std::unique_ptr<Daemon> daemon;

  Rig() : dir("furuta-safety") {
    io = connect_rig(config, {BackendChoice::simulated, {}, /*virtual_time=*/true});
    motor = std::make_unique<HookedLink>(*io.motor_link);
    encoder = std::make_unique<HookedLink>(*io.encoder_link);
    settings = daemon_settings_from_config(config);
    settings.recorder.logs_dir = dir.path() / "logs";
    settings.recorder.motor_device = bridge::format_trace_device_line(io.motor->device_info());
    settings.recorder.encoder_device = bridge::format_trace_device_line(io.encoder->device_info());
    settings.loop.wait_when_queue_full = true;  // virtual time outruns the logger thread
    settings.loop.rest_wait_s = 5.0;            // the rest check needs a second of observation
  }
  ~Rig() { daemon.reset(); }  // before the links and the rig it drives

  sim::SimulatedRig& sim() { return *io.simulated_rig; }

  // Builds the daemon (settings are final from here) and queues the session.
  void create(const furuta::rig_command_t& start) {
    create();
    const furuta::rig_status_t reply = daemon->handle_command(start);
    ASSERT_TRUE(reply.request_accepted) << reply.request_reason;
  }
  void create() {
    daemon = std::make_unique<Daemon>(settings, *motor, *encoder, *io.clock, lcm);
    motor->watch(daemon->loop().counters());
    encoder->watch(daemon->loop().counters());
  }
  // Runs until the loop has finished the session and exited.
  void run() {
    daemon->loop().exit_when_idle();
    daemon->start();
    daemon->wait();
  }
  StopReason last_stop() const { return daemon->loop().counters().last_stop.load(); }

  // Lets the simulated board run on for a while after the loop has exited (the test thread owns
  // the clock again) and returns the duty it applies by then.
  double applied_duty_later() {
    static_cast<bridge::VirtualClock&>(*io.clock).advance_ns(200'000'000);
    sim().advance_to_now();
    const auto& truth = sim().truth();
    if (truth.empty()) return -1.0;
    // The record must be fresh, i.e. from after the loop stopped writing.
    EXPECT_GE(truth.back().generated_ns,
              io.clock->now_ns() - 2 * config.simulation.report_period_ns);
    return truth.back().applied_duty;
  }
};

struct LogExpectation {
  bool zero_write_failed = false;  // the board was gone: the zero is logged as a failed write
};

// The session log: complete and readable, consecutive samples from 0, the end record giving the
// reason, a fatal fault record for faults, the last motor output the zero command.
void expect_complete_log(const std::optional<fs::path>& path, StopReason reason,
                         const LogExpectation& expect = {}) {
  ASSERT_TRUE(path.has_value()) << "no log was finished";
  const session_log::SessionLog log = session_log::load_session_log(*path);
  EXPECT_TRUE(log.complete());
  EXPECT_EQ(log.read_stats.damaged_regions, 0u);
  EXPECT_FALSE(log.read_stats.truncated_tail);
  EXPECT_EQ(log.undecodable_events, 0u);
  ASSERT_FALSE(log.samples.empty());
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    ASSERT_EQ(log.samples[i].seq, static_cast<std::int64_t>(i));
  }
  EXPECT_TRUE(log.missing_sequence_numbers().empty());
  ASSERT_TRUE(log.end.has_value());
  EXPECT_EQ(log.end->samples, static_cast<std::int64_t>(log.samples.size()));
  const std::string name(to_string(reason));
  EXPECT_EQ(log.end->end_reason.rfind(name, 0), 0u) << log.end->end_reason;
  if (is_fault(reason)) {
    bool found = false;
    for (const auto& f : log.faults) found = found || (f.fatal && f.reason == name);
    EXPECT_TRUE(found) << "no fatal fault record " << name;
  }
  bool drove = false;
  for (const auto& s : log.samples) drove = drove || s.commanded_duty != 0.0;
  EXPECT_TRUE(drove) << "the session never drove the motor";

  const auto last = testing::last_logged_motor_write(log);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->duty_raw, 0);
  if (expect.zero_write_failed) {
    EXPECT_EQ(last->kind, +furuta::rig_usb_report_t::KIND_ERROR);
    EXPECT_EQ(last->status, "disconnected");
  } else {
    EXPECT_EQ(last->kind, +furuta::rig_usb_report_t::KIND_OUTPUT) << last->status;
  }
}

// The motor link's own record: the session's last write was the zero, nothing but zeros after.
void expect_zero_written_last(const HookedLink& motor) {
  const testing::WriteSummary w = testing::summarize_writes(motor.events());
  EXPECT_TRUE(w.drove_motor);
  EXPECT_EQ(w.last_running_duty_raw, 0);
  EXPECT_EQ(w.nonzero_after_last_running, 0);
}

// A fault injected at kFaultCycle ends the session within a few cycles (the supervisor reacts in
// the cycle that sees it; staleness needs its count of empty cycles first).
void expect_reacted_within(const HookedLink& motor, int cycles) {
  const testing::WriteSummary w = testing::summarize_writes(motor.events());
  EXPECT_GE(w.last_running_write_cycle, kFaultCycle);
  EXPECT_LE(w.last_running_write_cycle, kFaultCycle + cycles);
}

// The whole check for a fault injected from the loop thread.
void run_fault(Rig& rig, StopReason reason, int reaction_cycles, std::function<void()> fault,
               const LogExpectation& log_expect = {}, bool check_wire = true) {
  rig.create(testing::start_command("bang_bang", 0.3, 60.0));
  rig.motor->at_running_cycle(kFaultCycle, std::move(fault));
  rig.run();
  EXPECT_EQ(rig.last_stop(), reason) << to_string(rig.last_stop());
  expect_zero_written_last(*rig.motor);
  expect_reacted_within(*rig.motor, reaction_cycles);
  expect_complete_log(rig.daemon->recorder().last_log(), reason, log_expect);
  if (check_wire) {
    EXPECT_EQ(rig.applied_duty_later(), 0.0);
  }
}

TEST(SafetyPaths, ArmOutsideItsLimitStopsTheMotor) {
  Rig rig;
  // The bang-bang's switching threshold (86 deg) lies beyond this limit: the arm swings past it.
  rig.settings.loop.safety.arm_limit_rad = 1.0;
  rig.create(testing::start_command("bang_bang", 0.3, 60.0));
  rig.run();
  EXPECT_EQ(rig.last_stop(), StopReason::arm_angle_limit);
  expect_zero_written_last(*rig.motor);
  expect_complete_log(rig.daemon->recorder().last_log(), StopReason::arm_angle_limit);
  const auto log = session_log::load_session_log(*rig.daemon->recorder().last_log());
  EXPECT_GT(std::abs(log.samples.back().arm_angle_rad), 1.0);  // the sample that tripped it
  EXPECT_EQ(log.samples.back().commanded_duty, 0.0);
  for (std::size_t i = 0; i + 1 < log.samples.size(); ++i) {
    EXPECT_LE(std::abs(log.samples[i].arm_angle_rad), 1.0) << i;
  }
  EXPECT_GT(log.samples.size(), 5u);  // mid-session, not at its first cycle
  EXPECT_EQ(rig.applied_duty_later(), 0.0);
}

TEST(SafetyPaths, DutyAboveTheMaximumStopsTheMotor) {
  Rig rig;
  // A session asking for more than the supervisor allows, as a bug upstream of the loop would: the
  // command validator would refuse 0.7 (limits.max_amplitude_duty 0.5), so the request goes to the
  // loop directly. The step profile starts at zero and steps up at 0.5 s, mid-session.
  ASSERT_LT(rig.settings.loop.safety.max_duty, 0.7);
  rig.create();
  ExcitationSpec spec = rig.settings.default_excitation;
  spec.kind = ProfileKind::step;
  spec.amplitude_duty = 0.7;
  spec.duration_s = 60.0;
  spec.step_time_s = 0.5;
  SessionRequest request;
  request.excitation = Excitation(spec);
  copy_text(request.session, "duty-limit");
  ASSERT_TRUE(rig.daemon->loop().request_session(request));
  rig.run();
  EXPECT_EQ(rig.last_stop(), StopReason::duty_limit);
  // Nothing above the maximum ever reached the wire: the cycle that computed 0.7 wrote the zero.
  for (const auto& e : rig.motor->events()) {
    EXPECT_LE(e.duty_raw, std::lround(rig.settings.loop.safety.max_duty * 255.0));
  }
  const testing::WriteSummary w = testing::summarize_writes(rig.motor->events());
  EXPECT_EQ(w.last_running_duty_raw, 0);
  EXPECT_EQ(w.nonzero_after_last_running, 0);
  // The first cycle at or after the step (0.5 s) computed the duty; it wrote the zero instead.
  const auto step_seq = static_cast<int>(std::ceil(0.5e9 / rig.settings.loop.period_ns));
  EXPECT_EQ(w.last_running_write_cycle, step_seq);

  const auto path = rig.daemon->recorder().last_log();
  ASSERT_TRUE(path.has_value());
  const auto log = session_log::load_session_log(*path);
  EXPECT_TRUE(log.complete());
  ASSERT_EQ(log.samples.size(), static_cast<std::size_t>(step_seq) + 1);
  for (const auto& s : log.samples) EXPECT_EQ(s.commanded_duty, 0.0);
  EXPECT_EQ(log.end->end_reason.rfind("duty_limit", 0), 0u) << log.end->end_reason;
  const auto last = testing::last_logged_motor_write(log);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->duty_raw, 0);
  EXPECT_EQ(rig.applied_duty_later(), 0.0);
}

TEST(SafetyPaths, StaleMotorReportsStopTheMotor) {
  Rig rig;
  const int n = rig.settings.loop.safety.stale_report_cycles;
  run_fault(rig, StopReason::stale_motor_reports, n + 1,
            [&rig] { rig.sim().stall(RigBoard::motor_1065, 2'000'000'000); });
}

TEST(SafetyPaths, StaleEncoderReportsStopTheMotor) {
  Rig rig;
  const int n = rig.settings.loop.safety.stale_report_cycles;
  run_fault(rig, StopReason::stale_encoder_reports, n + 1,
            [&rig] { rig.sim().stall(RigBoard::encoder_1047, 2'000'000'000); });
}

TEST(SafetyPaths, AStuckArmEncoderStopsTheMotorWithinItsCycles) {
  // The arm limit reads the arm's count: frozen, the arm could swing to its stop unseen (at duty
  // 0.5 it covers 150 deg in 0.2 s on this rig).
  Rig rig;
  const int n = rig.settings.loop.safety.stuck_arm_cycles;
  run_fault(rig, StopReason::arm_encoder_stuck, n + 1,
            [&rig] { rig.sim().stick_encoder(RigBoard::motor_1065, true); });
  const auto log = session_log::load_session_log(*rig.daemon->recorder().last_log());
  ASSERT_GE(log.samples.size(), static_cast<std::size_t>(n + 1));
  // The last n samples carry one count: the rule fired on the n-th, not before.
  const std::int32_t frozen = log.samples.back().arm_counts;
  for (std::size_t i = log.samples.size() - n; i < log.samples.size(); ++i) {
    EXPECT_EQ(log.samples[i].arm_counts, frozen) << i;
  }
}

TEST(SafetyPaths, AStuckPendulumEncoderEndsTheSessionOnceTheArmSwingsWithoutIt) {
  Rig rig;
  const double travel = rig.settings.loop.safety.stuck_pendulum_arm_travel_rad;
  // At amplitude 0.3 the arm covers a turn in well under 2 s (125 cycles).
  run_fault(rig, StopReason::pendulum_encoder_stuck, 125,
            [&rig] { rig.sim().stick_encoder(RigBoard::encoder_1047, true); });
  const auto log = session_log::load_session_log(*rig.daemon->recorder().last_log());
  // From the last pendulum count change to the end, the arm travelled at least the limit.
  std::size_t i = log.samples.size() - 1;
  while (i > 0 && log.samples[i - 1].pendulum_counts == log.samples.back().pendulum_counts) --i;
  double swept = 0.0;
  for (std::size_t k = i + 1; k < log.samples.size(); ++k) {
    swept += std::abs(log.samples[k].arm_angle_rad - log.samples[k - 1].arm_angle_rad);
  }
  EXPECT_GE(swept, travel - 1e-9);
  EXPECT_LT(swept, travel + 0.5);  // and it fired as soon as it had
}

TEST(SafetyPaths, NoProfileAtAnyAmplitudeTripsTheStuckEncoderRules) {
  // Healthy encoders, every profile from a tenth to the full command limit: whatever ends these
  // sessions (the arm limit, for the fast ones), it is never a stuck encoder.
  for (const char* profile : {"bang_bang", "free_decay", "step", "prbs", "chirp", "multisine"}) {
    for (const double amplitude : {0.05, 0.1, 0.2, 0.3, 0.5}) {
      SCOPED_TRACE(std::string(profile) + " " + std::to_string(amplitude));
      Rig rig;
      rig.create(testing::start_command(profile, amplitude, 20.0));
      rig.run();
      const StopReason stop = rig.last_stop();
      EXPECT_NE(stop, StopReason::arm_encoder_stuck);
      EXPECT_NE(stop, StopReason::pendulum_encoder_stuck);
      EXPECT_TRUE(stop == StopReason::duration_reached || stop == StopReason::arm_angle_limit)
          << to_string(stop);
    }
  }
}

TEST(SafetyPaths, UnpluggedMotorBoardIsAUsbErrorAndTheZeroIsStillTried) {
  Rig rig;
  // The zero write fails (the board is gone) and is logged as a failed write. The wire check is
  // moot: an unplugged 1065 sends no reports, and it loses its drive with its USB power anyway.
  run_fault(
      rig, StopReason::usb_error, 1, [&rig] { rig.sim().disconnect(RigBoard::motor_1065); },
      {.zero_write_failed = true}, /*check_wire=*/false);
  const auto log = session_log::load_session_log(*rig.daemon->recorder().last_log());
  EXPECT_NE(log.end->end_reason.find("disconnected"), std::string::npos) << log.end->end_reason;
}

TEST(SafetyPaths, UnpluggedEncoderBoardIsAUsbErrorAndTheMotorGoesToZero) {
  Rig rig;
  run_fault(rig, StopReason::usb_error, 1,
            [&rig] { rig.sim().disconnect(RigBoard::encoder_1047); });
}

TEST(SafetyPaths, UnderVoltageFlagStopsTheMotor) {
  Rig rig;
  // The flag rides on the next 1065 report, delivered within a cycle or two.
  run_fault(rig, StopReason::under_voltage, 2, [&rig] { rig.sim().set_under_voltage(true); });
}

TEST(SafetyPaths, OverTemperatureFlagStopsTheMotor) {
  Rig rig;
  run_fault(rig, StopReason::over_temperature, 2, [&rig] { rig.sim().set_over_temperature(true); });
}

TEST(SafetyPaths, SupplyAboveItsRangeStopsTheMotor) {
  Rig rig;
  run_fault(rig, StopReason::supply_out_of_range, 2,
            [&rig] { rig.sim().set_supply_voltage(40.0); });
}

TEST(SafetyPaths, SupplyBelowItsRangeStopsTheMotor) {
  Rig rig;
  run_fault(rig, StopReason::supply_out_of_range, 2, [&rig] { rig.sim().set_supply_voltage(5.0); });
}

TEST(SafetyPaths, EstopCommandStopsTheMotor) {
  Rig rig;
  furuta::rig_status_t reply{};
  run_fault(rig, StopReason::estop_command, 1, [&] {
    reply = rig.daemon->handle_command(testing::simple_command(furuta::rig_command_t::KIND_ESTOP));
  });
  EXPECT_TRUE(reply.request_accepted) << reply.request_reason;
}

TEST(SafetyPaths, StopCommandStopsTheMotor) {
  Rig rig;
  furuta::rig_status_t reply{};
  run_fault(rig, StopReason::stop_command, 1, [&] {
    reply = rig.daemon->handle_command(testing::simple_command(furuta::rig_command_t::KIND_STOP));
  });
  EXPECT_TRUE(reply.request_accepted) << reply.request_reason;
}

TEST(SafetyPaths, SignalStopsTheMotor) {
  Rig rig;
  // What furutad's signal thread does on SIGINT/SIGTERM.
  run_fault(rig, StopReason::signal, 1, [&rig] { rig.daemon->stop(StopReason::signal); });
}

TEST(SafetyPaths, ExceptionInTheLoopWritesTheZeroAfterItAndIsRethrown) {
  Rig rig;
  rig.create(testing::start_command("bang_bang", 0.3, 60.0));
  rig.motor->throw_at_running_cycle(kFaultCycle);
  rig.daemon->loop().exit_when_idle();
  rig.daemon->start();
  EXPECT_THROW(rig.daemon->wait(), std::runtime_error);
  EXPECT_EQ(rig.last_stop(), StopReason::exception);

  // In the link's record: the throw, then the zero, and nothing after.
  const auto& events = rig.motor->events();
  std::ptrdiff_t threw_at = -1;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i].kind == HookedLink::Event::Kind::threw) threw_at = static_cast<std::ptrdiff_t>(i);
  }
  ASSERT_GE(threw_at, 1);
  bool nonzero_before = false;
  for (std::ptrdiff_t i = 0; i < threw_at; ++i) nonzero_before |= events[i].duty_raw != 0;
  EXPECT_TRUE(nonzero_before);
  ASSERT_EQ(events.size(), static_cast<std::size_t>(threw_at) + 2) << "one write after the throw";
  EXPECT_EQ(events.back().kind, HookedLink::Event::Kind::write);
  EXPECT_EQ(events.back().duty_raw, 0);

  expect_complete_log(rig.daemon->recorder().last_log(), StopReason::exception);
  EXPECT_EQ(rig.applied_duty_later(), 0.0);
}

TEST(SafetyPaths, StartIsRefusedWhenNoLogCouldBeCreatedAndTheMotorNeverMoves) {
  Rig rig;
  // A logs directory under a regular file can never be created.
  const fs::path blocker = rig.dir.path() / "not-a-directory";
  std::ofstream(blocker) << "x";
  rig.settings.recorder.logs_dir = blocker / "logs";
  rig.create();
  const furuta::rig_status_t reply =
      rig.daemon->handle_command(testing::start_command("bang_bang", 0.3, 60.0));
  EXPECT_FALSE(reply.request_accepted);
  EXPECT_NE(reply.request_reason.find("cannot log a session"), std::string::npos)
      << reply.request_reason;
  EXPECT_NE(reply.request_reason.find(blocker.string()), std::string::npos) << reply.request_reason;
  rig.daemon->start();
  rig.daemon->stop(StopReason::signal);
  rig.daemon->wait();
  EXPECT_FALSE(testing::summarize_writes(rig.motor->events()).drove_motor);
}

TEST(SafetyPaths, LogThatCannotBeCreatedStopsTheSessionWithTheMotorAtZero) {
  Rig rig;
  // A short queue keeps the loop within a few cycles of the logger, so the failure reaches it
  // while the session runs (virtual time would otherwise run the loop far ahead).
  rig.settings.queue_capacity = 16;
  rig.create(testing::start_command("bang_bang", 0.3, 60.0));
  // The start passed the logs directory check; the directory is replaced by a regular file before
  // the session opens its log (a race the check cannot close).
  fs::remove_all(rig.settings.recorder.logs_dir);
  std::ofstream(rig.settings.recorder.logs_dir) << "x";
  rig.run();
  EXPECT_EQ(rig.last_stop(), StopReason::log_error);
  EXPECT_FALSE(rig.daemon->recorder().last_log().has_value());
  EXPECT_NE(rig.daemon->recorder().last_fault().find("session log"), std::string::npos)
      << rig.daemon->recorder().last_fault();
  const testing::WriteSummary w = testing::summarize_writes(rig.motor->events());
  EXPECT_EQ(w.last_running_duty_raw, 0);
  EXPECT_EQ(w.nonzero_after_last_running, 0);
  EXPECT_EQ(rig.applied_duty_later(), 0.0);
}

// What the child of the disk-full test reports.
struct DiskFullReport {
  int last_stop = -1;
  int last_running_duty_raw = -1;
  int nonzero_after_last_running = -1;
  bool drove_motor = false;
  double applied_duty_later = -1.0;
  std::array<char, 160> last_fault{};
};

TEST(SafetyPaths, DiskFullMidSessionStopsTheSessionKeepsWhatWasWrittenAndZeroesTheMotor) {
  TempDir dir("furuta-diskfull");
  const fs::path logs = dir.path() / "logs";
  session_log::testing::Pipe pipe;
  // A file size limit makes the log's writes fail with EFBIG, which the writer takes as a full
  // disk; it must apply to this session only, hence the child process.
  const pid_t pid = session_log::testing::fork_child([&] {
    pipe.close_read();
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{256 * 1024, 256 * 1024};
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) return 3;
    DiskFullReport report;
    {
      Rig rig;
      rig.settings.recorder.logs_dir = logs;
      rig.settings.queue_capacity = 16;  // the failure reaches the loop while the session runs
      rig.create();
      if (!rig.daemon->handle_command(testing::start_command("bang_bang", 0.3, 60.0))
               .request_accepted) {
        return 4;
      }
      rig.run();
      report.last_stop = static_cast<int>(rig.last_stop());
      const testing::WriteSummary w = testing::summarize_writes(rig.motor->events());
      report.last_running_duty_raw = w.last_running_duty_raw;
      report.nonzero_after_last_running = w.nonzero_after_last_running;
      report.drove_motor = w.drove_motor;
      report.applied_duty_later = rig.applied_duty_later();
      copy_text(report.last_fault, rig.daemon->recorder().last_fault().c_str());
    }
    return pipe.send(report) ? 0 : 5;
  });
  pipe.close_write();
  DiskFullReport report;
  const bool got = pipe.receive(report);
  ASSERT_EQ(session_log::testing::wait_child(pid), 0);
  ASSERT_TRUE(got);
  EXPECT_EQ(static_cast<StopReason>(report.last_stop), StopReason::log_error)
      << to_string(static_cast<StopReason>(report.last_stop));
  EXPECT_NE(std::string(report.last_fault.data()).find("disk_full"), std::string::npos)
      << report.last_fault.data();
  EXPECT_TRUE(report.drove_motor);
  EXPECT_EQ(report.last_running_duty_raw, 0);
  EXPECT_EQ(report.nonzero_after_last_running, 0);
  EXPECT_EQ(report.applied_duty_later, 0.0);

  // No finished log (its end could not be written), but the partial one is recovered with its
  // readable prefix: the start record and consecutive samples from 0.
  const auto recovered = session_log::recover_partial_logs(logs);
  ASSERT_EQ(recovered.size(), 1u);
  const auto log = session_log::load_session_log(recovered[0].path);
  EXPECT_TRUE(log.start.has_value());
  EXPECT_FALSE(log.end.has_value());
  EXPECT_GT(log.samples.size(), 50u);  // the failure came mid-session
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    ASSERT_EQ(log.samples[i].seq, static_cast<std::int64_t>(i));
  }
}

// A stop or an e-stop that arrives while a start request is still waiting for the pendulum to rest
// cancels it: the session must not start afterwards.
void expect_waiting_start_cancelled(std::int8_t kind) {
  Rig rig;
  rig.create(testing::start_command("bang_bang", 0.3, 2.0));
  furuta::rig_status_t reply{};
  // Cycle 10 is well inside the one second the rest check needs.
  rig.motor->at_cycle(10,
                      [&] { reply = rig.daemon->handle_command(testing::simple_command(kind)); });
  rig.run();
  EXPECT_TRUE(reply.request_accepted) << reply.request_reason;
  EXPECT_EQ(rig.daemon->loop().counters().sessions_completed.load(), 0);
  EXPECT_FALSE(rig.daemon->recorder().last_log().has_value());
  for (const auto& e : rig.motor->events()) EXPECT_EQ(e.duty_raw, 0);
}

TEST(SafetyPaths, EstopCancelsAStartStillWaitingForRest) {
  expect_waiting_start_cancelled(furuta::rig_command_t::KIND_ESTOP);
}

TEST(SafetyPaths, StopCancelsAStartStillWaitingForRest) {
  expect_waiting_start_cancelled(furuta::rig_command_t::KIND_STOP);
}

// An e-stop is never swallowed by another stop already pending: while idle it still brakes the
// motor, in the very cycle that takes it.
TEST(SafetyPaths, EstopWhileIdleBrakesEvenWithAnotherStopPending) {
  Rig rig;
  rig.create();
  furuta::rig_status_t reply{};
  rig.motor->at_cycle(10, [&] {
    rig.daemon->loop().request_stop(StopReason::log_error);  // e.g. the logger failing late
    reply = rig.daemon->handle_command(testing::simple_command(furuta::rig_command_t::KIND_ESTOP));
  });
  rig.motor->at_cycle(20, [&] { rig.daemon->loop().exit_when_idle(); });
  rig.daemon->start();
  rig.daemon->wait();
  EXPECT_TRUE(reply.request_accepted);
  int brakes = 0;
  for (const auto& e : rig.motor->events()) {
    if (e.kind == HookedLink::Event::Kind::write && e.cycle == 10 && e.duty_raw == 0) ++brakes;
  }
  EXPECT_EQ(brakes, 1);
}

// A command limit may equal the safety limit. A duty of exactly max_duty = 0.5 used to go out as
// raw 128 (round(127.5), 0.502): past the limit by half a wire step although the supervisor, which
// sees the double, passed it. The wire now rounds down onto the limit (found writing the command
// handler fuzz target's invariant: the duty the 1065 carries never exceeds max_duty).
TEST(SafetyPaths, TheWireNeverCarriesADutyAboveTheLimit) {
  Rig rig;
  rig.settings.loop.safety.max_duty = 0.5;
  rig.settings.command_limits.max_amplitude_duty = 0.5;
  rig.create(testing::start_command("bang_bang", 0.5, 0.5));
  rig.run();
  EXPECT_EQ(rig.last_stop(), StopReason::duration_reached);
  int peak = 0;
  for (const auto& e : rig.motor->events()) {
    if (e.kind == HookedLink::Event::Kind::write) peak = std::max(peak, e.duty_raw);
  }
  EXPECT_EQ(peak, 127);  // floor(0.5 * 255): 0.498, the largest step not above 0.5
}

}  // namespace
}  // namespace furuta::daemon
