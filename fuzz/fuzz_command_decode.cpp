// The raw LCM decode of rig_command_t, as a message on RIG_COMMAND reaches the daemon: any bytes
// from the network. Decoding must fail cleanly or give a message that re-encodes and decodes to
// itself; an exception here would escape the daemon's LCM thread.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "furuta/rig_command_t.hpp"

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

bool same(const furuta::rig_command_t& a, const furuta::rig_command_t& b) {
  // Bitwise for the doubles: NaN payloads travel unchanged.
  return a.request_id == b.request_id && a.kind == b.kind && a.profile == b.profile &&
         std::memcmp(&a.amplitude_duty, &b.amplitude_duty, sizeof(double)) == 0 &&
         std::memcmp(&a.duration_s, &b.duration_s, sizeof(double)) == 0 && a.label == b.label &&
         a.seed == b.seed;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 1 << 20) return 0;
  const std::vector<std::uint8_t> bytes(data, data + size);
  furuta::rig_command_t command{};
  const int used = command.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (used < 0) return 0;
  check(used <= static_cast<int>(size));
  std::vector<std::uint8_t> again(static_cast<std::size_t>(command.getEncodedSize()));
  check(command.encode(again.data(), 0, static_cast<int>(again.size())) ==
        static_cast<int>(again.size()));
  furuta::rig_command_t back{};
  check(back.decode(again.data(), 0, static_cast<int>(again.size())) ==
        static_cast<int>(again.size()));
  check(same(command, back));
  return 0;
}
