#pragma once
// The daemon's own reader of command datagrams on LCM's UDP multicast group.
//
// LCM's receive path costs two threads a select and a read per datagram. Under a flood of
// wrongly signed commands that is most of the daemon's time, and an e-stop waits in the socket
// behind the flood. This reader takes up to `kBatch` datagrams per system call (recvmmsg) from a
// socket of its own on the same group and port, and hands the LCM messages that fit in one
// datagram to the daemon in the order they arrived. The daemon then subscribes to nothing through
// LCM, so LCM opens no receive socket at all.
//
// LCM's one-datagram message ("LC02"): a 32-bit magic 0x4c433032 and a 32-bit sequence number,
// both big-endian, the channel name ending in a NUL, then the message's bytes. Larger messages
// travel as fragments ("LC03"); no command is that large, so fragments are not messages here.

#include <sys/socket.h>
#include <sys/uio.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace furuta::daemon {

// The group and port of an LCM "udpm://GROUP:PORT?options" URL.
struct UdpmAddress {
  std::string group;  // dotted IPv4, a multicast address
  std::uint16_t port = 0;
};

// nullopt for a URL of another provider (memq://, file://) or one that names no valid multicast
// group and port. "udpm://" alone is LCM's default group, 239.255.76.67:7667.
std::optional<UdpmAddress> parse_udpm_url(std::string_view url);

struct LcmDatagram {
  std::string_view channel;
  std::span<const std::uint8_t> message;
};

// One datagram as LCM sends a message that fits in it; nullopt for anything else: a fragment, a
// wrong magic, a header cut short, a channel name without its NUL within LCM's 63 characters.
std::optional<LcmDatagram> parse_lcm_datagram(std::span<const std::uint8_t> datagram);

// A UDP socket joined to the group, bound to its port beside LCM's own sockets (SO_REUSEADDR), so
// every process on the group still gets every datagram.
class MulticastReceiver {
 public:
  static constexpr std::size_t kBatch = 64;
  // Datagrams longer than this are reported as oversized, never read in part as a message.
  static constexpr std::size_t kMaxDatagramBytes = 4096;

  // Throws std::system_error naming the group, the port and the call that failed.
  // `receive_buffer_bytes`: the kernel's queue for this socket (capped by net.core.rmem_max).
  MulticastReceiver(const UdpmAddress& address, int receive_buffer_bytes);
  ~MulticastReceiver();
  MulticastReceiver(const MulticastReceiver&) = delete;
  MulticastReceiver& operator=(const MulticastReceiver&) = delete;

  // Waits up to `timeout_ms` for a datagram, then takes what is queued, up to kBatch, in one call.
  // Returns how many were taken (0 on timeout or a signal).
  std::size_t receive(int timeout_ms);
  // The i-th datagram of the last receive(); `oversized(i)` when it did not fit.
  std::span<const std::uint8_t> datagram(std::size_t i) const;
  bool oversized(std::size_t i) const;

 private:
  int fd_ = -1;
  std::vector<std::uint8_t> buffers_;  // kBatch slots of kMaxDatagramBytes
  // Set up once: recvmmsg writes only each message's length and flags.
  std::array<iovec, kBatch> slots_{};
  std::array<mmsghdr, kBatch> messages_{};
};

}  // namespace furuta::daemon
