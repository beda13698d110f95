// The generated message types encode and decode through LCM itself (memq://, no network).
#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <vector>

#include "furuta/rig_command_t.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/rig_signed_command_t.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/rig_usb_report_t.hpp"

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

namespace {

template <typename Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(out.data(), 0, static_cast<int>(out.size())), static_cast<int>(out.size()));
  return out;
}

void put_i32(std::vector<std::uint8_t>& bytes, std::size_t at, std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}

furuta::rig_command_t a_command() {
  furuta::rig_command_t c{};
  c.request_id = 5;
  c.kind = furuta::rig_command_t::KIND_START_SESSION;
  c.profile = "step";
  c.label = "x";
  return c;
}

// Offset of rig_command_t.profile's length: fingerprint (8), request_id (8), kind (1).
constexpr std::size_t kProfileLength = 17;

// Found by fuzz_command_decode: lcm-gen 1.3.1 trusts string lengths and array counts. A length of 0
// threw std::length_error out of LCM's dispatch (which ended furutad), INT32_MIN overflowed and
// read far past the buffer. lcmtypes/harden_generated.cmake makes them decode errors.
TEST(LcmTypes, HostileStringLengthsAreDecodeErrors) {
  for (std::int32_t length : {0, -1, -4, INT_MIN, INT_MAX}) {
    std::vector<std::uint8_t> bytes = encoded(a_command());
    put_i32(bytes, kProfileLength, length);
    furuta::rig_command_t out;
    int used = 0;
    EXPECT_NO_THROW(used = out.decode(bytes.data(), 0, static_cast<int>(bytes.size()))) << length;
    EXPECT_EQ(used, -1) << length;
  }
  // The smallest valid string (just the NUL) still decodes.
  furuta::rig_command_t empty = a_command();
  empty.profile.clear();
  const std::vector<std::uint8_t> bytes = encoded(empty);
  furuta::rig_command_t out;
  EXPECT_EQ(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(out.profile, "");
}

// Found by fuzz_command_decode: a string with a NUL inside decoded whole, but the encoder writes
// strlen() bytes, so the message did not survive a round trip (decode(encode(m)) != m). A string
// without its terminating NUL was taken too. Both are malformed: decode errors.
TEST(LcmTypes, StringsWithANulInsideOrNoTerminatorAreDecodeErrors) {
  const std::vector<std::uint8_t> good = encoded(a_command());  // profile "step": length 5
  ASSERT_EQ(good[kProfileLength + 3], 5);
  std::vector<std::uint8_t> inside = good;
  inside[kProfileLength + 4 + 1] = 0;  // "s\0ep"
  std::vector<std::uint8_t> unterminated = good;
  unterminated[kProfileLength + 4 + 4] = 'x';  // "stepx" with no NUL
  for (const auto* bytes : {&inside, &unterminated}) {
    furuta::rig_command_t out;
    EXPECT_EQ(out.decode(bytes->data(), 0, static_cast<int>(bytes->size())), -1);
  }
  furuta::rig_command_t out;
  EXPECT_EQ(out.decode(good.data(), 0, static_cast<int>(good.size())),
            static_cast<int>(good.size()));
  EXPECT_EQ(out.profile, "step");
}

TEST(LcmTypes, NegativeArrayCountsAreDecodeErrors) {
  furuta::rig_usb_report_t report{};
  report.status = "";
  report.length = 2;
  report.bytes = {1, 2};
  std::vector<std::uint8_t> bytes = encoded(report);
  // fingerprint 8, time 8, board 1, kind 1, status length 4 + NUL 1: the count is at 23.
  bytes[23] = 0xFF;
  bytes[24] = 0xFE;  // -2
  furuta::rig_usb_report_t out;
  int used = 0;
  EXPECT_NO_THROW(used = out.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  EXPECT_EQ(used, -1);
}

// A 60-byte signed command claiming 2^31 - 1 bytes of command: refused before anything is
// allocated for it (as generated, the decoder resized to 2 GB first; found by fuzz_signed_command).
TEST(LcmTypes, ArrayCountsBeyondTheBytesLeftAreDecodeErrors) {
  furuta::rig_signed_command_t signed_command{};
  signed_command.sender = "ana@rig";
  signed_command.command_size = 1;
  signed_command.command = {7};
  std::vector<std::uint8_t> bytes = encoded(signed_command);
  // fingerprint 8, sender length 4 + "ana@rig" 7 + NUL 1, time 8, nonce 8: the count is at 36.
  ASSERT_EQ(bytes[39], 1);
  for (const std::int32_t count : {std::numeric_limits<std::int32_t>::max(), 34, 33}) {
    for (int i = 0; i < 4; ++i) bytes[36 + i] = static_cast<std::uint8_t>(count >> (24 - 8 * i));
    furuta::rig_signed_command_t out;
    int used = 0;
    EXPECT_NO_THROW(used = out.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
    EXPECT_EQ(used, -1) << count;
    EXPECT_LT(out.command.capacity(), 1024u) << count;
  }
}

struct CommandSink {
  int received = 0;
  void on_command(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_command_t*) {
    ++received;
  }
};

TEST(LcmTypes, AHostileMessageIsDroppedByATypedSubscription) {
  lcm::LCM lcm("memq://");
  CommandSink sink;
  lcm.subscribe("RIG_COMMAND", &CommandSink::on_command, &sink);
  std::vector<std::uint8_t> bytes = encoded(a_command());
  put_i32(bytes, kProfileLength, 0);
  lcm.publish("RIG_COMMAND", bytes.data(), static_cast<unsigned>(bytes.size()));
  EXPECT_NO_THROW(lcm.handleTimeout(1000));
  EXPECT_EQ(sink.received, 0);
  const std::vector<std::uint8_t> good = encoded(a_command());
  lcm.publish("RIG_COMMAND", good.data(), static_cast<unsigned>(good.size()));
  lcm.handleTimeout(1000);
  EXPECT_EQ(sink.received, 1);
}

}  // namespace
