#include "furuta/firmware_bridge/codec_1065.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "codec_wire.hpp"

namespace furuta::bridge {

namespace {

constexpr double kRawFullScale = 255.0;

// Input report byte offsets (docs/phidget-protocol.md, "1065 input report").
constexpr std::size_t kInDigital = 0;
constexpr std::size_t kInFlags = 1;
constexpr std::size_t kInCurrent = 2;
constexpr std::size_t kInAnalog0 = 4;
constexpr std::size_t kInAnalog1 = 6;
constexpr std::size_t kInSupply = 8;
constexpr std::size_t kInBackEmfPlus = 10;
constexpr std::size_t kInBackEmfMinus = 12;
constexpr std::size_t kInEncoderPosition = 14;
constexpr std::size_t kInEncoderTime = 18;
constexpr std::size_t kInAppliedDuty = 20;
constexpr std::size_t kInCommandedDuty = 21;
constexpr std::size_t kInAcceleration = 22;
constexpr std::size_t kInBraking = 23;
constexpr std::size_t kInPacketCounter = 24;

// Current: amps = raw * 5 / 4096 / 150 / 0.0024. The vendor source marks this formula unchecked, so
// the current is a cross-check, never a control input.
constexpr double kCurrentAmpsPerRaw = 5.0 / 4096.0 / 150.0 / 0.0024;
// Analog sensors: the 12-bit ADC reading is scaled by 1.001 and clipped to 4095 before volts.
constexpr double kAnalogGain = 1.001;
constexpr double kAnalogMaxRaw = 4095.0;
constexpr double kAnalogFullScaleV = 5.0;
constexpr double kSupplyVoltsPerRaw = 80.0 / 2048.0;
constexpr double kBackEmfVoltsPerRaw = 80.0 / 4096.0;
// Encoder time stamp in units of 1/3 ms (inferred: the time of the last edge).
constexpr double kEncoderTimeRawPerS = 3000.0;

double signed_fraction(std::uint8_t raw, bool positive) {
  const double magnitude = raw / kRawFullScale;
  // raw 0 gives +0.0 either way, so a stopped motor never reads as -0.
  return positive || raw == 0 ? magnitude : -magnitude;
}

}  // namespace

double MotorOutput1065::duty_cycle() const {
  return signed_fraction(duty_raw, (flags & k1065OutDirectionPositive) != 0);
}

double MotorOutput1065::acceleration_pct_per_s() const {
  return acceleration_raw * k1065FullScaleAccelerationPctPerS / kRawFullScale;
}

double MotorOutput1065::braking_fraction() const {
  return braking_raw / kRawFullScale;
}

CodecStatus to_output_1065(const MotorCommand1065& command, MotorOutput1065& out) {
  const double duty = command.duty_cycle;
  const double accel = command.acceleration_pct_per_s;
  const double brake = command.braking_fraction;
  // Written as "inside the range" so NaN, which fails every comparison, is rejected too.
  const bool duty_ok = duty >= -1.0 && duty <= 1.0;
  const bool accel_ok =
      accel >= k1065MinAccelerationPctPerS && accel <= k1065FullScaleAccelerationPctPerS;
  const bool brake_ok = brake >= 0.0 && brake <= 1.0;
  if (!duty_ok || !accel_ok || !brake_ok) return CodecStatus::out_of_range;

  MotorOutput1065 o;
  o.flags = 0;
  // The vendor's packet sets the bit for `speed >= 0`, so zero goes out as "positive"; -0.0
  // compares equal to 0 and gets the same bit, so the two zeros are one report on the wire.
  if (duty >= 0.0) o.flags |= k1065OutDirectionPositive;
  if (command.back_emf_sensing) o.flags |= k1065OutBackEmfSensing;
  if (command.ratiometric) o.flags |= k1065OutRatiometric;
  // round(|duty %| * 255 / 100) == round(|duty| * 255); one multiplication keeps exact halves
  // exact.
  o.duty_raw = static_cast<std::uint8_t>(std::round(std::fabs(duty) * kRawFullScale));
  // Product first: for whole %/s values the product is exact and the single division correctly
  // rounded, so a true half (e.g. 3125 %/s -> 127.5) rounds up as the formula intends.
  o.acceleration_raw = static_cast<std::uint8_t>(
      std::round(accel * kRawFullScale / k1065FullScaleAccelerationPctPerS));
  o.braking_raw = static_cast<std::uint8_t>(std::round(brake * kRawFullScale));
  out = o;
  return CodecStatus::ok;
}

CodecStatus encode_output_1065(const MotorOutput1065& output, std::span<std::uint8_t> report) {
  if (report.size() < k1065OutputReportMinBytes) return CodecStatus::buffer_too_small;
  report[0] = output.flags;
  report[1] = output.duty_raw;
  report[2] = output.acceleration_raw;
  report[3] = output.braking_raw;
  std::fill(report.begin() + k1065OutputReportMinBytes, report.end(), std::uint8_t{0});
  return CodecStatus::ok;
}

CodecStatus decode_output_1065(std::span<const std::uint8_t> report, MotorOutput1065& output) {
  if (report.size() < k1065OutputReportMinBytes) return CodecStatus::too_short;
  output.flags = report[0];
  output.duty_raw = report[1];
  output.acceleration_raw = report[2];
  output.braking_raw = report[3];
  return CodecStatus::ok;
}

double MotorReport1065::motor_current_a() const {
  return current_raw * kCurrentAmpsPerRaw;
}

double MotorReport1065::analog_v(int index) const {
  // Not an exception: this runs on the real-time path. NaN makes a bad index impossible to miss.
  if (index < 0 || index > 1) return std::numeric_limits<double>::quiet_NaN();
  const double scaled = std::min(std::round(analog_raw[index] * kAnalogGain), kAnalogMaxRaw);
  return scaled * kAnalogFullScaleV / kAnalogMaxRaw;
}

double MotorReport1065::supply_voltage_v() const {
  return supply_raw * kSupplyVoltsPerRaw;
}

double MotorReport1065::back_emf_v() const {
  const int difference = static_cast<int>(back_emf_plus_raw) - static_cast<int>(back_emf_minus_raw);
  return difference * kBackEmfVoltsPerRaw;
}

double MotorReport1065::encoder_time_s() const {
  return encoder_time_raw / kEncoderTimeRawPerS;
}

double MotorReport1065::applied_duty() const {
  return signed_fraction(applied_duty_raw, (status_flags & k1065FlagActualDirection) != 0);
}

double MotorReport1065::commanded_duty() const {
  return signed_fraction(commanded_duty_raw, (status_flags & k1065FlagCommandedDirection) != 0);
}

double MotorReport1065::acceleration_pct_per_s() const {
  return acceleration_raw * k1065FullScaleAccelerationPctPerS / kRawFullScale;
}

double MotorReport1065::braking_pct() const {
  return braking_raw * 100.0 / kRawFullScale;
}

CodecStatus decode_input_1065(std::span<const std::uint8_t> report, MotorReport1065& out) {
  if (report.size() < k1065InputReportMinBytes) return CodecStatus::too_short;
  MotorReport1065 r;
  r.digital_inputs = report[kInDigital];
  r.status_flags = report[kInFlags];
  r.current_raw = wire::get_u16(report, kInCurrent);
  r.analog_raw[0] = wire::get_u16(report, kInAnalog0);
  r.analog_raw[1] = wire::get_u16(report, kInAnalog1);
  r.supply_raw = wire::get_u16(report, kInSupply);
  r.back_emf_plus_raw = wire::get_u16(report, kInBackEmfPlus);
  r.back_emf_minus_raw = wire::get_u16(report, kInBackEmfMinus);
  // Two's complement on the wire; the conversion from u32 is well defined since C++20.
  r.encoder_position = static_cast<std::int32_t>(wire::get_u32(report, kInEncoderPosition));
  r.encoder_time_raw = wire::get_u16(report, kInEncoderTime);
  r.applied_duty_raw = report[kInAppliedDuty];
  r.commanded_duty_raw = report[kInCommandedDuty];
  r.acceleration_raw = report[kInAcceleration];
  r.braking_raw = report[kInBraking];
  r.packet_counter = report[kInPacketCounter];
  out = r;
  return CodecStatus::ok;
}

CodecStatus encode_input_1065(const MotorReport1065& in, std::span<std::uint8_t> report) {
  if (report.size() < k1065InputReportMinBytes) return CodecStatus::buffer_too_small;
  report[kInDigital] = in.digital_inputs;
  report[kInFlags] = in.status_flags;
  wire::put_u16(report, kInCurrent, in.current_raw);
  wire::put_u16(report, kInAnalog0, in.analog_raw[0]);
  wire::put_u16(report, kInAnalog1, in.analog_raw[1]);
  wire::put_u16(report, kInSupply, in.supply_raw);
  wire::put_u16(report, kInBackEmfPlus, in.back_emf_plus_raw);
  wire::put_u16(report, kInBackEmfMinus, in.back_emf_minus_raw);
  wire::put_u32(report, kInEncoderPosition, static_cast<std::uint32_t>(in.encoder_position));
  wire::put_u16(report, kInEncoderTime, in.encoder_time_raw);
  report[kInAppliedDuty] = in.applied_duty_raw;
  report[kInCommandedDuty] = in.commanded_duty_raw;
  report[kInAcceleration] = in.acceleration_raw;
  report[kInBraking] = in.braking_raw;
  report[kInPacketCounter] = in.packet_counter;
  std::fill(report.begin() + k1065InputReportMinBytes, report.end(), std::uint8_t{0});
  return CodecStatus::ok;
}

std::uint16_t current_raw_from_a(double amps) {
  return static_cast<std::uint16_t>(wire::round_saturated(amps / kCurrentAmpsPerRaw, 0xFFFF));
}

std::uint16_t supply_raw_from_v(double volts) {
  return static_cast<std::uint16_t>(wire::round_saturated(volts / kSupplyVoltsPerRaw, 0xFFFF));
}

std::uint8_t duty_raw_from_fraction(double duty_magnitude) {
  // fabs: a signed duty passed by mistake still yields its magnitude rather than 0.
  return static_cast<std::uint8_t>(
      wire::round_saturated(std::fabs(duty_magnitude) * kRawFullScale, 0xFF));
}

}  // namespace furuta::bridge
