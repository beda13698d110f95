#include "furuta/firmware_bridge/usb_trace.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>  // mkdtemp

#include <filesystem>
#include <fstream>
#include <string>

#include "temp_dir.hpp"

namespace furuta::bridge {
namespace {

using furuta::testing::TempDir;

namespace fs = std::filesystem;

UsbTrace sample_trace() {
  UsbTrace t;
  t.device.vendor_id = 0x06C2;
  t.device.product_id = 0x003E;
  t.device.serial = "300001";
  t.device.firmware_version = 105;
  t.device.product_name = "1065 MotorControl 1-Motor";
  t.device.input_report_bytes = 25;
  t.device.output_report_bytes = 4;
  t.events.push_back({1'000, TraceEventKind::output, {0x01, 0x60, 0xFF, 0x00}, {}});
  t.events.push_back({8'000'000, TraceEventKind::input, {0x00, 0x04, 0xAB, 0xCD}, {}});
  t.events.push_back({16'000'000, TraceEventKind::error, {}, TransportStatus::disconnected});
  t.events.push_back({16'000'500, TraceEventKind::input, {}, {}});
  t.events.push_back({24'000'000, TraceEventKind::error, {}, TransportStatus::short_report});
  t.events.push_back({32'000'000, TraceEventKind::end, {}, {}});
  return t;
}

const std::string kSampleText =
    "# furuta usb trace v1\n"
    "device 06c2:003e serial=300001 firmware=105 in=25 out=4 name=1065_MotorControl_1-Motor\n"
    "1000 OUT 0160ff00\n"
    "8000000 IN  0004abcd\n"
    "16000000 ERR disconnected\n"
    "16000500 IN\n"
    "24000000 ERR short_report\n"
    "32000000 END\n";

std::string kHead() {
  return "# furuta usb trace v1\n"
         "device 06c2:003e serial=1 firmware=105 in=25 out=4 name=x\n";
}

void expect_same(const UsbTrace& a, const UsbTrace& b) {
  EXPECT_EQ(a.device.vendor_id, b.device.vendor_id);
  EXPECT_EQ(a.device.product_id, b.device.product_id);
  EXPECT_EQ(a.device.serial, b.device.serial);
  EXPECT_EQ(a.device.firmware_version, b.device.firmware_version);
  EXPECT_EQ(a.device.product_name, b.device.product_name);
  EXPECT_EQ(a.device.input_report_bytes, b.device.input_report_bytes);
  EXPECT_EQ(a.device.output_report_bytes, b.device.output_report_bytes);
  EXPECT_EQ(a.device.vendor_class_interface, b.device.vendor_class_interface);
  ASSERT_EQ(a.events.size(), b.events.size());
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(a.events[i].time_ns, b.events[i].time_ns);
    EXPECT_EQ(a.events[i].kind, b.events[i].kind);
    EXPECT_EQ(a.events[i].bytes, b.events[i].bytes);
    if (a.events[i].kind == TraceEventKind::error) {
      EXPECT_EQ(a.events[i].status, b.events[i].status);
    }
  }
}

TEST(UsbTrace, FormatsTheDocumentedText) {
  EXPECT_EQ(format_usb_trace(sample_trace()), kSampleText);
}

TEST(UsbTrace, ParsesTheDocumentedText) {
  expect_same(parse_usb_trace(kSampleText, "sample"), sample_trace());
}

TEST(UsbTrace, ParserToleratesCommentsBlankLinesCrlfUppercaseHexAndVendorClass) {
  const std::string text =
      "# furuta usb trace v1\r\n"
      "\n"
      "# recorded on the rig\n"
      "device 06C2:004f serial=300002 firmware=205 in=40 out=1 name=1047 vendor_class=1\r\n"
      "   \t\n"
      "5\tIN   7FFF80\r\n";
  const UsbTrace t = parse_usb_trace(text, "x");
  EXPECT_EQ(t.device.vendor_id, 0x06C2);
  EXPECT_EQ(t.device.product_id, 0x004F);
  EXPECT_EQ(t.device.firmware_version, 205);
  EXPECT_TRUE(t.device.vendor_class_interface);
  ASSERT_EQ(t.events.size(), 1u);
  EXPECT_EQ(t.events[0].bytes, (std::vector<std::uint8_t>{0x7F, 0xFF, 0x80}));
  // The flag survives a round trip through the writer.
  expect_same(parse_usb_trace(format_usb_trace(t), "again"), t);
}

TEST(UsbTrace, EveryFailureStatusRoundTrips) {
  UsbTrace t = sample_trace();
  t.events.clear();
  const TransportStatus all[] = {
      TransportStatus::timeout,          TransportStatus::not_found,
      TransportStatus::access_denied,    TransportStatus::busy,
      TransportStatus::disconnected,     TransportStatus::short_report,
      TransportStatus::io_error,         TransportStatus::not_open,
      TransportStatus::invalid_argument, TransportStatus::replay_mismatch,
      TransportStatus::replay_exhausted,
  };
  std::int64_t time = 0;
  for (TransportStatus s : all) t.events.push_back({time++, TraceEventKind::error, {}, s});
  expect_same(parse_usb_trace(format_usb_trace(t), "statuses"), t);
}

TEST(UsbTrace, TimesNeedNotRiseAcrossEventKinds) {
  // An input is stamped when it arrived, so it can come after an output written before it was read.
  const UsbTrace t = parse_usb_trace(kHead() + "20 OUT 00\n15 IN 01\n", "x");
  ASSERT_EQ(t.events.size(), 2u);
  EXPECT_EQ(t.events[1].time_ns, 15);
}

TEST(UsbTrace, WritesAtomicallyAndReadsBack) {
  TempDir dir;
  const fs::path file = dir.path() / "session.usbtrace";
  {
    std::ofstream old(file);
    old << "old contents that are not a trace\n";
  }
  write_usb_trace(file, sample_trace());
  expect_same(read_usb_trace(file), sample_trace());

  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, kSampleText);
  // The temporary was renamed, not left behind.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST(UsbTrace, WriteIntoAMissingDirectoryThrows) {
  TempDir dir;
  EXPECT_THROW(write_usb_trace(dir.path() / "no" / "such" / "dir.usbtrace", sample_trace()),
               fs::filesystem_error);
}

TEST(UsbTrace, ReadingAMissingFileNamesIt) {
  TempDir dir;
  const fs::path missing = dir.path() / "missing.usbtrace";
  try {
    read_usb_trace(missing);
    FAIL() << "no exception";
  } catch (const TraceFormatError& e) {
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_NE(std::string(e.what()).find("missing.usbtrace"), std::string::npos);
  }
}

// Expects a TraceFormatError at `line` whose message contains `needle`.
void expect_error(const std::string& text, int line, const std::string& needle) {
  try {
    parse_usb_trace(text, "bad.usbtrace");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const TraceFormatError& e) {
    EXPECT_EQ(e.file(), "bad.usbtrace");
    EXPECT_EQ(e.line(), line) << e.what();
    const std::string what = e.what();
    EXPECT_NE(what.find(needle), std::string::npos) << what;
    EXPECT_EQ(what.rfind("bad.usbtrace:" + std::to_string(line) + ": ", 0), 0u) << what;
  }
}

TEST(UsbTraceErrors, UnknownKind) {
  expect_error(kHead() + "10 IN 00\n20 INPUT 00\n", 4, "unknown event kind 'INPUT'");
  expect_error(kHead() + "10 in 00\n", 3, "unknown event kind 'in'");
  expect_error(kHead() + "10\n", 3, "without a kind");
}

TEST(UsbTraceErrors, OddHexLength) {
  expect_error(kHead() + "10 IN 0160f\n", 3, "odd hex length 5");
  expect_error(kHead() + "10 OUT 0g\n", 3, "bad hex digit");
}

TEST(UsbTraceErrors, BadTime) {
  expect_error(kHead() + "10 IN 00\n1x0 IN 00\n", 4, "bad time '1x0'");
  expect_error(kHead() + "99999999999999999999 IN 00\n", 3, "bad time");  // beyond int64
}

TEST(UsbTraceErrors, MissingDeviceLine) {
  expect_error("# furuta usb trace v1\n10 IN 00\n", 2, "missing device line");
  expect_error("# furuta usb trace v1\n\n", 2, "missing device line");
  expect_error("", 0, "missing device line");
  expect_error(kHead() + "device 06c2:003e\n", 3, "second device line");
}

TEST(UsbTraceErrors, BadDeviceLine) {
  expect_error("device 6c2:3e\n", 1, "bad vendor:product");
  expect_error("device 06c2:003e firmware=abc\n", 1, "bad firmware");
  expect_error("device 06c2:003e colour=blue\n", 1, "unknown device field 'colour'");
  expect_error("device 06c2:003e serial\n", 1, "without '='");
}

TEST(UsbTraceErrors, UnknownStatusName) {
  expect_error(kHead() + "10 ERR unplugged\n", 3, "unknown status name 'unplugged'");
  expect_error(kHead() + "10 ERR ok\n", 3, "status ok");
  expect_error(kHead() + "10 ERR\n", 3, "without a status");
}

TEST(UsbTraceErrors, TrailingTextOversizedReportAndVersion) {
  expect_error(kHead() + "10 IN 00 01\n", 3, "unexpected text");
  expect_error(kHead() + "10 IN " + std::string(2 * 65, 'a') + "\n", 3, "more than 64");
  expect_error("# furuta usb trace v2\n", 1, "unsupported trace version '2'");
}

TEST(UsbTraceDeviceLine, FormatsTheTraceFileDeviceLineAndParsesItBack) {
  UsbTrace t = sample_trace();
  t.device.vendor_class_interface = true;
  const std::string line = format_trace_device_line(t.device);
  EXPECT_EQ(line,
            "device 06c2:003e serial=300001 firmware=105 in=25 out=4 "
            "name=1065_MotorControl_1-Motor vendor_class=1");
  // The same line a whole trace carries, so the two cannot drift apart.
  EXPECT_NE(format_usb_trace(t).find("\n" + line + "\n"), std::string::npos);

  t.events.clear();
  expect_same(UsbTrace{parse_trace_device_line(line), {}}, t);
  expect_same(UsbTrace{parse_trace_device_line(line + "\r"), {}}, t);
}

TEST(UsbTraceDeviceLine, ErrorsAreOnLineOneOfTheDeviceLine) {
  const auto expect_line_error = [](const std::string& line, const std::string& needle) {
    try {
      parse_trace_device_line(line);
      ADD_FAILURE() << "no error for " << line;
    } catch (const TraceFormatError& e) {
      EXPECT_EQ(e.line(), 1) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_line_error("", "not a device line");
  expect_line_error("10 IN 00", "not a device line");
  expect_line_error("device 6c2:3e", "bad vendor:product");
  expect_line_error("device 06c2:003e colour=blue", "unknown device field 'colour'");
  expect_line_error("device 06c2:003e serial=1\ndevice 06c2:003e", "line break");
}

TEST(UsbTraceDeviceLine, StatusNamesMapBackToStatuses) {
  for (int value = 0; value <= static_cast<int>(TransportStatus::replay_exhausted); ++value) {
    const auto s = static_cast<TransportStatus>(value);
    EXPECT_EQ(transport_status_from_string(to_string(s)), s) << to_string(s);
  }
  EXPECT_EQ(transport_status_from_string("unknown"), std::nullopt);
  EXPECT_EQ(transport_status_from_string("unplugged"), std::nullopt);
  EXPECT_EQ(transport_status_from_string(""), std::nullopt);
  EXPECT_EQ(transport_status_from_string("Timeout"), std::nullopt);
}

}  // namespace
}  // namespace furuta::bridge
