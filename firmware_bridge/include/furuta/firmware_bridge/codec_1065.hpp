#pragma once
// Phidget 1065 MotorControl 1-Motor: byte-exact output and input reports.
// Structs hold the raw wire values (so a decode/encode round trip is exact); accessors give units.

#include <cstddef>
#include <cstdint>
#include <span>

namespace furuta::bridge {

enum class CodecStatus : std::uint8_t {
  ok,
  too_short,         // fewer bytes than the layout needs
  out_of_range,      // a value the wire format cannot carry
  buffer_too_small,  // output span shorter than the report
};

inline constexpr std::size_t k1065OutputReportMinBytes = 4;
inline constexpr std::size_t k1065InputReportMinBytes = 25;

// Output report byte 0 flags.
inline constexpr std::uint8_t k1065OutDirectionPositive = 0x01;
inline constexpr std::uint8_t k1065OutBackEmfSensing = 0x02;
inline constexpr std::uint8_t k1065OutRatiometric = 0x04;

// Input report byte 1 status flags.
inline constexpr std::uint8_t k1065FlagOverTemperature = 0x01;  // over-temperature or short
inline constexpr std::uint8_t k1065FlagUnderVoltage = 0x02;     // under-voltage lock-out
inline constexpr std::uint8_t k1065FlagBackEmfValid = 0x04;
inline constexpr std::uint8_t k1065FlagActualDirection = 0x08;  // set = positive
inline constexpr std::uint8_t k1065FlagRatiometricEcho = 0x10;
inline constexpr std::uint8_t k1065FlagBackEmfSensingEcho = 0x20;
inline constexpr std::uint8_t k1065FlagCommandedDirection = 0x40;  // set = positive

// Full-scale acceleration: raw 255 = 6250 %/s (0 to 100 % in 16 ms).
inline constexpr double k1065FullScaleAccelerationPctPerS = 6250.0;
// The smallest acceleration the vendor library accepts: 100 % in 4.08 s, rounded to two decimals
// (one raw step, 6250 / 255 = 24.5098..., would round to raw 1). Below it the vendor's setter
// refuses; raw 0 is never sent (docs/phidget-protocol.md).
inline constexpr double k1065MinAccelerationPctPerS = 24.51;

// What the host asks of the motor.
struct MotorCommand1065 {
  double duty_cycle = 0.0;  // [-1, 1]; sign is the direction
  double acceleration_pct_per_s = k1065FullScaleAccelerationPctPerS;  // [24.51, 6250]
  double braking_fraction = 0.0;                                      // [0, 1]
  bool back_emf_sensing = false;
  bool ratiometric = false;
};

// The output report as raw bytes 0..3.
struct MotorOutput1065 {
  std::uint8_t flags = 0;
  std::uint8_t duty_raw = 0;          // round(|duty %| * 255 / 100)
  std::uint8_t acceleration_raw = 0;  // round(accel / 6250 * 255)
  std::uint8_t braking_raw = 0;       // round(brake % * 255 / 100)

  double duty_cycle() const;  // signed [-1, 1]
  double acceleration_pct_per_s() const;
  double braking_fraction() const;
};

// Rounds a command to the wire; out_of_range for NaN or values outside the ranges above. As the
// vendor library does, a zero duty goes out with the direction bit set (its `speed >= 0`).
CodecStatus to_output_1065(const MotorCommand1065& command, MotorOutput1065& out);
// Writes bytes 0..3 and zero-pads the rest of `report` (the device's output report length).
CodecStatus encode_output_1065(const MotorOutput1065& output, std::span<std::uint8_t> report);
CodecStatus decode_output_1065(std::span<const std::uint8_t> report, MotorOutput1065& output);

// The input report, one every 8 ms. Multi-byte fields are big-endian on the wire.
struct MotorReport1065 {
  std::uint8_t digital_inputs = 0;
  std::uint8_t status_flags = 0;
  std::uint16_t current_raw = 0;
  std::uint16_t analog_raw[2] = {0, 0};
  std::uint16_t supply_raw = 0;
  std::uint16_t back_emf_plus_raw = 0;
  std::uint16_t back_emf_minus_raw = 0;
  std::int32_t encoder_position = 0;    // absolute count kept by the board
  std::uint16_t encoder_time_raw = 0;   // 1/3 ms units, time of the last edge (inferred)
  std::uint8_t applied_duty_raw = 0;    // sign from k1065FlagActualDirection
  std::uint8_t commanded_duty_raw = 0;  // sign from k1065FlagCommandedDirection
  std::uint8_t acceleration_raw = 0;
  std::uint8_t braking_raw = 0;
  std::uint8_t packet_counter = 0;  // +1 per report, wraps at 256

  bool over_temperature() const { return status_flags & k1065FlagOverTemperature; }
  bool under_voltage() const { return status_flags & k1065FlagUnderVoltage; }
  bool back_emf_valid() const { return status_flags & k1065FlagBackEmfValid; }
  double motor_current_a() const;    // raw * 5 / 4096 / 150 / 0.0024 (formula unchecked upstream)
  double analog_v(int index) const;  // min(round(raw * 1.001), 4095) * 5 / 4095
  double supply_voltage_v() const;   // raw * 80 / 2048
  double back_emf_v() const;         // (plus - minus) * 80 / 4096; meaningful when back_emf_valid()
  double encoder_time_s() const;     // raw / 3000
  double applied_duty() const;       // signed [-1, 1]
  double commanded_duty() const;     // signed [-1, 1]
  double acceleration_pct_per_s() const;  // raw * 6250 / 255
  double braking_pct() const;             // raw * 100 / 255
};

// too_short below k1065InputReportMinBytes; bytes past 24 are ignored.
CodecStatus decode_input_1065(std::span<const std::uint8_t> report, MotorReport1065& out);
// Writes bytes 0..24 and zero-pads the rest (used by the simulated rig).
CodecStatus encode_input_1065(const MotorReport1065& in, std::span<std::uint8_t> report);

// Inverses of the unit conversions, rounded and saturated, for producing reports (simulated rig).
std::uint16_t current_raw_from_a(double amps);
std::uint16_t supply_raw_from_v(double volts);
std::uint8_t duty_raw_from_fraction(double duty_magnitude);  // |duty| in [0, 1]

}  // namespace furuta::bridge
