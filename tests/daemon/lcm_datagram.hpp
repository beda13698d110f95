#pragma once
// One LCM message as LCM sends it in a single UDP datagram: "LC02", a sequence number (both 32-bit
// big-endian), the channel and its NUL, the message's bytes; and a port to send it to.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

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

// A UDP port on loopback that no one holds now (the kernel's pick for a socket closed again).
inline std::uint16_t free_loopback_udp_port() {
  const int probe = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  ::bind(probe, reinterpret_cast<sockaddr*>(&address), sizeof address);
  ::getsockname(probe, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(probe);
  return ntohs(address.sin_port);
}

}  // namespace furuta::testing
