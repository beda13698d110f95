#include "furuta/firmware_bridge/codec_1065.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace furuta::bridge {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void expect_same(const MotorReport1065& a, const MotorReport1065& b) {
  EXPECT_EQ(a.digital_inputs, b.digital_inputs);
  EXPECT_EQ(a.status_flags, b.status_flags);
  EXPECT_EQ(a.current_raw, b.current_raw);
  EXPECT_EQ(a.analog_raw[0], b.analog_raw[0]);
  EXPECT_EQ(a.analog_raw[1], b.analog_raw[1]);
  EXPECT_EQ(a.supply_raw, b.supply_raw);
  EXPECT_EQ(a.back_emf_plus_raw, b.back_emf_plus_raw);
  EXPECT_EQ(a.back_emf_minus_raw, b.back_emf_minus_raw);
  EXPECT_EQ(a.encoder_position, b.encoder_position);
  EXPECT_EQ(a.encoder_time_raw, b.encoder_time_raw);
  EXPECT_EQ(a.applied_duty_raw, b.applied_duty_raw);
  EXPECT_EQ(a.commanded_duty_raw, b.commanded_duty_raw);
  EXPECT_EQ(a.acceleration_raw, b.acceleration_raw);
  EXPECT_EQ(a.braking_raw, b.braking_raw);
  EXPECT_EQ(a.packet_counter, b.packet_counter);
}

// ---------------------------------------------------------------- output report (host -> board)

TEST(Codec1065Output, NegativeDutyWithBackEmfSensingAndFullAcceleration) {
  MotorCommand1065 command;
  command.duty_cycle = -0.375;  // -37.5 %: round(37.5 * 255 / 100) = round(95.625) = 96 = 0x60
  command.acceleration_pct_per_s = 6250.0;  // round(6250 / 6250 * 255) = 255 = 0xff
  command.braking_fraction = 0.0;           // 0
  command.back_emf_sensing = true;          // flags 0x02, direction bit clear (negative)
  MotorOutput1065 output;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);

  // A longer output report than the minimum: the tail must be zeroed, not left as it was.
  std::array<std::uint8_t, 8> report;
  report.fill(0xAA);
  ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
  const std::array<std::uint8_t, 8> expected = {0x02, 0x60, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x00};
  EXPECT_EQ(report, expected);
}

TEST(Codec1065Output, PositiveDutyRoundsHalvesUpAndSetsDirection) {
  MotorCommand1065 command;
  command.duty_cycle = 0.5;                 // round(50 * 255 / 100) = round(127.5) = 128 = 0x80
  command.acceleration_pct_per_s = 3125.0;  // round(3125 / 6250 * 255) = round(127.5) = 128 = 0x80
  command.braking_fraction = 0.25;          // round(25 * 255 / 100) = round(63.75) = 64 = 0x40
  command.ratiometric = true;               // 0x04, plus direction 0x01 -> 0x05
  MotorOutput1065 output;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  std::array<std::uint8_t, 4> report{};
  ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
  EXPECT_EQ(report, (std::array<std::uint8_t, 4>{0x05, 0x80, 0x80, 0x40}));
}

TEST(Codec1065Output, RangeEndsAndTinyDuties) {
  MotorCommand1065 command;
  command.duty_cycle = 1.0;                // 255 = 0xff, positive
  command.acceleration_pct_per_s = 24.51;  // the vendor's smallest: round(24.51 / 6250 * 255) = 1
  command.braking_fraction = 1.0;          // 255
  MotorOutput1065 output;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  std::array<std::uint8_t, 4> report{};
  ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
  EXPECT_EQ(report, (std::array<std::uint8_t, 4>{0x01, 0xFF, 0x01, 0xFF}));

  command = {};
  command.duty_cycle = -1.0;  // 255, negative: flags 0x00
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
  EXPECT_EQ(report, (std::array<std::uint8_t, 4>{0x00, 0xFF, 0xFF, 0x00}));

  // 0.19 % -> round(0.19 * 255 / 100) = round(0.4845) = 0; 0.2 % -> round(0.51) = 1.
  command.duty_cycle = 0.0019;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  EXPECT_EQ(output.duty_raw, 0);
  command.duty_cycle = -0.002;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  EXPECT_EQ(output.duty_raw, 1);
  EXPECT_EQ(output.flags & k1065OutDirectionPositive, 0);
}

// libphidget21 2.1.8 cphidgetmotorcontrol.c:634-651 (makePacket, 1065 branch): `if (motorSpeed >=
// 0) { velocity = round(speed * 255 / 100); dir = 1; }`, and buffer[0] = dir | 0x04 (ratiometric)
// | 0x02 (back-EMF). So a stop at full acceleration, ratiometric off, is 01 00 ff 00; -0.0 compares
// equal to 0 in C and goes out the same.
TEST(Codec1065Output, ZeroDutySetsTheDirectionBitAsTheVendorDoes) {
  for (const double zero : {0.0, -0.0}) {
    MotorCommand1065 command;
    command.duty_cycle = zero;
    MotorOutput1065 output;
    ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
    std::array<std::uint8_t, 4> report{};
    ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
    EXPECT_EQ(report, (std::array<std::uint8_t, 4>{0x01, 0x00, 0xFF, 0x00})) << zero;
    EXPECT_EQ(output.duty_cycle(), 0.0);
    EXPECT_FALSE(std::signbit(output.duty_cycle()));

    command.ratiometric = true;
    command.back_emf_sensing = true;
    ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
    ASSERT_EQ(encode_output_1065(output, report), CodecStatus::ok);
    EXPECT_EQ(report, (std::array<std::uint8_t, 4>{0x07, 0x00, 0xFF, 0x00})) << zero;
  }
  // A duty that rounds to raw 0 keeps its sign's bit, as the vendor's `speed >= 0` test does.
  MotorCommand1065 tiny;
  tiny.duty_cycle = -0.0019;
  MotorOutput1065 output;
  ASSERT_EQ(to_output_1065(tiny, output), CodecStatus::ok);
  EXPECT_EQ(output.flags, 0x00);
  EXPECT_EQ(output.duty_raw, 0);
}

// libphidget21 2.1.8 cphidgetmotorcontrol.c:84 sets the 1065's accelerationMin to
// round_double(100 / 4.08, 2) = 24.51 %/s, and the setter (:727, TESTRANGE(accelerationMin,
// accelerationMax)) refuses anything below it: raw 0 ("never ramp") is never sent.
TEST(Codec1065Output, AccelerationBelowTheVendorsMinimumIsRefused) {
  MotorCommand1065 command;
  MotorOutput1065 output;
  for (const double refused : {0.0, 1.0, 12.0, 24.5, 24.509, 6250.0 / 255.0}) {
    command.acceleration_pct_per_s = refused;
    EXPECT_EQ(to_output_1065(command, output), CodecStatus::out_of_range) << refused;
  }
  command.acceleration_pct_per_s = k1065MinAccelerationPctPerS;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  EXPECT_EQ(output.acceleration_raw, 1);  // round(24.51 * 255 / 6250) = round(1.00001) = 1
  command.acceleration_pct_per_s = 6250.0;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  EXPECT_EQ(output.acceleration_raw, 255);
}

TEST(Codec1065Output, RejectsWhatTheWireCannotCarryAndLeavesTheOutputAlone) {
  const MotorOutput1065 sentinel{0x07, 0x11, 0x22, 0x33};
  auto rejected = [&](MotorCommand1065 command) {
    MotorOutput1065 output = sentinel;
    const CodecStatus status = to_output_1065(command, output);
    const bool untouched = output.flags == sentinel.flags && output.duty_raw == sentinel.duty_raw &&
                           output.acceleration_raw == sentinel.acceleration_raw &&
                           output.braking_raw == sentinel.braking_raw;
    return status == CodecStatus::out_of_range && untouched;
  };
  MotorCommand1065 c;
  c.duty_cycle = kNaN;
  EXPECT_TRUE(rejected(c));
  c.duty_cycle = 1.0001;
  EXPECT_TRUE(rejected(c));
  c.duty_cycle = -1.5;
  EXPECT_TRUE(rejected(c));
  c.duty_cycle = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(rejected(c));

  c = {};
  c.acceleration_pct_per_s = -1.0;
  EXPECT_TRUE(rejected(c));
  c.acceleration_pct_per_s = 6250.1;
  EXPECT_TRUE(rejected(c));
  c.acceleration_pct_per_s = kNaN;
  EXPECT_TRUE(rejected(c));

  c = {};
  c.braking_fraction = -0.01;
  EXPECT_TRUE(rejected(c));
  c.braking_fraction = 1.01;
  EXPECT_TRUE(rejected(c));
  c.braking_fraction = kNaN;
  EXPECT_TRUE(rejected(c));
}

TEST(Codec1065Output, ShortBuffers) {
  std::array<std::uint8_t, 3> three{};
  EXPECT_EQ(encode_output_1065(MotorOutput1065{}, three), CodecStatus::buffer_too_small);
  MotorOutput1065 decoded;
  EXPECT_EQ(decode_output_1065(three, decoded), CodecStatus::too_short);
}

TEST(Codec1065Output, DecodesBytesAndConvertsUnits) {
  // flags 0x00 (negative), duty 0x60 = 96, acceleration 0x80 = 128, braking 0x40 = 64; the tail of
  // a longer report is ignored.
  const Bytes report = {0x00, 0x60, 0x80, 0x40, 0x99};
  MotorOutput1065 output;
  ASSERT_EQ(decode_output_1065(report, output), CodecStatus::ok);
  EXPECT_EQ(output.flags, 0x00);
  EXPECT_EQ(output.duty_raw, 96);
  EXPECT_EQ(output.acceleration_raw, 128);
  EXPECT_EQ(output.braking_raw, 64);
  EXPECT_DOUBLE_EQ(output.duty_cycle(), -96.0 / 255.0);                   // -0.37647
  EXPECT_DOUBLE_EQ(output.acceleration_pct_per_s(), 128.0 * 6250 / 255);  // 3137.25 %/s
  EXPECT_DOUBLE_EQ(output.braking_fraction(), 64.0 / 255.0);              // 0.25098

  const Bytes positive = {0x01, 0xFF, 0x00, 0x00};
  ASSERT_EQ(decode_output_1065(positive, output), CodecStatus::ok);
  EXPECT_DOUBLE_EQ(output.duty_cycle(), 1.0);
}

TEST(Codec1065Output, RoundTrips) {
  for (int duty = 0; duty <= 255; ++duty) {
    for (std::uint8_t flags : {0x00, 0x01, 0x02, 0x07}) {
      // Acceleration raw 0 and 1 read back below the vendor's 24.51 %/s minimum (1 is
      // 24.5098 %/s), which the command refuses; every raw value from 2 up round-trips.
      const MotorOutput1065 original{flags, static_cast<std::uint8_t>(duty),
                                     static_cast<std::uint8_t>(std::max(2, 255 - duty)), 0x5A};
      std::array<std::uint8_t, 6> report{};
      ASSERT_EQ(encode_output_1065(original, report), CodecStatus::ok);
      MotorOutput1065 back;
      ASSERT_EQ(decode_output_1065(report, back), CodecStatus::ok);
      EXPECT_EQ(back.flags, original.flags);
      EXPECT_EQ(back.duty_raw, original.duty_raw);
      EXPECT_EQ(back.acceleration_raw, original.acceleration_raw);
      EXPECT_EQ(back.braking_raw, original.braking_raw);
      // And the units convert back to the same raw values (the direction included, except that a
      // zero duty goes out as positive, as the vendor sends it).
      MotorCommand1065 command;
      command.duty_cycle = back.duty_cycle();
      command.acceleration_pct_per_s = back.acceleration_pct_per_s();
      command.braking_fraction = back.braking_fraction();
      command.back_emf_sensing = (flags & k1065OutBackEmfSensing) != 0;
      command.ratiometric = (flags & k1065OutRatiometric) != 0;
      MotorOutput1065 again;
      ASSERT_EQ(to_output_1065(command, again), CodecStatus::ok);
      EXPECT_EQ(again.duty_raw, original.duty_raw);
      EXPECT_EQ(again.acceleration_raw, original.acceleration_raw);
      EXPECT_EQ(again.braking_raw, original.braking_raw);
      EXPECT_EQ(again.flags,
                duty == 0 ? (original.flags | k1065OutDirectionPositive) : original.flags);
    }
  }
}

// ---------------------------------------------------------------- input report (board -> host)

// A report with every field distinct, written out by hand.
const Bytes kReportA = {
    0x05,                    // 0: digital inputs 0 and 2
    0x74,                    // 1: 0x40 commanded +, 0x20 BEMF sensing, 0x10 ratiometric, 0x04 BEMF
                             //    valid; 0x08 clear: actual direction negative
    0x01, 0x23,              // 2-3: current 0x0123 = 291
    0x08, 0x00,              // 4-5: analog 0 = 2048
    0x0F, 0xFF,              // 6-7: analog 1 = 4095
    0x01, 0x33,              // 8-9: supply 0x0133 = 307
    0x02, 0x00,              // 10-11: back-EMF plus 512
    0x01, 0x00,              // 12-13: back-EMF minus 256
    0xFF, 0xFE, 0x79, 0x60,  // 14-17: -100000 = 0x100000000 - 0x186a0 = 0xfffe7960
    0x17, 0x70,              // 18-19: encoder time 0x1770 = 6000
    0x60,                    // 20: applied duty 96
    0x80,                    // 21: commanded duty 128
    0xFF,                    // 22: acceleration 255
    0x33,                    // 23: braking 51
    0xFE,                    // 24: packet counter 254
};

MotorReport1065 report_a_struct() {
  MotorReport1065 r;
  r.digital_inputs = 0x05;
  r.status_flags = 0x74;
  r.current_raw = 291;
  r.analog_raw[0] = 2048;
  r.analog_raw[1] = 4095;
  r.supply_raw = 307;
  r.back_emf_plus_raw = 512;
  r.back_emf_minus_raw = 256;
  r.encoder_position = -100000;
  r.encoder_time_raw = 6000;
  r.applied_duty_raw = 96;
  r.commanded_duty_raw = 128;
  r.acceleration_raw = 255;
  r.braking_raw = 51;
  r.packet_counter = 254;
  return r;
}

TEST(Codec1065Input, DecodesEveryField) {
  Bytes longer = kReportA;
  longer.push_back(0xAA);  // bytes past 24 are ignored
  longer.push_back(0xBB);
  MotorReport1065 r;
  ASSERT_EQ(decode_input_1065(longer, r), CodecStatus::ok);
  expect_same(r, report_a_struct());

  EXPECT_FALSE(r.over_temperature());
  EXPECT_FALSE(r.under_voltage());
  EXPECT_TRUE(r.back_emf_valid());
  // 291 * 5 / 4096 / 150 / 0.0024 = 0.98673502604 A
  EXPECT_NEAR(r.motor_current_a(), 0.98673502604, 1e-10);
  // round(2048 * 1.001) = round(2050.048) = 2050; 2050 * 5 / 4095 = 2.5030525 V
  EXPECT_NEAR(r.analog_v(0), 2050.0 * 5 / 4095, 1e-12);
  EXPECT_NEAR(r.analog_v(0), 2.5030525031, 1e-9);
  // round(4095 * 1.001) = 4099, clipped to 4095: exactly full scale, 5 V
  EXPECT_DOUBLE_EQ(r.analog_v(1), 5.0);
  EXPECT_TRUE(std::isnan(r.analog_v(2)));
  EXPECT_TRUE(std::isnan(r.analog_v(-1)));
  // 307 * 80 / 2048 = 11.9921875 V (exact in binary)
  EXPECT_DOUBLE_EQ(r.supply_voltage_v(), 11.9921875);
  // (512 - 256) * 80 / 4096 = 5 V
  EXPECT_DOUBLE_EQ(r.back_emf_v(), 5.0);
  // 6000 / 3000 = 2 s
  EXPECT_DOUBLE_EQ(r.encoder_time_s(), 2.0);
  // 96 / 255, flag 0x08 clear: negative
  EXPECT_DOUBLE_EQ(r.applied_duty(), -96.0 / 255.0);
  // 128 / 255, flag 0x40 set: positive
  EXPECT_DOUBLE_EQ(r.commanded_duty(), 128.0 / 255.0);
  // 255 * 6250 / 255 = 6250 %/s; 51 * 100 / 255 = 20 %
  EXPECT_DOUBLE_EQ(r.acceleration_pct_per_s(), 6250.0);
  EXPECT_DOUBLE_EQ(r.braking_pct(), 20.0);
}

TEST(Codec1065Input, FaultFlagsExtremePositionAndNegativeBackEmf) {
  Bytes b(25, 0x00);
  b[1] = 0x0B;  // 0x01 over-temperature, 0x02 under-voltage, 0x08 actual +, 0x40 clear: commanded -
  b[10] = 0x00, b[11] = 0x00;  // BEMF plus 0
  b[12] = 0x08, b[13] = 0x00;  // BEMF minus 2048: (0 - 2048) * 80 / 4096 = -40 V
  b[14] = 0x7F, b[15] = 0xFF, b[16] = 0xFF, b[17] = 0xFF;  // INT32_MAX
  b[20] = 0xFF;                                            // applied 255, positive: +1
  b[21] = 0x40;                                            // commanded 64, negative: -64/255
  MotorReport1065 r;
  ASSERT_EQ(decode_input_1065(b, r), CodecStatus::ok);
  EXPECT_TRUE(r.over_temperature());
  EXPECT_TRUE(r.under_voltage());
  EXPECT_FALSE(r.back_emf_valid());
  EXPECT_DOUBLE_EQ(r.back_emf_v(), -40.0);
  EXPECT_EQ(r.encoder_position, 2147483647);
  EXPECT_DOUBLE_EQ(r.applied_duty(), 1.0);
  EXPECT_DOUBLE_EQ(r.commanded_duty(), -64.0 / 255.0);

  b[14] = 0x80, b[15] = 0x00, b[16] = 0x00, b[17] = 0x00;  // INT32_MIN
  ASSERT_EQ(decode_input_1065(b, r), CodecStatus::ok);
  EXPECT_EQ(r.encoder_position, std::numeric_limits<std::int32_t>::min());
  EXPECT_EQ(r.applied_duty_raw, 255);
}

TEST(Codec1065Input, ZeroDutyIsPositiveZero) {
  MotorReport1065 r;  // all zero, direction flags clear
  EXPECT_EQ(r.applied_duty(), 0.0);
  EXPECT_FALSE(std::signbit(r.applied_duty()));
  EXPECT_FALSE(std::signbit(r.commanded_duty()));
}

TEST(Codec1065Input, TooShort) {
  const Bytes b(kReportA.begin(), kReportA.begin() + 24);
  MotorReport1065 r;
  r.packet_counter = 7;
  EXPECT_EQ(decode_input_1065(b, r), CodecStatus::too_short);
  EXPECT_EQ(r.packet_counter, 7);  // untouched
  EXPECT_EQ(decode_input_1065({}, r), CodecStatus::too_short);
}

TEST(Codec1065Input, EncodesTheHandWrittenBytesAndZeroPads) {
  std::array<std::uint8_t, 32> report;
  report.fill(0xAA);
  ASSERT_EQ(encode_input_1065(report_a_struct(), report), CodecStatus::ok);
  Bytes expected = kReportA;
  expected.resize(32, 0x00);
  EXPECT_EQ(Bytes(report.begin(), report.end()), expected);

  std::array<std::uint8_t, 24> small{};
  EXPECT_EQ(encode_input_1065(report_a_struct(), small), CodecStatus::buffer_too_small);
}

TEST(Codec1065Input, RoundTrips) {
  MotorReport1065 original = report_a_struct();
  for (std::int32_t position : {0, 1, -1, 123456789, -2147483647 - 1, 2147483647}) {
    original.encoder_position = position;
    original.packet_counter = static_cast<std::uint8_t>(position);
    std::array<std::uint8_t, 25> report{};
    ASSERT_EQ(encode_input_1065(original, report), CodecStatus::ok);
    MotorReport1065 back;
    ASSERT_EQ(decode_input_1065(report, back), CodecStatus::ok);
    expect_same(back, original);
  }
}

// ---------------------------------------------------------------- producers' inverses

TEST(Codec1065Inverses, RoundAndSaturate) {
  // 0.98673502604 A is raw 291 (see DecodesEveryField); 1 A = 1 / 0.0033908 = 294.9 -> 295
  EXPECT_EQ(current_raw_from_a(0.98673502604), 291);
  EXPECT_EQ(current_raw_from_a(1.0), 295);
  EXPECT_EQ(current_raw_from_a(-2.0), 0);
  EXPECT_EQ(current_raw_from_a(1e9), 0xFFFF);
  EXPECT_EQ(current_raw_from_a(kNaN), 0);
  // 12 V * 2048 / 80 = 307.2 -> 307; 24 V -> 614.4 -> 614
  EXPECT_EQ(supply_raw_from_v(12.0), 307);
  EXPECT_EQ(supply_raw_from_v(24.0), 614);
  EXPECT_EQ(supply_raw_from_v(-1.0), 0);
  EXPECT_EQ(supply_raw_from_v(5000.0), 0xFFFF);  // 128000 saturates
  // 0.375 * 255 = 95.625 -> 96; 0.5 -> 127.5 -> 128; above 1 saturates
  EXPECT_EQ(duty_raw_from_fraction(0.375), 96);
  EXPECT_EQ(duty_raw_from_fraction(0.5), 128);
  EXPECT_EQ(duty_raw_from_fraction(-0.5), 128);
  EXPECT_EQ(duty_raw_from_fraction(1.2), 255);
  EXPECT_EQ(duty_raw_from_fraction(kNaN), 0);
}

}  // namespace
}  // namespace furuta::bridge
