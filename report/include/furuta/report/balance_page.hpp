#pragma once
// Balance sessions as a person reads them (`furuta report`, and the balance section of an
// identification's report.html): per log its figures (caught at, balanced for, angle from upright,
// duty, arm travel, how it ended, the law's time, the controller file) and one figure of four
// panels over time: the angle from upright, the arm angle, the duty and the controller's mode.
// The numbers are pipeline::summarize_balance's (SessionSummary::balance); nothing is recomputed.
//
//   report::BalanceReportInput input{version, {{path, pipeline::summarize_session(log, "")}}};
//   report::write_balance_report(dir, input);            // report.html, balance.json, figures

#include <filesystem>
#include <string>
#include <vector>

#include "furuta/pipeline/balance.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/json.hpp"

namespace furuta::report {

// One log of the report.
struct BalanceLogEntry {
  std::string name;                   // how the page names the log: the path as given
  pipeline::SessionSummary session;   // summarize_session's; `balance` set for a balance session
  std::vector<std::string> problems;  // session_log::integrity_problems' texts; empty: intact
};

struct BalanceReportInput {
  std::string software_version;
  std::vector<BalanceLogEntry> logs;  // in the order given
};

// The figure of one balance session: four panels over t [s] sharing the time axis, each a
// <g class="panel" id="..."> (ids "upright", "arm", "duty", "mode"): the angle from upright [deg],
// the arm angle [deg], the commanded duty, and the mode as coloured bands (swing-up, catch,
// balance, fallen) with a legend. Long sessions are thinned to each pixel column's first, lowest,
// highest and last value, so every excursion still shows.
std::string svg_balance(const pipeline::BalanceSummary& balance);

// balance.json: {"software_version", "logs": [{"log", "file", "profile", "samples", "end_reason",
// "intact", "problems", "balance": {figures, "controller"} or null}]} (docs/outputs.md).
Json balance_json(const BalanceReportInput& input);

// The page: what it is, then a section per log (a balance session's figures and figure; another
// log's profile and samples, said not to be a balance session).
std::string render_balance_html(const BalanceReportInput& input);

// The figure's file name for the n-th log (1-based): "balance_1.svg".
std::string balance_figure_name(std::size_t n);

// report.html, balance.json and balance_<n>.svg per balance session into `dir` (created).
// std::runtime_error when a file cannot be written.
void write_balance_report(const std::filesystem::path& dir, const BalanceReportInput& input);

}  // namespace furuta::report
