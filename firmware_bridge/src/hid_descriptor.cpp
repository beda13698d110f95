// A minimal HID report-descriptor walker: just enough to know how long the first input and output
// reports are (HID 1.11, section 6.2.2). It never trusts the descriptor's own lengths: every item
// is bounds-checked against the span, so a truncated or malformed descriptor ends the walk instead
// of reading past it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "furuta/firmware_bridge/usb_backends.hpp"

namespace furuta::bridge {

namespace {

// Short-item prefixes with the size bits (0-1) masked off: tag (bits 4-7) and type (bits 2-3).
constexpr std::uint8_t kItemInput = 0x80;        // main
constexpr std::uint8_t kItemOutput = 0x90;       // main
constexpr std::uint8_t kItemReportSize = 0x74;   // global
constexpr std::uint8_t kItemReportId = 0x84;     // global
constexpr std::uint8_t kItemReportCount = 0x94;  // global
constexpr std::uint8_t kItemPush = 0xA4;         // global
constexpr std::uint8_t kItemPop = 0xB4;          // global
constexpr std::uint8_t kLongItemPrefix = 0xFE;

// Push/Pop nest the global state; real descriptors use one or two levels. Deeper pushes are
// ignored (the state is still tracked, only the save is lost) rather than allocating.
constexpr std::size_t kMaxPushDepth = 8;

// Anything beyond this is not a report a USB full-speed board sends; it also keeps the sums far
// from overflow whatever the descriptor claims.
constexpr std::uint64_t kMaxReportBits = std::uint64_t{1} << 32;

struct GlobalState {
  std::uint32_t report_size = 0;   // bits per field
  std::uint32_t report_count = 0;  // fields
  std::uint32_t report_id = 0;     // 0: unnumbered reports
};

// The lengths of one report kind (input or output). All main items of that kind belonging to the
// report of the first such item are summed: a report built from several Input items (e.g. data then
// padding) is as long as all of them together, which is what the device sends and what a transfer
// must be sized for. (The vendor libraries take only the Report Count before the first item; for a
// single-item descriptor, like the Phidgets', both give the same answer.)
class ReportAccumulator {
 public:
  void add(const GlobalState& state) {
    if (!seen_) {
      seen_ = true;
      report_id_ = state.report_id;
    } else if (state.report_id != report_id_) {
      return;  // another report: not the first one's length
    }
    const std::uint64_t item_bits = static_cast<std::uint64_t>(state.report_size) *
                                    static_cast<std::uint64_t>(state.report_count);
    bits_ = (item_bits >= kMaxReportBits - bits_) ? kMaxReportBits : bits_ + item_bits;
  }
  std::size_t bytes() const { return static_cast<std::size_t>((bits_ + 7) / 8); }

 private:
  bool seen_ = false;
  std::uint32_t report_id_ = 0;
  std::uint64_t bits_ = 0;
};

std::uint32_t little_endian_value(std::span<const std::uint8_t> data) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    value |= static_cast<std::uint32_t>(data[i]) << (8 * i);
  }
  return value;
}

}  // namespace

HidReportLengths parse_hid_report_lengths(std::span<const std::uint8_t> descriptor) {
  GlobalState state;
  std::array<GlobalState, kMaxPushDepth> stack{};
  std::size_t depth = 0;    // pushes recorded in `stack`
  std::size_t dropped = 0;  // pushes beyond the stack, so their pops do not unbalance it
  ReportAccumulator input;
  ReportAccumulator output;

  std::size_t pos = 0;
  while (pos < descriptor.size()) {
    const std::uint8_t prefix = descriptor[pos];
    const std::size_t remaining = descriptor.size() - pos - 1;

    if (prefix == kLongItemPrefix) {
      // Long item: prefix, bDataSize, bLongItemTag, data. No defined long items carry report
      // layout, so they are skipped whole.
      if (remaining < 2) break;
      const std::size_t data_size = descriptor[pos + 1];
      if (remaining - 2 < data_size) break;
      pos += 3 + data_size;
      continue;
    }

    const std::size_t size_code = prefix & 0x03;
    const std::size_t data_size = size_code == 3 ? 4 : size_code;
    if (remaining < data_size) break;  // truncated item: its value is unknown, stop here
    const std::uint32_t value = little_endian_value(descriptor.subspan(pos + 1, data_size));
    pos += 1 + data_size;

    switch (prefix & 0xFC) {
      case kItemReportSize:
        state.report_size = value;
        break;
      case kItemReportCount:
        state.report_count = value;
        break;
      case kItemReportId:
        state.report_id = value;
        break;
      case kItemPush:
        if (depth < stack.size()) {
          stack[depth++] = state;
        } else {
          ++dropped;
        }
        break;
      case kItemPop:
        if (dropped > 0) {
          --dropped;
        } else if (depth > 0) {
          state = stack[--depth];
        }
        break;
      case kItemInput:
        input.add(state);
        break;
      case kItemOutput:
        output.add(state);
        break;
      default:
        break;  // other items do not change report lengths
    }
  }

  return HidReportLengths{.input_bytes = input.bytes(), .output_bytes = output.bytes()};
}

}  // namespace furuta::bridge
