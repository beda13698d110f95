#pragma once
// Phidget 1047 Encoder HighSpeed 4-input: byte-exact input report and channel-enable output report.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "furuta/firmware_bridge/codec_1065.hpp"  // CodecStatus

namespace furuta::bridge {

inline constexpr std::size_t k1047ChannelCount = 4;
inline constexpr std::size_t k1047ChannelBytes = 10;
inline constexpr std::size_t k1047InputReportMinBytes = k1047ChannelCount * k1047ChannelBytes;
inline constexpr std::size_t k1047OutputReportBytes = 1;
// Delta counts travel as u16 - 0x7FFF, taken as a 16-bit signed integer as the vendor library
// stores it: raw 0xFFFF is -32768, not +32768 (docs/phidget-protocol.md), so deltas span int16.
inline constexpr std::int32_t k1047DeltaOffset = 0x7FFF;
inline constexpr std::int32_t k1047MinDelta = -0x8000;
inline constexpr std::int32_t k1047MaxDelta = 0x7FFF;

inline constexpr std::uint8_t k1047FlagIndexSeen = 0x01;
inline constexpr std::uint8_t k1047FlagEnabledEcho = 0x02;
inline constexpr std::uint8_t k1047FlagDigitalInputFalse = 0x04;  // set = input false

// Seconds per packetTime/curTime tick: 1/12 MHz on firmware 1xx, 1/6 MHz on 2xx.
double tick_seconds_1047(int firmware_version);

struct EncoderChannel1047 {
  std::int32_t position_delta = 0;      // counts since the previous report
  std::int32_t index_delta = 0;         // index position = position - index_delta
  std::uint32_t packet_time_ticks = 0;  // u24: ticks since the previous report
  std::uint16_t cur_time_ticks = 0;     // ticks from the last edge to the report (inferred)
  std::uint8_t flags = 0;

  bool index_seen() const { return flags & k1047FlagIndexSeen; }
  bool enabled() const { return flags & k1047FlagEnabledEcho; }
  bool digital_input() const { return !(flags & k1047FlagDigitalInputFalse); }
};

struct EncoderReport1047 {
  std::array<EncoderChannel1047, k1047ChannelCount> channels{};
};

// too_short below 40 bytes.
CodecStatus decode_input_1047(std::span<const std::uint8_t> report, EncoderReport1047& out);
// out_of_range when a delta or packet time cannot be carried; zero-pads past byte 39.
CodecStatus encode_input_1047(const EncoderReport1047& in, std::span<std::uint8_t> report);

// The output report is one byte: bit i enables channel i.
CodecStatus encode_output_1047(std::uint8_t enable_mask, std::span<std::uint8_t> report);
CodecStatus decode_output_1047(std::span<const std::uint8_t> report, std::uint8_t& enable_mask);

}  // namespace furuta::bridge
