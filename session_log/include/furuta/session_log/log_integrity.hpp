#pragma once
// Whether a session log holds a whole session, and if not, what is wrong with it in words: the one
// rule `furuta log info`, `log export-csv`, `replay`, `identify` and `process-logs` all apply.
//
// Intact: a session start record, a session end record, no damaged region, no truncated tail, no
// event that fails to decode, one session only, sample sequence numbers 0, 1, 2, ... up to the
// count the end record gives, sample times increasing, and, in a sealed log, every event as the
// seal says it was written.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "furuta/session_log/session_log.hpp"

namespace furuta::session_log {

// A replayed log's seal says "intact" of a source that was (rig_log_seal_t::source_integrity).
inline constexpr const char* kIntact = "intact";
// The first version whose logs all carry a seal: a whole log of this version or later without
// one had its seal removed (an unsealed log of an earlier version is read with a note).
inline constexpr std::array<int, 3> kFirstSealingVersion = {0, 2, 0};

struct LogProblem {
  enum class Kind : std::uint8_t {
    not_a_session_log,  // no session start record: whatever the file is, it is not one of ours
    damaged,            // the reader skipped unreadable bytes
    truncated,          // the file ends inside an event
    undecodable,        // intact on disk, but not a message of its channel's type
    missing_samples,    // sequence numbers absent between the first sample and the last
    cut_short,          // no session end record
    joined,             // more than one session in the file, or events after its seal
    out_of_order,       // a sample sequence number repeated or going back
    time_goes_back,     // a sample's time not after the one before it
    count_mismatch,     // the end record counts other samples than the log holds
    altered,            // well-formed events, but not the ones the seal was made over
    damaged_source,     // a replay of a log that was not intact (its seal says so)
    seal_missing,       // a whole session by a version that seals every log, without its seal
  };
  Kind kind;
  std::string text;  // e.g. "damaged: 1 unreadable region(s), 64 bytes skipped"
};

// Every problem of the log, most fundamental first; empty when the log is intact.
std::vector<LogProblem> integrity_problems(const SessionLog& log);
// The problems joined by "; ".
std::string describe(const std::vector<LogProblem>& problems);
bool has_problem(const std::vector<LogProblem>& problems, LogProblem::Kind kind);
// Whether a log with these problems still has parts that can be trusted on their own (the runs of
// contiguous_sample_runs): not when it is not a session log, holds another session's events, or
// was changed after it was written, lost its seal, or replays a log that was not intact, since no
// part of it is then known to be what was recorded.
bool usable_in_part(const std::vector<LogProblem>& problems);

// What a reader should know about a log that is not a problem with it: a whole log written before
// logs carried a seal, whose integrity rests on its sequence numbers, times and counts alone.
std::vector<std::string> integrity_notes(const SessionLog& log);

// A run of samples [begin, end) (indices into SessionLog::samples) with consecutive sequence
// numbers, increasing times and no damaged region inside: what can be filtered and differentiated
// as one signal.
struct SampleRun {
  std::size_t begin = 0, end = 0;
  std::size_t size() const { return end - begin; }
};
// The log's samples cut at every gap (a missing or out-of-order sequence number, a time going
// back, a damaged region). One run for an intact log with samples; none for a log without samples.
std::vector<SampleRun> contiguous_sample_runs(const SessionLog& log);

}  // namespace furuta::session_log
