// The generated message types encode and decode through LCM itself (memq://, no network).
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include "furuta/rig_command_t.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/rig_status_t.hpp"

namespace {

struct SampleSink {
  std::vector<furuta::rig_sample_t> received;
  void on_sample(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_sample_t* msg) {
    received.push_back(*msg);
  }
};

TEST(LcmTypes, SampleWithVariableLengthReportListsRoundTripsThroughMemq) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  SampleSink sink;
  lcm.subscribe("RIG_SAMPLE", &SampleSink::on_sample, &sink);

  furuta::rig_sample_t sample{};
  sample.seq = 42;
  sample.session = "2026-11-21T10-00-00_bangbang";
  sample.arm_counts = -123456;
  sample.pendulum_angle_rad = -1.25;
  sample.n_motor_reports = 2;
  sample.motor_report_host_ns = {1000, 9000};
  sample.motor_packet_counter = {254, 255};
  sample.motor_encoder_time = {3, 27};
  sample.n_encoder_reports = 3;
  sample.encoder_report_host_ns = {2000, 10000, 18000};
  sample.encoder_packet_ticks = {96000, 96000, 96001};
  sample.encoder_delta_counts = {-5, 0, 7};
  sample.flags = furuta::rig_sample_t::FLAG_ENCODER_LOST;
  ASSERT_EQ(lcm.publish("RIG_SAMPLE", &sample), 0);
  ASSERT_GT(lcm.handleTimeout(100), 0);

  ASSERT_EQ(sink.received.size(), 1u);
  const auto& got = sink.received.front();
  EXPECT_EQ(got.seq, 42);
  EXPECT_EQ(got.session, sample.session);
  EXPECT_EQ(got.arm_counts, -123456);
  EXPECT_DOUBLE_EQ(got.pendulum_angle_rad, -1.25);
  EXPECT_EQ(got.encoder_delta_counts, sample.encoder_delta_counts);
  EXPECT_EQ(got.motor_packet_counter, sample.motor_packet_counter);
  EXPECT_EQ(got.flags, +furuta::rig_sample_t::FLAG_ENCODER_LOST);
}

TEST(LcmTypes, CommandStatusAndSessionCarryTheirConstants) {
  // lcm-gen's constants are in-class statics without definitions: compare them by value (+X).
  furuta::rig_command_t command{};
  command.kind = furuta::rig_command_t::KIND_START_SESSION;
  command.profile = "bang_bang";
  command.amplitude_duty = 0.4;
  std::vector<uint8_t> buffer(static_cast<size_t>(command.getEncodedSize()));
  ASSERT_EQ(command.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  furuta::rig_command_t decoded{};
  ASSERT_EQ(decoded.decode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  EXPECT_EQ(decoded.kind, +furuta::rig_command_t::KIND_START_SESSION);
  EXPECT_EQ(decoded.profile, "bang_bang");
  EXPECT_DOUBLE_EQ(decoded.amplitude_duty, 0.4);

  furuta::rig_status_t status{};
  status.state = furuta::rig_status_t::STATE_FAULT;
  status.last_fault = "usb: disconnected";
  EXPECT_GT(status.getEncodedSize(), 0);

  furuta::rig_session_t session{};
  session.event = furuta::rig_session_t::EVENT_END;
  session.end_reason = "duration reached";
  EXPECT_GT(session.getEncodedSize(), 0);
  // Different types must not decode as each other: LCM's fingerprint check catches it.
  std::vector<uint8_t> session_bytes(static_cast<size_t>(session.getEncodedSize()));
  session.encode(session_bytes.data(), 0, static_cast<int>(session_bytes.size()));
  furuta::rig_status_t wrong{};
  EXPECT_LT(wrong.decode(session_bytes.data(), 0, static_cast<int>(session_bytes.size())), 0);
}

}  // namespace
