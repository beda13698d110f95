#include "furuta/session_log/session_log.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/phidget_ids.hpp"
#include "furuta/firmware_bridge/replay_transport.hpp"
#include "test_support.hpp"

namespace furuta::session_log {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::TempDir;

template <typename Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

// lcm-gen types have no operator==; the same encoding is the same message, field for field.
template <typename Message>
void expect_same_messages(const std::vector<Message>& got, const std::vector<Message>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(encode(got[i]), encode(want[i])) << i;
}

bridge::DeviceInfo motor_device() {
  bridge::DeviceInfo d;
  d.vendor_id = bridge::kPhidgetsVendorId;
  d.product_id = bridge::kProductMotorControl1065;
  d.serial = "300001";
  d.firmware_version = 105;
  d.product_name = "1065 MotorControl 1-Motor";
  d.input_report_bytes = 4;
  d.output_report_bytes = 3;
  return d;
}

bridge::DeviceInfo encoder_device() {
  bridge::DeviceInfo d;
  d.vendor_id = bridge::kPhidgetsVendorId;
  d.product_id = bridge::kProductEncoder1047;
  d.serial = "300002";
  d.firmware_version = 205;
  d.product_name = "1047 Encoder";
  d.input_report_bytes = 2;
  d.output_report_bytes = 1;
  d.vendor_class_interface = true;
  return d;
}

rig_session_t session_record(std::int8_t event) {
  rig_session_t s{};
  s.event = event;
  s.session = "2024-06-01T12-00-00";
  s.label = "test run";
  s.profile = "bang_bang";
  s.amplitude_duty = 0.4;
  s.duration_s = 30;
  s.seed = 3;
  s.period_ns = 16'000'000;
  s.monotonic_ns = event == rig_session_t::EVENT_START ? 1'000'000'000 : 1'200'000'000;
  s.wall_time_ns = 1'717'243'200'000'000'000;
  s.rig_config_toml = "[rig]\nname = \"bench\"\n";
  s.software_version = "furuta 0.1";
  s.motor_device = bridge::format_trace_device_line(motor_device());
  s.encoder_device = bridge::format_trace_device_line(encoder_device());
  s.samples = event == rig_session_t::EVENT_END ? 10 : 0;
  s.end_reason = event == rig_session_t::EVENT_END ? "duration" : "";
  return s;
}

rig_sample_t sample(std::int64_t seq) {
  rig_sample_t s{};
  s.seq = seq;
  s.monotonic_ns = 1'000'000'000 + seq * 16'000'000;
  s.wall_time_ns = 1'717'243'200'000'000'000 + seq * 16'000'000;
  s.session = "2024-06-01T12-00-00";
  s.arm_counts = static_cast<std::int32_t>(seq * 10);
  s.pendulum_counts = static_cast<std::int32_t>(-seq);
  s.arm_angle_rad = 0.001 * static_cast<double>(seq);
  s.pendulum_angle_rad = -0.002 * static_cast<double>(seq);
  s.commanded_duty = seq % 2 == 0 ? 0.4 : -0.4;
  s.applied_duty = s.commanded_duty * 0.9;
  s.motor_current_a = 0.25;
  s.supply_voltage_v = 12.1;
  s.motor_status_flags = 0x08;
  s.encoder_flags = 1;
  s.n_motor_reports = 2;
  s.motor_report_host_ns = {s.monotonic_ns - 9'000'000, s.monotonic_ns - 1'000'000};
  s.motor_packet_counter = {static_cast<std::int16_t>(2 * seq),
                            static_cast<std::int16_t>(2 * seq + 1)};
  s.motor_encoder_time = {100, 124};
  s.n_encoder_reports = 1;
  s.encoder_report_host_ns = {s.monotonic_ns - 2'000'000};
  s.encoder_packet_ticks = {static_cast<std::int32_t>(seq * 16)};
  s.encoder_delta_counts = {-1};
  s.flags = seq == 5 ? rig_sample_t::FLAG_ENCODER_LOST : 0;
  return s;
}

rig_usb_report_t usb(std::int64_t time_ns, std::int8_t board, std::int8_t kind,
                     std::vector<std::uint8_t> bytes, std::string status = "") {
  rig_usb_report_t r{};
  r.time_ns = time_ns;
  r.board = board;
  r.kind = kind;
  r.status = std::move(status);
  r.length = static_cast<std::int16_t>(bytes.size());
  r.bytes = std::move(bytes);
  return r;
}

rig_fault_t fault(std::int64_t seq, const std::string& reason) {
  rig_fault_t f{};
  f.monotonic_ns = 1'000'000'000 + seq * 16'000'000;
  f.session = "2024-06-01T12-00-00";
  f.seq = seq;
  f.reason = reason;
  f.detail = "sample " + std::to_string(seq) + " missing";
  f.fatal = 0;
  return f;
}

constexpr std::int8_t kMotor = rig_usb_report_t::BOARD_MOTOR;
constexpr std::int8_t kEncoder = rig_usb_report_t::BOARD_ENCODER;
constexpr std::int8_t kIn = rig_usb_report_t::KIND_INPUT;
constexpr std::int8_t kOut = rig_usb_report_t::KIND_OUTPUT;
constexpr std::int8_t kErr = rig_usb_report_t::KIND_ERROR;

// A whole session as the daemon would log it, with what load_session_log should make of it.
struct SessionFixture {
  rig_session_t start = session_record(rig_session_t::EVENT_START);
  rig_session_t end = session_record(rig_session_t::EVENT_END);
  std::vector<rig_sample_t> samples;
  std::vector<rig_usb_report_t> usb_reports;
  std::vector<rig_fault_t> faults;

  SessionFixture() {
    for (std::int64_t seq = 0; seq < 10; ++seq) {
      if (seq != 4 && seq != 7) samples.push_back(sample(seq));
    }
    usb_reports = {
        usb(1'000'500'000, kMotor, kOut, {0x01, 0x60, 0xFF}),
        usb(1'008'000'000, kMotor, kIn, {0x00, 0x04, 0xAB, 0xCD}),
        usb(1'008'100'000, kEncoder, kIn, {0x10, 0x20}),
        usb(1'016'000'000, kMotor, kIn, {0x00, 0x05, 0xAB, 0xCE}),
        usb(1'020'000'000, kMotor, kOut, {0x01, 0x20, 0x00}),
        usb(1'024'000'000, kMotor, kErr, {}, "disconnected"),
        usb(1'030'000'000, kMotor, kIn, {0x00, 0x06}),  // short, as recorded
        usb(1'032'000'000, kEncoder, kErr, {}, "timeout"),
    };
    faults = {fault(4, "lost_reports"), fault(7, "overrun")};
  }

  // start, then samples, USB reports and faults interleaved by time, with extras, then end.
  fs::path write(const fs::path& dir, bool with_end = true) const {
    LcmLogWriter writer({dir, 1000ms}, "session");
    std::int64_t utime = 1'717'243'200'000'000;
    const auto put = [&](const char* channel, const std::vector<std::uint8_t>& data) {
      EXPECT_EQ(writer.write(channel, utime++, data), LogWriteStatus::ok);
    };
    put(kChannelSession, encode(start));
    for (std::size_t i = 0; i < samples.size(); ++i) {
      put(kChannelSample, encode(samples[i]));
      if (i < usb_reports.size()) put(kChannelUsb, encode(usb_reports[i]));
      if (i < faults.size()) put(kChannelFault, encode(faults[i]));
    }
    put(kChannelStatus, std::vector<std::uint8_t>{1, 2, 3});
    put("SOMETHING_ELSE", std::vector<std::uint8_t>{});
    put(kChannelSample, std::vector<std::uint8_t>{0xDE, 0xAD});  // not a sample
    put(kChannelUsb, encode(start));                             // a message of another type
    // A second start is not the start.
    rig_session_t restart = start;
    restart.label = "second start";
    put(kChannelSession, encode(restart));
    if (with_end) put(kChannelSession, encode(end));
    fs::path final_path;
    EXPECT_EQ(writer.finish(&final_path), LogWriteStatus::ok);
    return final_path;
  }
};

TEST(SessionLog, LoadsWhatWasWrittenByChannel) {
  TempDir dir;
  const SessionFixture f;
  const fs::path path = f.write(dir.path());
  const SessionLog log = load_session_log(path);

  EXPECT_EQ(log.path, path);
  ASSERT_TRUE(log.start.has_value());
  ASSERT_TRUE(log.end.has_value());
  EXPECT_TRUE(log.complete());
  EXPECT_EQ(encode(*log.start), encode(f.start));
  EXPECT_EQ(encode(*log.end), encode(f.end));
  expect_same_messages(log.samples, f.samples);
  expect_same_messages(log.usb_reports, f.usb_reports);
  expect_same_messages(log.faults, f.faults);
  EXPECT_EQ(log.unknown_channel_events, 2u);  // RIG_STATUS and SOMETHING_ELSE
  EXPECT_EQ(log.undecodable_events, 2u);
  EXPECT_EQ(log.read_stats.events, 1u + 8 + 8 + 2 + 5 + 1);
  EXPECT_EQ(log.read_stats.damaged_regions, 0u);
  EXPECT_FALSE(log.read_stats.truncated_tail);
}

TEST(SessionLog, FindsMissingSequenceNumbers) {
  TempDir dir;
  const SessionLog log = load_session_log(SessionFixture().write(dir.path()));
  EXPECT_EQ(log.missing_sequence_numbers(), (std::vector<std::int64_t>{4, 7}));
  // Each gap is explained by a fault record.
  ASSERT_EQ(log.faults.size(), 2u);
  EXPECT_EQ(log.faults[0].seq, 4);
  EXPECT_EQ(log.faults[1].seq, 7);

  SessionLog synthetic;
  EXPECT_TRUE(synthetic.missing_sequence_numbers().empty());
  for (const std::int64_t seq : {2, 0, 0, 5}) synthetic.samples.push_back(sample(seq));
  EXPECT_EQ(synthetic.missing_sequence_numbers(), (std::vector<std::int64_t>{1, 3, 4}));
  // A session numbers its samples from 0: a log whose first sample is 3 lacks 0, 1 and 2.
  synthetic.samples = {sample(3), sample(4)};
  EXPECT_EQ(synthetic.missing_sequence_numbers(), (std::vector<std::int64_t>{0, 1, 2}));
}

TEST(SessionLog, ASessionCutShortHasNoEnd) {
  TempDir dir;
  const SessionLog log = load_session_log(SessionFixture().write(dir.path(), false));
  EXPECT_TRUE(log.start.has_value());
  EXPECT_FALSE(log.end.has_value());
  EXPECT_FALSE(log.complete());
}

TEST(SessionLog, HostileMessagesAreCountedNotThrown) {
  TempDir dir;
  rig_usb_report_t report = usb(1, kMotor, kIn, {1, 2, 3, 4});
  std::vector<std::uint8_t> negative_length = encode(report);
  // The int16 length sits right before the 4 bytes: make it -1.
  negative_length[negative_length.size() - 6] = 0xFF;
  negative_length[negative_length.size() - 5] = 0xFF;
  std::vector<std::uint8_t> zero_string = encode(report);
  // The status string's length (it includes its NUL, so never 0) after hash, time, board, kind.
  for (std::size_t k = 18; k < 22; ++k) zero_string[k] = 0;
  std::vector<std::uint8_t> trailing = encode(report);
  trailing.push_back(0);

  LcmLogWriter writer({dir.path(), 1000ms}, "hostile");
  for (const auto& data : {negative_length, zero_string, trailing, encode(report)}) {
    ASSERT_EQ(writer.write(kChannelUsb, 0, data), LogWriteStatus::ok);
  }
  fs::path path;
  ASSERT_EQ(writer.finish(&path), LogWriteStatus::ok);
  const SessionLog log = load_session_log(path);
  EXPECT_EQ(log.undecodable_events, 3u);
  ASSERT_EQ(log.usb_reports.size(), 1u);
  EXPECT_EQ(log.usb_reports[0].bytes, (std::vector<std::uint8_t>{1, 2, 3, 4}));
}

TEST(SessionLog, LoadingAMissingFileThrows) {
  TempDir dir;
  EXPECT_THROW(load_session_log(dir.path() / "none.lcmlog"), std::runtime_error);
}

TEST(SessionLogUsbTrace, BuildsOneBoardsTraceFromTheLog) {
  TempDir dir;
  const SessionLog log = load_session_log(SessionFixture().write(dir.path()));
  const bridge::UsbTrace motor = usb_trace_from_log(log, kMotor);
  EXPECT_EQ(bridge::format_trace_device_line(motor.device),
            bridge::format_trace_device_line(motor_device()));
  ASSERT_EQ(motor.events.size(), 7u);  // 6 motor reports and the END
  EXPECT_EQ(motor.events[0].kind, bridge::TraceEventKind::output);
  EXPECT_EQ(motor.events[1].kind, bridge::TraceEventKind::input);
  EXPECT_EQ(motor.events[1].time_ns, 1'008'000'000);
  EXPECT_EQ(motor.events[4].kind, bridge::TraceEventKind::error);
  EXPECT_EQ(motor.events[4].status, bridge::TransportStatus::disconnected);
  EXPECT_EQ(motor.events[6].kind, bridge::TraceEventKind::end);
  EXPECT_EQ(motor.events[6].time_ns, 1'200'000'000);

  const bridge::UsbTrace encoder = usb_trace_from_log(log, kEncoder);
  EXPECT_TRUE(encoder.device.vendor_class_interface);
  ASSERT_EQ(encoder.events.size(), 3u);
  EXPECT_EQ(encoder.events[0].bytes, (std::vector<std::uint8_t>{0x10, 0x20}));
  EXPECT_EQ(encoder.events[1].status, bridge::TransportStatus::timeout);

  // The same trace as text, through the trace file format and back.
  EXPECT_EQ(bridge::format_usb_trace(bridge::parse_usb_trace(bridge::format_usb_trace(motor), "m")),
            bridge::format_usb_trace(motor));
}

TEST(SessionLogUsbTrace, TheReplayBackendPlaysTheLoggedSessionBack) {
  TempDir dir;
  const SessionLog log = load_session_log(SessionFixture().write(dir.path()));
  bridge::VirtualClock clock(1'000'000'000);
  bridge::ReplayTransport replay(usb_trace_from_log(log, kMotor), clock);

  bridge::DeviceMatch match;
  match.product_id = bridge::kProductMotorControl1065;
  match.serial = "300001";
  ASSERT_EQ(replay.open(match), bridge::TransportStatus::ok);
  EXPECT_EQ(replay.device_info().product_name, "1065 MotorControl 1-Motor");

  // The outputs the loop wrote, in order, are what was recorded.
  const std::vector<std::uint8_t> first_output{0x01, 0x60, 0xFF};
  EXPECT_EQ(replay.write_report(first_output), bridge::TransportStatus::ok);

  bridge::UsbReport report;
  ASSERT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::ok);
  EXPECT_EQ(report.host_time_ns, 1'008'000'000);
  EXPECT_EQ(std::vector<std::uint8_t>(report.view().begin(), report.view().end()),
            (std::vector<std::uint8_t>{0x00, 0x04, 0xAB, 0xCD}));
  ASSERT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::ok);
  EXPECT_EQ(report.host_time_ns, 1'016'000'000);
  EXPECT_EQ(report.bytes[3], 0xCE);

  const std::vector<std::uint8_t> second_output{0x01, 0x20, 0x00};
  EXPECT_EQ(replay.write_report(second_output), bridge::TransportStatus::ok);
  EXPECT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::disconnected);
  EXPECT_EQ(report.host_time_ns, 1'024'000'000);
  EXPECT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::short_report);
  EXPECT_EQ(report.length, 2u);
  EXPECT_TRUE(replay.finished());
  EXPECT_TRUE(replay.mismatches().empty());

  // Quiet until the recording's END, then nothing more to play.
  EXPECT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::timeout);
  EXPECT_EQ(replay.read_report(report, 100ms), bridge::TransportStatus::replay_exhausted);
}

TEST(SessionLogUsbTrace, RefusesWhatCannotBeATrace) {
  TempDir dir;
  SessionLog log = load_session_log(SessionFixture().write(dir.path()));
  EXPECT_THROW(usb_trace_from_log(log, 7), std::invalid_argument);

  SessionLog unknown_status = log;
  unknown_status.usb_reports.push_back(usb(2'000'000'000, kMotor, kErr, {}, "unplugged"));
  try {
    usb_trace_from_log(unknown_status, kMotor);
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("unplugged"), std::string::npos) << e.what();
  }
  SessionLog ok_error = log;
  ok_error.usb_reports.push_back(usb(2'000'000'000, kMotor, kErr, {}, "ok"));
  EXPECT_THROW(usb_trace_from_log(ok_error, kMotor), std::runtime_error);

  SessionLog no_start = log;
  no_start.start.reset();
  EXPECT_THROW(usb_trace_from_log(no_start, kMotor), std::runtime_error);

  SessionLog bad_device = log;
  bad_device.start->encoder_device = "device 6c2:3e";
  EXPECT_THROW(usb_trace_from_log(bad_device, kEncoder), bridge::TraceFormatError);
  EXPECT_NO_THROW(usb_trace_from_log(bad_device, kMotor));

  SessionLog oversized = log;
  oversized.usb_reports.push_back(
      usb(2'000'000'000, kMotor, kIn, std::vector<std::uint8_t>(bridge::kMaxReportBytes + 1)));
  EXPECT_THROW(usb_trace_from_log(oversized, kMotor), std::runtime_error);
}

}  // namespace
}  // namespace furuta::session_log
