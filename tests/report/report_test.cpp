// The HTML report: its text is escaped, absent parts are said to be absent, the warnings are
// found; and a real identification's report, opened in headless Chromium, renders every figure
// and table (the screenshot is kept in report_test_output/ of the test's working directory).
#include "furuta/report/report.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/report/tables.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::report::report_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

// Nothing the page shows may reach the network, and reading it needs no script.
void expect_self_contained(const std::string& html) {
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex(R"re(url\(\s*['"]?[^#'"\s])re")))
      << "url() to anything but an element of the page";
  EXPECT_FALSE(std::regex_search(
      html, std::regex(R"((src|href)\s*=\s*["']?\s*(https?:)?//)", std::regex::icase)));
  const std::regex href(R"re(href\s*=\s*"([^"]*)")re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), href); it != std::sregex_iterator();
       ++it) {
    EXPECT_EQ((*it)[1].str().rfind('#', 0), 0u) << "a link out of the page: " << (*it)[1].str();
  }
}

ReportInput minimal_input() {
  ReportInput in;
  in.software_version = "0.1.0-test";
  in.experiment_names = {"run1"};
  in.per_experiment.resize(1);
  in.per_experiment[0].estimate = {1e-3, 2e-3, 8e-4, 1.2e-3, 7e-2, 8e-2, 6e-4};
  in.combined = in.per_experiment[0];
  return in;
}

TEST(ReportHtml, EscapesEveryText) {
  ReportInput in = minimal_input();
  in.title = "run <b>1</b> & \"2\"";
  in.experiment_names = {"<script>alert(1)</script>"};
  in.rig = {{"configuration", "lab's <rig>"}};
  in.warnings = {{Warning::Stage::data, Warning::Kind::data, "seed1: lost <reports> & more"}};
  SessionSummary s;
  s.file = "a<b>.lcmlog";
  s.fatal_faults = {"usb <gone>"};
  in.sessions = {s};
  const std::string html = render_html(in);
  EXPECT_EQ(html.find("<b>"), std::string::npos);
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_EQ(html.find("<rig>"), std::string::npos);
  EXPECT_NE(html.find("run &lt;b&gt;1&lt;/b&gt; &amp; &quot;2&quot;"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("lost &lt;reports&gt; &amp; more"), std::string::npos);
  EXPECT_NE(html.find("fatal fault usb &lt;gone&gt;"), std::string::npos);
  EXPECT_EQ(escape_html("<a href='x'>&</a>"), "&lt;a href=&#39;x&#39;&gt;&amp;&lt;/a&gt;");
  expect_self_contained(html);
}

TEST(ReportHtml, AWarningThatAResultCannotBeUsedIsMarkedApartFromANote) {
  ReportInput in = minimal_input();
  in.warnings = {{Warning::Stage::output_error, Warning::Kind::failed, "did not converge: x"},
                 {Warning::Stage::output_error, Warning::Kind::note, "started from CAD"}};
  const std::string html = render_html(in);
  const std::size_t failed = html.find("<li class=\"failed\">");
  const std::size_t note = html.find("<li class=\"note\">");
  ASSERT_NE(failed, std::string::npos);
  ASSERT_NE(note, std::string::npos);
  EXPECT_NE(html.find("did not converge: x", failed), std::string::npos);
  EXPECT_LT(html.find("did not converge: x", failed), note);
  EXPECT_NE(html.find(".warnings li.failed"), std::string::npos) << "styled apart";
}

TEST(ReportHtml, SaysWhatWasNotRun) {
  const std::string html = render_html(minimal_input());
  EXPECT_NE(html.find("SIVIA was not run"), std::string::npos);
  EXPECT_NE(html.find("validated simulation was not run"), std::string::npos);
  EXPECT_NE(html.find("No held-out session"), std::string::npos);
  EXPECT_NE(html.find("class=\"none\""), std::string::npos) << "no warnings, and says so";
  // Table I always has its seven parameters.
  const std::size_t table = html.find("<table id=\"table-1\">");
  ASSERT_NE(table, std::string::npos);
  EXPECT_EQ(count(html.substr(table, html.find("</table>", table) - table), "<tr>"), 8u)
      << "a header row and 7 parameters";
  expect_self_contained(html);
}

TEST(ReportHtml, InlineSvgKeepsItsIdsToItself) {
  ReportInput in = minimal_input();
  const std::string svg =
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" height=\"10\"><clipPath "
      "id=\"plot\"><rect width=\"5\" height=\"5\"/></clipPath><g clip-path=\"url(#plot)\"/></svg>";
  in.signals_svg = {svg, svg};
  const std::string html = render_html(in);
  EXPECT_EQ(html.find("id=\"plot\""), std::string::npos);
  EXPECT_NE(html.find("<clipPath id=\"fig-signals-1-plot\">"), std::string::npos);
  EXPECT_NE(html.find("clip-path=\"url(#fig-signals-1-plot)\""), std::string::npos);
  EXPECT_NE(html.find("clip-path=\"url(#fig-signals-2-plot)\""), std::string::npos);
}

TEST(ReportHtml, InlineSvgLosesItsXmlDeclaration) {
  ReportInput in = minimal_input();
  in.signals_svg = {
      "<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
      "width=\"10\" height=\"10\"><rect width=\"5\" height=\"5\"/></svg>"};
  const std::string html = render_html(in);
  EXPECT_EQ(html.find("<?xml"), std::string::npos);
  EXPECT_NE(html.find("<figure id=\"fig-signals-1\">\n<svg xmlns"), std::string::npos);
}

TEST(ReportWarnings, EmptySetTruncationToleratedSamplesLogDamageAndShortTubes) {
  ReportInput in = minimal_input();
  SessionSummary s;
  s.file = "s.lcmlog";
  s.damaged_regions = 2;
  s.truncated_tail = true;
  s.fatal_faults = {"encoder_timeout"};
  in.sessions = {s};
  SiviaSummary sivia;
  sivia.empty = true;
  sivia.finding = "no parameter is consistent with the data";
  sivia.truncated = true;
  sivia.inconsistent_samples = 3;
  sivia.q = 3;
  in.sivia = sivia;
  validated::ScenarioResult tube;
  tube.scenario = validated::paper_scenario(1);
  tube.parameters.name = "LSMI";
  tube.t_reached_s = 1.5;
  tube.status = validated::IntegrationResult::Status::width_exceeded;
  tube.reason = "q2 wider than 2 pi";
  validated::ScenarioResult whole = tube;
  whole.scenario = validated::paper_scenario(2);
  whole.t_reached_s = whole.scenario.duration_s;
  whole.status = validated::IntegrationResult::Status::ok;
  whole.reason.clear();
  in.simulation = SimulationSummary{"the truth", {tube, whole}};

  const std::vector<Warning> w = derived_warnings(in);
  std::string all;
  for (const Warning& x : w) all += topic(x.stage) + ": " + x.text + "\n";
  EXPECT_NE(all.find("session: s.lcmlog: 2 damaged regions"), std::string::npos) << all;
  EXPECT_NE(all.find("session: s.lcmlog: the log's tail is truncated"), std::string::npos);
  EXPECT_NE(all.find("session: s.lcmlog: fatal fault encoder_timeout"), std::string::npos);
  // An empty or truncated paving is the run's warning (pipeline::run), not derived again here.
  EXPECT_EQ(all.find("empty"), std::string::npos) << all;
  EXPECT_EQ(all.find("truncated:"), std::string::npos) << all;
  EXPECT_NE(all.find("SIVIA: 3 samples inconsistent"), std::string::npos);
  EXPECT_NE(all.find("simulation: scenario (a), LSMI: the tube ended early, at 1.500 s of 4.0 s"),
            std::string::npos)
      << all;
  EXPECT_EQ(all.find("scenario (b)"), std::string::npos) << "a tube that reached the end";
  EXPECT_EQ(w.size(), 5u) << all;
  const std::string html = render_html(in);
  EXPECT_NE(html.find("The feasible set is empty."), std::string::npos);
  EXPECT_EQ(count(html, "<figure id=\"fig-6-"), 2u);
}

TEST(ReportWarnings, LsmiWarningsAreExcitationTheDatasAreSession) {
  identification::Identification id;
  id.processed.resize(1);
  id.processed[0].name = "run1";
  id.per_experiment.resize(1);
  id.per_experiment[0].warnings = {"poorly excited (relative standard deviation above 10 %): fv2"};
  id.combined.warnings = {"W is ill-conditioned (condition number 2e+05)"};
  id.warnings = {"run1: 4 samples missing from the log",
                 "run1: poorly excited (relative standard deviation above 10 %): fv2",
                 "all experiments: W is ill-conditioned (condition number 2e+05)"};
  const ReportInput in = report_input(id);
  ASSERT_EQ(in.warnings.size(), 3u);
  EXPECT_EQ(topic(in.warnings[0].stage), "session");
  EXPECT_EQ(in.warnings[0].kind, Warning::Kind::data);
  EXPECT_EQ(topic(in.warnings[1].stage), "LSMI");
  EXPECT_EQ(in.warnings[1].kind, Warning::Kind::suspect);
  EXPECT_EQ(topic(in.warnings[2].stage), "LSMI");
  EXPECT_EQ(in.warnings[2].kind, Warning::Kind::suspect);
  EXPECT_FALSE(in.validation);
}

TEST(ReportTableTwo, WithoutSiviaTheIntervalsItWouldStartFrom) {
  const model::Parameters<double> lsmi = {1e-3, 2e-3, 8e-4, 1.2e-3, 7e-2, 8e-2, 6e-4};
  config::SiviaConfig cfg;
  cfg.fv1_prior = {-1.5, 1.5};
  cfg.fv2_prior = {-0.5, 0.5};
  const std::vector<IntervalRow> rows = table_two(lsmi, cfg, nullptr);
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_NEAR(rows[0].lo, 1e-3 * 0.88, 1e-12);
  EXPECT_NEAR(rows[0].hi, 1e-3 * 1.12, 1e-12);
  EXPECT_NEAR(rows[4].hi, 7e-2 * 1.15, 1e-12);
  EXPECT_EQ(rows[6].lo, -0.5);
  EXPECT_EQ(rows[6].hi, 0.5);
  EXPECT_EQ(rows[5].origin, "prior (unknown, bisected)");
  EXPECT_NE(rows[2].origin.find("10 %"), std::string::npos);
  EXPECT_FALSE(rows[5].outer_hull);
}

// --- what a person reads in the tables: names whole, numbers short ---

identification::Identification two_sessions(const std::string& a, const std::string& b) {
  identification::Identification id;
  id.processed.resize(2);
  id.processed[0].name = a;
  id.processed[1].name = b;
  id.per_experiment.resize(2);
  for (auto& r : id.per_experiment) r.estimate = {1e-3, 2e-3, 8e-4, 1.2e-3, 7e-2, 8e-2, 6e-4};
  id.combined = id.per_experiment[0];
  return id;
}

TEST(ReportTables, TableOneKeysLongSessionNamesInsteadOfCuttingThem) {
  const std::string a = "2026-11-25T08-02-00Z_bang-bang", b = "2026-11-25T08-02-00Z_bang-bang-2";
  const std::string table = format_table_one(two_sessions(a, b));
  // Before: the heads were the names' last 24 characters, "1-25T08-02-00Z_bang-bang".
  EXPECT_EQ(table.find("1-25T08-02-00Z_bang-bang "), std::string::npos) << table;
  EXPECT_EQ(table.rfind("E1: " + a + "\nE2: " + b + "\n", 0), 0u) << table;
  const std::string header = table.substr(table.find("p     unit"));
  EXPECT_EQ(header.substr(0, header.find('\n')).find("E1"), 19u) << header;
  EXPECT_NE(header.substr(0, header.find('\n')).find("E2"), std::string::npos) << header;
  // Names that fit head their columns themselves.
  const std::string short_names = format_table_one(two_sessions("run1", "run2"));
  EXPECT_EQ(short_names.rfind("p     unit         run1", 0), 0u) << short_names;
  EXPECT_EQ(short_names.find("E1"), std::string::npos);
  // The page keys them alike and lists the names under the table.
  ReportInput in = report_input(two_sessions(a, b));
  const std::string html = render_html(in);
  EXPECT_NE(html.find("<th scope=\"col\">E1</th><th scope=\"col\">E2</th>"), std::string::npos);
  EXPECT_NE(html.find("<li><strong>E2</strong>: " + b + "</li>"), std::string::npos);
}

TEST(ReportTables, TableThreeStatusAndSiviaBoundsHaveAFewDigits) {
  validated::ScenarioResult r;
  r.scenario = validated::paper_scenario(1);
  r.parameters.name = "SIVIA";
  r.status = validated::IntegrationResult::Status::width_exceeded;
  r.reason =
      "enclosure width 6.7367745165386133 > max_width 6.2831853071795862 at t = "
      "0.058721594480886791";
  r.t_reached_s = 0.058721594480886791;
  const std::string short_reason = "enclosure width 6.737 > max_width 6.283 at t = 0.05872";
  const std::string table = format_table_three({r});
  EXPECT_NE(table.find("ended (width_exceeded): " + short_reason), std::string::npos) << table;
  EXPECT_EQ(table.find("6.7367745"), std::string::npos) << table;
  ReportInput in = minimal_input();
  in.simulation = SimulationSummary{"the truth", {r}};
  const std::string html = render_html(in);
  EXPECT_NE(html.find("<td>ended (width_exceeded): enclosure width 6.737 &gt; max_width 6.283 "
                      "at t = 0.05872</td>"),
            std::string::npos);
  EXPECT_EQ(html.find("6.7367745"), std::string::npos) << "nor in the warnings";

  // SIVIA's hull: 6 digits, rounded outward (it still holds what the interval holds).
  identification::GuaranteedResult g;
  g.unknown.fill(false);
  g.unknown[5] = g.unknown[6] = true;
  interval::Box box(model::kParameterCount, interval::Interval(1.0, 2.0));
  box[5] = interval::Interval(0.079512345678901234, 0.080545678901234567);
  box[6] = interval::Interval(-1.0000000000000002e-05, 6.4200000000000004e-04);
  g.paving.prior = box;
  g.paving.inner = {box};
  const std::string sivia = sivia_summary_text(g, std::nullopt);
  // (0.000642 reads back as the very double of the bound, so it is not widened.)
  EXPECT_NE(sivia.find("fv1 in [0.0795123, 0.0805457] N m s"), std::string::npos) << sivia;
  EXPECT_NE(sivia.find("fv2 in [-1.00001e-05, 0.000642] N m s"), std::string::npos) << sivia;
}

TEST(ReportTorque, TheCaptionsSayHowTheTorqueWasHad) {
  for (const auto& [kind, csv, says] :
       {std::tuple{identification::InputKind::duty, false, "by eq. 4 from the logged duty cycle"},
        std::tuple{identification::InputKind::duty, true, "by eq. 4 from the recorded duty"},
        std::tuple{identification::InputKind::voltage, true,
                   "from the recorded voltage via the import spec's [motor]"},
        std::tuple{identification::InputKind::torque, true, "as recorded"}}) {
    EXPECT_NE(torque_source(kind, csv).find(says), std::string::npos) << says;
  }
  identification::Identification id = two_sessions("a.csv", "b.csv");
  id.raw.resize(2);
  id.raw[0].input_kind = identification::InputKind::voltage;
  ReportInput in = report_input(id);
  in.signals_svg = {"<svg xmlns=\"http://www.w3.org/2000/svg\"></svg>"};
  const std::string html = render_html(in);
  EXPECT_NE(html.find("motor torque (from the recorded voltage via the import spec&#39;s [motor]"),
            std::string::npos);
  EXPECT_EQ(html.find("eq. 4"), std::string::npos) << "a voltage rig has no eq. 4";
}

// --- the report of a real identification, in a real browser ---

// A session of the simulated rig (the configuration's bang-bang), in virtual time.
fs::path simulated_session(const fs::path& logs, std::int64_t seed) {
  return furuta::testing::simulated_session_log(logs, "seed" + std::to_string(seed), seed, 6.0);
}

// Measures what the browser laid out, into an element --dump-dom serialises.
constexpr const char* kCheckScript = R"(<script>
(function () {
  const figures = Array.from(document.querySelectorAll('figure')).map(function (f) {
    const svg = f.querySelector('svg');
    const box = svg ? svg.getBBox() : null;
    const shown = svg ? svg.getBoundingClientRect() : null;
    return {id: f.id, svg: !!svg, width: box ? box.width : 0, height: box ? box.height : 0,
            shown_width: shown ? shown.width : 0, shown_height: shown ? shown.height : 0,
            elements: svg ? svg.querySelectorAll('*').length : 0,
            caption: f.querySelector('figcaption') ? f.querySelector('figcaption').textContent : '',
            axes: svg ? Array.from(svg.querySelectorAll('g.axis')).map(function (a) {
              const label = a.querySelector('.axis-label');
              return {kind: a.classList.contains('x') ? 'x' : 'y',
                      ticks: a.querySelectorAll('text.tick').length,
                      label: label ? label.textContent : ''};
            }) : []};
  });
  const tables = Array.from(document.querySelectorAll('table')).map(function (t) {
    return {id: t.id, rows: t.tBodies.length ? t.tBodies[0].rows.length : 0,
            columns: t.tHead ? t.tHead.rows[0].cells.length : 0,
            width: t.scrollWidth, room: t.parentElement.clientWidth,
            scrolls: t.parentElement.scrollWidth > t.parentElement.clientWidth};
  });
  const out = document.createElement('pre');
  out.id = 'report-check';
  out.textContent = JSON.stringify({figures: figures, tables: tables,
                                    sections: document.querySelectorAll('section').length,
                                    viewport: window.innerWidth,
                                    page_width: document.documentElement.scrollWidth});
  document.body.appendChild(out);
})();
</script>
)";

std::string unescape_text(std::string s) {
  const std::pair<const char*, const char*> entities[] = {
      {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&#39;", "'"}, {"&amp;", "&"}};
  for (const auto& [from, to] : entities) {
    const std::string f = from;
    for (std::size_t at = s.find(f); at != std::string::npos; at = s.find(f, at + 1)) {
      s.replace(at, f.size(), to);
    }
  }
  return s;
}

std::string chromium_command() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const std::string probe = std::string("command -v ") + name + " >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return name;
  }
  return {};
}

int run_chromium(const std::string& chromium, const fs::path& profile, const std::string& args,
                 const fs::path& stdout_file, const fs::path& log_file) {
  const std::string command = "timeout 60 " + chromium +
                              " --headless --no-sandbox --disable-gpu --no-first-run "
                              "--disable-extensions --user-data-dir='" +
                              profile.string() + "' " + args + " >'" + stdout_file.string() +
                              "' 2>'" + log_file.string() + "'";
  return std::system(command.c_str());
}

// The page `html` measured in headless Chromium at 1280 x `height`: a copy with kCheckScript
// (the report itself carries no script), its DOM dumped, the script's JSON read back. Nothing, and
// `why`, when Chromium fails or the script did not run.
std::optional<nlohmann::json> measured_in_browser(const std::string& chromium,
                                                  const std::string& html, const fs::path& dir,
                                                  int height, std::string& why) {
  const fs::path checked = dir / "checked.html";
  std::string with_script = html;
  with_script.insert(with_script.rfind("</body>"), kCheckScript);
  write_text(checked, with_script);
  const fs::path dom = dir / "dom.html";
  const int rc = run_chromium(chromium, dir / "profile",
                              "--window-size=1280," + std::to_string(height) +
                                  " --dump-dom 'file://" + checked.string() + "'",
                              dom, dir / "chromium.log");
  if (rc != 0) {
    why = "chromium --dump-dom failed: " + read_text(dir / "chromium.log");
    return std::nullopt;
  }
  const std::string dumped = read_text(dom);
  const std::string open = "<pre id=\"report-check\">";
  const std::size_t at = dumped.find(open);
  if (at == std::string::npos) {
    why = "the check script did not run: " + dumped.substr(0, 500);
    return std::nullopt;
  }
  const std::size_t end = dumped.find("</pre>", at);
  return nlohmann::json::parse(
      unescape_text(dumped.substr(at + open.size(), end - at - open.size())));
}

TEST(ReportInBrowser, ARealIdentificationRendersEveryFigureAndTable) {
  const std::string chromium = chromium_command();
  ASSERT_FALSE(chromium.empty())
      << "headless Chromium is needed to check the report renders: install Debian's chromium "
         "(scripts/setup.sh does)";

  TempDir dir;
  const fs::path fit1 = simulated_session(dir.path() / "logs", 1);
  const fs::path fit2 = simulated_session(dir.path() / "logs", 2);
  const fs::path held_out = simulated_session(dir.path() / "logs", 3);
  ASSERT_FALSE(fit1.empty() || fit2.empty() || held_out.empty());
  app::IdentifyCommandOptions options;
  options.logs = {fit1, fit2};
  options.validate = held_out;
  options.output_dir = dir.path() / "identification";
  options.sivia = true;
  options.threads = 2;
  options.simulate = true;
  options.simulate_seconds = 0.3;  // the tubes' length does not change what the page must show
  std::ostringstream out, err;
  ASSERT_EQ(app::run_identify_command(options, out, err), 0) << err.str();
  const fs::path report = options.output_dir / "report.html";
  EXPECT_NE(out.str().find("report: " + report.string()), std::string::npos) << out.str();
  ASSERT_TRUE(fs::exists(report));
  const std::string html = read_text(report);
  expect_self_contained(html);
  // The terminal: Table I once, before SIVIA's summary; no "10.000000 %", no 17-digit bounds.
  const std::string printed = out.str();
  EXPECT_EQ(count(printed, "p     unit"), 1u) << printed;
  EXPECT_LT(printed.find("p     unit"), printed.find("\nSIVIA (")) << printed;
  EXPECT_EQ(printed.find("10.000000"), std::string::npos) << printed;
  EXPECT_FALSE(std::regex_search(printed, std::regex(R"([0-9]\.[0-9]{9,})"))) << printed;
  // The configuration came from the first log; its name alone ("furuta") would not say so.
  EXPECT_NE(html.find("<td>carried by " + fit1.filename().string()), std::string::npos);

  const nlohmann::json results =
      nlohmann::json::parse(read_text(options.output_dir / "results.json"));
  const bool sivia_found_a_set = !results["sivia"].value("empty", false);
  const std::size_t scenario_rows = results["simulation"]["results"].size();
  EXPECT_EQ(scenario_rows, sivia_found_a_set ? 12u : 8u) << "SIVIA, LSMI, output error";
  ASSERT_TRUE(results.contains("output_error"));
  for (const char* key : {"estimate", "std_dev", "input_lag_s", "angle_rms_rad", "segments",
                          "iterations", "converged", "message", "held_out_free_run"}) {
    EXPECT_TRUE(results["output_error"].contains(key)) << key;
  }
  EXPECT_EQ(results["output_error"]["estimate"].size(), 7u);
  EXPECT_NE(printed.find("output error"), std::string::npos) << printed;
  EXPECT_NE(printed.find("held-out free run on"), std::string::npos) << printed;

  // Measured at the width of a common laptop screen.
  std::string why;
  const std::optional<nlohmann::json> measured =
      measured_in_browser(chromium, html, dir.path(), 4000, why);
  ASSERT_TRUE(measured.has_value()) << why;
  const nlohmann::json& check = *measured;

  // Every figure drawn, with geometry.
  std::size_t signals = 0, fig6 = 0;
  bool fig4 = false, fig5 = false, free_run = false;
  for (const auto& f : check["figures"]) {
    const std::string id = f["id"];
    EXPECT_TRUE(f["svg"].get<bool>()) << id;
    EXPECT_GT(f["width"].get<double>(), 100) << id;
    EXPECT_GT(f["height"].get<double>(), 50) << id;
    EXPECT_GT(f["shown_width"].get<double>(), 100) << id << ": laid out on the page";
    EXPECT_GT(f["elements"].get<int>(), 5) << id;
    EXPECT_FALSE(f["caption"].get<std::string>().empty()) << id;
    if (id.rfind("fig-signals-", 0) == 0) ++signals;
    if (id.rfind("fig-6-", 0) == 0) ++fig6;
    fig4 = fig4 || id == "fig-4";
    fig5 = fig5 || id == "fig-5";
    free_run = free_run || id == "fig-free-run";
  }
  EXPECT_EQ(signals, 2u);
  // Every time series has a labelled time axis and value axes with ticks beyond min and max; the
  // paving's axes have ticks too.
  for (const auto& f : check["figures"]) {
    const std::string id = f["id"];
    const bool time_series = id.rfind("fig-signals-", 0) == 0 || id == "fig-5" ||
                             id == "fig-free-run" || id.rfind("fig-6-", 0) == 0;
    std::size_t time_axes = 0, value_axes = 0;
    for (const auto& a : f["axes"]) {
      EXPECT_GE(a["ticks"].get<int>(), 3) << id << ": " << a.dump();
      EXPECT_FALSE(a["label"].get<std::string>().empty()) << id << ": " << a.dump();
      if (a["kind"] == "x" && a["label"] == "t [s]") ++time_axes;
      if (a["kind"] == "y") ++value_axes;
    }
    if (time_series) {
      EXPECT_GE(time_axes, 1u) << id << ": no time axis labelled t [s]";
      EXPECT_GE(value_axes, 1u) << id;
    }
    if (id.rfind("fig-signals-", 0) == 0) {
      EXPECT_EQ(value_axes, 7u) << id << ": q1, q2, dq1, dq2, ddq1, ddq2, tau on their own axes";
    }
    if (id == "fig-free-run") {
      EXPECT_EQ(value_axes, 2u) << id << ": q1 and q2 on their own axes";
    }
    if (id == "fig-4") {
      EXPECT_EQ(f["axes"].size(), 2u);
    }
  }
  // No table wider than a 1280 px window, nor wider than the room the page gives it.
  EXPECT_EQ(check["viewport"].get<int>(), 1280);
  EXPECT_LE(check["page_width"].get<int>(), 1280);
  for (const auto& t : check["tables"]) {
    EXPECT_LE(t["width"].get<int>(), 1280) << t.dump();
    EXPECT_LE(t["width"].get<int>(), t["room"].get<int>()) << t.dump();
    EXPECT_FALSE(t["scrolls"].get<bool>()) << t.dump();
  }
  EXPECT_TRUE(fig4);
  EXPECT_TRUE(fig5);
  EXPECT_TRUE(free_run);
  EXPECT_EQ(fig6, scenario_rows);

  // Tables with the right rows.
  std::map<std::string, std::pair<int, int>> tables;
  for (const auto& t : check["tables"]) {
    tables[t["id"].get<std::string>()] = {t["rows"].get<int>(), t["columns"].get<int>()};
  }
  EXPECT_EQ(tables["table-1"].first, 7) << "one row per parameter";
  // parameter, unit, 2 experiments, all, output error, CAD, truth
  EXPECT_EQ(tables["table-1"].second, 8);
  EXPECT_EQ(tables["table-2"].first, 7);
  EXPECT_EQ(tables["table-3"].first, static_cast<int>(scenario_rows));
  EXPECT_EQ(tables["sessions"].first, 3) << "two fitted, one held out";
  EXPECT_EQ(tables["lsmi-diagnostics"].first, 3);
  EXPECT_EQ(check["sections"].get<int>(), 8);
  // Every tube that stopped short of its 0.3 s is a warning, and no other.
  std::size_t short_tubes = 0;
  for (const auto& r : results["simulation"]["results"]) {
    if (r["t_reached_s"].get<double>() + 1e-9 < r["duration_s"].get<double>()) ++short_tubes;
  }
  EXPECT_EQ(count(html, "the tube ended early"), short_tubes);

  // A screenshot a person can look at, kept beside the test's working directory.
  const fs::path keep = fs::current_path() / "report_test_output";
  fs::create_directories(keep);
  fs::copy_file(report, keep / "report.html", fs::copy_options::overwrite_existing);
  const fs::path png = keep / "report.png";
  fs::remove(png);
  const int shot = run_chromium(chromium, dir.path() / "profile",
                                "--hide-scrollbars --window-size=1280,4000 --screenshot='" +
                                    png.string() + "' 'file://" + report.string() + "'",
                                dir.path() / "shot.out", dir.path() / "shot.log");
  ASSERT_EQ(shot, 0) << read_text(dir.path() / "shot.log");
  ASSERT_TRUE(fs::exists(png)) << read_text(dir.path() / "shot.log");
  const std::string image = read_text(png);
  EXPECT_EQ(image.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_GT(image.size(), 50'000u) << "a page of figures compresses to more than a blank page";
  std::printf("[ measured ] report %zu bytes, screenshot %s (%zu bytes)\n", html.size(),
              png.c_str(), image.size());
}

// `furuta report` on a balance session of the simulated rig, opened in the browser: its figure of
// four panels laid out with labelled time and value axes, its figures table within the page.
TEST(ReportInBrowser, ABalanceReportRendersItsFigureAndTable) {
  const std::string chromium = chromium_command();
  ASSERT_FALSE(chromium.empty()) << "headless Chromium is needed: install Debian's chromium";
  TempDir dir;
  app::ControllerDesignOptions design;
  design.results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
  design.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  design.output = dir.path() / "controller.toml";
  std::ostringstream design_out, design_err;
  ASSERT_EQ(app::run_controller_design_command(design, design_out, design_err), 0)
      << design_err.str();
  app::RunOptions session;
  session.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  session.simulated = true;
  session.virtual_time = true;
  session.logs_dir = dir.path() / "logs";
  session.lcm_url = "memq://";
  session.session.balance = design.output;
  session.session.duration_s = 20.0;
  std::ostringstream run_out, run_err;
  ASSERT_EQ(app::run_session_command(session, run_out, run_err), 0) << run_err.str();
  app::ReportCommandOptions options;
  for (const auto& entry : fs::directory_iterator(session.logs_dir)) {
    if (entry.path().extension() == ".lcmlog") options.logs.push_back(entry.path());
  }
  ASSERT_EQ(options.logs.size(), 1u);
  options.output_dir = dir.path() / "balance";
  std::ostringstream out, err;
  ASSERT_EQ(app::run_report_command(options, out, err), 0) << err.str();
  const fs::path report = options.output_dir / "report.html";
  const std::string html = read_text(report);
  expect_self_contained(html);

  std::string why;
  const std::optional<nlohmann::json> measured =
      measured_in_browser(chromium, html, dir.path(), 2000, why);
  ASSERT_TRUE(measured.has_value()) << why;
  const nlohmann::json& check = *measured;
  ASSERT_EQ(check["figures"].size(), 1u);
  const auto& f = check["figures"][0];
  EXPECT_EQ(f["id"], "fig-balance-1");
  EXPECT_TRUE(f["svg"].get<bool>());
  EXPECT_GT(f["height"].get<double>(), 400) << "four panels stacked";
  EXPECT_GT(f["shown_width"].get<double>(), 600) << "laid out on the page";
  EXPECT_FALSE(f["caption"].get<std::string>().empty());
  std::size_t time_axes = 0, value_axes = 0;
  for (const auto& a : f["axes"]) {
    EXPECT_GE(a["ticks"].get<int>(), 3) << a.dump();
    EXPECT_FALSE(a["label"].get<std::string>().empty()) << a.dump();
    if (a["kind"] == "x" && a["label"] == "t [s]") ++time_axes;
    if (a["kind"] == "y") ++value_axes;
  }
  EXPECT_EQ(time_axes, 4u) << "each panel on the time axis";
  EXPECT_EQ(value_axes, 3u) << "the angle from upright, the arm angle, the duty; the mode is bands";
  ASSERT_EQ(check["tables"].size(), 1u);
  const auto& t = check["tables"][0];
  EXPECT_EQ(t["id"], "balance-figures-1");
  EXPECT_GE(t["rows"].get<int>(), 12);
  EXPECT_LE(t["width"].get<int>(), t["room"].get<int>()) << t.dump();
  EXPECT_FALSE(t["scrolls"].get<bool>()) << t.dump();
  EXPECT_LE(check["page_width"].get<int>(), 1280);

  const fs::path keep = fs::current_path() / "report_test_output";
  fs::create_directories(keep);
  const fs::path png = keep / "balance.png";
  fs::remove(png);
  const int shot = run_chromium(chromium, dir.path() / "profile",
                                "--hide-scrollbars --window-size=1280,1400 --screenshot='" +
                                    png.string() + "' 'file://" + report.string() + "'",
                                dir.path() / "shot.out", dir.path() / "shot.log");
  ASSERT_EQ(shot, 0) << read_text(dir.path() / "shot.log");
  EXPECT_TRUE(fs::exists(png));
  fs::copy_file(report, keep / "balance.html", fs::copy_options::overwrite_existing);
}

}  // namespace
}  // namespace furuta::report::report_test
