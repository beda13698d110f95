// What a session log says about itself.
#include <utility>

#include "furuta/pipeline/balance.hpp"
#include "furuta/pipeline/pipeline.hpp"

namespace furuta::pipeline {

SessionSummary summarize_session(const session_log::SessionLog& log, std::string role) {
  SessionSummary s;
  s.file = log.path.filename().string();
  s.role = std::move(role);
  if (log.start) {
    s.label = log.start->label;
    s.profile = log.start->profile;
    s.amplitude_duty = log.start->amplitude_duty;
    s.duration_s = log.start->duration_s;
    s.period_s = static_cast<double>(log.start->period_ns) * 1e-9;
    s.seed = log.start->seed;
  }
  s.samples = log.samples.size();
  s.missing_samples = log.missing_sequence_numbers().size();
  if (!log.samples.empty()) {
    // The counters are cumulative over the session: the last sample holds the totals.
    s.motor_lost_reports = log.samples.back().motor_lost_reports;
    s.encoder_lost_reports = log.samples.back().encoder_lost_reports;
    s.overruns = log.samples.back().overruns;
  }
  s.faults = log.faults.size();
  for (const auto& f : log.faults) {
    if (f.fatal)
      s.fatal_faults.push_back(f.reason + (f.detail.empty() ? "" : " (" + f.detail + ")"));
  }
  s.complete = log.complete();
  if (log.end) s.end_reason = log.end->end_reason;
  s.damaged_regions = log.read_stats.damaged_regions;
  s.truncated_tail = log.read_stats.truncated_tail;
  s.balance = summarize_balance(log);
  return s;
}

}  // namespace furuta::pipeline
