#include "bridge_session.hpp"

#include <array>
#include <cmath>

#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/lost_reports.hpp"

namespace furuta::app {

using bridge::TransportStatus;

namespace {

bool write_duty(bridge::Transport& motor, double duty) {
  bridge::MotorCommand1065 command;
  command.duty_cycle = duty;
  bridge::MotorOutput1065 output;
  if (bridge::to_output_1065(command, output) != bridge::CodecStatus::ok) return false;
  std::array<std::uint8_t, bridge::kMaxReportBytes> bytes{};
  const std::size_t length = motor.device_info().output_report_bytes;
  if (length < bridge::k1065OutputReportMinBytes || length > bytes.size()) return false;
  if (bridge::encode_output_1065(output, {bytes.data(), length}) != bridge::CodecStatus::ok) {
    return false;
  }
  return motor.write_report({bytes.data(), length}) == TransportStatus::ok;
}

}  // namespace

BridgeSessionResult run_bridge_session(bridge::Transport& motor, bridge::Transport& encoder,
                                       bridge::Clock& clock, const BridgeSessionSpec& spec) {
  BridgeSessionResult result;
  std::array<std::uint8_t, bridge::k1047OutputReportBytes> enable{};
  bridge::encode_output_1047(static_cast<std::uint8_t>(1u << spec.pendulum_channel), enable);
  if (encoder.write_report(enable) != TransportStatus::ok) {
    result.stop_reason = "cannot enable the pendulum encoder channel";
    ++result.transport_errors;
    write_duty(motor, 0.0);
    return result;
  }

  bridge::PacketCounterTracker1065 motor_counter;
  bridge::ReportTimingTracker1047 encoder_timing(
      bridge::tick_seconds_1047(encoder.device_info().firmware_version));
  BridgeSample state;
  const std::int64_t start_ns = clock.now_ns();
  const auto cycles =
      static_cast<std::int64_t>(std::llround(spec.duration_s * 1e9 / spec.period_ns));
  result.samples.reserve(static_cast<std::size_t>(cycles));

  auto fail = [&](const char* what, TransportStatus status) {
    ++result.transport_errors;
    result.stop_reason = std::string(what) + ": " + std::string(bridge::to_string(status));
  };

  for (std::int64_t k = 1; k <= cycles && result.stop_reason.empty(); ++k) {
    const std::int64_t wake_ns = start_ns + k * spec.period_ns;
    clock.sleep_until_ns(wake_ns);
    state.time_ns = wake_ns;
    state.motor_reports = 0;
    state.encoder_reports = 0;

    bridge::UsbReport report;
    TransportStatus status;
    while ((status = motor.read_report(report, std::chrono::nanoseconds(0))) ==
           TransportStatus::ok) {
      bridge::MotorReport1065 decoded;
      if (bridge::decode_input_1065(report.view(), decoded) != bridge::CodecStatus::ok) continue;
      motor_counter.observe(decoded.packet_counter);
      ++state.motor_reports;
      state.arm_counts = decoded.encoder_position;
      state.applied_duty = decoded.applied_duty();
      state.motor_current_a = decoded.motor_current_a();
      state.supply_voltage_v = decoded.supply_voltage_v();
      state.motor_status_flags = decoded.status_flags;
      state.motor_report_host_ns = report.host_time_ns;
    }
    if (status != TransportStatus::timeout) fail("1065 read", status);
    while ((status = encoder.read_report(report, std::chrono::nanoseconds(0))) ==
           TransportStatus::ok) {
      bridge::EncoderReport1047 decoded;
      if (bridge::decode_input_1047(report.view(), decoded) != bridge::CodecStatus::ok) continue;
      const auto& channel = decoded.channels[static_cast<std::size_t>(spec.pendulum_channel)];
      encoder_timing.observe(channel.packet_time_ticks, report.host_time_ns);
      ++state.encoder_reports;
      state.pendulum_counts += channel.position_delta;
      state.encoder_report_host_ns = report.host_time_ns;
    }
    if (status != TransportStatus::timeout && result.stop_reason.empty()) fail("1047 read", status);

    state.motor_lost_total = motor_counter.total_lost();
    state.encoder_lost_total = encoder_timing.total_lost();
    state.arm_angle_rad = bridge::counts_to_rad(spec.arm_encoder, state.arm_counts);
    state.pendulum_angle_rad = bridge::counts_to_rad(spec.pendulum_encoder, state.pendulum_counts);

    const double t_s = static_cast<double>(wake_ns - start_ns) * 1e-9;
    const bool positive =
        static_cast<std::int64_t>(std::floor(t_s / spec.switch_period_s)) % 2 == 0;
    state.commanded_duty = positive ? spec.amplitude_duty : -spec.amplitude_duty;
    if (result.stop_reason.empty() && !write_duty(motor, state.commanded_duty)) {
      fail("1065 write", TransportStatus::io_error);
    }
    result.samples.push_back(state);
  }
  // The motor is left at zero on every way out of the loop.
  write_duty(motor, 0.0);
  if (result.stop_reason.empty()) result.stop_reason = "duration reached";
  return result;
}

}  // namespace furuta::app
