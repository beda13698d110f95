// The 1065 decoders on arbitrary bytes: never out of bounds, and whatever decodes re-encodes to the
// same bytes (the structs hold raw wire values). The host-side conversion of a motor command is
// fuzzed too: it must refuse NaN and out-of-range values, and round only within half a step.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "furuta/firmware_bridge/codec_1065.hpp"

using namespace furuta::bridge;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

void input_report(std::span<const std::uint8_t> bytes) {
  MotorReport1065 report;
  const CodecStatus status = decode_input_1065(bytes, report);
  check((status == CodecStatus::ok) == (bytes.size() >= k1065InputReportMinBytes));
  if (status != CodecStatus::ok) return;
  std::vector<std::uint8_t> again(bytes.size());
  check(encode_input_1065(report, again) == CodecStatus::ok);
  check(std::memcmp(again.data(), bytes.data(), k1065InputReportMinBytes) == 0);
  for (double v : {report.motor_current_a(), report.analog_v(0), report.analog_v(1),
                   report.supply_voltage_v(), report.back_emf_v(), report.encoder_time_s(),
                   report.acceleration_pct_per_s(), report.braking_pct()}) {
    check(std::isfinite(v));
  }
  check(std::fabs(report.applied_duty()) <= 1.0 && std::fabs(report.commanded_duty()) <= 1.0);
}

void output_report(std::span<const std::uint8_t> bytes) {
  MotorOutput1065 output;
  const CodecStatus status = decode_output_1065(bytes, output);
  check((status == CodecStatus::ok) == (bytes.size() >= k1065OutputReportMinBytes));
  if (status != CodecStatus::ok) return;
  std::vector<std::uint8_t> again(bytes.size());
  check(encode_output_1065(output, again) == CodecStatus::ok);
  check(std::memcmp(again.data(), bytes.data(), k1065OutputReportMinBytes) == 0);
  check(std::fabs(output.duty_cycle()) <= 1.0);
}

void command(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 3 * sizeof(double) + 1) return;
  MotorCommand1065 c;
  std::memcpy(&c.duty_cycle, bytes.data(), sizeof(double));
  std::memcpy(&c.acceleration_pct_per_s, bytes.data() + 8, sizeof(double));
  std::memcpy(&c.braking_fraction, bytes.data() + 16, sizeof(double));
  c.back_emf_sensing = bytes[24] & 1;
  c.ratiometric = bytes[24] & 2;
  MotorOutput1065 out;
  const CodecStatus status = to_output_1065(c, out);
  const bool in_range = std::fabs(c.duty_cycle) <= 1.0 && c.acceleration_pct_per_s >= 0 &&
                        c.acceleration_pct_per_s <= k1065FullScaleAccelerationPctPerS &&
                        c.braking_fraction >= 0 && c.braking_fraction <= 1.0;
  check((status == CodecStatus::ok) == in_range);
  if (status != CodecStatus::ok) return;
  // Half a raw step, plus rounding slack.
  check(std::fabs(out.duty_cycle() - c.duty_cycle) <= 0.5 / 255 + 1e-12);
  check(std::fabs(out.braking_fraction() - c.braking_fraction) <= 0.5 / 255 + 1e-12);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Copies of exactly `size` bytes, so ASan sees any read past the report.
  const std::vector<std::uint8_t> bytes(data, data + size);
  input_report(bytes);
  output_report(bytes);
  command(bytes);
  return 0;
}
