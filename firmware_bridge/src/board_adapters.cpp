// The Phidget boards as role adapters (board_roles.hpp): the 1065 as the motor board, the 1047 as
// the encoder board, and the registry that makes an adapter by its configuration name.
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>

#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/lost_reports.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"

namespace furuta::bridge {

namespace {

// The largest 1065 duty step that is not above max_duty (0 for a NaN or negative limit).
std::uint8_t max_duty_raw_1065(double max_duty) {
  if (!(max_duty > 0.0)) return 0;
  if (max_duty >= 1.0) return 255;
  // The slack keeps a limit that is an exact step (0.6 = 153/255) on that step despite rounding.
  return static_cast<std::uint8_t>(std::floor(max_duty * 255.0 + 1e-9));
}

class MotorBoard1065 final : public MotorBoard {
 public:
  explicit MotorBoard1065(const MotorBoardSettings& settings)
      : max_duty_raw_(max_duty_raw_1065(settings.max_duty)),
        acceleration_pct_per_s_(settings.acceleration_pct_per_s > 0
                                    ? settings.acceleration_pct_per_s
                                    : k1065FullScaleAccelerationPctPerS) {}

  std::optional<MotorReading> read(std::span<const std::uint8_t> report,
                                   std::int64_t host_ns) noexcept override {
    MotorReport1065 r;
    if (decode_input_1065(report, r) != CodecStatus::ok) return std::nullopt;
    MotorReading m;
    m.host_ns = host_ns;
    m.position_counts = r.encoder_position;
    m.applied_duty = r.applied_duty();
    m.current_a = r.motor_current_a();
    m.supply_v = r.supply_voltage_v();
    m.over_temperature = r.over_temperature();
    m.under_voltage = r.under_voltage();
    m.status_flags = r.status_flags;
    m.report_counter = r.packet_counter;
    m.board_time = r.encoder_time_raw;
    m.lost_before = counter_.observe(r.packet_counter);
    return m;
  }

  bool write(const MotorCommand& command, std::span<std::uint8_t> report) const noexcept override {
    MotorCommand1065 c;
    c.duty_cycle = command.duty;
    c.braking_fraction = command.braking_fraction;
    c.acceleration_pct_per_s = acceleration_pct_per_s_;
    MotorOutput1065 output;
    if (to_output_1065(c, output) != CodecStatus::ok) return false;
    // |duty| travels in steps of 1/255 rounded to nearest, so a duty at exactly the limit could
    // reach the board half a step above it. The wire never carries more: round down onto it.
    output.duty_raw = std::min(output.duty_raw, max_duty_raw_);
    if (report.size() < k1065OutputReportMinBytes) return false;
    return encode_output_1065(output, report) == CodecStatus::ok;
  }

  std::optional<MotorWrite> read_write(
      std::span<const std::uint8_t> report) const noexcept override {
    MotorOutput1065 o;
    if (decode_output_1065(report, o) != CodecStatus::ok) return std::nullopt;
    // Raw acceleration 0 is never sent; taken as the slowest ramp the wire can express (one step).
    const double slowest = k1065FullScaleAccelerationPctPerS / 255.0;
    return MotorWrite{o.duty_cycle(), std::max(o.acceleration_pct_per_s(), slowest),
                      o.braking_fraction()};
  }

  void restart() noexcept override { counter_.reset(); }

  // One raw step of each reading, through the codec's own conversions.
  MotorResolution resolution() const noexcept override {
    MotorReport1065 one_step;
    one_step.applied_duty_raw = 1;
    one_step.status_flags = k1065FlagActualDirection;
    one_step.supply_raw = 1;
    return {one_step.applied_duty(), one_step.supply_voltage_v()};
  }

 private:
  std::uint8_t max_duty_raw_;
  double acceleration_pct_per_s_;
  PacketCounterTracker1065 counter_;
};

class EncoderBoard1047 final : public EncoderBoard {
 public:
  EncoderBoard1047(const DeviceInfo& device, int channel)
      : channel_(static_cast<std::size_t>(channel)),
        timing_(tick_seconds_1047(device.firmware_version)) {
    if (channel < 0 || static_cast<std::size_t>(channel) >= k1047ChannelCount) {
      throw std::invalid_argument("1047 encoder: channel must be 0..3");
    }
  }

  std::optional<EncoderReading> read(std::span<const std::uint8_t> report,
                                     std::int64_t host_ns) noexcept override {
    EncoderReport1047 r;
    if (decode_input_1047(report, r) != CodecStatus::ok) return std::nullopt;
    const EncoderChannel1047& ch = r.channels[channel_];
    EncoderReading e;
    e.host_ns = host_ns;
    e.delta_counts = ch.position_delta;
    e.board_ticks = ch.packet_time_ticks;
    e.flags = ch.flags;
    e.lost_before = timing_.observe(ch.packet_time_ticks, host_ns);
    return e;
  }

  std::size_t enable(std::span<std::uint8_t> report) const noexcept override {
    if (report.size() < k1047OutputReportBytes) return 0;
    const auto mask = static_cast<std::uint8_t>(1u << channel_);
    return encode_output_1047(mask, report.first(k1047OutputReportBytes)) == CodecStatus::ok
               ? k1047OutputReportBytes
               : 0;
  }

  void restart() noexcept override { timing_.reset(); }

 private:
  std::size_t channel_;
  ReportTimingTracker1047 timing_;
};

struct Registry {
  std::mutex mutex;
  std::map<std::string, MotorBoardKind, std::less<>> motor = {
      {std::string(kShippedMotorBoard),
       {.make = [](const DeviceInfo&, const MotorBoardSettings& s) -> std::unique_ptr<MotorBoard> {
          return std::make_unique<MotorBoard1065>(s);
        },
        .usb = {kPhidgetsVendorId, kProductMotorControl1065},
        .min_acceleration_pct_per_s = k1065MinAccelerationPctPerS,
        .max_acceleration_pct_per_s = k1065FullScaleAccelerationPctPerS}}};
  std::map<std::string, EncoderBoardKind, std::less<>> encoder = {
      {std::string(kShippedEncoderBoard),
       {.make = [](const DeviceInfo& d, int channel) -> std::unique_ptr<EncoderBoard> {
          return std::make_unique<EncoderBoard1047>(d, channel);
        },
        .usb = {kPhidgetsVendorId, kProductEncoder1047}}}};
};

Registry& registry() {
  static Registry r;
  return r;
}

template <typename Map>
std::vector<std::string> names(const Map& map) {
  std::vector<std::string> out;
  for (const auto& [name, maker] : map) out.push_back(name);
  return out;
}

template <typename Map>
typename Map::mapped_type find_kind(const Map& map, std::string_view kind, const char* role) {
  const auto it = map.find(kind);
  if (it != map.end()) return it->second;
  std::string known;
  for (const auto& [name, maker] : map) known += (known.empty() ? "" : ", ") + name;
  throw std::invalid_argument(std::string("no ") + role + " board '" + std::string(kind) +
                              "' (known: " + known + ")");
}

}  // namespace

MotorBoardKind motor_board_kind(std::string_view kind) {
  std::lock_guard lock(registry().mutex);
  return find_kind(registry().motor, kind, "motor");
}

EncoderBoardKind encoder_board_kind(std::string_view kind) {
  std::lock_guard lock(registry().mutex);
  return find_kind(registry().encoder, kind, "encoder");
}

std::unique_ptr<MotorBoard> make_motor_board(std::string_view kind, const DeviceInfo& device,
                                             const MotorBoardSettings& settings) {
  return motor_board_kind(kind).make(device, settings);
}

std::unique_ptr<EncoderBoard> make_encoder_board(std::string_view kind, const DeviceInfo& device,
                                                 int channel) {
  return encoder_board_kind(kind).make(device, channel);
}

bool register_motor_board(std::string_view kind, const MotorBoardKind& board) {
  if (board.make == nullptr) return false;
  std::lock_guard lock(registry().mutex);
  return registry().motor.emplace(std::string(kind), board).second;
}

bool register_encoder_board(std::string_view kind, const EncoderBoardKind& board) {
  if (board.make == nullptr) return false;
  std::lock_guard lock(registry().mutex);
  return registry().encoder.emplace(std::string(kind), board).second;
}

std::vector<std::string> motor_board_kinds() {
  std::lock_guard lock(registry().mutex);
  return names(registry().motor);
}

std::vector<std::string> encoder_board_kinds() {
  std::lock_guard lock(registry().mutex);
  return names(registry().encoder);
}

}  // namespace furuta::bridge
