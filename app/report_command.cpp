// `furuta report LOG... -o DIR`: balance sessions' figures and plots from their logs, as one HTML
// page with balance.json beside it (report/'s balance_page.hpp makes both).
#include <ostream>
#include <string>
#include <vector>

#include "balance_text.hpp"
#include "commands.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/balance_page.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

int run_report_command(const ReportCommandOptions& options, std::ostream& out, std::ostream& err) {
  if (options.logs.empty()) {
    err << "furuta report: no log given: name the session logs to report\n";
    return kExitNotDone;
  }
  if (options.output_dir.empty()) {
    err << "furuta report: -o is empty: give the directory for the report's files\n";
    return kExitNotDone;
  }
  // The directory is replaced whole: a log inside it would be deleted with the old files.
  if (const auto input = report::input_in_the_way(options.output_dir, options.logs)) {
    err << "furuta report: -o " << options.output_dir.string() << " would overwrite the input "
        << input->string() << " (the output directory is replaced whole): give another -o\n";
    return kExitNotDone;
  }
  report::BalanceReportInput input;
  input.software_version = daemon::kSoftwareVersion;
  // What makes the report done in part: each named on err once the files are written.
  std::vector<std::string> in_part;
  for (const std::filesystem::path& path : options.logs) {
    const session_log::SessionLog log = session_log::load_session_log(path);
    const auto problems = session_log::integrity_problems(log);
    // A file that is no session log has nothing to report: bad input, nothing is written.
    if (session_log::has_problem(problems, session_log::LogProblem::Kind::not_a_session_log)) {
      err << "furuta report: " << path.string() << ": " << session_log::describe(problems) << "\n";
      return kExitNotDone;
    }
    report::BalanceLogEntry entry{path.string(), pipeline::summarize_session(log, ""), {}};
    for (const auto& p : problems) entry.problems.push_back(p.text);
    if (!problems.empty()) {
      in_part.push_back(path.string() + " is not intact (reported as far as it goes): " +
                        session_log::describe(problems));
    }
    // Another session's log is said to be one (its profile and samples), not refused: a
    // directory's logs can be reported together whatever ran.
    if (!entry.session.balance) {
      in_part.push_back(path.string() + " is not a balance session (profile " +
                        (entry.session.profile.empty() ? "-" : entry.session.profile) +
                        "): its section says only what it is");
    }
    input.logs.push_back(std::move(entry));
  }
  bool replaced = false;
  try {
    // A directory it may not replace or cannot write, or one another run is writing, is refused
    // before anything is written; the lock is held until the files are in place.
    report::RunDirectory dir(options.output_dir);
    report::write_balance_report(dir.staging(), input);
    replaced = dir.commit();
  } catch (const report::OutputDirectoryError& e) {
    err << "furuta report: -o " << options.output_dir.string() << ": " << e.what() << "\n";
    return kExitNotDone;
  }
  for (const report::BalanceLogEntry& log : input.logs) {
    out << log.name << "\n";
    if (log.session.balance) {
      out << balance_text(*log.session.balance);
    } else {
      out << "  not a balance session: profile "
          << (log.session.profile.empty() ? "-" : log.session.profile) << ", "
          << log.session.samples << " samples\n";
    }
  }
  out << "wrote " << (options.output_dir / "balance.json").string() << " and figures in "
      << options.output_dir.string() << "\n";
  out << "report: " << (options.output_dir / "report.html").string() << "\n";
  if (replaced) {
    out << "(the previous run's files in " << options.output_dir.string() << " were replaced)\n";
  }
  for (const std::string& part : in_part) err << "furuta report: done in part: " << part << "\n";
  return in_part.empty() ? kExitDone : kExitPartOrRefused;
}

}  // namespace furuta::app
