#pragma once
// Whether a session log holds a whole session, and if not, what is wrong with it in words: the one
// rule `furuta log info`, `log export-csv`, `replay`, `identify` and `process-logs` all apply.
//
// Intact: a session start record, a session end record, no damaged region, no truncated tail, no
// event that fails to decode, no sample sequence number missing between the first and the last.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "furuta/session_log/session_log.hpp"

namespace furuta::session_log {

struct LogProblem {
  enum class Kind : std::uint8_t {
    not_a_session_log,  // no session start record: whatever the file is, it is not one of ours
    damaged,            // the reader skipped unreadable bytes
    truncated,          // the file ends inside an event
    undecodable,        // intact on disk, but not a message of its channel's type
    missing_samples,    // sequence numbers absent between the first sample and the last
    cut_short,          // no session end record
  };
  Kind kind;
  std::string text;  // e.g. "damaged: 1 unreadable region(s), 64 bytes skipped"
};

// Every problem of the log, most fundamental first; empty when the log is intact.
std::vector<LogProblem> integrity_problems(const SessionLog& log);
// The problems joined by "; ".
std::string describe(const std::vector<LogProblem>& problems);
bool has_problem(const std::vector<LogProblem>& problems, LogProblem::Kind kind);

// A run of samples [begin, end) (indices into SessionLog::samples) with consecutive sequence
// numbers and no damaged region inside: what can be filtered and differentiated as one signal.
struct SampleRun {
  std::size_t begin = 0, end = 0;
  std::size_t size() const { return end - begin; }
};
// The log's samples cut at every gap (a missing or out-of-order sequence number, a damaged
// region). One run for an intact log with samples; none for a log without samples.
std::vector<SampleRun> contiguous_sample_runs(const SessionLog& log);

}  // namespace furuta::session_log
