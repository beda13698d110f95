// The daemon end to end, in virtual time: simulated rig, memq LCM, session log, replay.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <lcm/lcm-cpp.hpp>

#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/session_log/session_log.hpp"
#include "temp_dir.hpp"

namespace furuta::daemon {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

struct SampleCounter {
  std::vector<std::int64_t> seqs;
  std::vector<furuta::rig_status_t> statuses;
  void on_sample(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_sample_t* m) {
    seqs.push_back(m->seq);
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_status_t* m) {
    statuses.push_back(*m);
  }
};

furuta::rig_command_t start_command(double duration_s, double amplitude = 0.3) {
  furuta::rig_command_t c{};
  c.request_id = 7;
  c.kind = furuta::rig_command_t::KIND_START_SESSION;
  c.profile = "bang_bang";
  c.amplitude_duty = amplitude;
  c.duration_s = duration_s;
  c.label = "e2e";
  c.seed = 3;
  return c;
}

struct RunResult {
  std::optional<fs::path> log;
  std::vector<std::int64_t> published;
  StopReason stop = StopReason::none;
};

// Runs one session through a daemon on `connection` in virtual time; `during` may act mid-session.
RunResult run_session(const config::RigConfig& rig, RigConnection& connection, const fs::path& logs,
                      const furuta::rig_command_t& command,
                      const std::function<void(Daemon&)>& during = {}) {
  DaemonSettings settings = daemon_settings_from_config(rig);
  settings.recorder.logs_dir = logs;
  settings.recorder.motor_device =
      bridge::format_trace_device_line(connection.motor->device_info());
  settings.recorder.encoder_device =
      bridge::format_trace_device_line(connection.encoder->device_info());
  settings.loop.wait_when_queue_full = true;  // virtual time outruns the logger thread
  settings.loop.rest_wait_s = 5.0;            // the rest check needs a second of observation
  lcm::LCM lcm("memq://");
  SampleCounter counter;
  lcm.subscribe(session_log::kChannelSample, &SampleCounter::on_sample, &counter);
  RunResult result;
  {
    Daemon daemon(settings, *connection.motor_link, *connection.encoder_link, *connection.clock,
                  lcm);
    const furuta::rig_status_t reply = daemon.handle_command(command);
    EXPECT_TRUE(reply.request_accepted) << reply.request_reason;
    daemon.loop().exit_when_idle();
    daemon.start();
    if (during) during(daemon);
    daemon.wait();
    result.log = daemon.recorder().last_log();
    result.stop = daemon.loop().counters().last_stop.load();
  }
  // The daemon's LCM thread is gone: dispatch what it left queued in memq.
  while (lcm.handleTimeout(0) > 0) {
  }
  result.published = counter.seqs;
  return result;
}

// The duty of the last output report written to the 1065, as logged.
int last_motor_duty_raw(const session_log::SessionLog& log) {
  const bridge::UsbTrace trace =
      session_log::usb_trace_from_log(log, furuta::rig_usb_report_t::BOARD_MOTOR);
  const bridge::TraceEvent* last_out = nullptr;
  for (const auto& e : trace.events) {
    if (e.kind == bridge::TraceEventKind::output) last_out = &e;
  }
  if (!last_out) return -1;
  bridge::MotorOutput1065 out;
  if (bridge::decode_output_1065(last_out->bytes, out) != bridge::CodecStatus::ok) return -2;
  return out.duty_raw;
}

config::RigConfig shipped_rig() {
  config::RigConfig rig = config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  rig.simulation.usb_latency_jitter_ns = 1'500'000;
  rig.simulation.pendulum_angle_noise_rad = 1e-3;
  return rig;
}

TEST(DaemonEndToEnd, TenSecondBangBangSessionIsPublishedLoggedAndReplayedExactly) {
  TempDir dir;
  const config::RigConfig rig = shipped_rig();
  RigConnection live = connect_rig(rig, {BackendChoice::simulated, {}, /*virtual_time=*/true});
  const RunResult run = run_session(rig, live, dir.path() / "logs", start_command(10.0));

  EXPECT_EQ(run.stop, StopReason::duration_reached);
  // 10 s at 16 ms: 625 samples, consecutive, every one published.
  ASSERT_EQ(run.published.size(), 625u);
  for (std::size_t i = 0; i < run.published.size(); ++i) ASSERT_EQ(run.published[i], i);

  ASSERT_TRUE(run.log.has_value());
  const session_log::SessionLog log = session_log::load_session_log(*run.log);
  EXPECT_TRUE(log.complete());
  EXPECT_EQ(log.read_stats.damaged_regions, 0u);
  ASSERT_EQ(log.samples.size(), 625u);
  EXPECT_TRUE(log.missing_sequence_numbers().empty());
  EXPECT_EQ(log.end->samples, 625);
  EXPECT_EQ(log.end->end_reason, "duration_reached");
  EXPECT_EQ(log.start->profile, "bang_bang");
  EXPECT_NE(log.start->rig_config_toml.find("[simulation.parameters]"), std::string::npos);
  double arm_span = 0;
  for (const auto& s : log.samples) arm_span = std::max(arm_span, std::abs(s.arm_angle_rad));
  EXPECT_GT(arm_span, 0.5);  // the arm really moved
  EXPECT_LT(arm_span, rig.safety.arm_limit_rad);

  // The last report written to the motor is a zero command.
  EXPECT_EQ(last_motor_duty_raw(log), 0);

  // Replay the logged USB traffic through the replay backend: the same samples, exactly.
  // The replayed loop's first cycle falls on the recorded session's first deadline, and the session
  // starts there: the rest check already passed in the original (the pendulum's noise made it
  // wait).
  RigConnection replay = connect_rig(rig, {BackendChoice::replay, *run.log, /*virtual_time=*/true,
                                           log.start->monotonic_ns - log.start->period_ns});
  config::RigConfig replay_rig = rig;
  replay_rig.daemon.rest_check_s = 0.0;
  const RunResult again =
      run_session(replay_rig, replay, dir.path() / "replay-logs", start_command(10.0));
  ASSERT_TRUE(again.log.has_value());
  const session_log::SessionLog replayed = session_log::load_session_log(*again.log);
  ASSERT_EQ(replayed.samples.size(), log.samples.size()) << replayed.end->end_reason;
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const auto& a = log.samples[i];
    const auto& b = replayed.samples[i];
    SCOPED_TRACE(i);
    ASSERT_EQ(a.seq, b.seq);
    ASSERT_EQ(a.monotonic_ns, b.monotonic_ns);
    ASSERT_EQ(a.arm_counts, b.arm_counts);
    ASSERT_EQ(a.pendulum_counts, b.pendulum_counts);
    ASSERT_EQ(a.arm_angle_rad, b.arm_angle_rad);
    ASSERT_EQ(a.pendulum_angle_rad, b.pendulum_angle_rad);
    ASSERT_EQ(a.commanded_duty, b.commanded_duty);
    ASSERT_EQ(a.applied_duty, b.applied_duty);
    ASSERT_EQ(a.motor_report_host_ns, b.motor_report_host_ns);
    ASSERT_EQ(a.encoder_delta_counts, b.encoder_delta_counts);
    ASSERT_EQ(a.flags, b.flags);
  }
}

TEST(DaemonEndToEnd, AStopRequestMidSessionEndsItWithZeroLastAndAReadableLog) {
  TempDir dir;
  const config::RigConfig rig = shipped_rig();
  RigConnection live = connect_rig(rig, {BackendChoice::simulated, {}, true});
  const RunResult run = run_session(rig, live, dir.path(), start_command(60.0), [](Daemon& daemon) {
    // Wait (in real time) until the session is under way, then stop as SIGTERM does.
    while (daemon.loop().counters().state.load() != LoopState::running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    daemon.stop(StopReason::signal);
  });
  EXPECT_EQ(run.stop, StopReason::signal);
  ASSERT_TRUE(run.log.has_value());
  const session_log::SessionLog log = session_log::load_session_log(*run.log);
  EXPECT_TRUE(log.complete());
  EXPECT_LT(log.samples.size(), 3750u);  // stopped well before 60 s
  EXPECT_TRUE(log.missing_sequence_numbers().empty());
  EXPECT_EQ(log.end->end_reason.rfind("signal", 0), 0u) << log.end->end_reason;
  EXPECT_EQ(last_motor_duty_raw(log), 0);
  // On the wire: let the simulated board run on; the duty it applies has ramped to zero.
  auto& clock = static_cast<bridge::VirtualClock&>(*live.clock);
  clock.advance_ns(100'000'000);
  live.simulated_rig->advance_to_now();
  EXPECT_EQ(live.simulated_rig->truth().back().applied_duty, 0.0);
}

}  // namespace
}  // namespace furuta::daemon
