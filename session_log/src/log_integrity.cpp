#include "furuta/session_log/log_integrity.hpp"

#include <algorithm>
#include <sstream>

namespace furuta::session_log {

namespace {

// "301-307, 500, ..." : enough to find the gaps in an export, not a list of a million numbers.
std::string ranges_text(const std::vector<std::int64_t>& sorted) {
  constexpr std::size_t kRangesShown = 3;
  std::ostringstream text;
  std::size_t shown = 0;
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i;
    while (j + 1 < sorted.size() && sorted[j + 1] == sorted[j] + 1) ++j;
    if (shown == kRangesShown) {
      text << ", ...";
      break;
    }
    text << (shown == 0 ? "" : ", ") << sorted[i];
    if (j > i) text << "-" << sorted[j];
    ++shown;
    i = j + 1;
  }
  return text.str();
}

}  // namespace

std::vector<LogProblem> integrity_problems(const SessionLog& log) {
  using Kind = LogProblem::Kind;
  const LogReadStats& stats = log.read_stats;
  std::vector<LogProblem> problems;
  const auto add = [&](Kind kind, const std::ostringstream& text) {
    problems.push_back({kind, text.str()});
  };
  if (!log.start) {
    std::ostringstream t;
    t << "not a session log: no session start record (" << stats.events << " readable events, "
      << stats.bytes_skipped << " bytes unreadable)";
    add(Kind::not_a_session_log, t);
  }
  if (stats.damaged_regions > 0) {
    std::ostringstream t;
    t << "damaged: " << stats.damaged_regions << " unreadable region(s), " << stats.bytes_skipped
      << " bytes skipped";
    add(Kind::damaged, t);
  }
  if (stats.truncated_tail) {
    std::ostringstream t;
    t << "truncated: the file ends inside an event after " << stats.readable_prefix_bytes
      << " readable bytes";
    add(Kind::truncated, t);
  }
  if (log.undecodable_events > 0) {
    std::ostringstream t;
    t << log.undecodable_events << " event(s) are not messages of their channel's type";
    add(Kind::undecodable, t);
  }
  const std::vector<std::int64_t> missing = log.missing_sequence_numbers();
  if (!missing.empty()) {
    std::ostringstream t;
    t << missing.size() << " sample(s) missing (sequence numbers " << ranges_text(missing) << ")";
    add(Kind::missing_samples, t);
  }
  if (log.start && !log.end) {
    std::ostringstream t;
    t << "cut short: no session end record (as in a log recovered after a crash)";
    add(Kind::cut_short, t);
  }
  return problems;
}

std::string describe(const std::vector<LogProblem>& problems) {
  std::string text;
  for (const LogProblem& p : problems) text += (text.empty() ? "" : "; ") + p.text;
  return text;
}

bool has_problem(const std::vector<LogProblem>& problems, LogProblem::Kind kind) {
  return std::any_of(problems.begin(), problems.end(),
                     [kind](const LogProblem& p) { return p.kind == kind; });
}

std::vector<SampleRun> contiguous_sample_runs(const SessionLog& log) {
  std::vector<SampleRun> runs;
  const auto& samples = log.samples;
  if (samples.empty()) return runs;
  std::size_t begin = 0;
  auto damage = log.damage_before_sample.begin();
  for (std::size_t i = 1; i < samples.size(); ++i) {
    while (damage != log.damage_before_sample.end() && *damage < i) ++damage;
    const bool damaged_here = damage != log.damage_before_sample.end() && *damage == i;
    if (damaged_here || samples[i].seq != samples[i - 1].seq + 1) {
      runs.push_back({begin, i});
      begin = i;
    }
  }
  runs.push_back({begin, samples.size()});
  return runs;
}

}  // namespace furuta::session_log
