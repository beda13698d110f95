// The boards' role adapters (board_roles.hpp): each reads what its codec decodes, in units, with
// its loss detection; writes never exceed the duty limit; the registry makes them by name.
#include "furuta/firmware_bridge/board_roles.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"

namespace furuta::bridge {
namespace {

std::array<std::uint8_t, 32> motor_report(std::uint8_t counter, std::uint8_t flags = 0) {
  MotorReport1065 r;
  r.status_flags = flags;
  r.current_raw = 1000;
  r.supply_raw = supply_raw_from_v(12.0);
  r.encoder_position = -123456;
  r.encoder_time_raw = 777;
  r.applied_duty_raw = 51;
  r.status_flags |= k1065FlagActualDirection;
  r.packet_counter = counter;
  std::array<std::uint8_t, 32> bytes{};
  EXPECT_EQ(encode_input_1065(r, bytes), CodecStatus::ok);
  return bytes;
}

TEST(BoardRoles, TheMotorAdapterReadsWhatTheCodecDecodesInUnits) {
  auto board = make_motor_board("1065", {}, {});
  const auto bytes = motor_report(7);
  MotorReport1065 decoded;
  ASSERT_EQ(decode_input_1065(bytes, decoded), CodecStatus::ok);
  const std::optional<MotorReading> m = board->read(bytes, 42);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->host_ns, 42);
  EXPECT_EQ(m->position_counts, -123456);
  EXPECT_DOUBLE_EQ(m->applied_duty, decoded.applied_duty());
  EXPECT_DOUBLE_EQ(m->applied_duty, 0.2);
  EXPECT_DOUBLE_EQ(m->current_a, decoded.motor_current_a());
  EXPECT_DOUBLE_EQ(m->supply_v, decoded.supply_voltage_v());
  EXPECT_EQ(m->report_counter, 7u);
  EXPECT_EQ(m->board_time, 777u);
  EXPECT_FALSE(m->over_temperature);
  EXPECT_FALSE(m->under_voltage);
  EXPECT_EQ(m->lost_before, 0);
  // Too short to be a report: nothing read.
  EXPECT_FALSE(board->read(std::span(bytes).first(10), 43));
}

TEST(BoardRoles, OnlyTheProtectionBitsOfTheMotorBoardAreFaults) {
  auto board = make_motor_board("1065", {}, {});
  std::uint8_t counter = 0;
  EXPECT_TRUE(board->read(motor_report(counter++, k1065FlagOverTemperature), 0)->over_temperature);
  EXPECT_TRUE(board->read(motor_report(counter++, k1065FlagUnderVoltage), 0)->under_voltage);
  for (std::uint8_t flag : {0x04, 0x08, 0x10, 0x20, 0x40, 0x80, 0xFC}) {
    const auto m = board->read(motor_report(counter++, flag), 0);
    ASSERT_TRUE(m);
    EXPECT_FALSE(m->over_temperature || m->under_voltage) << static_cast<int>(flag);
    EXPECT_EQ(m->status_flags & flag, flag);  // logged as they came
  }
}

TEST(BoardRoles, AGapInTheMotorBoardsCounterIsCountedAndRestartForgetsIt) {
  auto board = make_motor_board("1065", {}, {});
  EXPECT_EQ(board->read(motor_report(10), 0)->lost_before, 0);
  EXPECT_EQ(board->read(motor_report(13), 0)->lost_before, 2);
  board->restart();
  EXPECT_EQ(board->read(motor_report(200), 0)->lost_before, 0);
}

TEST(BoardRoles, TheMotorAdapterNeverWritesAboveItsDutyLimit) {
  auto board = make_motor_board("1065", {}, {.max_duty = 0.6, .acceleration_pct_per_s = 0});
  std::array<std::uint8_t, 8> report{};
  ASSERT_TRUE(board->write({0.6, 0.0}, report));
  MotorOutput1065 out;
  ASSERT_EQ(decode_output_1065(report, out), CodecStatus::ok);
  EXPECT_LE(out.duty_cycle(), 0.6);
  EXPECT_EQ(out.acceleration_pct_per_s(), k1065FullScaleAccelerationPctPerS);  // 0: the fastest
  EXPECT_FALSE(board->write({std::nan(""), 0.0}, report));
  EXPECT_FALSE(board->write({0.1, 0.0}, std::span(report).first(2)));
  // Just above a step's midpoint rounds up on the wire, onto the limit's step at most.
  auto loose = make_motor_board("1065", {}, {.max_duty = 0.5, .acceleration_pct_per_s = 0});
  ASSERT_TRUE(loose->write({0.5, 0.0}, report));
  ASSERT_EQ(decode_output_1065(report, out), CodecStatus::ok);
  EXPECT_LE(out.duty_cycle(), 0.5);
  EXPECT_GT(out.duty_cycle(), 0.49);
}

TEST(BoardRoles, AWrittenCommandReadsBackAsTheBoardTakesIt) {
  auto board = make_motor_board("1065", {}, {.max_duty = 1.0, .acceleration_pct_per_s = 625});
  std::array<std::uint8_t, 8> report{};
  ASSERT_TRUE(board->write({-0.4, 0.5}, report));
  const std::optional<MotorWrite> w = board->read_write(report);
  ASSERT_TRUE(w);
  EXPECT_NEAR(w->duty, -0.4, 0.5 / 255);
  EXPECT_NEAR(w->braking_fraction, 0.5, 0.5 / 255);
  EXPECT_NEAR(w->acceleration_pct_per_s, 625, 6250.0 / 255);
  // A raw acceleration of 0 (never sent) is the slowest ramp the wire can say, not a frozen duty.
  MotorOutput1065 frozen;
  frozen.duty_raw = 100;
  frozen.acceleration_raw = 0;
  ASSERT_EQ(encode_output_1065(frozen, report), CodecStatus::ok);
  EXPECT_DOUBLE_EQ(board->read_write(report)->acceleration_pct_per_s, 6250.0 / 255);
}

TEST(BoardRoles, TheMotorAdaptersResolutionIsOneStepOfItsReadings) {
  auto board = make_motor_board("1065", {}, {});
  const MotorResolution step = board->resolution();
  EXPECT_DOUBLE_EQ(step.duty_step, 1.0 / 255.0);
  EXPECT_DOUBLE_EQ(step.supply_step_v, 80.0 / 2048.0);
  // Every reading it gives is a whole number of those steps.
  for (std::uint8_t counter = 0; counter < 5; ++counter) {
    const auto m = board->read(motor_report(counter), 0);
    ASSERT_TRUE(m);
    const double duty_steps = m->applied_duty / step.duty_step;
    const double supply_steps = m->supply_v / step.supply_step_v;
    EXPECT_NEAR(duty_steps, std::round(duty_steps), 1e-9);
    EXPECT_NEAR(supply_steps, std::round(supply_steps), 1e-9);
  }
}

TEST(BoardRoles, TheEncoderAdapterReadsItsChannelAndEnablesIt) {
  EncoderReport1047 r;
  r.channels[2].position_delta = -17;
  r.channels[2].packet_time_ticks = 96000;
  r.channels[2].flags = k1047FlagEnabledEcho;
  r.channels[0].position_delta = 5;
  std::array<std::uint8_t, 64> bytes{};
  ASSERT_EQ(encode_input_1047(r, bytes), CodecStatus::ok);
  DeviceInfo device;
  device.firmware_version = 101;
  auto board = make_encoder_board("1047", device, 2);
  const std::optional<EncoderReading> e = board->read(bytes, 99);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->host_ns, 99);
  EXPECT_EQ(e->delta_counts, -17);
  EXPECT_EQ(e->board_ticks, 96000u);
  EXPECT_EQ(e->flags, k1047FlagEnabledEcho);
  std::array<std::uint8_t, 8> enable{};
  ASSERT_EQ(board->enable(enable), k1047OutputReportBytes);
  std::uint8_t mask = 0;
  ASSERT_EQ(decode_output_1047(enable, mask), CodecStatus::ok);
  EXPECT_EQ(mask, 1u << 2);
  EXPECT_THROW(make_encoder_board("1047", device, 4), std::invalid_argument);
}

TEST(BoardRoles, AnUnknownBoardIsRefusedNamingTheKnownOnesAndANewOneCanBeAdded) {
  try {
    make_encoder_board("9999", {}, 0);
    FAIL() << "an unknown board was made";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no encoder board '9999' (known: 1047"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(register_encoder_board(
      "1047",
      {.make = [](const DeviceInfo&, int) -> std::unique_ptr<EncoderBoard> { return nullptr; },
       .usb = {}}));
  EXPECT_FALSE(register_motor_board("board-roles-test-no-maker", {}));
  MotorBoardKind kind = motor_board_kind("1065");
  kind.make = [](const DeviceInfo&, const MotorBoardSettings& s) {
    return make_motor_board("1065", {}, s);
  };
  kind.usb.product_id = 0x7777;
  EXPECT_TRUE(register_motor_board("board-roles-test", kind));
  const auto kinds = motor_board_kinds();
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "board-roles-test"), kinds.end());
  EXPECT_TRUE(make_motor_board("board-roles-test", {}, {})->read(motor_report(1), 0));
  EXPECT_EQ(motor_board_kind("board-roles-test").usb.product_id, 0x7777);
  EXPECT_EQ(motor_board_kind("1065").usb.product_id, kProductMotorControl1065);
  EXPECT_EQ(encoder_board_kind("1047").usb.product_id, kProductEncoder1047);
  EXPECT_EQ(motor_board_kind("1065").max_acceleration_pct_per_s, k1065FullScaleAccelerationPctPerS);
}

}  // namespace
}  // namespace furuta::bridge
