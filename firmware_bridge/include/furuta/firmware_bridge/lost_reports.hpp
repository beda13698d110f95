#pragma once
// Lost-report detection: a gap is an event with a count, never silently absorbed.

#include <cstdint>

#include "furuta/firmware_bridge/phidget_ids.hpp"

namespace furuta::bridge {

// 1065: the u8 packet counter goes up by one per report.
class PacketCounterTracker1065 {
 public:
  // Reports lost between the previous observed report and this one (0 for the first after reset).
  int observe(std::uint8_t packet_counter);
  std::int64_t total_lost() const { return total_lost_; }
  void reset();

 private:
  bool have_previous_ = false;
  std::uint8_t previous_ = 0;
  std::int64_t total_lost_ = 0;
};

// 1047: no counter, and its counts are deltas, so a lost report loses counts. The board's
// packetTime says how much board time each report covers; the host's receive time says how much
// host time passed. Their difference (the lag) rises by one report period for each report lost,
// while USB latency and the loop reading reports in batches only move it temporarily. The tracker
// takes the minimum lag over blocks of reports and reports a loss when one block's minimum exceeds
// the previous block's by more than half a period; clock drift between blocks is far smaller than
// that. Losses are therefore found up to one block late, and a report delayed on the host for
// longer than a whole block is indistinguishable from a lost one.
//
// host_time_ns must be each report's arrival time (see UsbReport::host_time_ns). Times taken when a
// loop drains reports in batches sit on the loop's grid, and then clock drift and latency move the
// lag in whole report periods, exactly as a loss does: the tracker would count false losses.
class ReportTimingTracker1047 {
 public:
  ReportTimingTracker1047(double tick_seconds, std::int64_t report_period_ns = kReportPeriodNs,
                          int block_reports = 8);
  // Reports found lost at this observation (they happened earlier, within the last two blocks).
  int observe(std::uint32_t packet_time_ticks, std::int64_t host_time_ns);
  std::int64_t total_lost() const { return total_lost_; }
  void reset();

 private:
  double tick_ns_;
  std::int64_t period_ns_;
  int block_reports_;
  bool started_ = false;
  std::int64_t host_start_ns_ = 0;
  double board_elapsed_ns_ = 0.0;
  int in_block_ = 0;
  double block_min_lag_ns_ = 0.0;
  bool have_reference_ = false;
  double reference_lag_ns_ = 0.0;
  std::int64_t total_lost_ = 0;
};

}  // namespace furuta::bridge
