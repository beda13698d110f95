// The simulated rig from two threads, and every fault it can inject.
#include <gtest/gtest.h>

#include "simulated_rig_bench.hpp"

namespace furuta::sim {
namespace {

using namespace rig_test;  // NOLINT(google-build-using-namespace): the rig tests' own helpers

// A daemon reads both boards from its loop thread while a supervisor or a test injects faults from
TEST(SimulatedRig, TransportsAndTheFaultApiWorkFromTwoThreads) {
  MonotonicClock clock;
  SimulatedRig rig({}, clock);
  auto motor = rig.make_transport();
  auto encoder = rig.make_transport();
  ASSERT_EQ(motor->open(match_1065()), TransportStatus::ok);
  ASSERT_EQ(encoder->open(match_1047()), TransportStatus::ok);
  std::atomic<bool> done{false};
  std::thread injector([&] {
    bool on = false;
    while (!done) {
      rig.set_over_temperature(on = !on);
      rig.corrupt_reports(RigBoard::encoder_1047, 1);
      (void)rig.true_state();
      (void)rig.devices();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  int motor_ok = 0;
  int encoder_ok = 0;
  UsbReport r;
  while (motor_ok < 6) {
    ASSERT_EQ(motor->read_report(r, milliseconds(200)), TransportStatus::ok);
    ++motor_ok;
    while (encoder->read_report(r, milliseconds(0)) == TransportStatus::ok) ++encoder_ok;
  }
  done = true;
  injector.join();
  EXPECT_GE(encoder_ok, 4);
}

// ---------------------------------------------------------------- faults

TEST(SimulatedRig, DroppedMotorReportsLeaveAPacketCounterGap) {
  Bench b;
  b.run_until(100 * kMs);
  b.rig.drop_reports(RigBoard::motor_1065, 2);
  b.run_until(300 * kMs);
  int gaps = 0;
  for (std::size_t i = 1; i < b.motor_reports.size(); ++i) {
    const auto step = static_cast<std::uint8_t>(decode_1065(b.motor_reports[i]).packet_counter -
                                                decode_1065(b.motor_reports[i - 1]).packet_counter);
    if (step != 1) {
      EXPECT_EQ(step, 3);  // two reports missing
      ++gaps;
    }
  }
  EXPECT_EQ(gaps, 1);
  const std::vector<TruthRecord> all = b.truth_of(RigBoard::motor_1065, false);
  EXPECT_EQ(
      std::count_if(all.begin(), all.end(), [](const TruthRecord& t) { return !t.delivered; }), 2);
}

TEST(SimulatedRig, ADroppedEncoderReportLosesItsDeltaForGood) {
  SimulatedRigConfig config = swinging();
  Bench b(config);
  b.run_until(50 * kMs);
  b.rig.drop_reports(RigBoard::encoder_1047, 1);
  b.run_until(1 * kS);
  const std::vector<TruthRecord> all = b.truth_of(RigBoard::encoder_1047, false);
  std::int64_t lost = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].delivered) continue;
    ASSERT_GT(i, 0u);
    lost += pendulum_count(config, all[i].state.q2) - pendulum_count(config, all[i - 1].state.q2);
  }
  ASSERT_NE(lost, 0) << "the pendulum should move during the dropped report";
  std::int64_t sum = 0;
  for (const Received& r : b.encoder_reports) sum += decode_1047(r).channels[0].position_delta;
  const std::int64_t truth_total =
      pendulum_count(config, all.back().state.q2) - pendulum_count(config, config.initial_state.q2);
  EXPECT_EQ(sum, truth_total - lost);
  EXPECT_EQ(b.encoder_reports.size() + 1, all.size());
}

TEST(SimulatedRig, DelayedReportsArriveLateAndInOrder) {
  Bench b;
  b.run_until(100 * kMs);
  b.rig.delay_reports(RigBoard::motor_1065, 1, 20 * kMs);
  b.run_until(300 * kMs);
  const std::vector<TruthRecord> truth = b.truth_of(RigBoard::motor_1065);
  ASSERT_EQ(truth.size(), b.motor_reports.size());
  int late = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const std::int64_t latency = b.motor_reports[i].report.host_time_ns - truth[i].generated_ns;
    if (truth[i].generated_ns == 104 * kMs) {
      EXPECT_EQ(latency, 21 * kMs);
      ++late;
    } else if (truth[i].generated_ns > 104 * kMs && truth[i].generated_ns < 125 * kMs) {
      // Queued behind the late one, delivered together with it.
      EXPECT_EQ(b.motor_reports[i].report.host_time_ns, 125 * kMs);
    } else {
      EXPECT_EQ(latency, 1 * kMs);
    }
  }
  EXPECT_EQ(late, 1);
}

TEST(SimulatedRig, TruncatedReportsComeBackShort) {
  Bench b;
  b.run_until(50 * kMs);
  b.rig.truncate_reports(RigBoard::motor_1065, 2, 10);
  b.rig.truncate_reports(RigBoard::encoder_1047, 1, 7);
  b.run_until(150 * kMs);
  int short_motor = 0;
  for (const Received& r : b.motor_reports) {
    if (r.status == TransportStatus::short_report) {
      EXPECT_EQ(r.report.length, 10u);
      ++short_motor;
    } else {
      EXPECT_EQ(r.status, TransportStatus::ok);
      EXPECT_EQ(r.report.length, 25u);
    }
  }
  EXPECT_EQ(short_motor, 2);
  int short_encoder = 0;
  for (const Received& r : b.encoder_reports) {
    if (r.status == TransportStatus::short_report) {
      EXPECT_EQ(r.report.length, 7u);
      ++short_encoder;
    }
  }
  EXPECT_EQ(short_encoder, 1);
}

TEST(SimulatedRig, CorruptedReportsDifferFromAnUndamagedTwinInAFewBits) {
  SimulatedRigConfig config = swinging();
  Bench clean(config);
  Bench damaged(config);
  clean.run_until(100 * kMs);
  damaged.run_until(100 * kMs);
  damaged.rig.corrupt_reports(RigBoard::motor_1065, 3);
  clean.run_until(400 * kMs);
  damaged.run_until(400 * kMs);
  ASSERT_EQ(clean.motor_reports.size(), damaged.motor_reports.size());
  int differing = 0;
  for (std::size_t i = 0; i < clean.motor_reports.size(); ++i) {
    const Received& a = clean.motor_reports[i];
    const Received& d = damaged.motor_reports[i];
    EXPECT_EQ(d.status, TransportStatus::ok);
    int bits = 0;
    for (std::size_t k = 0; k < a.report.length; ++k) {
      bits += std::popcount(static_cast<unsigned>(a.report.bytes[k] ^ d.report.bytes[k]));
    }
    if (bits != 0) {
      EXPECT_LE(bits, 3);
      ++differing;
    }
  }
  EXPECT_EQ(differing, 3);
  EXPECT_TRUE(same_bytes(clean.encoder_reports, damaged.encoder_reports));
}

TEST(SimulatedRig, StallHoldsReportsThenDeliversThemInABurst) {
  Bench b;
  b.run_until(100 * kMs);
  const std::size_t before = b.motor_reports.size();
  b.rig.stall(RigBoard::motor_1065, 50 * kMs);
  b.run_until(149 * kMs);
  EXPECT_EQ(b.motor_reports.size(), before);  // nothing during the stall
  b.run_until(150 * kMs);
  const std::size_t burst = b.motor_reports.size() - before;
  EXPECT_GE(burst, 6u);
  for (std::size_t i = before; i < b.motor_reports.size(); ++i) {
    EXPECT_EQ(b.motor_reports[i].report.host_time_ns, 150 * kMs);
  }
  b.run_until(300 * kMs);
  for (std::size_t i = 1; i < b.motor_reports.size(); ++i) {
    EXPECT_EQ(decode_1065(b.motor_reports[i]).packet_counter,
              static_cast<std::uint8_t>(decode_1065(b.motor_reports[i - 1]).packet_counter + 1))
        << "a stall delays, it does not lose";
  }
  // The other board carried on.
  EXPECT_GE(b.encoder_reports.size(), 35u);
}

TEST(SimulatedRig, DisconnectThenReconnectResetsTheBoard) {
  Bench b(swinging());
  ASSERT_EQ(b.command(0.3), TransportStatus::ok);
  b.run_until(1 * kS);
  b.rig.disconnect(RigBoard::motor_1065);
  b.rig.disconnect(RigBoard::encoder_1047);
  UsbReport r;
  EXPECT_EQ(b.motor->read_report(r, milliseconds(0)), TransportStatus::disconnected);
  EXPECT_EQ(b.motor->read_report(r, milliseconds(20)), TransportStatus::disconnected);
  EXPECT_EQ(b.command(0.3), TransportStatus::disconnected);
  EXPECT_EQ(b.encoder->read_report(r, milliseconds(0)), TransportStatus::disconnected);
  EXPECT_TRUE(b.rig.devices().empty());
  auto other = b.rig.make_transport();
  EXPECT_EQ(other->open(match_1065()), TransportStatus::not_found);

  b.clock.advance_ns(200 * kMs);
  b.rig.reconnect(RigBoard::motor_1065);
  b.rig.reconnect(RigBoard::encoder_1047);
  const std::int64_t reconnected_ns = b.clock.now_ns();
  const double q1_at_power_up = b.rig.true_state().q1;
  EXPECT_EQ(b.rig.devices().size(), 2u);
  // The stale handles stay dead until closed and reopened.
  EXPECT_EQ(b.motor->read_report(r, milliseconds(0)), TransportStatus::disconnected);
  b.motor->close();
  b.encoder->close();
  ASSERT_EQ(b.motor->open(match_1065()), TransportStatus::ok);
  ASSERT_EQ(b.encoder->open(match_1047()), TransportStatus::ok);
  const std::size_t motor_before = b.motor_reports.size();
  const std::size_t encoder_before = b.encoder_reports.size();
  b.run_until(b.clock.now_ns() + 100 * kMs);
  ASSERT_GT(b.motor_reports.size(), motor_before);
  const MotorReport1065 first = decode_1065(b.motor_reports[motor_before]);
  EXPECT_EQ(first.packet_counter, 0);
  EXPECT_EQ(first.applied_duty(), 0.0);
  EXPECT_EQ(first.commanded_duty(), 0.0);
  // The position restarts from zero where the arm was at power-up.
  const double cpr = arm_counts_per_rad(b.rig.config());
  for (const TruthRecord& t : b.truth_of(RigBoard::motor_1065, false)) {
    if (t.generated_ns <= reconnected_ns) continue;
    EXPECT_LE(std::abs(first.encoder_position - (t.state.q1 - q1_at_power_up) * cpr), 1.0);
    EXPECT_EQ(t.applied_duty, 0.0);  // motor off since the unplug
    break;
  }
  ASSERT_GT(b.encoder_reports.size(), encoder_before);
  for (std::size_t i = encoder_before; i < b.encoder_reports.size(); ++i) {
    const EncoderReport1047 e = decode_1047(b.encoder_reports[i]);
    EXPECT_FALSE(e.channels[0].enabled());
    EXPECT_EQ(e.channels[0].position_delta, 0);
  }
}

TEST(SimulatedRig, StuckEncoderFreezesItsCount) {
  Bench b(swinging());
  ASSERT_EQ(b.command(0.2), TransportStatus::ok);
  b.run_until(200 * kMs);
  b.rig.stick_encoder(RigBoard::motor_1065, true);
  b.rig.stick_encoder(RigBoard::encoder_1047, true);
  const std::size_t motor_from = b.motor_reports.size();
  const std::size_t encoder_from = b.encoder_reports.size();
  b.run_until(400 * kMs);
  ASSERT_GT(b.motor_reports.size(), motor_from + 20);
  const std::int32_t frozen = decode_1065(b.motor_reports[motor_from]).encoder_position;
  for (std::size_t i = motor_from; i < b.motor_reports.size(); ++i) {
    EXPECT_EQ(decode_1065(b.motor_reports[i]).encoder_position, frozen);
  }
  // The first 1047 report after sticking still carries the counts made before it stuck.
  for (std::size_t i = encoder_from + 1; i < b.encoder_reports.size(); ++i) {
    EXPECT_EQ(decode_1047(b.encoder_reports[i]).channels[0].position_delta, 0);
  }
  EXPECT_GT(std::abs(b.rig.true_state().dq1), 1.0);  // the arm kept turning
  b.rig.stick_encoder(RigBoard::motor_1065, false);
  const std::size_t resumed = b.motor_reports.size();
  b.run_until(500 * kMs);
  // Counting resumes from the frozen value: the turns while stuck are lost, not replayed.
  const std::int32_t next = decode_1065(b.motor_reports[resumed]).encoder_position;
  EXPECT_LT(std::abs(next - frozen), 200);
  EXPECT_NE(decode_1065(b.motor_reports.back()).encoder_position, frozen);
}

TEST(SimulatedRig, InjectedBoardFaultsShowInTheStatusByte) {
  Bench b;
  b.run_until(50 * kMs);
  b.rig.set_under_voltage(true);
  b.run_until(100 * kMs);
  b.rig.set_under_voltage(false);
  b.rig.set_over_temperature(true);
  b.rig.set_supply_voltage(6.5);
  b.run_until(150 * kMs);
  const std::vector<TruthRecord> truth = b.truth_of(RigBoard::motor_1065);
  ASSERT_EQ(truth.size(), b.motor_reports.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const std::uint8_t status = b.motor_reports[i].report.bytes[1];
    const MotorReport1065 m = decode_1065(b.motor_reports[i]);
    const std::int64_t g = truth[i].generated_ns;
    EXPECT_EQ((status & k1065FlagUnderVoltage) != 0, g > 50 * kMs && g <= 100 * kMs) << g;
    EXPECT_EQ((status & k1065FlagOverTemperature) != 0, g > 100 * kMs) << g;
    EXPECT_NEAR(m.supply_voltage_v(), g > 100 * kMs ? 6.5 : 12.0, 0.05);
  }
}

}  // namespace
}  // namespace furuta::sim
