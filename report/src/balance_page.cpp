// Balance sessions on a page: the sections an identification's report.html shares with
// `furuta report`'s own page, that page, balance.json and the writer.
#include "furuta/report/balance_page.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "format.hpp"
#include "furuta/report/outputs.hpp"
#include "html_page.hpp"

namespace furuta::report {

namespace {

// "3.20 s", or "never caught".
std::string caught_text(const pipeline::BalanceSummary& b) {
  return b.caught_at_s ? fixed(*b.caught_at_s, 2) + " s" : "never caught";
}

// An end record's reason as words: "pendulum fell: 36.0 deg from upright, ...", "duration
// reached"; a log without one was cut short.
std::string ended_text(const pipeline::SessionSummary& s) {
  if (!s.complete && s.end_reason.empty()) return "cut short (no end record)";
  std::string reason = s.end_reason.empty() ? std::string("yes") : s.end_reason;
  const std::size_t kind_end = std::min(reason.find(':'), reason.size());
  std::replace(reason.begin(), reason.begin() + static_cast<long>(kind_end), '_', ' ');
  return reason;
}

// The law's time in microseconds: the loop's budget is a period of milliseconds.
std::string microseconds(std::int64_t ns) {
  return short_number(static_cast<double>(ns) * 1e-3, 4) + " \u00b5s";
}

// Which estimate of which identification the controller was designed from.
std::string parameters_text(const pipeline::BalanceController& c) {
  if (!c.unreadable.empty()) return "the record's TOML does not read: " + c.unreadable;
  std::string text = c.parameters_source.empty() ? std::string("-") : c.parameters_source;
  if (!c.results.empty()) text += " of " + c.results;
  if (!c.rig.empty()) text += ", for rig " + c.rig;
  return text;
}

std::vector<std::vector<std::string>> figures_rows(const pipeline::SessionSummary& s,
                                                   const pipeline::BalanceSummary& b) {
  const bool balanced = b.balanced_s > 0;
  std::vector<std::vector<std::string>> rows = {
      {"caught at", caught_text(b)},
      {"balanced for", fixed(b.balanced_s, 2) + " s"},
      {"angle from upright while balancing, RMS",
       balanced ? fixed(b.upright_rms_deg, 3) + " deg" : "-"},
      {"angle from upright while balancing, max",
       balanced ? fixed(b.upright_max_deg, 3) + " deg" : "-"},
      {"duty while balancing, RMS", balanced ? fixed(b.duty_rms, 4) : "-"},
      {"max |duty| (whole session)", fixed(b.max_abs_duty, 4)},
      {"arm travel, max |arm angle|", fixed(b.max_abs_arm_deg, 1) + " deg"},
      {"fell", b.fell ? "yes" : "no"},
      {"ended", ended_text(s)},
      {"law time, median / max",
       microseconds(b.law_time_p50_ns) + " / " + microseconds(b.law_time_max_ns)},
      {"controller cycles",
       std::to_string(b.cycles) + " of " + std::to_string(s.samples) + " samples"},
  };
  if (b.controller) {
    rows.push_back({"controller file", b.controller->path});
    rows.push_back({"controller SHA-256", b.controller->sha256});
    rows.push_back({"designed from", parameters_text(*b.controller)});
  } else {
    rows.push_back({"controller file", "the log has no controller record"});
  }
  return rows;
}

// A page of its own: the head, the style, what the page is.
void balance_page_head(Html& h, const BalanceReportInput& in) {
  const std::string title = "Balance report";
  h.document_start(
      title, in.software_version +
                 ": balance sessions of a rotary inverted (Furuta) pendulum, from their logs: "
                 "when the controller caught the pendulum, how well it held it upright, the "
                 "duty and arm travel it took, and the controller file it ran. The numbers are "
                 "also in balance.json.");
  h.raw("</header>\n<nav>\n<ol>\n");
  for (std::size_t i = 0; i < in.logs.size(); ++i) {
    h.raw("<li><a href=\"#balance-log-" + std::to_string(i + 1) + "\">");
    h.text(in.logs[i].name);
    h.raw("</a></li>\n");
  }
  h.raw("</ol>\n</nav>\n");
}

Json balance_figures_json(const pipeline::BalanceSummary& b) {
  Json j;
  j["cycles"] = b.cycles;
  j["caught_at_s"] = b.caught_at_s ? Json(*b.caught_at_s) : Json(nullptr);
  j["balanced_s"] = b.balanced_s;
  j["upright_rms_deg"] = b.upright_rms_deg;
  j["upright_max_deg"] = b.upright_max_deg;
  j["duty_rms"] = b.duty_rms;
  j["max_abs_duty"] = b.max_abs_duty;
  j["max_abs_arm_deg"] = b.max_abs_arm_deg;
  j["fell"] = b.fell;
  j["law_time_p50_ns"] = b.law_time_p50_ns;
  j["law_time_max_ns"] = b.law_time_max_ns;
  if (b.controller) {
    const pipeline::BalanceController& c = *b.controller;
    Json controller;
    controller["path"] = c.path;
    controller["sha256"] = c.sha256;
    controller["parameters_source"] = c.parameters_source;
    controller["results"] = c.results;
    controller["rig"] = c.rig;
    if (!c.unreadable.empty()) controller["unreadable"] = c.unreadable;
    j["controller"] = controller;
  } else {
    j["controller"] = nullptr;
  }
  return j;
}

}  // namespace

void balance_log_sections(Html& h, const std::vector<BalanceLogEntry>& logs,
                          const std::string& heading) {
  std::size_t figure = 0;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    const BalanceLogEntry& log = logs[i];
    const pipeline::SessionSummary& s = log.session;
    h.raw("<section class=\"balance-log\" id=\"balance-log-" + std::to_string(i + 1) + "\">\n");
    h.element(heading, log.name);
    h.raw("\n");
    for (const std::string& problem : log.problems) {
      h.paragraph("Not intact: " + problem + ".", "absent");
    }
    if (!s.balance) {
      h.paragraph("Not a balance session: profile " + (s.profile.empty() ? "-" : s.profile) + ", " +
                      std::to_string(s.samples) + " samples, ended: " + ended_text(s) +
                      ". Its log holds no controller cycles to report.",
                  "absent");
      h.raw("</section>\n");
      continue;
    }
    const pipeline::BalanceSummary& b = *s.balance;
    ++figure;
    const std::string n = std::to_string(figure);
    h.paragraph("Session " + (s.label.empty() ? std::string() : "labelled " + s.label + ", ") +
                "profile " + s.profile + ", " + fixed(s.duration_s, 1) + " s asked, " +
                std::to_string(s.samples) + " samples at " + short_number(s.period_s * 1e3) +
                " ms.");
    h.table("balance-figures-" + n, "Balance figures", {"", "value"}, figures_rows(s, b));
    h.figure("fig-balance-" + n, svg_balance(b),
             "The pendulum's angle from upright [deg], the arm angle [deg], the commanded duty and "
             "the controller's mode (swing-up grey, catch amber, balance green, fallen red) over "
             "time t [s] since the session started.");
    h.raw("</section>\n");
  }
}

Json balance_json(const BalanceReportInput& input) {
  Json doc;
  doc["software_version"] = input.software_version;
  Json logs = Json::array();
  for (const BalanceLogEntry& log : input.logs) {
    const pipeline::SessionSummary& s = log.session;
    Json j;
    j["log"] = log.name;
    j["file"] = s.file;
    j["label"] = s.label;
    j["profile"] = s.profile;
    j["samples"] = s.samples;
    j["end_reason"] = s.complete || !s.end_reason.empty() ? Json(s.end_reason) : Json(nullptr);
    j["intact"] = log.problems.empty();
    j["problems"] = log.problems;
    j["balance"] = s.balance ? balance_figures_json(*s.balance) : Json(nullptr);
    logs.push_back(j);
  }
  doc["logs"] = logs;
  return doc;
}

std::string render_balance_html(const BalanceReportInput& input) {
  Html h;
  balance_page_head(h, input);
  balance_log_sections(h, input.logs, "h2");
  h.raw("</body>\n</html>\n");
  return h.str();
}

std::string balance_figure_name(std::size_t n) {
  return "balance_" + std::to_string(n) + ".svg";
}

void write_balance_report(const std::filesystem::path& dir, const BalanceReportInput& input) {
  std::filesystem::create_directories(dir);
  std::size_t n = 0;
  for (const BalanceLogEntry& log : input.logs) {
    if (log.session.balance) {
      write_text_file(dir / balance_figure_name(++n), svg_balance(*log.session.balance));
    }
  }
  write_text_file(dir / "balance.json", json_text(balance_json(input), 4));
  write_text_file(dir / "report.html", render_balance_html(input));
}

}  // namespace furuta::report
