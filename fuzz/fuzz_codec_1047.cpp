// The 1047 decoders on arbitrary bytes: never out of bounds, and whatever decodes re-encodes to the
// same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "furuta/firmware_bridge/codec_1047.hpp"

using namespace furuta::bridge;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  EncoderReport1047 report;
  const CodecStatus status = decode_input_1047(bytes, report);
  check((status == CodecStatus::ok) == (size >= k1047InputReportMinBytes));
  if (status == CodecStatus::ok) {
    for (const EncoderChannel1047& ch : report.channels) {
      check(ch.position_delta >= k1047MinDelta && ch.position_delta <= k1047MaxDelta);
      check(ch.index_delta >= k1047MinDelta && ch.index_delta <= k1047MaxDelta);
      check(ch.packet_time_ticks <= 0xFFFFFFu);
    }
    std::vector<std::uint8_t> again(size);
    check(encode_input_1047(report, again) == CodecStatus::ok);
    check(std::memcmp(again.data(), bytes.data(), k1047InputReportMinBytes) == 0);
  }
  std::uint8_t mask = 0;
  if (decode_output_1047(bytes, mask) == CodecStatus::ok) {
    // Decoding is raw (a replay shows high bits as they were); encoding refuses bits above
    // channel 3.
    std::vector<std::uint8_t> again(size);
    const CodecStatus encoded = encode_output_1047(mask, again);
    check((encoded == CodecStatus::ok) == (mask < (1u << k1047ChannelCount)));
    if (encoded == CodecStatus::ok) check(again[0] == bytes[0]);
  } else {
    check(size < k1047OutputReportBytes);
  }
  for (int firmware : {0, 100, 199, 200, 299, 1000, -1}) {
    (void)tick_seconds_1047(firmware);
  }
  return 0;
}
