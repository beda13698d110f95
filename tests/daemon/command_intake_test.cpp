// The daemon's own reader of LCM command datagrams: LCM's URL and one-datagram message format, and
// the socket's batches. That the format is LCM's own is proven end to end by daemon_udp_multicast
// (the furuta CLI publishes through LCM, furutad reads through this reader).
#include "furuta/daemon/command_intake.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <system_error>
#include <vector>

#include "lcm_datagram.hpp"

namespace furuta::daemon {
namespace {

TEST(CommandIntake, ReadsTheGroupAndPortOfAnLcmMulticastUrl) {
  const auto address = parse_udpm_url("udpm://239.255.12.34:20123?ttl=0");
  ASSERT_TRUE(address);
  EXPECT_EQ(address->group, "239.255.12.34");
  EXPECT_EQ(address->port, 20123);

  const auto lcm_default = parse_udpm_url("udpm://");
  ASSERT_TRUE(lcm_default);
  EXPECT_EQ(lcm_default->group, "239.255.76.67");
  EXPECT_EQ(lcm_default->port, 7667);
  const auto group_only = parse_udpm_url("udpm://239.1.2.3?ttl=1");
  ASSERT_TRUE(group_only);
  EXPECT_EQ(group_only->port, 7667);
}

TEST(CommandIntake, OtherProvidersAndBadAddressesAreNotMulticastGroups) {
  EXPECT_FALSE(parse_udpm_url("memq://"));
  EXPECT_FALSE(parse_udpm_url(""));
  EXPECT_FALSE(parse_udpm_url("file:///tmp/x.lcmlog"));
  EXPECT_FALSE(parse_udpm_url("udpm://10.0.0.1:7667"));        // not a multicast group
  EXPECT_FALSE(parse_udpm_url("udpm://239.255.76.67:0"));      // no port
  EXPECT_FALSE(parse_udpm_url("udpm://239.255.76.67:70000"));  // beyond 16 bits
  EXPECT_FALSE(parse_udpm_url("udpm://239.255.76.67:76x"));
  EXPECT_FALSE(parse_udpm_url("udpm://rig.local:7667"));
}

TEST(CommandIntake, AOneDatagramMessageGivesItsChannelAndBytes) {
  const std::vector<std::uint8_t> bytes{1, 2, 0, 3};
  const std::vector<std::uint8_t> datagram =
      furuta::testing::lcm_datagram("RIG_COMMAND", bytes, 77);
  const auto message = parse_lcm_datagram(datagram);
  ASSERT_TRUE(message);
  EXPECT_EQ(message->channel, "RIG_COMMAND");
  EXPECT_EQ(std::vector<std::uint8_t>(message->message.begin(), message->message.end()), bytes);

  const std::vector<std::uint8_t> no_bytes = furuta::testing::lcm_datagram("X", {}, 0);
  const auto empty = parse_lcm_datagram(no_bytes);
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->channel, "X");
  EXPECT_TRUE(empty->message.empty());
}

TEST(CommandIntake, FragmentsAndDamagedHeadersAreNotMessages) {
  std::vector<std::uint8_t> fragment = furuta::testing::lcm_datagram("RIG_COMMAND", {1, 2, 3}, 1);
  fragment[3] = 0x33;  // "LC03": one fragment of a message too large for a datagram
  EXPECT_FALSE(parse_lcm_datagram(fragment));

  const std::vector<std::uint8_t> whole =
      furuta::testing::lcm_datagram("RIG_COMMAND", {1, 2, 3}, 1);
  for (std::size_t cut = 0; cut < 8 + 11 + 1; ++cut) {  // header, channel and its NUL
    EXPECT_FALSE(parse_lcm_datagram(std::span(whole).first(cut))) << cut << " bytes";
  }
  // A channel is at most 63 characters: 64 without a NUL are not a header.
  std::vector<std::uint8_t> long_name = furuta::testing::lcm_datagram(std::string(70, 'C'), {1}, 1);
  EXPECT_FALSE(parse_lcm_datagram(long_name));
  EXPECT_TRUE(parse_lcm_datagram(furuta::testing::lcm_datagram(std::string(63, 'C'), {1}, 1)));
}

void send_to_port(std::uint16_t port, const std::vector<std::uint8_t>& datagram) {
  const int sender = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(port);
  EXPECT_EQ(::sendto(sender, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&to),
                     sizeof to),
            static_cast<ssize_t>(datagram.size()));
  ::close(sender);
}

// The socket is bound to the group's port on every address: datagrams sent to that port on
// loopback reach it as the group's do, so the batches are tested where multicast is not routed.
TEST(CommandIntake, TakesWhatIsQueuedInOneBatchAndMarksWhatDidNotFit) {
  const UdpmAddress address{"239.255.201.17", furuta::testing::free_loopback_udp_port()};
  std::optional<MulticastReceiver> receiver;
  try {
    receiver.emplace(address, 1 << 20);
  } catch (const std::system_error& e) {
    GTEST_SKIP() << "no multicast here: " << e.what();
  }
  EXPECT_EQ(receiver->receive(0), 0u);  // nothing queued: returns at once

  for (std::uint32_t i = 0; i < 5; ++i) {
    send_to_port(address.port, furuta::testing::lcm_datagram("RIG_COMMAND", {std::uint8_t(i)}, i));
  }
  send_to_port(address.port,
               furuta::testing::lcm_datagram("RIG_COMMAND", std::vector<std::uint8_t>(5000, 7), 5));
  std::vector<std::uint8_t> seen;
  std::vector<bool> oversized;
  for (int tries = 0; tries < 100 && seen.size() < 6; ++tries) {
    const std::size_t n = receiver->receive(100);
    for (std::size_t i = 0; i < n; ++i) {
      const auto message = parse_lcm_datagram(receiver->datagram(i));
      ASSERT_TRUE(message);
      seen.push_back(message->message[0]);
      oversized.push_back(receiver->oversized(i));
    }
  }
  EXPECT_EQ(seen, (std::vector<std::uint8_t>{0, 1, 2, 3, 4, 7}));  // in the order sent
  EXPECT_EQ(oversized, (std::vector<bool>{false, false, false, false, false, true}));
  EXPECT_LE(receiver->datagram(5).size(), MulticastReceiver::kMaxDatagramBytes);
}

}  // namespace
}  // namespace furuta::daemon
