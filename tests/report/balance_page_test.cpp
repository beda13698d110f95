// The balance page from a summary made by hand: its four panels, the mode as bands, long sessions
// thinned without losing an excursion, every text escaped, balance.json holding the summary's
// figures, a log that is no balance session said to be one, and the identification's page with a
// balance section exactly when a session is one.
#include "furuta/report/balance_page.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "furuta/report/json.hpp"
#include "furuta/report/report.hpp"
#include "furuta/rig_control_t.hpp"

namespace furuta::report::balance_page_test {
namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

// `seconds` of 16 ms cycles: swing-up, catch at 3 s, balance from 3.5 s, a wobble of the angle,
// the arm and the duty; one excursion of each at 10 s.
pipeline::BalanceSummary summary(double seconds) {
  pipeline::BalanceSummary b;
  for (double t = 0; t < seconds; t += 0.016) {
    const std::int8_t mode = t < 3.0   ? furuta::rig_control_t::MODE_SWING_UP
                             : t < 3.5 ? furuta::rig_control_t::MODE_CATCH
                                       : furuta::rig_control_t::MODE_BALANCE;
    const bool spike = std::fabs(t - 10.0) < 0.008;
    b.time_s.push_back(t);
    b.mode.push_back(mode);
    b.upright_error_deg.push_back(spike ? 7.25 : (t < 3 ? 180 - 60 * t : 0.3 * std::sin(t)));
    b.arm_deg.push_back(spike ? -88.5 : 20 * std::sin(0.5 * t));
    b.duty.push_back(spike ? 0.41 : 0.1 * std::cos(3 * t));
  }
  b.cycles = static_cast<std::int64_t>(b.time_s.size());
  b.caught_at_s = 3.0;
  b.balanced_s = seconds - 3.5;
  b.upright_rms_deg = 0.2123;
  b.upright_max_deg = 7.25;
  b.duty_rms = 0.0707;
  b.max_abs_duty = 0.41;
  b.max_abs_arm_deg = 88.5;
  b.end_reason = "duration_reached";
  b.law_time_p50_ns = 2150;
  b.law_time_max_ns = 48000;
  b.controller =
      pipeline::BalanceController{"/lab/C <1>.toml",  std::string(64, 'a'), "output-error",
                                  "ids/results.json", "furuta-lab-1",       ""};
  return b;
}

BalanceLogEntry balance_log(const std::string& name, double seconds) {
  BalanceLogEntry log;
  log.name = name;
  log.session.file = name;
  log.session.profile = "balance";
  log.session.samples = static_cast<std::size_t>(seconds / 0.016);
  log.session.period_s = 0.016;
  log.session.duration_s = seconds;
  log.session.complete = true;
  log.session.end_reason = "duration_reached";
  log.session.balance = summary(seconds);
  return log;
}

BalanceLogEntry bang_bang_log() {
  BalanceLogEntry log;
  log.name = "logs/bang.lcmlog";
  log.session.file = "bang.lcmlog";
  log.session.profile = "bang_bang";
  log.session.samples = 375;
  log.session.complete = true;
  log.session.end_reason = "duration_reached";
  return log;
}

// The polyline of the panel with id `panel` (as the svg itself names it, before a page prefixes
// it), as (x, y) pairs.
std::vector<std::pair<double, double>> trace(const std::string& svg, const std::string& panel) {
  const std::size_t at = svg.find("id=\"" + panel + "\"");
  EXPECT_NE(at, std::string::npos) << panel;
  const std::size_t points = svg.find("points=\"", svg.find("class=\"trace\"", at)) + 8;
  const std::string text = svg.substr(points, svg.find('"', points) - points);
  std::vector<std::pair<double, double>> out;
  const std::regex pair(R"(([-0-9.]+),([-0-9.]+))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), pair); it != std::sregex_iterator();
       ++it) {
    out.emplace_back(std::stod((*it)[1].str()), std::stod((*it)[2].str()));
  }
  return out;
}

TEST(BalanceFigure, FourPanelsOnOneTimeAxisAndTheModeAsBands) {
  const std::string svg = svg_balance(summary(30));
  for (const char* id : {"upright", "arm", "duty", "mode"}) {
    EXPECT_NE(svg.find("<g class=\"panel\" id=\"" + std::string(id) + "\">"), std::string::npos)
        << id;
  }
  EXPECT_EQ(count(svg, "class=\"trace\""), 3u);
  EXPECT_EQ(count(svg, ">t [s]</text>"), 4u);
  EXPECT_NE(svg.find(">angle [deg]</text>"), std::string::npos);
  EXPECT_NE(svg.find(">duty</text>"), std::string::npos);
  // One band per run of a mode, in order, and a legend naming all four.
  const std::size_t swing = svg.find("data-mode=\"swing-up\"");
  const std::size_t caught = svg.find("data-mode=\"catch\"");
  const std::size_t balance = svg.find("data-mode=\"balance\"");
  EXPECT_EQ(count(svg, "class=\"mode-band\""), 3u);
  EXPECT_LT(swing, caught);
  EXPECT_LT(caught, balance);
  for (const char* mode : {">swing-up<", ">catch<", ">balance<", ">fallen<"}) {
    EXPECT_NE(svg.find(mode), std::string::npos) << mode;
  }
}

TEST(BalanceFigure, ALongSessionIsThinnedWithoutLosingAnExcursion) {
  // 600 s of 16 ms cycles: 37,500 per trace, thinned to a few per pixel column.
  const pipeline::BalanceSummary b = summary(600);
  const std::string svg = svg_balance(b);
  for (const char* panel : {"upright", "arm", "duty"}) {
    const auto points = trace(svg, panel);
    EXPECT_LT(points.size(), 4 * 900u) << panel;
    EXPECT_GT(points.size(), 900u) << panel;
  }
  // The excursion at 10 s is the duty's highest point and the arm's lowest: still drawn.
  // SVG's y grows downwards: a value's highest point is its smallest y.
  const auto extreme_y = [](const std::vector<std::pair<double, double>>& p, bool top) {
    double y = top ? 1e9 : -1e9;
    for (const auto& point : p) y = top ? std::min(y, point.second) : std::max(y, point.second);
    return y;
  };
  const std::string full = svg_balance(summary(30));
  EXPECT_LT(std::fabs(extreme_y(trace(svg, "duty"), true) - extreme_y(trace(full, "duty"), true)),
            3.0)
      << "the duty's peak reaches the same height as unthinned";
  EXPECT_LT(std::fabs(extreme_y(trace(svg, "arm"), false) - extreme_y(trace(full, "arm"), false)),
            3.0);
  // Short sessions are drawn whole.
  EXPECT_EQ(trace(full, "duty").size(), summary(30).time_s.size());
}

TEST(BalancePage, EachLogHasItsFiguresItsFigureAndEveryTextEscaped) {
  BalanceReportInput in;
  in.software_version = "furuta 0.1.0-test";
  in.logs = {balance_log("logs/<b>one</b>.lcmlog", 30), bang_bang_log(),
             balance_log("logs/two.lcmlog", 20)};
  in.logs[2].problems = {"cut short: no end record"};
  const std::string html = render_balance_html(in);
  EXPECT_EQ(html.find("<b>"), std::string::npos);
  EXPECT_NE(html.find("logs/&lt;b&gt;one&lt;/b&gt;.lcmlog"), std::string::npos);
  EXPECT_NE(html.find("/lab/C &lt;1&gt;.toml"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  // A section per log, linked from the contents; the figures numbered over the balance logs.
  for (const char* id : {"balance-log-1", "balance-log-2", "balance-log-3"}) {
    EXPECT_NE(html.find("<section class=\"balance-log\" id=\"" + std::string(id) + "\">"),
              std::string::npos)
        << id;
    EXPECT_NE(html.find("href=\"#" + std::string(id) + "\""), std::string::npos) << id;
  }
  for (const char* id : {"fig-balance-1", "fig-balance-2"}) {
    EXPECT_NE(html.find("<figure id=\"" + std::string(id) + "\">"), std::string::npos) << id;
    for (const char* panel : {"upright", "arm", "duty", "mode"}) {
      EXPECT_NE(html.find("id=\"" + std::string(id) + "-" + panel + "\""), std::string::npos)
          << id << " " << panel;
    }
  }
  EXPECT_EQ(html.find("fig-balance-3"), std::string::npos);
  EXPECT_NE(html.find("<table id=\"balance-figures-1\">"), std::string::npos);
  // The figures as the table says them.
  for (const char* cell :
       {"<td>3.00 s</td>", "<td>26.50 s</td>", "<td>0.212 deg</td>", "<td>7.250 deg</td>",
        "<td>0.0707</td>", "<td>0.4100</td>", "<td>88.5 deg</td>", "<td>no</td>",
        "<td>duration reached</td>", "<td>2.15 \u00b5s / 48 \u00b5s</td>",
        "<td>output-error of ids/results.json, for rig furuta-lab-1</td>"}) {
    EXPECT_NE(html.find(cell), std::string::npos) << cell;
  }
  EXPECT_NE(html.find(std::string(64, 'a')), std::string::npos) << "the controller's SHA-256";
  // The other log is said to be what it is.
  EXPECT_NE(html.find("Not a balance session: profile bang_bang, 375 samples, ended: duration "
                      "reached"),
            std::string::npos);
  EXPECT_NE(html.find("Not intact: cut short: no end record."), std::string::npos);
}

TEST(BalancePage, AFallAndANeverCaughtSessionAreSaidSo) {
  BalanceReportInput in;
  in.logs = {balance_log("fell.lcmlog", 20)};
  pipeline::BalanceSummary& b = *in.logs[0].session.balance;
  b.caught_at_s.reset();
  b.balanced_s = 0;
  b.fell = true;
  b.controller.reset();
  in.logs[0].session.end_reason = "pendulum_fell: 36.0 deg from upright, beyond the fall limit";
  const std::string html = render_balance_html(in);
  EXPECT_NE(html.find("<td>never caught</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>yes</td>"), std::string::npos);
  // The reason's kind in words, its detail as written.
  EXPECT_NE(html.find("<td>pendulum fell: 36.0 deg from upright, beyond the fall limit</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>the log has no controller record</td>"), std::string::npos);
  EXPECT_EQ(html.find("0.212 deg"), std::string::npos) << "no balancing: no RMS to show";
}

TEST(BalanceJson, HoldsTheSummarysFiguresAndSaysWhichLogIsNone) {
  BalanceReportInput in;
  in.software_version = "furuta 0.1.0-test";
  in.logs = {balance_log("a.lcmlog", 30), bang_bang_log()};
  const nlohmann::json j = nlohmann::json::parse(json_text(balance_json(in), 4));
  EXPECT_EQ(j["software_version"], "furuta 0.1.0-test");
  ASSERT_EQ(j["logs"].size(), 2u);
  const pipeline::BalanceSummary& b = *in.logs[0].session.balance;
  const nlohmann::json& f = j["logs"][0]["balance"];
  EXPECT_EQ(j["logs"][0]["log"], "a.lcmlog");
  EXPECT_EQ(j["logs"][0]["profile"], "balance");
  EXPECT_TRUE(j["logs"][0]["intact"].get<bool>());
  EXPECT_EQ(f["cycles"].get<std::int64_t>(), b.cycles);
  EXPECT_EQ(f["caught_at_s"].get<double>(), *b.caught_at_s);
  EXPECT_EQ(f["balanced_s"].get<double>(), b.balanced_s);
  EXPECT_EQ(f["upright_rms_deg"].get<double>(), b.upright_rms_deg);
  EXPECT_EQ(f["upright_max_deg"].get<double>(), b.upright_max_deg);
  EXPECT_EQ(f["duty_rms"].get<double>(), b.duty_rms);
  EXPECT_EQ(f["max_abs_duty"].get<double>(), b.max_abs_duty);
  EXPECT_EQ(f["max_abs_arm_deg"].get<double>(), b.max_abs_arm_deg);
  EXPECT_EQ(f["fell"].get<bool>(), b.fell);
  EXPECT_EQ(f["law_time_p50_ns"].get<std::int64_t>(), b.law_time_p50_ns);
  EXPECT_EQ(f["law_time_max_ns"].get<std::int64_t>(), b.law_time_max_ns);
  EXPECT_EQ(f["controller"]["sha256"], b.controller->sha256);
  EXPECT_EQ(f["controller"]["parameters_source"], "output-error");
  EXPECT_FALSE(f["controller"].contains("unreadable"));
  EXPECT_TRUE(j["logs"][1]["balance"].is_null());
  EXPECT_EQ(j["logs"][1]["profile"], "bang_bang");
  EXPECT_EQ(j["logs"][1]["samples"], 375);
  // Never caught: null, not 0.
  in.logs[0].session.balance->caught_at_s.reset();
  EXPECT_TRUE(balance_json(in)["logs"][0]["balance"]["caught_at_s"].is_null());
}

TEST(BalanceInTheIdentificationReport, ASectionPerBalanceSessionOnlyWhenThereIsOne) {
  ReportInput in;
  in.software_version = "0.1.0-test";
  in.experiment_names = {"run1"};
  in.per_experiment.resize(1);
  in.combined = in.per_experiment[0];
  SessionSummary excitation = bang_bang_log().session;
  in.sessions = {excitation};
  const std::string without = render_html(in);
  EXPECT_EQ(without.find("id=\"balance\""), std::string::npos);
  EXPECT_EQ(without.find("Balance sessions"), std::string::npos);

  in.sessions = {balance_log("b1.lcmlog", 30).session, excitation,
                 balance_log("b2.lcmlog", 30).session};
  const std::string html = render_html(in);
  const std::size_t section = html.find("<section id=\"balance\">");
  ASSERT_NE(section, std::string::npos);
  EXPECT_NE(html.find("href=\"#balance\""), std::string::npos) << "in the contents";
  EXPECT_LT(html.find("<section id=\"summary\">"), section);
  EXPECT_LT(section, html.find("<section id=\"warnings\">"));
  EXPECT_NE(html.find("<h3>b1.lcmlog</h3>"), std::string::npos);
  EXPECT_NE(html.find("<h3>b2.lcmlog</h3>"), std::string::npos);
  EXPECT_EQ(html.find("<h3>bang.lcmlog</h3>"), std::string::npos) << "only balance sessions";
  EXPECT_NE(html.find("<figure id=\"fig-balance-2\">"), std::string::npos);
  EXPECT_NE(html.find("id=\"fig-balance-2-mode\""), std::string::npos);
}

}  // namespace
}  // namespace furuta::report::balance_page_test
