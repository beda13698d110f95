#include "furuta/firmware_bridge/replay_transport.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>  // mkdtemp

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::bridge {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

constexpr std::int64_t kMs = 1'000'000;

DeviceInfo small_device() {
  DeviceInfo d;
  d.vendor_id = kPhidgetsVendorId;
  d.product_id = kProductMotorControl1065;
  d.serial = "300001";
  d.firmware_version = 105;
  d.product_name = "1065 MotorControl 1-Motor";
  d.input_report_bytes = 4;  // small reports keep the hand-written traces readable
  d.output_report_bytes = 2;
  return d;
}

DeviceMatch match_1065(std::optional<std::string> serial = std::nullopt) {
  DeviceMatch m;
  m.product_id = kProductMotorControl1065;
  m.serial = std::move(serial);
  return m;
}

TraceEvent in(std::int64_t t, Bytes b) {
  return {t, TraceEventKind::input, std::move(b), {}};
}
TraceEvent out(std::int64_t t, Bytes b) {
  return {t, TraceEventKind::output, std::move(b), {}};
}
TraceEvent err(std::int64_t t, TransportStatus s) {
  return {t, TraceEventKind::error, {}, s};
}

Bytes bytes_of(const UsbReport& r) {
  return Bytes(r.bytes.begin(), r.bytes.begin() + r.length);
}

// ---------------------------------------------------------------- ReplayTransport

TEST(ReplayTransport, OpensOnlyTheRecordedDevice) {
  VirtualClock clock;
  ReplayTransport t(UsbTrace{small_device(), {}}, clock);
  EXPECT_FALSE(t.is_open());

  DeviceMatch other_product = match_1065();
  other_product.product_id = kProductEncoder1047;
  EXPECT_EQ(t.open(other_product), TransportStatus::not_found);
  DeviceMatch other_vendor = match_1065();
  other_vendor.vendor_id = 0x1234;
  EXPECT_EQ(t.open(other_vendor), TransportStatus::not_found);
  EXPECT_EQ(t.open(match_1065("300002")), TransportStatus::not_found);
  EXPECT_FALSE(t.is_open());

  EXPECT_EQ(t.open(match_1065("300001")), TransportStatus::ok);
  EXPECT_TRUE(t.is_open());
  t.close();
  EXPECT_FALSE(t.is_open());
  EXPECT_EQ(t.open(match_1065()), TransportStatus::ok);  // no serial asked: any
  EXPECT_EQ(t.device_info().serial, "300001");
  EXPECT_EQ(t.device_info().input_report_bytes, 4u);
}

TEST(ReplayTransport, NothingWorksBeforeOpen) {
  VirtualClock clock;
  ReplayTransport t(UsbTrace{small_device(), {in(0, {1, 2, 3, 4})}}, clock);
  UsbReport r;
  EXPECT_EQ(t.read_report(r, 10ms), TransportStatus::not_open);
  const Bytes o = {1, 2};
  EXPECT_EQ(t.write_report(o), TransportStatus::not_open);
  EXPECT_EQ(clock.now_ns(), 0);
  EXPECT_TRUE(t.written_outputs().empty());
}

TEST(ReplayTransport, DeliversReportsAtTheirRecordedTimesInVirtualTime) {
  VirtualClock clock(0);
  UsbTrace trace{small_device(), {in(8 * kMs, {1, 1, 1, 1}), in(16 * kMs, {2, 2, 2, 2})}};
  ReplayTransport t(std::move(trace), clock);
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);
  UsbReport r;

  // Poll: nothing yet, and no time passes.
  EXPECT_EQ(t.read_report(r, 0ns), TransportStatus::timeout);
  EXPECT_EQ(clock.now_ns(), 0);
  // Too short a wait: the clock moves exactly to the deadline.
  EXPECT_EQ(t.read_report(r, 5ms), TransportStatus::timeout);
  EXPECT_EQ(clock.now_ns(), 5 * kMs);
  // Long enough: the clock moves to the report's time, not to the deadline.
  EXPECT_EQ(t.read_report(r, 10ms), TransportStatus::ok);
  EXPECT_EQ(clock.now_ns(), 8 * kMs);
  EXPECT_EQ(r.host_time_ns, 8 * kMs);
  EXPECT_EQ(bytes_of(r), (Bytes{1, 1, 1, 1}));
  // A deadline landing exactly on the report still gets it.
  EXPECT_EQ(t.read_report(r, 8ms), TransportStatus::ok);
  EXPECT_EQ(clock.now_ns(), 16 * kMs);
  EXPECT_EQ(bytes_of(r), (Bytes{2, 2, 2, 2}));
  EXPECT_TRUE(t.finished());
  // The end of the recording is not a timeout: there is nothing to wait for.
  EXPECT_EQ(t.read_report(r, 100ms), TransportStatus::replay_exhausted);
  EXPECT_EQ(clock.now_ns(), 16 * kMs);
}

TEST(ReplayTransport, ReportsAlreadyDueAreDeliveredAtOnceWithTheirOwnTimes) {
  VirtualClock clock(0);
  UsbTrace trace{small_device(), {in(8 * kMs, {1, 0, 0, 0}), in(16 * kMs, {2, 0, 0, 0})}};
  ReplayTransport t(std::move(trace), clock);
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);
  clock.advance_ns(20 * kMs);  // the loop was busy: both have queued up
  UsbReport r;
  ASSERT_EQ(t.read_report(r, 0ns), TransportStatus::ok);
  EXPECT_EQ(r.host_time_ns, 8 * kMs);
  ASSERT_EQ(t.read_report(r, 0ns), TransportStatus::ok);
  EXPECT_EQ(r.host_time_ns, 16 * kMs);
  EXPECT_EQ(clock.now_ns(), 20 * kMs);
}

TEST(ReplayTransport, ErrorsAndShortReportsRecur) {
  VirtualClock clock;
  UsbTrace trace{small_device(),
                 {in(1 * kMs, {9, 8}), err(2 * kMs, TransportStatus::disconnected),
                  in(3 * kMs, {1, 2, 3, 4, 5})}};
  ReplayTransport t(std::move(trace), clock);
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);
  UsbReport r;
  // Two bytes where the device sends four: short, and the bytes that came are there.
  EXPECT_EQ(t.read_report(r, 10ms), TransportStatus::short_report);
  EXPECT_EQ(bytes_of(r), (Bytes{9, 8}));
  EXPECT_EQ(t.read_report(r, 10ms), TransportStatus::disconnected);
  EXPECT_EQ(clock.now_ns(), 2 * kMs);
  EXPECT_EQ(r.length, 0u);
  // After a reconnect the replay goes on where it was.
  t.close();
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);
  EXPECT_FALSE(t.finished());
  EXPECT_EQ(t.read_report(r, 10ms), TransportStatus::ok);  // longer than needed is fine
  EXPECT_EQ(bytes_of(r), (Bytes{1, 2, 3, 4, 5}));
  EXPECT_TRUE(t.finished());
}

TEST(ReplayTransport, CheckModeCatchesAMismatchAndNamesItsIndex) {
  VirtualClock clock;
  UsbTrace trace{small_device(),
                 {out(0, {0x01, 0x10}), in(8 * kMs, {0, 0, 0, 0}), out(9 * kMs, {0x01, 0x20}),
                  out(10 * kMs, {0x01, 0x30})}};
  ReplayTransport t(std::move(trace), clock, ReplayTransport::OutputMode::check);
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);

  EXPECT_EQ(t.write_report(Bytes{0x01, 0x10}), TransportStatus::ok);
  clock.advance_ns(9 * kMs);
  EXPECT_EQ(t.write_report(Bytes{0x01, 0x21}), TransportStatus::replay_mismatch);
  // The mismatched recording is consumed: the next write is compared with the next one.
  EXPECT_EQ(t.write_report(Bytes{0x01, 0x30}), TransportStatus::ok);
  // Nothing left to compare with.
  EXPECT_EQ(t.write_report(Bytes{0x00, 0x00}), TransportStatus::replay_mismatch);

  ASSERT_EQ(t.mismatches().size(), 2u);
  EXPECT_EQ(t.mismatches()[0].output_index, 1u);
  EXPECT_EQ(t.mismatches()[0].time_ns, 9 * kMs);
  EXPECT_EQ(t.mismatches()[0].expected, (Bytes{0x01, 0x20}));
  EXPECT_EQ(t.mismatches()[0].actual, (Bytes{0x01, 0x21}));
  EXPECT_EQ(t.mismatches()[1].output_index, 3u);
  EXPECT_TRUE(t.mismatches()[1].expected.empty());
  EXPECT_EQ(t.mismatches()[1].actual, (Bytes{0x00, 0x00}));
  EXPECT_EQ(t.written_outputs().size(), 4u);

  // A different length is a mismatch too, even when one is a prefix of the other.
  VirtualClock clock2;
  ReplayTransport t2(UsbTrace{small_device(), {out(0, {0x01, 0x10})}}, clock2);
  ASSERT_EQ(t2.open(match_1065()), TransportStatus::ok);
  EXPECT_EQ(t2.write_report(Bytes{0x01, 0x10, 0x00}), TransportStatus::replay_mismatch);
}

TEST(ReplayTransport, RecordModeKeepsWhatWasWritten) {
  VirtualClock clock(100);
  ReplayTransport t(UsbTrace{small_device(), {out(0, {0xFF})}}, clock,
                    ReplayTransport::OutputMode::record);
  ASSERT_EQ(t.open(match_1065()), TransportStatus::ok);
  EXPECT_EQ(t.write_report(Bytes{0x01, 0x02}), TransportStatus::ok);
  clock.advance_ns(5);
  EXPECT_EQ(t.write_report(Bytes{0x03}), TransportStatus::ok);
  EXPECT_TRUE(t.mismatches().empty());
  ASSERT_EQ(t.written_outputs().size(), 2u);
  EXPECT_EQ(t.written_outputs()[0].time_ns, 100);
  EXPECT_EQ(t.written_outputs()[0].kind, TraceEventKind::output);
  EXPECT_EQ(t.written_outputs()[0].bytes, (Bytes{0x01, 0x02}));
  EXPECT_EQ(t.written_outputs()[1].time_ns, 105);
  EXPECT_EQ(t.written_outputs()[1].bytes, (Bytes{0x03}));
}

// ---------------------------------------------------------------- RecordingTransport

// A device that behaves on the clock like a real one: scripted inputs (or failures) arrive at given
// times; reads wait for them up to the timeout.
class ScriptedDevice final : public Transport {
 public:
  struct Item {
    std::int64_t time_ns;
    TransportStatus status;  // ok or short_report: `bytes` arrive; anything else: that failure
    Bytes bytes;
  };
  struct Log {
    std::vector<Bytes> writes;
    int opens = 0;
  };

  ScriptedDevice(Clock& clock, DeviceInfo info, std::vector<Item> items, Log& log)
      : clock_(clock), info_(std::move(info)), items_(std::move(items)), log_(log) {}

  TransportStatus open(const DeviceMatch& match) override {
    if (match.product_id != info_.product_id) return TransportStatus::not_found;
    ++log_.opens;
    open_ = true;
    return TransportStatus::ok;
  }
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override {
    if (!open_) return TransportStatus::not_open;
    const std::int64_t deadline = clock_.now_ns() + timeout.count();
    if (next_ >= items_.size() || items_[next_].time_ns > deadline) {
      clock_.sleep_until_ns(deadline);
      return TransportStatus::timeout;
    }
    const Item& item = items_[next_++];
    clock_.sleep_until_ns(item.time_ns);
    std::copy(item.bytes.begin(), item.bytes.end(), report.bytes.begin());
    report.length = item.bytes.size();
    report.host_time_ns = item.time_ns;  // stamped on arrival, as the simulated rig does
    return item.status;
  }
  TransportStatus write_report(std::span<const std::uint8_t> report) override {
    if (!open_) return TransportStatus::not_open;
    if (fail_writes) return TransportStatus::io_error;
    log_.writes.emplace_back(report.begin(), report.end());
    return TransportStatus::ok;
  }
  void close() override { open_ = false; }
  bool is_open() const override { return open_; }
  const DeviceInfo& device_info() const override { return info_; }

  bool fail_writes = false;

 private:
  Clock& clock_;
  DeviceInfo info_;
  std::vector<Item> items_;
  std::size_t next_ = 0;
  bool open_ = false;
  Log& log_;
};

TEST(RecordingTransport, RecordsReadsWritesAndErrorsButNotTimeouts) {
  VirtualClock clock;
  ScriptedDevice::Log log;
  auto device = std::make_unique<ScriptedDevice>(
      clock, small_device(),
      std::vector<ScriptedDevice::Item>{{8 * kMs, TransportStatus::ok, {1, 2, 3, 4}},
                                        {16 * kMs, TransportStatus::short_report, {5, 6}},
                                        {24 * kMs, TransportStatus::disconnected, {}}},
      log);
  ScriptedDevice* raw = device.get();
  RecordingTransport rec(std::move(device), clock);
  ASSERT_EQ(rec.open(match_1065()), TransportStatus::ok);
  EXPECT_TRUE(rec.is_open());
  EXPECT_EQ(rec.trace().device.serial, "300001");
  EXPECT_EQ(rec.device_info().product_id, kProductMotorControl1065);

  UsbReport r;
  EXPECT_EQ(rec.read_report(r, 2ms), TransportStatus::timeout);  // t = 2 ms, not recorded
  EXPECT_EQ(rec.read_report(r, 10ms), TransportStatus::ok);      // t = 8 ms
  EXPECT_EQ(rec.write_report(Bytes{0x01, 0x60}), TransportStatus::ok);
  raw->fail_writes = true;
  EXPECT_EQ(rec.write_report(Bytes{0x01, 0x61}), TransportStatus::io_error);  // not recorded
  raw->fail_writes = false;
  clock.sleep_until_ns(20 * kMs);  // the loop polls late: the report arrived at 16 ms
  EXPECT_EQ(rec.read_report(r, 0ms), TransportStatus::short_report);
  EXPECT_EQ(r.host_time_ns, 16 * kMs);
  EXPECT_EQ(rec.read_report(r, 10ms), TransportStatus::disconnected);  // t = 24 ms
  rec.close();
  EXPECT_FALSE(rec.is_open());
  ASSERT_EQ(log.writes.size(), 1u);  // passed through

  const auto& ev = rec.trace().events;
  ASSERT_EQ(ev.size(), 5u);
  EXPECT_EQ(ev[0].kind, TraceEventKind::input);
  EXPECT_EQ(ev[0].time_ns, 8 * kMs);
  EXPECT_EQ(ev[0].bytes, (Bytes{1, 2, 3, 4}));
  EXPECT_EQ(ev[1].kind, TraceEventKind::output);
  EXPECT_EQ(ev[1].time_ns, 8 * kMs);
  EXPECT_EQ(ev[1].bytes, (Bytes{0x01, 0x60}));
  EXPECT_EQ(ev[2].kind, TraceEventKind::input);  // short: kept with its bytes
  EXPECT_EQ(ev[2].time_ns, 16 * kMs);            // when it arrived, not when it was read (20 ms)
  EXPECT_EQ(ev[2].bytes, (Bytes{5, 6}));
  EXPECT_EQ(ev[3].kind, TraceEventKind::error);
  EXPECT_EQ(ev[3].time_ns, 24 * kMs);
  EXPECT_EQ(ev[3].status, TransportStatus::disconnected);
  EXPECT_EQ(ev[4].kind, TraceEventKind::end);  // close() marks when the recording stopped
  EXPECT_EQ(ev[4].time_ns, 24 * kMs);
}

TEST(RecordingTransport, FailedOpenRecordsNoDevice) {
  VirtualClock clock;
  ScriptedDevice::Log log;
  RecordingTransport rec(std::make_unique<ScriptedDevice>(clock, small_device(),
                                                          std::vector<ScriptedDevice::Item>{}, log),
                         clock);
  DeviceMatch wrong = match_1065();
  wrong.product_id = kProductEncoder1047;
  EXPECT_EQ(rec.open(wrong), TransportStatus::not_found);
  EXPECT_EQ(rec.trace().device.product_id, 0);
  EXPECT_FALSE(rec.is_open());
}

// What a consumer of a transport sees: every call's outcome and when it returned.
struct Seen {
  TransportStatus status;
  Bytes bytes;
  std::int64_t host_time_ns;
  std::int64_t returned_at_ns;
  bool operator==(const Seen&) const = default;
};

// A 16 ms loop: wait for the first report up to 3 ms, drain what else is queued, reconnect after a
// disconnect, and write a command derived from what was read.
std::vector<Seen> drive(Transport& t, VirtualClock& clock, int cycles) {
  std::vector<Seen> seen;
  std::uint8_t last = 0;
  for (int cycle = 0; cycle < cycles; ++cycle) {
    clock.sleep_until_ns(cycle * 16 * kMs);
    for (bool first = true;; first = false) {
      UsbReport r;
      const TransportStatus s = t.read_report(r, first ? 3ms : 0ms);
      const bool has_data = s == TransportStatus::ok || s == TransportStatus::short_report;
      seen.push_back(
          {s, has_data ? bytes_of(r) : Bytes{}, has_data ? r.host_time_ns : 0, clock.now_ns()});
      if (has_data && r.length > 0) last = r.bytes[r.length - 1];
      if (s == TransportStatus::timeout || s == TransportStatus::replay_exhausted) break;
      if (s == TransportStatus::disconnected) {
        t.close();
        if (t.open(match_1065()) != TransportStatus::ok) return seen;
      }
    }
    const Bytes command = {static_cast<std::uint8_t>(cycle), last};
    const TransportStatus w = t.write_report(command);
    seen.push_back({w, command, 0, clock.now_ns()});
  }
  return seen;
}

TEST(RecordAndReplay, AFileRoundTripReplaysIdenticalBytesAtIdenticalTimes) {
  // Reports every 8 ms with 1 ms of latency and some jitter, a short one, and a disconnect.
  std::vector<ScriptedDevice::Item> items;
  for (int k = 0; k < 30; ++k) {
    const std::int64_t t = k * 8 * kMs + kMs + (k % 3) * 700'000;
    const auto b = static_cast<std::uint8_t>(k);
    if (k == 11) {
      items.push_back({t, TransportStatus::short_report, {b, 0xEE}});
    } else if (k == 17) {
      items.push_back({t, TransportStatus::disconnected, {}});
    } else {
      items.push_back({t, TransportStatus::ok, {b, 0x7F, 0xFF, static_cast<std::uint8_t>(b * 3)}});
    }
  }
  constexpr int kCycles = 14;  // 224 ms: stops before the script runs out

  VirtualClock live_clock;
  ScriptedDevice::Log log;
  RecordingTransport rec(std::make_unique<ScriptedDevice>(live_clock, small_device(), items, log),
                         live_clock);
  ASSERT_EQ(rec.open(match_1065()), TransportStatus::ok);
  const std::vector<Seen> live = drive(rec, live_clock, kCycles);
  EXPECT_EQ(log.opens, 2);  // reconnected once

  char dir_template[] = "/tmp/furuta_replay_XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::filesystem::path file = std::filesystem::path(dir_template) / "live.usbtrace";
  write_usb_trace(file, rec.trace());
  UsbTrace loaded = read_usb_trace(file);
  std::filesystem::remove_all(dir_template);

  VirtualClock replay_clock;
  ReplayTransport replay(std::move(loaded), replay_clock, ReplayTransport::OutputMode::check);
  ASSERT_EQ(replay.open(match_1065("300001")), TransportStatus::ok);
  const std::vector<Seen> again = drive(replay, replay_clock, kCycles);

  // Everything matches except the very last read: live, it timed out waiting for a report the
  // recording never saw; in replay the recording has simply ended.
  ASSERT_EQ(again.size(), live.size());
  ASSERT_GE(live.size(), 40u);  // the loop really read and wrote
  for (std::size_t i = 0; i + 2 < live.size(); ++i) {
    EXPECT_EQ(again[i], live[i]) << "call " << i;
  }
  const std::size_t last_read = live.size() - 2;
  EXPECT_EQ(live[last_read].status, TransportStatus::timeout);
  EXPECT_EQ(again[last_read].status, TransportStatus::replay_exhausted);
  EXPECT_EQ(again.back(), live.back());  // the last write
  EXPECT_TRUE(replay.mismatches().empty());
  EXPECT_TRUE(replay.finished());

  int short_reports = 0, disconnects = 0, timeouts = 0;
  for (const Seen& s : live) {
    short_reports += s.status == TransportStatus::short_report;
    disconnects += s.status == TransportStatus::disconnected;
    timeouts += s.status == TransportStatus::timeout;
  }
  EXPECT_EQ(short_reports, 1);
  EXPECT_EQ(disconnects, 1);
  EXPECT_GE(timeouts, kCycles - 1);
}

TEST(RecordAndReplay, ReplayOfADifferentLoopReportsTheFirstDivergentOutput) {
  VirtualClock live_clock;
  ScriptedDevice::Log log;
  std::vector<ScriptedDevice::Item> items;
  for (int k = 0; k < 10; ++k) {
    items.push_back(
        {k * 8 * kMs + kMs, TransportStatus::ok, {static_cast<std::uint8_t>(k), 0, 0, 1}});
  }
  RecordingTransport rec(std::make_unique<ScriptedDevice>(live_clock, small_device(), items, log),
                         live_clock);
  ASSERT_EQ(rec.open(match_1065()), TransportStatus::ok);
  drive(rec, live_clock, 4);

  // The same loop, except its third command differs.
  VirtualClock clock;
  ReplayTransport replay(rec.trace(), clock);
  ASSERT_EQ(replay.open(match_1065()), TransportStatus::ok);
  for (int cycle = 0; cycle < 4; ++cycle) {
    clock.sleep_until_ns(cycle * 16 * kMs);
    UsbReport r;
    while (replay.read_report(r, cycle == 0 ? 3ms : 0ms) == TransportStatus::ok) {
    }
    // Live it wrote {cycle, 1} (the last byte of the last report).
    const Bytes command = {static_cast<std::uint8_t>(cycle),
                           static_cast<std::uint8_t>(cycle == 2 ? 0 : 1)};
    replay.write_report(command);
  }
  ASSERT_EQ(replay.mismatches().size(), 1u);
  EXPECT_EQ(replay.mismatches()[0].output_index, 2u);
  EXPECT_EQ(replay.mismatches()[0].expected, (Bytes{2, 1}));
  EXPECT_EQ(replay.mismatches()[0].actual, (Bytes{2, 0}));
  EXPECT_EQ(replay.mismatches()[0].time_ns, 32 * kMs);  // the third cycle's start
}

}  // namespace
}  // namespace furuta::bridge

namespace furuta::bridge {
namespace {

// After its last input the recorded device stayed quiet until the recording's END: reads up to then
// time out as they did live, and only reads reaching past it are exhausted.
TEST(ReplayTransport, ReadsAfterTheLastInputTimeOutUntilTheRecordingsEnd) {
  UsbTrace trace;
  trace.device.vendor_id = kPhidgetsVendorId;
  trace.device.product_id = kProductEncoder1047;
  trace.device.input_report_bytes = 2;
  trace.events.push_back({8'000'000, TraceEventKind::input, {1, 2}, {}});
  trace.events.push_back({16'000'000, TraceEventKind::end, {}, {}});
  VirtualClock clock(0);
  ReplayTransport replay(trace, clock);
  ASSERT_EQ(replay.open({kPhidgetsVendorId, kProductEncoder1047, {}}), TransportStatus::ok);
  UsbReport report;
  EXPECT_EQ(replay.read_report(report, std::chrono::milliseconds(10)), TransportStatus::ok);
  EXPECT_EQ(replay.read_report(report, std::chrono::milliseconds(8)), TransportStatus::timeout);
  EXPECT_EQ(clock.now_ns(), 16'000'000);
  EXPECT_EQ(replay.read_report(report, std::chrono::nanoseconds(0)), TransportStatus::timeout);
  EXPECT_EQ(replay.read_report(report, std::chrono::nanoseconds(1)),
            TransportStatus::replay_exhausted);
  EXPECT_TRUE(replay.finished());

  // Without an END the recording's length is unknown: exhausted straight after the last input.
  trace.events.pop_back();
  VirtualClock clock2(0);
  ReplayTransport unterminated(trace, clock2);
  ASSERT_EQ(unterminated.open({kPhidgetsVendorId, kProductEncoder1047, {}}), TransportStatus::ok);
  EXPECT_EQ(unterminated.read_report(report, std::chrono::milliseconds(10)), TransportStatus::ok);
  EXPECT_EQ(unterminated.read_report(report, std::chrono::nanoseconds(0)),
            TransportStatus::replay_exhausted);
}

}  // namespace
}  // namespace furuta::bridge
