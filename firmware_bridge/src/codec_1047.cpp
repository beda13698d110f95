#include "furuta/firmware_bridge/codec_1047.hpp"

#include <algorithm>

#include "codec_wire.hpp"

namespace furuta::bridge {

namespace {

// Per-channel byte offsets within the channel's 10 bytes (docs/phidget-protocol.md, "1047 input
// report").
constexpr std::size_t kChPosition = 0;
constexpr std::size_t kChIndex = 2;
constexpr std::size_t kChPacketTime = 4;
constexpr std::size_t kChCurTime = 7;
constexpr std::size_t kChFlags = 9;

constexpr std::uint32_t kMaxPacketTimeTicks = 0xFFFFFF;  // u24
// Firmware 2xx runs its tick at half the rate of 1xx.
constexpr int kFirstFirmware2xx = 200;
constexpr double kTickHz1xx = 12e6;
constexpr double kTickHz2xx = 6e6;
// Only channels 0..3 exist; a higher bit is a caller bug, not a channel.
constexpr std::uint8_t kValidEnableBits = (1u << k1047ChannelCount) - 1;

bool delta_fits(std::int32_t delta) {
  return delta >= k1047MinDelta && delta <= k1047MaxDelta;
}

// The difference wraps to int16 (C++20 defines the narrowing as modulo 2^16): 0xFFFF -> -32768.
std::int32_t decode_delta(std::uint16_t raw) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(raw - k1047DeltaOffset));
}

std::uint16_t encode_delta(std::int32_t delta) {
  return static_cast<std::uint16_t>(delta + k1047DeltaOffset);
}

}  // namespace

double tick_seconds_1047(int firmware_version) {
  return firmware_version < kFirstFirmware2xx ? 1.0 / kTickHz1xx : 1.0 / kTickHz2xx;
}

CodecStatus decode_input_1047(std::span<const std::uint8_t> report, EncoderReport1047& out) {
  if (report.size() < k1047InputReportMinBytes) return CodecStatus::too_short;
  for (std::size_t i = 0; i < k1047ChannelCount; ++i) {
    const std::size_t base = i * k1047ChannelBytes;
    EncoderChannel1047& ch = out.channels[i];
    ch.position_delta = decode_delta(wire::get_u16(report, base + kChPosition));
    ch.index_delta = decode_delta(wire::get_u16(report, base + kChIndex));
    ch.packet_time_ticks = wire::get_u24(report, base + kChPacketTime);
    ch.cur_time_ticks = wire::get_u16(report, base + kChCurTime);
    ch.flags = report[base + kChFlags];
  }
  return CodecStatus::ok;
}

CodecStatus encode_input_1047(const EncoderReport1047& in, std::span<std::uint8_t> report) {
  if (report.size() < k1047InputReportMinBytes) return CodecStatus::buffer_too_small;
  // Check everything first so a rejected report leaves the buffer untouched.
  for (const EncoderChannel1047& ch : in.channels) {
    if (!delta_fits(ch.position_delta) || !delta_fits(ch.index_delta) ||
        ch.packet_time_ticks > kMaxPacketTimeTicks) {
      return CodecStatus::out_of_range;
    }
  }
  for (std::size_t i = 0; i < k1047ChannelCount; ++i) {
    const std::size_t base = i * k1047ChannelBytes;
    const EncoderChannel1047& ch = in.channels[i];
    wire::put_u16(report, base + kChPosition, encode_delta(ch.position_delta));
    wire::put_u16(report, base + kChIndex, encode_delta(ch.index_delta));
    wire::put_u24(report, base + kChPacketTime, ch.packet_time_ticks);
    wire::put_u16(report, base + kChCurTime, ch.cur_time_ticks);
    report[base + kChFlags] = ch.flags;
  }
  std::fill(report.begin() + k1047InputReportMinBytes, report.end(), std::uint8_t{0});
  return CodecStatus::ok;
}

CodecStatus encode_output_1047(std::uint8_t enable_mask, std::span<std::uint8_t> report) {
  if (report.size() < k1047OutputReportBytes) return CodecStatus::buffer_too_small;
  if ((enable_mask & ~kValidEnableBits) != 0) return CodecStatus::out_of_range;
  report[0] = enable_mask;
  std::fill(report.begin() + k1047OutputReportBytes, report.end(), std::uint8_t{0});
  return CodecStatus::ok;
}

CodecStatus decode_output_1047(std::span<const std::uint8_t> report, std::uint8_t& enable_mask) {
  if (report.size() < k1047OutputReportBytes) return CodecStatus::too_short;
  // Raw, like the other decoders: a replayed report is shown as it was, high bits included.
  enable_mask = report[0];
  return CodecStatus::ok;
}

}  // namespace furuta::bridge
