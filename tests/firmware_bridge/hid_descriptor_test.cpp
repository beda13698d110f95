// The report-descriptor walker, on hand-written descriptors: the lengths it must find, and that no
// malformed input makes it read outside the span (run under ASan/valgrind to make that bite; the
// truncation tests also copy each prefix into an exactly-sized heap buffer for that reason).

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "furuta/firmware_bridge/usb_backends.hpp"

namespace furuta::bridge {
namespace {

// Shaped like a vendor-defined Phidget descriptor (1065-like): 25-byte input, 4-byte output.
const std::vector<std::uint8_t> kPhidgetLike = {
    0x06, 0x00, 0xFF,  // Usage Page (Vendor Defined 0xFF00)
    0x09, 0x01,        // Usage (1)
    0xA1, 0x01,        // Collection (Application)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x19,        //   Report Count (25)
    0x09, 0x01,        //   Usage (1)
    0x81, 0x02,        //   Input (Data, Var, Abs)
    0x95, 0x04,        //   Report Count (4)
    0x09, 0x01,        //   Usage (1)
    0x91, 0x02,        //   Output (Data, Var, Abs)
    0xC0,              // End Collection
};

HidReportLengths parse(const std::vector<std::uint8_t>& bytes) {
  return parse_hid_report_lengths(std::span<const std::uint8_t>(bytes.data(), bytes.size()));
}

TEST(HidDescriptor, PhidgetLikeDescriptorGivesInputAndOutputLengths) {
  const HidReportLengths lengths = parse(kPhidgetLike);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 4u);
}

TEST(HidDescriptor, EncoderLikeDescriptorWithEightByteOutput) {
  const std::vector<std::uint8_t> bytes = {0x06, 0x00, 0xFF, 0x09, 0x01, 0xA1,
                                           0x01, 0x75, 0x08,  // page, usage, collection, size 8
                                           0x95, 0x28, 0x09, 0x01, 0x81, 0x02,  // 40 bytes in
                                           0x95, 0x08, 0x09, 0x01, 0x91, 0x02,  // 8 bytes out
                                           0xC0};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 40u);
  EXPECT_EQ(lengths.output_bytes, 8u);
}

TEST(HidDescriptor, MissingOutputItemGivesZeroOutput) {
  const std::vector<std::uint8_t> bytes = {0x06, 0x00, 0xFF, 0xA1, 0x01, 0x75,
                                           0x08, 0x95, 0x19, 0x81, 0x02, 0xC0};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 0u);
}

TEST(HidDescriptor, EmptyDescriptorGivesZeros) {
  const HidReportLengths lengths = parse_hid_report_lengths({});
  EXPECT_EQ(lengths.input_bytes, 0u);
  EXPECT_EQ(lengths.output_bytes, 0u);
}

// Chosen behaviour: the Input items of one report are summed (what the device really sends), not
// only the Report Count before the first one as the vendor libraries do.
TEST(HidDescriptor, SeveralInputItemsInOneReportAreSummed) {
  const std::vector<std::uint8_t> bytes = {0x06, 0x00, 0xFF, 0xA1, 0x01,        //
                                           0x75, 0x08, 0x95, 0x10, 0x81, 0x02,  // 16 bytes of data
                                           0x95, 0x09, 0x81, 0x03,  // 9 bytes of constant padding
                                           0x95, 0x04, 0x91, 0x02,  // 4 bytes out
                                           0xC0};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 4u);
}

TEST(HidDescriptor, ReportSizeOtherThanEightBitsRoundsUpToBytes) {
  const std::vector<std::uint8_t> bytes = {
      0x75, 0x01, 0x95, 0x05, 0x81, 0x02,  // 5 one-bit buttons
      0x75, 0x03, 0x95, 0x01, 0x81, 0x03,  // 3 bits of padding: one byte so far
      0x75, 0x10, 0x95, 0x02, 0x81, 0x02,  // two 16-bit fields: 5 bytes
      0x75, 0x01, 0x95, 0x0C, 0x91, 0x02,  // 12 one-bit outputs: 2 bytes (rounded up)
  };
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 5u);
  EXPECT_EQ(lengths.output_bytes, 2u);
}

TEST(HidDescriptor, MultiByteItemDataIsLittleEndian) {
  const std::vector<std::uint8_t> bytes = {
      0x75, 0x08,                    // Report Size (8)
      0x96, 0x00, 0x01,              // Report Count (256), 2-byte data
      0x81, 0x02,                    //
      0x97, 0x03, 0x00, 0x00, 0x00,  // Report Count (3), 4-byte data (size code 3)
      0x91, 0x02};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 256u);
  EXPECT_EQ(lengths.output_bytes, 3u);
}

TEST(HidDescriptor, LongItemsAreSkippedWhole) {
  // A long item whose data would read as Report Count (99) / Input if it were walked as short
  // items.
  const std::vector<std::uint8_t> bytes = {0x75, 0x08, 0x95, 0x19,  //
                                           0xFE, 0x04, 0x10, 0x95, 0x63, 0x81,
                                           0x02,  // long item: 4 data bytes, tag 0x10
                                           0x81, 0x02, 0x95, 0x04, 0x91, 0x02};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 4u);
}

TEST(HidDescriptor, PushAndPopRestoreGlobals) {
  const std::vector<std::uint8_t> bytes = {
      0x75, 0x08, 0x95, 0x19,  // size 8, count 25
      0xA4,                    // Push
      0x95, 0x02, 0x75, 0x10,  // count 2, size 16 (feature-like, not used)
      0xB4,                    // Pop: back to 8 x 25
      0x81, 0x02,              //
      0xB4,                    // unbalanced Pop: ignored
      0x95, 0x04, 0x91, 0x02};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 4u);
}

TEST(HidDescriptor, OnlyTheFirstNumberedReportIsMeasured) {
  const std::vector<std::uint8_t> bytes = {
      0x85, 0x01, 0x75, 0x08, 0x95, 0x19, 0x81, 0x02,  // report 1: 25 bytes in
      0x85, 0x02, 0x95, 0x30, 0x81, 0x02,              // report 2: 48 bytes in (ignored)
      0x85, 0x01, 0x95, 0x04, 0x91, 0x02};             // report 1: 4 bytes out
  const HidReportLengths lengths = parse(bytes);
  EXPECT_EQ(lengths.input_bytes, 25u);
  EXPECT_EQ(lengths.output_bytes, 4u);
}

TEST(HidDescriptor, HugeCountsSaturateInsteadOfOverflowing) {
  const std::vector<std::uint8_t> bytes = {0x77, 0xFF, 0xFF, 0xFF, 0xFF,  // Report Size (2^32 - 1)
                                           0x97, 0xFF, 0xFF, 0xFF, 0xFF,  // Report Count (2^32 - 1)
                                           0x81, 0x02, 0x81, 0x02};
  const HidReportLengths lengths = parse(bytes);
  EXPECT_GT(lengths.input_bytes, 0u);
  EXPECT_LE(lengths.input_bytes, (std::size_t{1} << 32) / 8);
}

// Every prefix of a valid descriptor, in an exactly-sized allocation so an over-read is a heap
// overflow a sanitizer would catch. A cut through an item ends the walk: the cut item counts for
// nothing, the items before it keep their effect.
TEST(HidDescriptor, EveryTruncationIsSafeAndMonotonic) {
  for (std::size_t n = 0; n <= kPhidgetLike.size(); ++n) {
    const auto copy = std::make_unique<std::uint8_t[]>(n == 0 ? 1 : n);
    std::copy(kPhidgetLike.begin(), kPhidgetLike.begin() + static_cast<std::ptrdiff_t>(n),
              copy.get());
    const HidReportLengths lengths = parse_hid_report_lengths(std::span(copy.get(), n));
    // The Input item ends at byte 20 and the Output item at byte 26 (see kPhidgetLike).
    EXPECT_EQ(lengths.input_bytes, n >= 20 ? 25u : 0u) << "prefix " << n;
    EXPECT_EQ(lengths.output_bytes, n >= 26 ? 4u : 0u) << "prefix " << n;
  }
}

TEST(HidDescriptor, TruncatedItemDataIsNotRead) {
  // Report Count claims 4 data bytes but only 2 remain; a Report Count taken from beyond the end
  // would change the answer.
  const std::vector<std::uint8_t> a = {0x75, 0x08, 0x95, 0x19, 0x81, 0x02, 0x97, 0x04, 0x00};
  EXPECT_EQ(parse(a).input_bytes, 25u);
  EXPECT_EQ(parse(a).output_bytes, 0u);

  // A long item whose stated size runs past the end, and one cut inside its header.
  const std::vector<std::uint8_t> b = {0x75, 0x08, 0x95, 0x19, 0x81, 0x02, 0xFE, 0xFF, 0x10, 0x91};
  EXPECT_EQ(parse(b).input_bytes, 25u);
  EXPECT_EQ(parse(b).output_bytes, 0u);
  const std::vector<std::uint8_t> c = {0x75, 0x08, 0x95, 0x04, 0x91, 0x02, 0xFE};
  EXPECT_EQ(parse(c).output_bytes, 4u);
  const std::vector<std::uint8_t> d = {0x75, 0x08, 0x95, 0x04, 0x91, 0x02, 0xFE, 0x00};
  EXPECT_EQ(parse(d).output_bytes, 4u);
}

TEST(HidDescriptor, GarbageNeverCrashes) {
  // Deterministic pseudo-random bytes, each length in its own exactly-sized allocation.
  std::uint32_t state = 12345;
  for (int round = 0; round < 2000; ++round) {
    const std::size_t n = static_cast<std::size_t>(round % 64);
    const auto bytes = std::make_unique<std::uint8_t[]>(n == 0 ? 1 : n);
    for (std::size_t i = 0; i < n; ++i) {
      state = state * 1664525u + 1013904223u;
      bytes[i] = static_cast<std::uint8_t>(state >> 24);
    }
    const HidReportLengths lengths = parse_hid_report_lengths(std::span(bytes.get(), n));
    EXPECT_LE(lengths.input_bytes, (std::size_t{1} << 32) / 8);
  }
}

}  // namespace
}  // namespace furuta::bridge
