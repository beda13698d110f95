// The USB transport (the libusb backend's logic) against the simulated rig's USB bus: boards that
// show the descriptors and answer the requests the real ones do, for each supported firmware
// generation. The expected bytes and versions follow the vendor's own code; each test says where.

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"
#include "furuta/firmware_bridge/usb_device.hpp"
#include "furuta/simulator/simulated_rig.hpp"

namespace furuta::bridge::usb_transport_test {
namespace {

using sim::RigBoard;
using sim::SimulatedRig;
using sim::SimulatedRigConfig;
using std::chrono::milliseconds;

// --------------------------------------------------------------------- firmware versions

// HID boards: libphidget21 2.1.8 linux/cusblinux.c:467-470 reads bcdDevice < 0x100 as bcd * 100,
// otherwise (bcd >> 8) * 100 + (bcd & 0xff), the low byte taken as binary.
TEST(FirmwareVersion, HidBoardsAsLibphidget21ReadsThem) {
  EXPECT_EQ(firmware_version_hid(0x0105), 105);
  EXPECT_EQ(firmware_version_hid(0x0101), 101);
  EXPECT_EQ(firmware_version_hid(0x0001), 100);  // below 0x100: times 100
  EXPECT_EQ(firmware_version_hid(0x0002), 200);
  EXPECT_EQ(firmware_version_hid(0x0210), 216);  // the low byte is binary for HID
  EXPECT_EQ(firmware_version_hid(0x011E), 130);
}

// Vendor-class boards: libphidget22 1.10 src/plat/linux/usblinux.c:993-998 reads bcdDevice as
// binary-coded decimal: 0x0210 is firmware 210 (the project used to say 216).
TEST(FirmwareVersion, VendorClassBoardsAsLibphidget22ReadsThem) {
  EXPECT_EQ(firmware_version_vendor_class(0x0210), 210);
  EXPECT_EQ(firmware_version_vendor_class(0x0200), 200);
  EXPECT_EQ(firmware_version_vendor_class(0x0299), 299);
  EXPECT_EQ(firmware_version_vendor_class(0x0310), 310);
  EXPECT_EQ(firmware_version_from_bcd(0x0210, true), 210);
  EXPECT_EQ(firmware_version_from_bcd(0x0210, false), 216);
}

TEST(FirmwareVersion, TheSimulatedBoardsDescriptorsReadBackAsTheirVersion) {
  for (int version = 100; version <= 999; ++version) {
    EXPECT_EQ(firmware_version_vendor_class(bcd_device_from_firmware(version, true)), version);
    EXPECT_EQ(firmware_version_hid(bcd_device_from_firmware(version, false)), version);
  }
}

// What the vendor drives: the 1065 on 100-199 (cphidgetmotorcontrol.c, every 1065 branch tests
// `deviceVersion >= 100 && < 200`), the 1047 on 100-199 as HID (cphidgetencoder.c) and 200-299 as
// a vendor-class device (libphidget22 devices.gen.c).
TEST(FirmwareVersion, KnownRangesPerBoardAndInterfaceClass) {
  EXPECT_TRUE(firmware_known(kProductMotorControl1065, false, 105));
  EXPECT_TRUE(firmware_known(kProductMotorControl1065, false, 199));
  EXPECT_FALSE(firmware_known(kProductMotorControl1065, false, 200));
  EXPECT_FALSE(firmware_known(kProductMotorControl1065, false, 99));
  EXPECT_FALSE(firmware_known(kProductMotorControl1065, true, 105));
  EXPECT_TRUE(firmware_known(kProductEncoder1047, false, 101));
  EXPECT_FALSE(firmware_known(kProductEncoder1047, false, 210));  // 2xx is vendor class
  EXPECT_TRUE(firmware_known(kProductEncoder1047, true, 210));
  EXPECT_FALSE(firmware_known(kProductEncoder1047, true, 310));  // 1047_2 3xx: deadTime, unknown
  EXPECT_FALSE(firmware_known(kProductEncoder1047, true, 199));
  EXPECT_FALSE(firmware_known(kProductEncoder1057, false, 300));  // no codec for it
}

// --------------------------------------------------------------------- the transport on the rig

DeviceMatch match(std::uint16_t product) {
  return DeviceMatch{kPhidgetsVendorId, product, {}};
}

struct UsbBench {
  explicit UsbBench(int firmware_1047) : clock(0), rig(config(firmware_1047), clock) {}

  static SimulatedRigConfig config(int firmware_1047) {
    SimulatedRigConfig c;
    c.firmware_1047 = firmware_1047;
    c.record_truth = false;
    return c;
  }

  std::unique_ptr<Transport> transport() { return make_usb_transport(rig.make_usb_bus()); }

  VirtualClock clock;
  SimulatedRig rig;
};

// Reads until a report comes (the rig ticks every 8 ms).
TransportStatus read_one(Transport& t, UsbReport& report) {
  TransportStatus status = TransportStatus::timeout;
  for (int i = 0; i < 10 && status == TransportStatus::timeout; ++i) {
    status = t.read_report(report, milliseconds(20));
  }
  return status;
}

// A 1047_2 with firmware 2xx: vendor-class interface 0, one 64-byte interrupt IN endpoint, 40-byte
// reports, channels enabled only by the vendor's interface-recipient request.
TEST(UsbTransport, VendorClass1047TakesItsFortyByteReportsFromASixtyFourByteEndpoint) {
  UsbBench bench(210);
  const auto encoder = bench.transport();
  ASSERT_EQ(encoder->open(match(kProductEncoder1047)), TransportStatus::ok);
  const DeviceInfo& info = encoder->device_info();
  EXPECT_TRUE(info.vendor_class_interface);
  EXPECT_EQ(info.firmware_version, 210);  // bcdDevice 0x0210, as libphidget22 reads it
  EXPECT_EQ(info.input_report_bytes, 40u);
  EXPECT_EQ(info.output_report_bytes, 1u);
  EXPECT_EQ(info.serial, "300002");

  // Enable channel 0 (goes out as the 0x41 vendor request) and see the board echo it.
  const std::array<std::uint8_t, 1> enable{0x01};
  ASSERT_EQ(encoder->write_report(enable), TransportStatus::ok);
  int enabled_reports = 0;
  for (int i = 0; i < 20; ++i) {
    UsbReport report;
    ASSERT_EQ(read_one(*encoder, report), TransportStatus::ok) << "report " << i;
    EXPECT_EQ(report.length, 40u);  // whole, though shorter than the 64-byte packet size
    EncoderReport1047 decoded;
    ASSERT_EQ(decode_input_1047(report.view(), decoded), CodecStatus::ok);
    if (decoded.channels[0].enabled()) ++enabled_reports;
    // 8 ms at the 2xx firmware's 6 MHz tick.
    EXPECT_EQ(decoded.channels[0].packet_time_ticks, 48000u);
  }
  EXPECT_GE(enabled_reports, 19);
}

// libphidget22 1.10 src/plat/linux/usblinux.c:278-281 sends the 2xx firmware's output as
// bmRequestType 0x41 (vendor, interface), bRequest 0x02, wValue 0x0100, wIndex 0, 1 byte. The
// simulated board, like one that checks the recipient, stalls any other; 0x40 was the old guess.
TEST(UsbTransport, VendorClass1047AnswersOnlyTheInterfaceRecipientWrite) {
  UsbBench bench(210);
  const std::unique_ptr<UsbBus> bus = bench.rig.make_usb_bus();
  std::vector<UsbDeviceDescription> devices;
  std::string error;
  ASSERT_EQ(bus->list(kPhidgetsVendorId, devices, error), TransportStatus::ok);
  const UsbDeviceDescription* board = nullptr;
  for (const auto& d : devices) {
    if (d.product_id == kProductEncoder1047) board = &d;
  }
  ASSERT_NE(board, nullptr);
  EXPECT_EQ(board->interface_class, kUsbClassVendorSpecific);
  EXPECT_EQ(board->bcd_device, 0x0210);
  ASSERT_EQ(board->endpoints.size(), 1u);
  EXPECT_EQ(board->endpoints[0].address, 0x81);
  EXPECT_EQ(board->endpoints[0].max_packet_bytes, 64);

  std::unique_ptr<UsbDevice> device;
  ASSERT_EQ(bus->open(*board, device), TransportStatus::ok);
  std::array<std::uint8_t, 1> mask{0x01};
  std::size_t sent = 0;
  EXPECT_EQ(device->control_transfer({0x40, 0x02, 0x0100, 0}, mask, sent, milliseconds(10)),
            TransportStatus::io_error);  // device recipient: not answered
  EXPECT_EQ(sent, 0u);
  EXPECT_EQ(device->control_transfer({0x41, 0x02, 0x0100, 0}, mask, sent, milliseconds(10)),
            TransportStatus::ok);
  EXPECT_EQ(sent, 1u);
  // A HID request means nothing to it either.
  EXPECT_EQ(device->control_transfer({0x21, 0x09, 0x0200, 0}, mask, sent, milliseconds(10)),
            TransportStatus::io_error);
}

TEST(UsbTransport, VendorClass1047ReportShorterThanTheCodecNeedsIsShort) {
  UsbBench bench(210);
  const auto encoder = bench.transport();
  ASSERT_EQ(encoder->open(match(kProductEncoder1047)), TransportStatus::ok);
  bench.rig.truncate_reports(RigBoard::encoder_1047, 1, 30);
  UsbReport report;
  EXPECT_EQ(read_one(*encoder, report), TransportStatus::short_report);
  EXPECT_EQ(report.length, 30u);
  EXPECT_EQ(read_one(*encoder, report), TransportStatus::ok);
  EXPECT_EQ(report.length, 40u);
}

// The HID generation: report lengths from the report descriptor (GET_DESCRIPTOR 0x22), output by
// SET_REPORT, firmware 0x0101 read as libphidget21 does.
TEST(UsbTransport, Hid1047AndThe1065ThroughTheirReportDescriptors) {
  UsbBench bench(101);
  const auto encoder = bench.transport();
  ASSERT_EQ(encoder->open(match(kProductEncoder1047)), TransportStatus::ok);
  EXPECT_FALSE(encoder->device_info().vendor_class_interface);
  EXPECT_EQ(encoder->device_info().firmware_version, 101);
  EXPECT_EQ(encoder->device_info().input_report_bytes, 40u);
  EXPECT_EQ(encoder->device_info().output_report_bytes, 1u);
  const std::array<std::uint8_t, 1> enable{0x01};
  ASSERT_EQ(encoder->write_report(enable), TransportStatus::ok);

  const auto motor = bench.transport();
  ASSERT_EQ(motor->open(match(kProductMotorControl1065)), TransportStatus::ok);
  EXPECT_EQ(motor->device_info().firmware_version, 105);
  EXPECT_EQ(motor->device_info().input_report_bytes, 25u);
  EXPECT_EQ(motor->device_info().output_report_bytes, 4u);

  // Full duty forward, then the stop the vendor sends (01 00 ff 00); the board echoes both.
  MotorOutput1065 output;
  MotorCommand1065 command;
  command.duty_cycle = 1.0;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  std::array<std::uint8_t, 4> bytes{};
  ASSERT_EQ(encode_output_1065(output, bytes), CodecStatus::ok);
  ASSERT_EQ(motor->write_report(bytes), TransportStatus::ok);
  UsbReport report;
  MotorReport1065 decoded;
  ASSERT_EQ(read_one(*motor, report), TransportStatus::ok);
  ASSERT_EQ(decode_input_1065(report.view(), decoded), CodecStatus::ok);
  EXPECT_EQ(decoded.commanded_duty(), 1.0);

  command.duty_cycle = 0.0;
  ASSERT_EQ(to_output_1065(command, output), CodecStatus::ok);
  ASSERT_EQ(encode_output_1065(output, bytes), CodecStatus::ok);
  EXPECT_EQ(bytes, (std::array<std::uint8_t, 4>{0x01, 0x00, 0xFF, 0x00}));
  ASSERT_EQ(motor->write_report(bytes), TransportStatus::ok);
  ASSERT_EQ(read_one(*motor, report), TransportStatus::ok);
  ASSERT_EQ(decode_input_1065(report.view(), decoded), CodecStatus::ok);
  EXPECT_EQ(decoded.commanded_duty(), 0.0);
}

TEST(UsbTransport, SerialSelectsTheBoardAndABoardInUseIsBusy) {
  UsbBench bench(210);
  const auto first = bench.transport();
  EXPECT_EQ(first->open({kPhidgetsVendorId, kProductEncoder1047, std::string("999")}),
            TransportStatus::not_found);
  ASSERT_EQ(first->open({kPhidgetsVendorId, kProductEncoder1047, std::string("300002")}),
            TransportStatus::ok);
  const auto second = bench.transport();
  EXPECT_EQ(second->open(match(kProductEncoder1047)), TransportStatus::busy);
  first->close();
  EXPECT_EQ(second->open(match(kProductEncoder1047)), TransportStatus::ok);
}

TEST(UsbTransport, AnUnpluggedBoardReadsAsDisconnected) {
  UsbBench bench(210);
  const auto encoder = bench.transport();
  ASSERT_EQ(encoder->open(match(kProductEncoder1047)), TransportStatus::ok);
  bench.rig.disconnect(RigBoard::encoder_1047);
  UsbReport report;
  EXPECT_EQ(encoder->read_report(report, milliseconds(20)), TransportStatus::disconnected);
  EXPECT_EQ(encoder->open(match(kProductEncoder1047)), TransportStatus::not_found);
}

// Discovery reads each board's firmware as the vendor does for its interface class.
TEST(UsbDiscovery, ListsTheSimulatedBoardsWithTheVendorsFirmwareVersions) {
  for (const int firmware : {101, 210, 310}) {
    UsbBench bench(firmware);
    const std::unique_ptr<UsbBus> bus = bench.rig.make_usb_bus();
    const DiscoveryResult found = discover_phidgets(*bus);
    EXPECT_TRUE(found.error.empty());
    ASSERT_EQ(found.devices.size(), 2u);
    for (const DeviceInfo& d : found.devices) {
      if (d.product_id == kProductMotorControl1065) {
        EXPECT_EQ(d.firmware_version, 105);
        EXPECT_FALSE(d.vendor_class_interface);
      } else {
        EXPECT_EQ(d.firmware_version, firmware);
        EXPECT_EQ(d.vendor_class_interface, firmware >= 200);
      }
    }
  }
}

}  // namespace
}  // namespace furuta::bridge::usb_transport_test
