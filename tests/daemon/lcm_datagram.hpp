#pragma once
// One LCM message as LCM sends it in a single UDP datagram: "LC02", a sequence number (both 32-bit
// big-endian), the channel and its NUL, the message's bytes.

#include <cstdint>
#include <string>
#include <vector>

namespace furuta::testing {

inline std::vector<std::uint8_t> lcm_datagram(const std::string& channel,
                                              const std::vector<std::uint8_t>& message,
                                              std::uint32_t sequence) {
  std::vector<std::uint8_t> datagram{'L', 'C', '0', '2'};
  for (int shift = 24; shift >= 0; shift -= 8) {
    datagram.push_back(static_cast<std::uint8_t>(sequence >> shift));
  }
  datagram.insert(datagram.end(), channel.begin(), channel.end());
  datagram.push_back(0);
  datagram.insert(datagram.end(), message.begin(), message.end());
  return datagram;
}

}  // namespace furuta::testing
