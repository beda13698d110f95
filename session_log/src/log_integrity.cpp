#include "furuta/session_log/log_integrity.hpp"

#include <algorithm>
#include <cctype>
#include <optional>
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

// The version a start record names ("furuta 0.2.0 (git ...)", or a bare "0.2.0"), if any.
std::optional<std::array<int, 3>> version_of(const std::string& software_version) {
  for (std::size_t i = 0; i < software_version.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(software_version[i]))) continue;
    if (i > 0 && software_version[i - 1] != ' ') continue;
    std::array<int, 3> v{};
    char dot1 = 0, dot2 = 0;
    std::istringstream in(software_version.substr(i));
    if (in >> v[0] >> dot1 >> v[1] >> dot2 >> v[2] && dot1 == '.' && dot2 == '.') return v;
    return std::nullopt;
  }
  return std::nullopt;
}

// A whole log (both records, every byte readable) that has no seal though its version seals.
bool seal_removed(const SessionLog& log) {
  if (log.seal || !log.complete() || log.read_stats.damaged_regions > 0 ||
      log.read_stats.truncated_tail) {
    return false;
  }
  const auto version = version_of(log.start->software_version);
  return version && *version >= kFirstSealingVersion;
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
  if (log.start_records > 1 || log.end_records > 1 || log.events_after_seal > 0 ||
      log.foreign_samples > 0) {
    std::ostringstream t;
    t << "joined: more than one session in one file (" << log.start_records << " start and "
      << log.end_records << " end records, " << log.foreign_samples
      << " sample(s) of another session, " << log.events_after_seal
      << " event(s) after the log's seal)";
    add(Kind::joined, t);
  }
  for (std::size_t i = 1; i < log.samples.size(); ++i) {
    const auto& before = log.samples[i - 1];
    const auto& s = log.samples[i];
    if (s.seq <= before.seq) {
      std::ostringstream t;
      t << "out of order: sample seq " << s.seq << " follows seq " << before.seq
        << (s.seq == before.seq ? " (a sample repeated)" : "");
      add(Kind::out_of_order, t);
      break;
    }
  }
  for (std::size_t i = 1; i < log.samples.size(); ++i) {
    const auto& before = log.samples[i - 1];
    const auto& s = log.samples[i];
    if (s.monotonic_ns <= before.monotonic_ns) {
      std::ostringstream t;
      t << "time goes back: sample seq " << s.seq << " is timed ";
      if (s.monotonic_ns == before.monotonic_ns) {
        t << "at the same time as";
      } else {
        t << static_cast<double>(before.monotonic_ns - s.monotonic_ns) * 1e-9 << " s before";
      }
      t << " seq " << before.seq << " that precedes it";
      add(Kind::time_goes_back, t);
      break;
    }
  }
  if (log.end) {
    std::int64_t last_seq = -1;
    for (const auto& s : log.samples) last_seq = std::max(last_seq, s.seq);
    // Missing, repeated or reordered samples are named above; this is the count itself.
    if (log.end->samples != last_seq + 1) {
      std::ostringstream t;
      t << "count mismatch: the end record counts " << log.end->samples
        << " sample(s), the log holds " << log.samples.size();
      if (!log.samples.empty()) t << " (the last is seq " << last_seq << ")";
      add(Kind::count_mismatch, t);
    }
  }
  // Damage or a cut tail already says the bytes are not what was written; the seal would only
  // repeat it.
  if (log.seal && stats.damaged_regions == 0 && !stats.truncated_tail) {
    const auto& seal = *log.seal;
    const bool same_counts = seal.events == static_cast<std::int64_t>(log.digested_events) &&
                             seal.samples == static_cast<std::int64_t>(log.digested_samples);
    const bool same_session = !log.start || seal.session == log.start->session;
    if (!log.seal_digest_matches || !log.seal_header_matches || !same_counts || !same_session) {
      std::ostringstream t;
      t << "altered: the events are not the ones the log's seal was made over (sealed "
        << seal.events << " events with " << seal.samples << " samples, read "
        << log.digested_events << " with " << log.digested_samples << "; the "
        << seal.digest_algorithm << " digest " << (log.seal_digest_matches ? "matches" : "differs")
        << "): changed, added, removed or reordered after the session was written";
      add(Kind::altered, t);
    }
  }
  if (seal_removed(log)) {
    std::ostringstream t;
    t << "seal missing: written by " << log.start->software_version
      << ", which seals every log, but it has no seal (removed, or the writer stopped between "
         "the end record and the seal)";
    add(Kind::seal_missing, t);
  }
  if (log.seal && !log.seal->source_integrity.empty() && log.seal->source_integrity != kIntact) {
    std::ostringstream t;
    t << "replayed from a log that was not intact (" << log.seal->source
      << "): " << log.seal->source_integrity;
    add(Kind::damaged_source, t);
  }
  return problems;
}

bool usable_in_part(const std::vector<LogProblem>& problems) {
  using Kind = LogProblem::Kind;
  return !has_problem(problems, Kind::not_a_session_log) && !has_problem(problems, Kind::joined) &&
         !has_problem(problems, Kind::altered) && !has_problem(problems, Kind::damaged_source) &&
         !has_problem(problems, Kind::seal_missing);
}

std::vector<std::string> integrity_notes(const SessionLog& log) {
  std::vector<std::string> notes;
  if (log.complete() && !log.seal && log.read_stats.damaged_regions == 0 &&
      !log.read_stats.truncated_tail && !seal_removed(log)) {
    notes.push_back(
        "no seal: written before session logs were sealed, so its integrity rests on its sequence "
        "numbers, times and counts alone (a changed value inside a sample cannot be seen)");
  }
  return notes;
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
    if (damaged_here || samples[i].seq != samples[i - 1].seq + 1 ||
        samples[i].monotonic_ns <= samples[i - 1].monotonic_ns) {
      runs.push_back({begin, i});
      begin = i;
    }
  }
  runs.push_back({begin, samples.size()});
  return runs;
}

}  // namespace furuta::session_log
