#pragma once
// The identification trigger: the session logs that are complete in a logs directory become
// identifications without anyone asking. One pass is what furuta-identify@.service runs when its
// path unit sees the directory change; watch_logs is the same job in a loop, for machines without
// systemd.
//
// Layout, for a logs directory L and an identifications directory I:
// - L/<session>.lcmlog: complete logs, pending (L/.partial/ is the daemon's: never touched);
// - L/done/<session>.lcmlog: identified, or not (a label [automation] does not name: said per log);
// - L/failed/<session>.lcmlog, with L/failed/<session>.reason.txt saying why;
// - I/<first fit session>/: one identification (results.json, report.html, batch.json, ...).
//
// Crash safety: an identification is written into I/.tmp-<name>/ and renamed into place; a journal
// (L/.commit) names it and its logs until they are all in done/. Whatever point a pass dies at,
// the next one finds every log either pending (the stale temporary directory is removed and the
// identification redone) or in done/ with its identification complete.

#include <chrono>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "furuta/config/rig_config.hpp"

namespace furuta::app {

struct LogProcessorOptions {
  std::filesystem::path logs_dir;
  std::filesystem::path identifications_dir;
  config::AutomationConfig automation;  // which sessions form one identification, and what it runs
  // Empty: each batch is fitted with the configuration its first log carries (as `identify`
  // without -c); else this file's rig and [identification] fit every batch (as `identify -c`).
  std::filesystem::path fit_config;
};

struct ProcessingPass {
  std::vector<std::filesystem::path> identifications;  // written by this pass, in place
  int logs_done = 0;                                   // identified, moved to done/
  int logs_not_identified = 0;  // a label [automation] does not name: moved to done/, unfitted
  int logs_failed = 0;          // moved to failed/, with their reason
  int logs_waiting = 0;         // left pending: their identification is not complete yet
  bool recovered = false;       // a crashed pass's work was finished or undone first
};

// One pass: takes the directory's lock (a second pass waits for the first), finishes or undoes
// what a crashed pass left, then moves unreadable, damaged and cut-short logs to failed/ and
// identifies every complete batch ([automation]), until a listing finds nothing more to do (logs
// that landed meanwhile are taken too: a trigger may have been lost while this pass ran). A log
// the intake refuses on its own (too short, no samples) goes to failed/ alone and the rest of its
// batch waits for another; a batch refused only as a whole (logs of two rigs), or whose fit
// fails, goes to failed/ together.
// Throws std::runtime_error when the logs directory is not an existing directory (it is never
// created: done/ and failed/ inside it and the identifications directory are), or when the
// directories cannot be created, locked or read.
ProcessingPass process_logs(const LogProcessorOptions& options, std::ostream& out,
                            std::ostream& err);

// Passes until keep_going() turns false: one at once, then one whenever a log lands (inotify), and
// one every rescan_interval whatever happened (an event can be missed; a pass costs nothing when
// there is nothing to do). keep_going is asked at least every 250 ms.
void watch_logs(const LogProcessorOptions& options, const std::function<bool()>& keep_going,
                std::chrono::milliseconds rescan_interval, std::ostream& out, std::ostream& err);

}  // namespace furuta::app
