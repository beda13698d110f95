#include "furuta/daemon/command_intake.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <system_error>

namespace furuta::daemon {

namespace {

constexpr std::uint32_t kLcmShortMagic = 0x4c433032;  // "LC02"
constexpr std::size_t kLcmHeaderBytes = 8;            // magic, sequence number
constexpr std::size_t kLcmMaxChannelChars = 63;       // LCM_MAX_CHANNEL_NAME_LENGTH
constexpr std::string_view kLcmDefaultGroup = "239.255.76.67";
constexpr std::uint16_t kLcmDefaultPort = 7667;

std::uint32_t big_endian_u32(const std::uint8_t* bytes) {
  return (std::uint32_t{bytes[0]} << 24) | (std::uint32_t{bytes[1]} << 16) |
         (std::uint32_t{bytes[2]} << 8) | std::uint32_t{bytes[3]};
}

[[noreturn]] void throw_socket_error(const UdpmAddress& address, const char* call) {
  const int error = errno;
  throw std::system_error(
      error, std::generic_category(),
      "command intake on " + address.group + ":" + std::to_string(address.port) + ": " + call);
}

}  // namespace

std::optional<UdpmAddress> parse_udpm_url(std::string_view url) {
  constexpr std::string_view kScheme = "udpm://";
  if (url.substr(0, kScheme.size()) != kScheme) return std::nullopt;
  std::string_view network = url.substr(kScheme.size());
  network = network.substr(0, network.find('?'));
  UdpmAddress address{std::string(kLcmDefaultGroup), kLcmDefaultPort};
  if (network.empty()) return address;
  const std::size_t colon = network.find(':');
  address.group = std::string(network.substr(0, colon));
  if (colon != std::string_view::npos) {
    const std::string_view port = network.substr(colon + 1);
    unsigned value = 0;
    const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (error != std::errc{} || end != port.data() + port.size() || value == 0 || value > 65535) {
      return std::nullopt;
    }
    address.port = static_cast<std::uint16_t>(value);
  }
  in_addr group{};
  if (inet_pton(AF_INET, address.group.c_str(), &group) != 1 ||
      !IN_MULTICAST(ntohl(group.s_addr))) {
    return std::nullopt;
  }
  return address;
}

std::optional<LcmDatagram> parse_lcm_datagram(std::span<const std::uint8_t> datagram) {
  if (datagram.size() < kLcmHeaderBytes + 1) return std::nullopt;
  if (big_endian_u32(datagram.data()) != kLcmShortMagic) return std::nullopt;
  const std::span<const std::uint8_t> rest = datagram.subspan(kLcmHeaderBytes);
  const std::size_t search = std::min(rest.size(), kLcmMaxChannelChars + 1);
  const auto* nul = static_cast<const std::uint8_t*>(std::memchr(rest.data(), 0, search));
  if (nul == nullptr) return std::nullopt;
  const auto channel_chars = static_cast<std::size_t>(nul - rest.data());
  return LcmDatagram{std::string_view(reinterpret_cast<const char*>(rest.data()), channel_chars),
                     rest.subspan(channel_chars + 1)};
}

MulticastReceiver::MulticastReceiver(const UdpmAddress& address, int receive_buffer_bytes)
    : buffers_(kBatch * kMaxDatagramBytes) {
  for (std::size_t i = 0; i < kBatch; ++i) {
    slots_[i].iov_base = buffers_.data() + i * kMaxDatagramBytes;
    slots_[i].iov_len = kMaxDatagramBytes;
    messages_[i].msg_hdr.msg_iov = &slots_[i];
    messages_[i].msg_hdr.msg_iovlen = 1;
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw_socket_error(address, "socket");
  try {
    const int one = 1;
    if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0) {
      throw_socket_error(address, "setsockopt(SO_REUSEADDR)");
    }
    // A smaller queue than asked is not an error: the kernel caps it at net.core.rmem_max.
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof receive_buffer_bytes);
    sockaddr_in bind_address{};
    bind_address.sin_family = AF_INET;
    bind_address.sin_addr.s_addr = htonl(INADDR_ANY);
    bind_address.sin_port = htons(address.port);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&bind_address), sizeof bind_address) != 0) {
      throw_socket_error(address, "bind");
    }
    ip_mreq membership{};
    if (inet_pton(AF_INET, address.group.c_str(), &membership.imr_multiaddr) != 1) {
      errno = EINVAL;
      throw_socket_error(address, "inet_pton");
    }
    membership.imr_interface.s_addr = htonl(INADDR_ANY);
    if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0) {
      throw_socket_error(address, "setsockopt(IP_ADD_MEMBERSHIP)");
    }
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

MulticastReceiver::~MulticastReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t MulticastReceiver::receive(int timeout_ms) {
  pollfd waiting{fd_, POLLIN, 0};
  if (::poll(&waiting, 1, timeout_ms) <= 0) return 0;
  const int taken = ::recvmmsg(fd_, messages_.data(), kBatch, MSG_DONTWAIT, nullptr);
  return taken > 0 ? static_cast<std::size_t>(taken) : 0;
}

std::span<const std::uint8_t> MulticastReceiver::datagram(std::size_t i) const {
  return {buffers_.data() + i * kMaxDatagramBytes,
          std::min<std::size_t>(messages_[i].msg_len, kMaxDatagramBytes)};
}

bool MulticastReceiver::oversized(std::size_t i) const {
  return (messages_[i].msg_hdr.msg_flags & MSG_TRUNC) != 0;
}

}  // namespace furuta::daemon
