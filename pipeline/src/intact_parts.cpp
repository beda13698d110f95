// A log that is not intact as recordings of its contiguous runs of samples.
#include <algorithm>
#include <sstream>

#include "furuta/pipeline/pipeline.hpp"
#include "furuta/session_log/log_integrity.hpp"

namespace furuta::pipeline {

namespace {

std::string seq_range(const session_log::SessionLog& log, const session_log::SampleRun& run) {
  return "seq " + std::to_string(log.samples[run.begin].seq) + "-" +
         std::to_string(log.samples[run.end - 1].seq);
}

// The run's samples as a log of their own: experiment_from_log then resamples and names it without
// seeing anything on the other side of a gap. The USB reports (the commands written, for the
// output-error input) are those within the run's time: the input before the run's first command
// is then its first sample's echoed duty, held, as for any log.
session_log::SessionLog run_log(const session_log::SessionLog& log,
                                const session_log::SampleRun& run) {
  session_log::SessionLog part;
  part.path = log.path;
  part.start = log.start;
  part.end = log.end;
  part.samples.assign(log.samples.begin() + static_cast<std::ptrdiff_t>(run.begin),
                      log.samples.begin() + static_cast<std::ptrdiff_t>(run.end));
  const std::int64_t from_ns = part.samples.front().monotonic_ns;
  const std::int64_t to_ns = part.samples.back().monotonic_ns;
  for (const auto& r : log.usb_reports) {
    if (r.time_ns >= from_ns && r.time_ns <= to_ns) part.usb_reports.push_back(r);
  }
  return part;
}

}  // namespace

IntactParts intact_part_recordings(const session_log::SessionLog& log, Role role,
                                   std::size_t min_samples, const config::RigConfig& rig) {
  const std::vector<session_log::SampleRun> runs = session_log::contiguous_sample_runs(log);
  std::vector<session_log::SampleRun> kept, too_short, not_chosen;
  for (const auto& run : runs) (run.size() >= min_samples ? kept : too_short).push_back(run);
  if (role == Role::held_out && kept.size() > 1) {
    // One held-out recording per batch: the longest run, the others set aside.
    const session_log::SampleRun chosen = *std::max_element(
        kept.begin(), kept.end(), [](const auto& a, const auto& b) { return a.size() < b.size(); });
    for (const auto& run : kept) {
      if (run.begin != chosen.begin) not_chosen.push_back(run);
    }
    kept = {chosen};
  }

  std::size_t used = 0;
  for (const auto& run : kept) used += run.size();
  const std::string file = log.path.filename().string();
  std::ostringstream account;
  account << file << ": not intact (" << session_log::describe(session_log::integrity_problems(log))
          << "); ";
  if (kept.empty()) {
    account << "no contiguous run of samples is as long as the " << min_samples
            << " the fit needs (" << runs.size() << " run(s), the longest ";
    std::size_t longest = 0;
    for (const auto& run : runs) longest = std::max(longest, run.size());
    account << longest << " samples)";
    return {{}, account.str()};
  }
  account << "used " << used << " of its " << log.samples.size() << " samples as " << kept.size()
          << " separate part(s) (";
  for (std::size_t i = 0; i < kept.size(); ++i) {
    account << (i == 0 ? "" : ", ") << seq_range(log, kept[i]);
  }
  account << ")";
  const auto list = [&](const std::vector<session_log::SampleRun>& dropped, const char* why) {
    if (dropped.empty()) return;
    account << "; dropped " << dropped.size() << " run(s) " << why << ": ";
    for (std::size_t i = 0; i < dropped.size(); ++i) {
      account << (i == 0 ? "" : ", ") << seq_range(log, dropped[i]) << " (" << dropped[i].size()
              << " samples)";
    }
  };
  const std::string shorter = "shorter than the " + std::to_string(min_samples) + " samples needed";
  list(too_short, shorter.c_str());
  list(not_chosen, "(held out: only the longest run is used)");

  IntactParts parts;
  parts.account = account.str();
  const std::string role_name = role == Role::fit ? "fit" : "held out";
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const session_log::SessionLog part = run_log(log, kept[i]);
    identification::RawExperiment e = identification::experiment_from_log(part);
    identification::OeExperiment oe = identification::oe_experiment_from_log(part, rig);
    // Named by its samples whenever the log was cut: Table I's columns and the held-out fit say
    // which part they are.
    if (runs.size() > 1) e.name += " (" + seq_range(log, kept[i]) + ")";
    oe.name = e.name;
    // The session's own warnings (lost reports, overruns) once, with the account.
    if (i == 0) {
      e.warnings.push_back(parts.account);
    } else {
      e.warnings.clear();
    }
    std::optional<SessionSummary> summary;
    if (i == 0) summary = summarize_session(log, role_name);
    parts.recordings.push_back(
        {std::move(e), std::move(summary), std::move(oe), !log.control.empty()});
  }
  return parts;
}

}  // namespace furuta::pipeline
