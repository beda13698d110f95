#include "furuta/firmware_bridge/codec_1047.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

namespace furuta::bridge {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Four channels at offsets 0, 10, 20, 30; deltas travel as u16 = delta + 0x7fff, read back as the
// vendor does: libphidget21 2.1.8 cphidgetencoder.c, the 1047 branch of the input parser, computes
// (u16 - 0x7fff) into `short positionChange[]` / `indexChange[]`, so the difference wraps to int16.
const Bytes kReport = {
    // channel 0
    0x80, 0x04,        // position +5: 5 + 0x7fff = 0x8004
    0x7F, 0xFF,        // index 0: 0x7fff
    0x01, 0x77, 0x00,  // packetTime 96000 = 0x017700 (8 ms at 12 MHz)
    0x01, 0x23,        // curTime 0x0123 = 291
    0x03,              // index seen, enabled; 0x04 clear: digital input true
    // channel 1
    0x7F, 0xFC,        // position -3: 0x7ffc
    0x00, 0x00,        // index -0x7fff: 0x0000
    0xFF, 0xFF, 0xFF,  // packetTime 0xffffff = 16777215 (largest u24)
    0xFF, 0xFF,        // curTime 65535
    0x06,              // enabled, digital input false
    // channel 2
    0xFF, 0xFF,        // position -0x8000: 0xffff - 0x7fff = 0x8000 as int16 (not +32768)
    0x80, 0x00,        // index +1: 0x8000
    0x00, 0xBB, 0x80,  // packetTime 48000 = 0x00bb80 (8 ms at 6 MHz)
    0x00, 0x00,        // curTime 0
    0x00,              // disabled
    // channel 3
    0x00, 0x00,        // position -0x7fff: 0x0000
    0x80, 0x63,        // index +100: 0x7fff + 0x64 = 0x8063
    0x00, 0x00, 0x01,  // packetTime 1
    0x80, 0x00,        // curTime 0x8000 = 32768
    0x02,              // enabled
};

EncoderReport1047 report_struct() {
  EncoderReport1047 r;
  r.channels[0] = {5, 0, 96000, 291, 0x03};
  r.channels[1] = {-3, -0x7FFF, 0xFFFFFF, 65535, 0x06};
  r.channels[2] = {-0x8000, 1, 48000, 0, 0x00};
  r.channels[3] = {-0x7FFF, 100, 1, 32768, 0x02};
  return r;
}

void expect_same(const EncoderReport1047& a, const EncoderReport1047& b) {
  for (std::size_t i = 0; i < k1047ChannelCount; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(a.channels[i].position_delta, b.channels[i].position_delta);
    EXPECT_EQ(a.channels[i].index_delta, b.channels[i].index_delta);
    EXPECT_EQ(a.channels[i].packet_time_ticks, b.channels[i].packet_time_ticks);
    EXPECT_EQ(a.channels[i].cur_time_ticks, b.channels[i].cur_time_ticks);
    EXPECT_EQ(a.channels[i].flags, b.channels[i].flags);
  }
}

TEST(Codec1047Input, DecodesEveryChannel) {
  ASSERT_EQ(kReport.size(), 40u);
  EncoderReport1047 r;
  ASSERT_EQ(decode_input_1047(kReport, r), CodecStatus::ok);
  expect_same(r, report_struct());

  EXPECT_TRUE(r.channels[0].index_seen());
  EXPECT_TRUE(r.channels[0].enabled());
  EXPECT_TRUE(r.channels[0].digital_input());
  EXPECT_FALSE(r.channels[1].index_seen());
  EXPECT_TRUE(r.channels[1].enabled());
  EXPECT_FALSE(r.channels[1].digital_input());
  EXPECT_FALSE(r.channels[2].enabled());
  EXPECT_TRUE(r.channels[3].enabled());
}

TEST(Codec1047Input, IgnoresBytesPastTheFourChannels) {
  Bytes longer = kReport;
  longer.resize(64, 0xEE);
  EncoderReport1047 r;
  ASSERT_EQ(decode_input_1047(longer, r), CodecStatus::ok);
  expect_same(r, report_struct());
}

TEST(Codec1047Input, TooShort) {
  const Bytes b(kReport.begin(), kReport.begin() + 39);
  EncoderReport1047 r;
  EXPECT_EQ(decode_input_1047(b, r), CodecStatus::too_short);
  EXPECT_EQ(decode_input_1047({}, r), CodecStatus::too_short);
}

TEST(Codec1047Input, EncodesTheHandWrittenBytesAndZeroPads) {
  std::array<std::uint8_t, 44> report;
  report.fill(0xAA);
  ASSERT_EQ(encode_input_1047(report_struct(), report), CodecStatus::ok);
  Bytes expected = kReport;
  expected.resize(44, 0x00);
  EXPECT_EQ(Bytes(report.begin(), report.end()), expected);

  std::array<std::uint8_t, 39> small{};
  EXPECT_EQ(encode_input_1047(report_struct(), small), CodecStatus::buffer_too_small);
}

TEST(Codec1047Input, RejectsDeltasAndTimesBeyondTheWireAndWritesNothing) {
  auto rejected = [](EncoderReport1047 r) {
    std::array<std::uint8_t, 40> report;
    report.fill(0xAA);
    const CodecStatus status = encode_input_1047(r, report);
    bool untouched = true;
    for (std::uint8_t b : report) untouched = untouched && b == 0xAA;
    return status == CodecStatus::out_of_range && untouched;
  };
  EncoderReport1047 r = report_struct();
  r.channels[3].position_delta = 0x8000;  // one above the largest: it would read back as -32768
  EXPECT_TRUE(rejected(r));
  r = report_struct();
  r.channels[3].position_delta = -0x8001;  // one below the smallest
  EXPECT_TRUE(rejected(r));
  r = report_struct();
  r.channels[1].index_delta = 0x8000;
  EXPECT_TRUE(rejected(r));
  r = report_struct();
  r.channels[2].index_delta = -0x8001;
  EXPECT_TRUE(rejected(r));
  r = report_struct();
  r.channels[0].packet_time_ticks = 0x1000000;  // 25 bits
  EXPECT_TRUE(rejected(r));
}

TEST(Codec1047Input, RoundTrips) {
  EncoderReport1047 original = report_struct();
  for (std::int32_t delta : {k1047MinDelta, -1000, -1, 0, 1, 1000, k1047MaxDelta}) {
    for (auto& ch : original.channels) {
      ch.position_delta = delta;
      ch.index_delta = -delta + 1 > k1047MaxDelta ? k1047MaxDelta : -delta + 1;
    }
    std::array<std::uint8_t, 40> report{};
    ASSERT_EQ(encode_input_1047(original, report), CodecStatus::ok);
    EncoderReport1047 back;
    ASSERT_EQ(decode_input_1047(report, back), CodecStatus::ok);
    expect_same(back, original);
  }
}

// The vendor's reading of the two extremes (cphidgetencoder.c, 1047 branch: `short` deltas):
// 0xffff - 0x7fff = 0x8000 stored in a short is -32768, 0x0000 - 0x7fff is -32767. A delta of
// +32768 cannot be carried at all, so the two codecs agree on every one of the 65536 raw values.
TEST(Codec1047Input, RawFFFFIsMinus32768AsTheVendorReadsIt) {
  Bytes report(40, 0x00);
  for (std::size_t i = 0; i < k1047ChannelCount; ++i) {
    report[10 * i + 0] = 0xFF;  // position raw 0xffff
    report[10 * i + 1] = 0xFF;
    report[10 * i + 2] = 0x00;  // index raw 0x0000
    report[10 * i + 3] = 0x00;
  }
  EncoderReport1047 r;
  ASSERT_EQ(decode_input_1047(report, r), CodecStatus::ok);
  for (const EncoderChannel1047& ch : r.channels) {
    EXPECT_EQ(ch.position_delta, -32768);
    EXPECT_EQ(ch.index_delta, -32767);
  }
  for (std::uint32_t raw = 0; raw <= 0xFFFF; ++raw) {
    report[0] = static_cast<std::uint8_t>(raw >> 8);
    report[1] = static_cast<std::uint8_t>(raw);
    ASSERT_EQ(decode_input_1047(report, r), CodecStatus::ok);
    const auto vendor = static_cast<std::int16_t>(static_cast<std::uint16_t>(raw - 0x7FFF));
    ASSERT_EQ(r.channels[0].position_delta, vendor) << "raw " << raw;
    std::array<std::uint8_t, 40> again{};
    ASSERT_EQ(encode_input_1047(r, again), CodecStatus::ok);
    ASSERT_EQ(again[0] << 8 | again[1], static_cast<int>(raw)) << "raw " << raw;
  }
}

TEST(Codec1047Output, EnableMaskIsOneByte) {
  std::array<std::uint8_t, 1> one{};
  ASSERT_EQ(encode_output_1047(0x05, one), CodecStatus::ok);  // channels 0 and 2
  EXPECT_EQ(one[0], 0x05);

  std::array<std::uint8_t, 3> longer;
  longer.fill(0xAA);
  ASSERT_EQ(encode_output_1047(0x0F, longer), CodecStatus::ok);
  EXPECT_EQ(longer, (std::array<std::uint8_t, 3>{0x0F, 0x00, 0x00}));

  EXPECT_EQ(encode_output_1047(0x10, one), CodecStatus::out_of_range);  // there is no channel 4
  EXPECT_EQ(encode_output_1047(0x01, std::span<std::uint8_t>{}), CodecStatus::buffer_too_small);

  std::uint8_t mask = 0xEE;
  EXPECT_EQ(decode_output_1047(std::span<const std::uint8_t>{}, mask), CodecStatus::too_short);
  EXPECT_EQ(mask, 0xEE);
  for (std::uint8_t m = 0; m < 16; ++m) {
    ASSERT_EQ(encode_output_1047(m, one), CodecStatus::ok);
    ASSERT_EQ(decode_output_1047(one, mask), CodecStatus::ok);
    EXPECT_EQ(mask, m);
  }
}

TEST(Codec1047, TickLengthDependsOnFirmwareGeneration) {
  EXPECT_DOUBLE_EQ(tick_seconds_1047(101), 1.0 / 12e6);
  EXPECT_DOUBLE_EQ(tick_seconds_1047(199), 1.0 / 12e6);
  EXPECT_DOUBLE_EQ(tick_seconds_1047(200), 1.0 / 6e6);
  EXPECT_DOUBLE_EQ(tick_seconds_1047(205), 1.0 / 6e6);
  // 96000 ticks on 1xx and 48000 on 2xx are both one 8 ms report period.
  EXPECT_NEAR(96000 * tick_seconds_1047(101), 0.008, 1e-15);
  EXPECT_NEAR(48000 * tick_seconds_1047(205), 0.008, 1e-15);
}

}  // namespace
}  // namespace furuta::bridge
