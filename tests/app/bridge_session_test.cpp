// A session through the bridge on the simulated rig, recorded at the USB level, then replayed.
#include "bridge_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <sstream>
#include <utility>

#include "commands.hpp"
#include "furuta/firmware_bridge/replay_transport.hpp"
#include "furuta/firmware_bridge/simulated_rig.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::app {
namespace {

using namespace furuta::bridge;

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("furuta-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

BridgeSessionSpec spec_for(const SimulatedRigConfig& rig, double amplitude) {
  BridgeSessionSpec spec;
  spec.duration_s = 5.0;
  spec.amplitude_duty = amplitude;
  spec.switch_period_s = 0.4;
  spec.pendulum_channel = rig.pendulum_channel;
  spec.arm_encoder = {rig.motor_encoder_counts_per_rev, rig.motor.total_ratio(), 1, 0.0};
  spec.pendulum_encoder = {rig.pendulum_encoder_counts_per_rev, 1.0, 1, 0.0};
  return spec;
}

struct Recorded {
  BridgeSessionResult result;
  UsbTrace motor, encoder;
};

// A virtual clock that runs an action once, when time first passes a given instant: faults in the
// middle of a session without reaching into the session loop.
class ClockWithAction final : public Clock {
 public:
  explicit ClockWithAction(std::int64_t start_ns) : clock_(start_ns) {}
  std::int64_t now_ns() const override { return clock_.now_ns(); }
  void sleep_until_ns(std::int64_t deadline_ns) override {
    clock_.sleep_until_ns(deadline_ns);
    if (action_ && clock_.now_ns() >= action_at_ns_) std::exchange(action_, nullptr)();
  }
  void at(std::int64_t when_ns, std::function<void()> action) {
    action_at_ns_ = when_ns;
    action_ = std::move(action);
  }

 private:
  VirtualClock clock_;
  std::int64_t action_at_ns_ = 0;
  std::function<void()> action_;
};

Recorded record_session(const SimulatedRigConfig& config, const BridgeSessionSpec& spec,
                        bool drop_some = false) {
  ClockWithAction clock(1'000'000'000);
  SimulatedRig rig(config, clock);
  RecordingTransport motor(rig.make_transport(), clock);
  RecordingTransport encoder(rig.make_transport(), clock);
  EXPECT_EQ(motor.open({kPhidgetsVendorId, kProductMotorControl1065, {}}), TransportStatus::ok);
  EXPECT_EQ(encoder.open({kPhidgetsVendorId, kProductEncoder1047, {}}), TransportStatus::ok);
  if (drop_some) {
    clock.at(3'000'000'000, [&rig] {
      rig.drop_reports(RigBoard::motor_1065, 3);
      rig.drop_reports(RigBoard::encoder_1047, 2);
    });
  }
  Recorded r;
  r.result = run_bridge_session(motor, encoder, clock, spec);
  motor.close();  // records END: the replay then times out where the live session did
  encoder.close();
  r.motor = motor.trace();
  r.encoder = encoder.trace();
  return r;
}

BridgeSessionResult replay(const UsbTrace& motor_trace, const UsbTrace& encoder_trace,
                           const BridgeSessionSpec& spec, std::size_t* mismatches = nullptr) {
  VirtualClock clock(1'000'000'000);
  ReplayTransport motor(motor_trace, clock);
  ReplayTransport encoder(encoder_trace, clock);
  EXPECT_EQ(motor.open({kPhidgetsVendorId, kProductMotorControl1065, {}}), TransportStatus::ok);
  EXPECT_EQ(encoder.open({kPhidgetsVendorId, kProductEncoder1047, {}}), TransportStatus::ok);
  BridgeSessionResult result = run_bridge_session(motor, encoder, clock, spec);
  if (mismatches) *mismatches = motor.mismatches().size() + encoder.mismatches().size();
  return result;
}

SimulatedRigConfig noisy_rig() {
  SimulatedRigConfig config;
  config.seed = 7;
  config.pendulum_angle_noise_rad = 2e-3;
  config.arm_angle_noise_rad = 1e-4;
  config.usb_latency_jitter_ns = 2'000'000;
  return config;
}

TEST(BridgeSession, ABangBangSessionMovesTheArmAndTheRigTracksItsCommands) {
  const SimulatedRigConfig config = noisy_rig();
  const Recorded r = record_session(config, spec_for(config, 0.3));
  EXPECT_EQ(r.result.transport_errors, 0) << r.result.stop_reason;
  ASSERT_EQ(r.result.samples.size(), 313u);  // 5 s / 16 ms
  double arm_span = 0, pendulum_span = 0;
  int motor_reports = 0;
  for (const auto& s : r.result.samples) {
    arm_span = std::max(arm_span, std::abs(s.arm_angle_rad));
    pendulum_span = std::max(pendulum_span, std::abs(s.pendulum_angle_rad));
    motor_reports += s.motor_reports;
  }
  EXPECT_GT(arm_span, 0.3);                 // the arm swings under +-30 % duty
  EXPECT_GT(pendulum_span, 0.05);           // and the pendulum follows
  EXPECT_NEAR(motor_reports, 5000 / 8, 2);  // one 1065 report per 8 ms, none lost
  EXPECT_EQ(r.result.samples.back().motor_lost_total, 0);
}

TEST(BridgeSession, AReplayOfTheRecordedSessionReproducesTheDecodedValuesExactly) {
  const SimulatedRigConfig config = noisy_rig();
  const BridgeSessionSpec spec = spec_for(config, 0.3);
  const Recorded r = record_session(config, spec);

  // Through the trace file format, not just in memory.
  TempDir dir;
  write_usb_trace(dir.path / "motor.trace", r.motor);
  write_usb_trace(dir.path / "encoder.trace", r.encoder);
  std::size_t mismatches = 99;
  const BridgeSessionResult replayed =
      replay(read_usb_trace(dir.path / "motor.trace"), read_usb_trace(dir.path / "encoder.trace"),
             spec, &mismatches);
  EXPECT_EQ(mismatches, 0u);
  ASSERT_EQ(replayed.samples.size(), r.result.samples.size());
  for (std::size_t i = 0; i < replayed.samples.size(); ++i) {
    ASSERT_EQ(replayed.samples[i], r.result.samples[i]) << "cycle " << i;
  }
}

TEST(BridgeSession, LostReportsAreCountedLiveAndAgainInTheReplay) {
  const SimulatedRigConfig config = noisy_rig();
  const BridgeSessionSpec spec = spec_for(config, 0.3);
  const Recorded r = record_session(config, spec, /*drop_some=*/true);
  EXPECT_EQ(r.result.samples.back().motor_lost_total, 3);
  EXPECT_EQ(r.result.samples.back().encoder_lost_total, 2);
  const BridgeSessionResult replayed = replay(r.motor, r.encoder, spec);
  EXPECT_EQ(replayed.samples, r.result.samples);
}

TEST(BridgeSession, AReplayDrivenWithDifferentCommandsReportsTheMismatch) {
  const SimulatedRigConfig config = noisy_rig();
  const Recorded r = record_session(config, spec_for(config, 0.3));
  std::size_t mismatches = 0;
  replay(r.motor, r.encoder, spec_for(config, 0.5), &mismatches);
  EXPECT_GT(mismatches, 0u);
}

TEST(SimulateCommand, WritesTheSessionAndConfirmsTheReplay) {
  TempDir dir;
  SimulateOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.output_dir = dir.path / "session";
  options.duration_s = 3.0;
  std::ostringstream out, err;
  EXPECT_EQ(run_simulate_command(options, out, err), 0) << out.str() << err.str();
  EXPECT_NE(out.str().find("identical decoded values"), std::string::npos) << out.str();
  EXPECT_TRUE(std::filesystem::exists(options.output_dir / "samples.csv"));
  EXPECT_GT(std::filesystem::file_size(options.output_dir / "motor_1065.trace"), 10'000u);
  EXPECT_GT(std::filesystem::file_size(options.output_dir / "encoder_1047.trace"), 10'000u);
}

}  // namespace
}  // namespace furuta::app
