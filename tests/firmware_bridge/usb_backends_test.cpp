// The real-hardware backends on a machine without Phidgets (the build machine, a CI container):
// what they must say when there is nothing to open, and that an unopened transport refuses to work.
// Nothing here can exercise a real board; those paths are checked on the rig.

#include "furuta/firmware_bridge/usb_backends.hpp"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

namespace furuta::bridge {
namespace {

using std::chrono::milliseconds;

DeviceMatch match(std::uint16_t product, std::optional<std::string> serial = std::nullopt) {
  DeviceMatch m;
  m.product_id = product;
  m.serial = std::move(serial);
  return m;
}

// Whether this machine has any Phidget at all; the "nothing found" tests are skipped when it does
// (a developer's rig), since then open() may rightly succeed.
bool phidgets_present(const DiscoveryResult& found) {
  return !found.devices.empty() || !found.access_denied.empty();
}

TEST(Discovery, FindsNoBoardsHereAndDoesNotCrash) {
  const DiscoveryResult found = discover_phidgets();
  if (phidgets_present(found)) GTEST_SKIP() << "Phidget hardware attached";
  EXPECT_TRUE(found.devices.empty());
  EXPECT_TRUE(found.access_denied.empty());
  // libusb either started (no error) or could not (a container without usbfs): then it says why.
  if (!found.error.empty()) {
    EXPECT_NE(found.error.find("libusb"), std::string::npos);
  }
}

TEST(Discovery, RepeatedCallsAreIndependent) {
  // Each call owns its libusb context; nothing leaks from one into the next.
  const DiscoveryResult first = discover_phidgets();
  const DiscoveryResult second = discover_phidgets();
  EXPECT_EQ(first.error.empty(), second.error.empty());
  EXPECT_EQ(first.devices.size(), second.devices.size());
}

TEST(HidapiTransport, OpenFindsNothingWithoutHardware) {
  if (phidgets_present(discover_phidgets())) GTEST_SKIP() << "Phidget hardware attached";
  auto transport = make_hidapi_transport();
  // hidapi enumerates hidraw nodes through udev/sysfs; with no Phidget there is none to match,
  // whether or not this machine has USB at all: not_found is the only right answer.
  for (std::uint16_t product : {kProductMotorControl1065, kProductEncoder1047}) {
    EXPECT_EQ(transport->open(match(product)), TransportStatus::not_found);
    EXPECT_FALSE(transport->is_open());
  }
  EXPECT_EQ(transport->open(match(kProductMotorControl1065, "300001")), TransportStatus::not_found);
}

TEST(LibusbTransport, OpenFindsNothingWithoutHardware) {
  const DiscoveryResult found = discover_phidgets();
  if (phidgets_present(found)) GTEST_SKIP() << "Phidget hardware attached";
  // With libusb running, no device matches: not_found. Where libusb cannot start (no usbfs in a
  // container; discovery reports the same as `error`) the bus cannot be read at all, which is an
  // io_error, not a claim that the board is absent.
  const TransportStatus expected =
      found.error.empty() ? TransportStatus::not_found : TransportStatus::io_error;
  auto transport = make_libusb_transport();
  EXPECT_EQ(transport->open(match(kProductEncoder1047)), expected);
  EXPECT_EQ(transport->open(match(kProductMotorControl1065, "1")), expected);
  EXPECT_FALSE(transport->is_open());
}

void expect_unopened_transport_refuses(Transport& transport) {
  EXPECT_FALSE(transport.is_open());
  UsbReport report;
  report.length = 7;  // stale length from an earlier read must not survive
  EXPECT_EQ(transport.read_report(report, milliseconds(1)), TransportStatus::not_open);
  EXPECT_EQ(report.length, 0u);
  EXPECT_EQ(transport.read_report(report, milliseconds(0)), TransportStatus::not_open);
  const std::array<std::uint8_t, 4> output{0x01, 0x80, 0xFF, 0x00};
  EXPECT_EQ(transport.write_report(output), TransportStatus::not_open);
  transport.close();  // closing a closed transport is harmless
  transport.close();
  EXPECT_FALSE(transport.is_open());
}

TEST(HidapiTransport, UnopenedTransportReportsNotOpen) {
  auto transport = make_hidapi_transport();
  expect_unopened_transport_refuses(*transport);
}

TEST(LibusbTransport, UnopenedTransportReportsNotOpen) {
  auto transport = make_libusb_transport();
  expect_unopened_transport_refuses(*transport);
}

TEST(UsbBackends, FailedOpenLeavesTransportUnopened) {
  if (phidgets_present(discover_phidgets())) GTEST_SKIP() << "Phidget hardware attached";
  auto hid = make_hidapi_transport();
  auto usb = make_libusb_transport();
  hid->open(match(kProductMotorControl1065));
  usb->open(match(kProductMotorControl1065));
  expect_unopened_transport_refuses(*hid);
  expect_unopened_transport_refuses(*usb);
}

TEST(UsbBackends, ManyHidapiTransportsShareTheLibrary) {
  // The hid_init/hid_exit guard is reference-counted: transports created and destroyed in any order
  // (and again after the count fell to zero) keep working.
  for (int round = 0; round < 3; ++round) {
    auto a = make_hidapi_transport();
    auto b = make_hidapi_transport();
    a.reset();
    UsbReport report;
    EXPECT_EQ(b->read_report(report, milliseconds(0)), TransportStatus::not_open);
  }
}

}  // namespace
}  // namespace furuta::bridge
