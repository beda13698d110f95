#pragma once
// The simulated rig on virtual time with both boards open, polled as a host loop would: shared by
// the rig's tests (simulated_rig_test.cpp: protocol, physics, determinism;
// simulated_rig_faults_test.cpp: threads and injected faults).

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <thread>
#include <vector>

#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::sim::rig_test {

using namespace bridge;  // NOLINT(google-build-using-namespace): the boards' types and codecs

using std::chrono::milliseconds;
constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kS = 1'000'000'000;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

inline DeviceMatch match_1065() {
  return DeviceMatch{kPhidgetsVendorId, kProductMotorControl1065, {}};
}
inline DeviceMatch match_1047() {
  return DeviceMatch{kPhidgetsVendorId, kProductEncoder1047, {}};
}

struct Received {
  TransportStatus status = TransportStatus::ok;
  UsbReport report;
};

// A rig on virtual time with both boards open, polled like a host loop would.
struct Bench {
  explicit Bench(SimulatedRigConfig config = {}, bool enable_pendulum = true)
      : clock(0), rig(std::move(config), clock) {
    motor = rig.make_transport();
    encoder = rig.make_transport();
    EXPECT_EQ(motor->open(match_1065()), TransportStatus::ok);
    EXPECT_EQ(encoder->open(match_1047()), TransportStatus::ok);
    if (enable_pendulum) {
      EXPECT_EQ(enable(static_cast<std::uint8_t>(1u << rig.config().pendulum_channel)),
                TransportStatus::ok);
    }
  }

  TransportStatus enable(std::uint8_t mask) {
    std::uint8_t byte = 0;
    EXPECT_EQ(encode_output_1047(mask, {&byte, 1}), CodecStatus::ok);
    return encoder->write_report({&byte, 1});
  }

  TransportStatus command(double duty, double accel = k1065FullScaleAccelerationPctPerS,
                          double braking = 0.0) {
    MotorCommand1065 c;
    c.duty_cycle = duty;
    c.acceleration_pct_per_s = accel;
    c.braking_fraction = braking;
    MotorOutput1065 out;
    EXPECT_EQ(to_output_1065(c, out), CodecStatus::ok);
    std::vector<std::uint8_t> bytes(rig.config().output_report_bytes_1065);
    EXPECT_EQ(encode_output_1065(out, bytes), CodecStatus::ok);
    return motor->write_report(bytes);
  }

  // Moves virtual time to `until_ns` in `step_ns` steps, draining both boards at each step.
  void run_until(std::int64_t until_ns, std::int64_t step_ns = kMs) {
    while (clock.now_ns() < until_ns) {
      clock.advance_ns(std::min(step_ns, until_ns - clock.now_ns()));
      drain();
    }
  }
  void drain() {
    drain_one(*motor, motor_reports);
    drain_one(*encoder, encoder_reports);
  }
  static void drain_one(Transport& t, std::vector<Received>& into) {
    for (;;) {
      Received r;
      r.status = t.read_report(r.report, std::chrono::nanoseconds(0));
      if (r.status == TransportStatus::timeout || r.status == TransportStatus::disconnected ||
          r.status == TransportStatus::not_open) {
        return;
      }
      into.push_back(r);
    }
  }

  std::vector<TruthRecord> truth_of(RigBoard board, bool delivered_only = true) const {
    std::vector<TruthRecord> out;
    for (const TruthRecord& t : rig.truth()) {
      if (t.board == board && (t.delivered || !delivered_only)) out.push_back(t);
    }
    return out;
  }

  VirtualClock clock;
  SimulatedRig rig;
  std::unique_ptr<Transport> motor;
  std::unique_ptr<Transport> encoder;
  std::vector<Received> motor_reports;
  std::vector<Received> encoder_reports;
};

inline MotorReport1065 decode_1065(const Received& r) {
  MotorReport1065 m;
  EXPECT_EQ(decode_input_1065(r.report.view(), m), CodecStatus::ok);
  return m;
}

inline EncoderReport1047 decode_1047(const Received& r) {
  EncoderReport1047 e;
  EXPECT_EQ(decode_input_1047(r.report.view(), e), CodecStatus::ok);
  return e;
}

inline double arm_counts_per_rad(const SimulatedRigConfig& c) {
  return c.motor_encoder_counts_per_rev * c.motor.total_ratio() / kTwoPi;
}
inline double pendulum_counts_per_rad(const SimulatedRigConfig& c) {
  return c.pendulum_encoder_counts_per_rev / kTwoPi;
}
inline std::int64_t pendulum_count(const SimulatedRigConfig& c, double q2) {
  return static_cast<std::int64_t>(std::floor(q2 * pendulum_counts_per_rad(c)));
}

inline SimulatedRigConfig swinging() {
  SimulatedRigConfig c;
  c.initial_state.q2 = 0.6;
  return c;
}

// ---------------------------------------------------------------- timing and contents

// Whether two runs delivered the same reports, byte for byte and at the same times.
inline bool same_bytes(const std::vector<Received>& a, const std::vector<Received>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].report.length != b[i].report.length ||
        a[i].report.host_time_ns != b[i].report.host_time_ns ||
        !std::equal(a[i].report.bytes.begin(), a[i].report.bytes.begin() + a[i].report.length,
                    b[i].report.bytes.begin())) {
      return false;
    }
  }
  return true;
}

}  // namespace furuta::sim::rig_test
