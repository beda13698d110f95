#include "furuta/firmware_bridge/lost_reports.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

namespace furuta::bridge {
namespace {

// ---------------------------------------------------------------- 1065 packet counter

TEST(PacketCounterTracker1065, CountsGapsAcrossTheWrap) {
  PacketCounterTracker1065 t;
  EXPECT_EQ(t.observe(200), 0);  // first after construction: nothing to compare with
  EXPECT_EQ(t.observe(201), 0);
  EXPECT_EQ(t.observe(203), 1);  // 202 lost
  EXPECT_EQ(t.observe(254), 50);
  EXPECT_EQ(t.observe(255), 0);
  EXPECT_EQ(t.observe(0), 0);  // wraps without loss
  EXPECT_EQ(t.observe(1), 0);
  EXPECT_EQ(t.total_lost(), 51);

  PacketCounterTracker1065 w;
  w.observe(254);
  EXPECT_EQ(w.observe(1), 2);  // 255 and 0 lost
  EXPECT_EQ(w.total_lost(), 2);
}

TEST(PacketCounterTracker1065, ADuplicateIsNotALoss) {
  PacketCounterTracker1065 t;
  t.observe(10);
  EXPECT_EQ(t.observe(10), 0);
  EXPECT_EQ(t.observe(11), 0);
  EXPECT_EQ(t.total_lost(), 0);
  // The largest gap it can see: 254 reports between 11 and 10.
  EXPECT_EQ(t.observe(10), 254);
}

TEST(PacketCounterTracker1065, ResetForgetsThePreviousCounterAndTheTotal) {
  PacketCounterTracker1065 t;
  t.observe(5);
  t.observe(9);
  ASSERT_EQ(t.total_lost(), 3);
  t.reset();  // e.g. the board was reconnected and restarted its counter
  EXPECT_EQ(t.total_lost(), 0);
  EXPECT_EQ(t.observe(0), 0);
  EXPECT_EQ(t.observe(1), 0);
}

// ---------------------------------------------------------------- 1047 timing

constexpr std::int64_t kPeriodNs = 8'000'000;
constexpr std::uint32_t kTicksPerPeriod = 96'000;  // 8 ms at 12 MHz (firmware 1xx)
constexpr double kTickS = 1.0 / 12e6;
constexpr std::int64_t kTenMinutesReports = 10 * 60 * 1'000'000'000LL / kPeriodNs;  // 75000

// A synthetic 1047 seen from the host. The board produces report k at host time
// k * period * (1 + drift) (its crystal is off by `drift_ppm`), each claiming one nominal period of
// ticks; a report reaches the host after `latency + jitter`; the host either stamps each report
// when it arrives or reads in batches every 16 ms, stamping the whole batch with the read time.
struct Scenario {
  double drift_ppm = 0.0;  // > 0: board clock slow
  std::int64_t latency_ns = 1'000'000;
  std::int64_t jitter_ns = 0;  // uniform in [0, jitter]
  bool batched = false;
  std::int64_t read_period_ns = 16'000'000;
  std::int64_t read_phase_ns = 0;
  std::set<std::int64_t> lost;  // report indices the host never sees
  std::int64_t reports = kTenMinutesReports;
  std::uint32_t seed = 1;
};

struct Outcome {
  std::int64_t total = 0;
  std::vector<std::int64_t> found_at;  // index of the report at whose observation losses were found
};

Outcome run(const Scenario& s, int block_reports = 8) {
  ReportTimingTracker1047 tracker(kTickS, kPeriodNs, block_reports);
  std::mt19937 rng(s.seed);
  std::uniform_int_distribution<std::int64_t> jitter(0, s.jitter_ns);
  Outcome out;
  std::int64_t last_host = 0;
  for (std::int64_t k = 0; k < s.reports; ++k) {
    const double generated = static_cast<double>(k * kPeriodNs) * (1.0 + s.drift_ppm * 1e-6);
    const std::int64_t arrival =
        static_cast<std::int64_t>(generated) + s.latency_ns + (s.jitter_ns > 0 ? jitter(rng) : 0);
    if (s.lost.contains(k)) continue;
    std::int64_t host = arrival;
    if (s.batched) {
      const std::int64_t since = arrival - s.read_phase_ns;
      host = s.read_phase_ns + (since + s.read_period_ns - 1) / s.read_period_ns * s.read_period_ns;
    }
    // Reports are read in order: one cannot be stamped before the one ahead of it.
    host = std::max(host, last_host);
    last_host = host;
    const int lost = tracker.observe(kTicksPerPeriod, host);
    EXPECT_GE(lost, 0);
    if (lost > 0) out.found_at.push_back(k);
  }
  out.total = tracker.total_lost();
  return out;
}

TEST(ReportTimingTracker1047, BatchedReadsWithoutLossFindNothingInTenMinutes) {
  Scenario s;
  s.batched = true;
  // Two reports per 16 ms read: the earlier one's host time is 8 ms late, the later one's on time.
  for (std::int64_t phase : {0LL, 3'000'000LL, 8'500'000LL}) {
    s.read_phase_ns = phase;
    const Outcome o = run(s);
    EXPECT_EQ(o.total, 0) << "read phase " << phase;
  }
}

TEST(ReportTimingTracker1047, BatchedReadsFindOneLostReportWithinTwoBlocks) {
  for (std::int64_t lost_index : {30'001LL, 30'004LL, 30'007LL, 50'000LL}) {
    Scenario s;
    s.batched = true;
    s.lost = {lost_index};
    const Outcome o = run(s);
    EXPECT_EQ(o.total, 1) << "lost " << lost_index;
    ASSERT_EQ(o.found_at.size(), 1u);
    EXPECT_GT(o.found_at[0], lost_index);
    EXPECT_LE(o.found_at[0], lost_index + 16) << "found later than two blocks of 8";
  }
}

TEST(ReportTimingTracker1047, ThreeConsecutiveLostCountAsThree) {
  Scenario s;
  s.batched = true;
  s.lost = {40'000, 40'001, 40'002};
  const Outcome o = run(s);
  EXPECT_EQ(o.total, 3);
  ASSERT_EQ(o.found_at.size(), 1u);  // one event, three reports
  EXPECT_LE(o.found_at[0], 40'002 + 16);
}

TEST(ReportTimingTracker1047, SeparateLossesAreEachCountedOnce) {
  Scenario s;
  s.lost = {1'000, 20'000, 20'001, 60'000};
  const Outcome o = run(s);
  EXPECT_EQ(o.total, 4);
  EXPECT_EQ(o.found_at.size(), 3u);
}

TEST(ReportTimingTracker1047, ClockDriftOfHundredPpmEitherWayIsNotLoss) {
  // 100 ppm over 10 minutes is 60 ms, seven and a half report periods of accumulated lag.
  for (double ppm : {100.0, -100.0}) {
    Scenario s;
    s.drift_ppm = ppm;
    const Outcome o = run(s);
    EXPECT_EQ(o.total, 0) << ppm << " ppm";
  }
}

TEST(ReportTimingTracker1047, ClockDriftDoesNotHideARealLoss) {
  for (double ppm : {100.0, -100.0}) {
    Scenario s;
    s.drift_ppm = ppm;
    s.lost = {45'000};
    const Outcome o = run(s);
    EXPECT_EQ(o.total, 1) << ppm << " ppm";
  }
}

TEST(ReportTimingTracker1047, RandomUsbLatencyUpToThreeMsIsNotLoss) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    Scenario s;
    s.latency_ns = 200'000;
    s.jitter_ns = 3'000'000;
    s.seed = seed;
    const Outcome o = run(s);
    EXPECT_EQ(o.total, 0) << "seed " << seed;
  }
}

TEST(ReportTimingTracker1047, RandomLatencyAndDriftTogetherStillFindTheLoss) {
  Scenario s;
  s.jitter_ns = 3'000'000;
  s.drift_ppm = 100.0;
  s.lost = {10'000, 50'000, 50'001};
  s.seed = 7;
  const Outcome o = run(s);
  EXPECT_EQ(o.total, 3);
}

TEST(ReportTimingTracker1047, FastBoardClockWithBatchedReadsIsNotLoss) {
  // A board running fast lowers the lag; the reference follows it down.
  Scenario s;
  s.batched = true;
  s.drift_ppm = -100.0;
  const Outcome o = run(s);
  EXPECT_EQ(o.total, 0);
}

TEST(ReportTimingTracker1047, FirmwareTwoHundredTicksAndBlockSize) {
  // 2xx firmware ticks at 6 MHz: 48000 ticks per period. Blocks of 4.
  ReportTimingTracker1047 tracker(1.0 / 6e6, kPeriodNs, 4);
  std::int64_t host = 5'000'000'000;
  int found = 0;
  for (int k = 0; k < 200; ++k) {
    host += kPeriodNs;
    if (k == 100) host += kPeriodNs;  // one report missing before this one
    found += tracker.observe(48'000, host);
  }
  EXPECT_EQ(found, 1);
  EXPECT_EQ(tracker.total_lost(), 1);
}

TEST(ReportTimingTracker1047, ResetStartsAfresh) {
  ReportTimingTracker1047 tracker(kTickS);
  std::int64_t host = 0;
  for (int k = 0; k < 40; ++k) {
    host += kPeriodNs;
    if (k == 20) host += 2 * kPeriodNs;
    tracker.observe(kTicksPerPeriod, host);
  }
  ASSERT_EQ(tracker.total_lost(), 2);
  tracker.reset();
  EXPECT_EQ(tracker.total_lost(), 0);
  // After a reset a big jump in host time (a reconnect) is the new start, not a loss.
  host += 10'000'000'000;
  for (int k = 0; k < 40; ++k) {
    host += kPeriodNs;
    EXPECT_EQ(tracker.observe(kTicksPerPeriod, host), 0);
  }
  EXPECT_EQ(tracker.total_lost(), 0);
}

}  // namespace
}  // namespace furuta::bridge
