#include "furuta/firmware_bridge/lost_reports.hpp"

#include <algorithm>
#include <cmath>

namespace furuta::bridge {

int PacketCounterTracker1065::observe(std::uint8_t packet_counter) {
  if (!have_previous_) {
    have_previous_ = true;
    previous_ = packet_counter;
    return 0;
  }
  // Modulo-256 step: 254 -> 1 is a step of 3, so 2 reports were lost.
  const auto step = static_cast<std::uint8_t>(packet_counter - previous_);
  previous_ = packet_counter;
  // A repeated counter (step 0) is a duplicate, e.g. a report delivered twice by a backend. Loss
  // only ever makes the counter jump forward, so a duplicate cannot come from loss; reading it as
  // 255 lost reports would turn a harmless repeat into a false alarm of two seconds of data. The
  // one ambiguity left (exactly 256 lost in a row) would show up as a stall far longer than any the
  // loop tolerates.
  if (step == 0) return 0;
  const int lost = step - 1;
  total_lost_ += lost;
  return lost;
}

void PacketCounterTracker1065::reset() {
  have_previous_ = false;
  previous_ = 0;
  total_lost_ = 0;
}

ReportTimingTracker1047::ReportTimingTracker1047(double tick_seconds, std::int64_t report_period_ns,
                                                 int block_reports)
    : tick_ns_(tick_seconds * 1e9),
      period_ns_(report_period_ns),
      // A block of fewer than one report would never complete.
      block_reports_(std::max(block_reports, 1)) {}

int ReportTimingTracker1047::observe(std::uint32_t packet_time_ticks, std::int64_t host_time_ns) {
  if (!started_) {
    // The first report's packetTime covers time before we were listening, so it is not counted:
    // the lag is measured relative to this report, and only its changes matter.
    started_ = true;
    host_start_ns_ = host_time_ns;
    board_elapsed_ns_ = 0.0;
  } else {
    board_elapsed_ns_ += static_cast<double>(packet_time_ticks) * tick_ns_;
  }
  const double lag_ns = static_cast<double>(host_time_ns - host_start_ns_) - board_elapsed_ns_;

  block_min_lag_ns_ = in_block_ == 0 ? lag_ns : std::min(block_min_lag_ns_, lag_ns);
  if (++in_block_ < block_reports_) return 0;
  in_block_ = 0;

  if (!have_reference_) {
    have_reference_ = true;
    reference_lag_ns_ = block_min_lag_ns_;
    return 0;
  }
  const double period = static_cast<double>(period_ns_);
  const double excess = block_min_lag_ns_ - reference_lag_ns_;
  if (excess > period / 2.0) {
    const auto lost = static_cast<int>(std::llround(excess / period));
    total_lost_ += lost;
    // Move up by whole periods only, so the residue (latency, drift) is followed by the next block
    // instead of being counted again or hiding the next loss.
    reference_lag_ns_ += lost * period;
    return lost;
  }
  // Includes a falling minimum (a block of unusually quick deliveries, or a board clock running
  // fast): the reference follows it so the comparison stays between neighbouring blocks.
  reference_lag_ns_ = block_min_lag_ns_;
  return 0;
}

void ReportTimingTracker1047::reset() {
  started_ = false;
  host_start_ns_ = 0;
  board_elapsed_ns_ = 0.0;
  in_block_ = 0;
  block_min_lag_ns_ = 0.0;
  have_reference_ = false;
  reference_lag_ns_ = 0.0;
  total_lost_ = 0;
}

}  // namespace furuta::bridge
