// The verification page from a certificate made by hand: verification.json read back holds every
// given number (a step a line, unbounded and empty intervals as null), the figure has its three
// panels with the tube as one band each, the trajectories, the bound and the failure's time only
// when the proof failed, long runs stay small without losing an excursion, and the page says what
// was proven or which bound failed and when, with the assumptions' units and the sampled counts.
#include "furuta/report/verification_page.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "furuta/report/json.hpp"
#include "temp_dir.hpp"

namespace furuta::report::verification_page_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;
using interval::Interval;
using nlohmann::json;

constexpr double kPeriodS = 0.016;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kUprightRad = 5.0 / kDegPerRad;

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Boxes narrowing about upright: the state's half-widths shrink as e^(-t), the duty's too.
verification::LoopStepBox step_box(std::size_t k) {
  verification::LoopStepBox b;
  b.t0_s = static_cast<double>(k) * kPeriodS;
  b.t1_s = static_cast<double>(k + 1) * kPeriodS;
  const double shrink = std::exp(-b.t0_s);
  const double end = std::exp(-b.t1_s);
  const std::array<double, 4> half = {0.03, 0.05, 0.2, 0.4};
  for (std::size_t i = 0; i < 4; ++i) {
    b.over[i] = Interval(-half[i] * shrink, half[i] * shrink);
    b.at_end[i] = Interval(-half[i] * end, half[i] * end);
    b.estimate[i] = Interval(-1.5 * half[i] * end, 1.5 * half[i] * end);
  }
  b.duty = Interval(-0.2 * end, 0.1 * end);
  return b;
}

// A trajectory inside those boxes: every sample and four inner steps per period, the angles a
// decaying wobble at `fraction` of the box, the duty within its box.
verification::LoopTrajectory trajectory(double fraction, std::size_t periods) {
  verification::LoopTrajectory t;
  const auto state = [&](double time) {
    const double envelope = fraction * std::exp(-time) * std::cos(9 * time);
    return std::array<double, 4>{0.03 * envelope, 0.05 * envelope, 0.2 * envelope, 0.4 * envelope};
  };
  for (std::size_t k = 0; k <= periods; ++k) {
    verification::LoopSample s;
    s.t_s = static_cast<double>(k) * kPeriodS;
    s.state = state(s.t_s);
    s.duty = -0.05 * fraction * std::exp(-s.t_s);
    t.samples.push_back(s);
    if (k == periods) break;
    for (int j = 1; j <= 4; ++j) {
      const double inner = s.t_s + j * kPeriodS / 4;
      t.inner_t_s.push_back(inner);
      t.inner_state.push_back(state(inner));
    }
  }
  return t;
}

// 50 periods certified to 0.8 s, or (failed) 31 proven and the pendulum's bound reached at the
// 32nd; two trajectories drawn.
VerificationReportInput report_input(bool certified) {
  VerificationReportInput in;
  in.software_version = "furuta 0.9.0";
  in.controller = "controllers/<lab> balance.toml";
  in.parameters_source = "output-error estimate of results.json +- 3 sd";
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    in.loop.parameters[k] = Interval(1e-3 * static_cast<double>(k + 1), 1.25e-3 * (k + 1));
  }
  in.loop.duty_torque_nm = Interval(0.0298, 0.0302);
  in.loop.back_emf_nm_s = Interval(0.0021, 0.0023);
  in.loop.lag_s = Interval(0.001, 0.003);
  in.loop.ramp_duty_per_s = 120;
  in.loop.reading_age_s = 0.002;
  in.loop.arm_count_rad = 2 * std::numbers::pi / 4000;
  in.loop.pendulum_count_rad = 2 * std::numbers::pi / 4096;
  in.start.state = {Interval(-0.01, 0.01), Interval(-0.02, 0.02), Interval(-0.05, 0.05),
                    Interval(-0.1, 0.1)};
  in.start.estimate_error = {Interval(-0.001, 0.001), Interval(-0.002, 0.002),
                             Interval(-0.01, 0.01), Interval(-0.03, 0.03)};
  in.limits = {kUprightRad, 1.5};
  in.options.horizon_s = 0.8;
  in.options.max_symbols = 1500;
  in.split.max_pieces = 32;
  in.certificate.horizon_s = 0.8;
  in.certificate.seconds = 12.5;
  in.certificate.pieces = 3;
  in.certificate.largest_symbol_count = 840;
  const std::size_t steps = certified ? 50 : 31;
  for (std::size_t k = 0; k < steps; ++k) in.certificate.steps.push_back(step_box(k));
  if (!certified) {
    in.certificate.failure = verification::Failure{verification::FailureKind::pendulum_limit, 0.496,
                                                   Interval(-0.0901, 0.0850), kUprightRad};
  } else {
    verification::StartRegion region;
    region.scale = 0.75;
    region.start = in.start;
    for (Interval& x : region.start.state) x = Interval(0.75 * x.lo(), 0.75 * x.hi());
    region.certificate = in.certificate;
    region.verifications = 7;
    in.start_region = region;
  }
  in.sampled.trajectories = 20;
  in.sampled.checks = 123456;
  in.sampled.outside = certified ? 0 : 2;
  if (!certified) in.sampled.first_outside_s = 0.3;
  in.sampled.drawn = {trajectory(0.9, 50), trajectory(-0.6, 50)};
  return in;
}

json written_json(const VerificationReportInput& in, const fs::path& dir) {
  write_verification_report(dir, in);
  std::ifstream file(dir / "verification.json");
  return json::parse(file);
}

void expect_interval(const json& j, const Interval& x, const std::string& what) {
  ASSERT_TRUE(j.is_array()) << what;
  ASSERT_EQ(j.size(), 2u) << what;
  EXPECT_EQ(j[0].get<double>(), x.lo()) << what;
  EXPECT_EQ(j[1].get<double>(), x.hi()) << what;
}

void expect_box(const json& j, const verification::StateBox& box, const std::string& what) {
  ASSERT_EQ(j.size(), 4u) << what;
  for (std::size_t i = 0; i < 4; ++i)
    expect_interval(j[i], box[i], what + "[" + std::to_string(i) + "]");
}

TEST(VerificationJson, HoldsEveryGivenNumberAndAStepALine) {
  const VerificationReportInput in = report_input(true);
  TempDir dir;
  const json j = written_json(in, dir.path());

  EXPECT_EQ(j["software_version"], "furuta 0.9.0");
  EXPECT_EQ(j["controller"], in.controller);
  EXPECT_EQ(j["parameters_source"], in.parameters_source);
  EXPECT_EQ(j["certified"], true);
  EXPECT_EQ(j["horizon_s"].get<double>(), 0.8);
  EXPECT_EQ(j["seconds"].get<double>(), 12.5);
  EXPECT_EQ(j["pieces"], 3);
  EXPECT_EQ(j["handover_s"].get<double>(), 0.0);
  EXPECT_EQ(j["largest_symbol_count"], 840);
  EXPECT_TRUE(j["failure"].is_null());

  const json& a = j["assumptions"];
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    expect_interval(a["parameters"][model::kParameterNames[k]], in.loop.parameters[k],
                    model::kParameterNames[k]);
  }
  expect_interval(a["duty_torque_nm"], in.loop.duty_torque_nm, "duty_torque_nm");
  expect_interval(a["back_emf_nm_s"], in.loop.back_emf_nm_s, "back_emf_nm_s");
  expect_interval(a["lag_s"], in.loop.lag_s, "lag_s");
  EXPECT_EQ(a["ramp_duty_per_s"].get<double>(), 120);
  EXPECT_EQ(a["reading_age_s"].get<double>(), 0.002);
  EXPECT_EQ(a["arm_count_rad"].get<double>(), in.loop.arm_count_rad);
  EXPECT_EQ(a["pendulum_count_rad"].get<double>(), in.loop.pendulum_count_rad);
  expect_box(a["start"]["state"], in.start.state, "start.state");
  expect_box(a["start"]["estimate_error"], in.start.estimate_error, "start.estimate_error");
  EXPECT_EQ(a["limits"]["upright_rad"].get<double>(), kUprightRad);
  EXPECT_EQ(a["limits"]["arm_rad"].get<double>(), 1.5);
  EXPECT_EQ(a["max_symbols"], 1500);
  EXPECT_EQ(a["max_pieces"], 32);

  EXPECT_EQ(j["state_order"], json({"q1", "q2 - pi", "dq1", "dq2"}));
  ASSERT_EQ(j["steps"].size(), in.certificate.steps.size());
  for (const std::size_t k : {std::size_t{0}, std::size_t{17}, std::size_t{49}}) {
    const json& s = j["steps"][k];
    const verification::LoopStepBox& b = in.certificate.steps[k];
    EXPECT_EQ(s["t0_s"].get<double>(), b.t0_s);
    EXPECT_EQ(s["t1_s"].get<double>(), b.t1_s);
    expect_box(s["over"], b.over, "over");
    expect_box(s["at_end"], b.at_end, "at_end");
    expect_box(s["estimate"], b.estimate, "estimate");
    expect_interval(s["duty"], b.duty, "duty");
  }

  const json& r = j["start_region"];
  EXPECT_EQ(r["scale"].get<double>(), 0.75);
  expect_box(r["state"], in.start_region->start.state, "start_region.state");
  expect_box(r["estimate_error"], in.start_region->start.estimate_error,
             "start_region.estimate_error");
  EXPECT_EQ(r["verifications"], 7);
  EXPECT_EQ(r["certified"], true);

  EXPECT_EQ(j["sampled"], json({{"trajectories", 20},
                                {"checks", 123456},
                                {"outside", 0},
                                {"first_outside_s", nullptr},
                                {"on_start_region", false}}));

  // One step a line: a program can stream the steps, a person diff them.
  const std::string text = read_text(dir.path() / "verification.json");
  std::istringstream lines(text);
  std::size_t step_lines = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.find("\"t0_s\"") != std::string::npos) {
      ++step_lines;
      EXPECT_NE(line.find("\"duty\""), std::string::npos) << line;
    }
  }
  EXPECT_EQ(step_lines, in.certificate.steps.size());
}

TEST(VerificationJson, AFailureNamesItsKindAndTheEnclosureAgainstTheLimit) {
  const VerificationReportInput in = report_input(false);
  TempDir dir;
  const json j = written_json(in, dir.path());
  EXPECT_EQ(j["certified"], false);
  const json& f = j["failure"];
  EXPECT_EQ(f["kind"], "pendulum_limit");
  EXPECT_EQ(f["t_s"].get<double>(), 0.496);
  expect_interval(f["value"], Interval(-0.0901, 0.0850), "value");
  EXPECT_EQ(f["limit"].get<double>(), kUprightRad);
  EXPECT_EQ(j["steps"].size(), 31u);
  EXPECT_TRUE(j["start_region"].is_null());
  EXPECT_EQ(j["sampled"]["outside"], 2);
  EXPECT_EQ(j["sampled"]["first_outside_s"].get<double>(), 0.3);

  // Every kind by its name.
  const std::vector<std::pair<verification::FailureKind, const char*>> kinds = {
      {verification::FailureKind::arm_limit, "arm_limit"},
      {verification::FailureKind::duty_limit, "duty_limit"},
      {verification::FailureKind::law_mode, "law_mode"},
      {verification::FailureKind::no_enclosure, "no_enclosure"}};
  for (const auto& [kind, name] : kinds) {
    VerificationReportInput other = in;
    other.certificate.failure->kind = kind;
    EXPECT_EQ(verification_json(other)["failure"]["kind"], name);
  }
}

TEST(VerificationJson, UnboundedAndEmptyIntervalsStayValidJson) {
  VerificationReportInput in = report_input(false);
  // A tube that diverged: the last step's pendulum unbounded, one side of the arm's open, the
  // duty's enclosure empty.
  in.certificate.steps.back().over[1] = Interval::entire();
  in.certificate.steps.back().over[0] = Interval(-0.1, std::numeric_limits<double>::infinity());
  in.certificate.steps.back().duty = Interval::empty();
  in.certificate.failure->kind = verification::FailureKind::no_enclosure;
  in.certificate.failure->value = Interval::entire();
  TempDir dir;
  const json j = written_json(in, dir.path());
  const json& last = j["steps"].back();
  EXPECT_EQ(last["over"][1], json({nullptr, nullptr}));
  EXPECT_EQ(last["over"][0][0].get<double>(), -0.1);
  EXPECT_TRUE(last["over"][0][1].is_null());
  EXPECT_TRUE(last["duty"].is_null());
  EXPECT_EQ(j["failure"]["value"], json({nullptr, nullptr}));
  // The figure still draws: its band clipped to the plot, nothing non-finite written.
  const std::string svg = read_text(dir.path() / "verification.svg");
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

// The panel `id`'s part of the figure (up to the next panel).
std::string panel_text(const std::string& svg, const std::string& id) {
  const std::size_t at = svg.find("<g class=\"panel\" id=\"" + id + "\">");
  EXPECT_NE(at, std::string::npos) << id;
  if (at == std::string::npos) return {};
  const std::size_t next = svg.find("<g class=\"panel\"", at + 1);
  return svg.substr(at, next == std::string::npos ? std::string::npos : next - at);
}

// The points of the n-th element with `cls` in `svg`, as (x, y).
std::vector<std::pair<double, double>> points_of(const std::string& svg, const std::string& cls,
                                                 std::size_t n = 0) {
  std::size_t at = svg.find("class=\"" + cls + "\"");
  for (std::size_t i = 0; i < n && at != std::string::npos; ++i) {
    at = svg.find("class=\"" + cls + "\"", at + 1);
  }
  std::vector<std::pair<double, double>> out;
  if (at == std::string::npos) return out;
  const std::size_t from = svg.find("points=\"", at) + 8;
  const std::string text = svg.substr(from, svg.find('"', from) - from);
  const std::regex pair(R"(([-0-9.]+),([-0-9.]+))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), pair); it != std::sregex_iterator();
       ++it) {
    out.emplace_back(std::stod((*it)[1].str()), std::stod((*it)[2].str()));
  }
  return out;
}

TEST(VerificationFigure, ThreePanelsEachWithItsBandAndTheTrajectories) {
  const std::string svg = svg_verification(report_input(true));
  for (const char* id : {"upright", "arm", "duty"}) {
    const std::string panel = panel_text(svg, id);
    EXPECT_EQ(count(panel, "<polygon class=\"tube-band\""), 1u) << id;
    EXPECT_EQ(count(panel, "<polyline class=\"trajectory\""), 2u) << id;
    EXPECT_EQ(count(panel, ">t [s]</text>"), 1u) << id;
    EXPECT_EQ(count(panel, "class=\"failure\""), 0u) << id;
    // The trajectories lie within their band's vertical extent (both drawn on one axis).
    double band_top = 1e9, band_bottom = -1e9;
    for (const auto& [x, y] : points_of(panel, "tube-band")) {
      band_top = std::min(band_top, y);
      band_bottom = std::max(band_bottom, y);
    }
    for (std::size_t n = 0; n < 2; ++n) {
      const auto points = points_of(panel, "trajectory", n);
      EXPECT_GT(points.size(), 40u) << id;
      for (const auto& [x, y] : points) {
        EXPECT_GE(y, band_top - 0.11) << id;
        EXPECT_LE(y, band_bottom + 0.11) << id;
      }
    }
  }
  // The stated bound, dashed, in the upright panel only.
  EXPECT_EQ(count(panel_text(svg, "upright"), "<line class=\"bound\""), 2u);
  EXPECT_EQ(count(svg, "<line class=\"bound\""), 2u);
  EXPECT_NE(svg.find("bound +-5"), std::string::npos);
  EXPECT_NE(svg.find(">angle [deg]</text>"), std::string::npos);
  EXPECT_NE(svg.find(">duty</text>"), std::string::npos);
  EXPECT_NE(svg.find("certified to 0.8 s"), std::string::npos);
}

TEST(VerificationFigure, MarksWhereTheProofStoppedOnlyWhenItFailed) {
  const std::string svg = svg_verification(report_input(false));
  for (const char* id : {"upright", "arm", "duty"}) {
    EXPECT_EQ(count(panel_text(svg, id), "<line class=\"failure\""), 1u) << id;
  }
  EXPECT_NE(svg.find("not certified: pendulum limit at t = 0.496 s"), std::string::npos);
  // At t = 0.496 s of the 0.8 s axis, in the same place in every panel.
  std::vector<std::string> xs;
  const std::regex line(R"re(<line class="failure" x1="([-0-9.]+)")re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), line); it != std::sregex_iterator();
       ++it) {
    xs.push_back((*it)[1].str());
  }
  ASSERT_EQ(xs.size(), 3u);
  EXPECT_EQ(xs[0], xs[1]);
  EXPECT_EQ(xs[1], xs[2]);
  const double left = 72, width = 960 - 72 - 20;
  EXPECT_NEAR(std::stod(xs[0]), left + 0.496 / 0.8 * width, 0.1);
}

TEST(VerificationFigure, ALongRunStaysSmallWithoutLosingAnExcursion) {
  // 60 s of 16 ms periods: 3750 steps, trajectories of 3751 samples and 15000 inner states.
  VerificationReportInput in = report_input(true);
  in.options.horizon_s = in.certificate.horizon_s = 60;
  in.certificate.steps.clear();
  for (std::size_t k = 0; k < 3750; ++k) in.certificate.steps.push_back(step_box(k));
  in.sampled.drawn = {trajectory(0.9, 3750), trajectory(-0.6, 3750)};
  // An excursion of the first trajectory's pendulum at one inner state, 30 s in.
  verification::LoopTrajectory& first = in.sampled.drawn.front();
  std::size_t spike = 0;
  while (first.inner_t_s[spike] < 30.0) ++spike;
  first.inner_state[spike][1] = 0.06;
  const std::string svg = svg_verification(in);
  EXPECT_LT(svg.size(), 250'000u);
  const std::string upright = panel_text(svg, "upright");
  for (const char* id : {"upright", "arm", "duty"}) {
    const std::string panel = panel_text(svg, id);
    EXPECT_LT(points_of(panel, "tube-band").size(), 2000u) << id;
    EXPECT_LT(points_of(panel, "trajectory", 0).size(), 1300u) << id;
  }
  // The highest point of the pendulum's first trajectory (smallest y) is the excursion, 30 s in.
  const auto points = points_of(upright, "trajectory", 0);
  const auto top = std::min_element(points.begin(), points.end(), [](const auto& a, const auto& b) {
    return a.second < b.second;
  });
  ASSERT_NE(top, points.end());
  const double left = 72, width = 960 - 72 - 20;
  EXPECT_NEAR(top->first, left + first.inner_t_s[spike] / 60 * width, 0.1);
}

TEST(VerificationPage, SaysWhatWasProvenUnderWhichAssumptions) {
  const std::string html = render_verification_html(report_input(true));
  EXPECT_NE(html.find("Certified to 0.8 s"), std::string::npos);
  EXPECT_NE(html.find("within 5 deg of upright"), std::string::npos);
  EXPECT_NE(html.find("50 periods of 16 ms, to t = 0.8 s"), std::string::npos);
  EXPECT_EQ(html.find("Not certified"), std::string::npos);
  // The assumptions, each with its unit.
  for (const char* text :
       {">mu1<", ">fv2<", "kg m\u00b2", "N m s", "[0.0298, 0.0302] N m per unit duty",
        "[0.0021, 0.0023] N m s", "[1, 3] ms", "120 duty/s", "2 ms before each sample",
        "4000 per turn", "4096 per turn", "|q2 - pi| &lt; 5 deg", "|q1| &lt; 85.9437 deg",
        "[-1.14592, 1.14592] deg", "[-5.72958, 5.72958] deg/s", "[-1.71888, 1.71888] deg/s",
        ">0.8 s<", ">1500<", ">32<"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  EXPECT_NE(html.find("3 pieces of the start and parameter boxes (split to at most 32)"),
            std::string::npos);
  EXPECT_NE(html.find("in 12.5 s"), std::string::npos);
  EXPECT_NE(html.find("840 noise symbols"), std::string::npos);
  EXPECT_NE(html.find("scaled by 0.75"), std::string::npos);
  EXPECT_NE(html.find("7 verifications"), std::string::npos);
  EXPECT_NE(html.find("20 trajectories, 123456 checks, 0 outside."), std::string::npos);
  // The figure last, its panels' ids prefixed by the figure's.
  const std::size_t figure = html.find("<figure id=\"fig-verification\">");
  ASSERT_NE(figure, std::string::npos);
  EXPECT_GT(figure, html.find("id=\"sampled\""));
  EXPECT_NE(html.find("id=\"fig-verification-upright\""), std::string::npos);
  // Every text escaped.
  EXPECT_NE(html.find("controllers/&lt;lab&gt; balance.toml"), std::string::npos);
  EXPECT_EQ(html.find("<lab>"), std::string::npos);
}

TEST(VerificationPage, NamesTheFailureItsTimeAndTheEnclosureAgainstTheBound) {
  const std::string html = render_verification_html(report_input(false));
  EXPECT_EQ(html.find("Certified to"), std::string::npos);
  EXPECT_NE(html.find("Not certified (pendulum_limit at t = 0.496 s of the 0.8 s asked)"),
            std::string::npos);
  EXPECT_NE(html.find("At t = 0.496 s the pendulum&#39;s angle from upright"), std::string::npos)
      << html.substr(html.find("not-certified"), 800);
  // The enclosure in degrees, rounded outward, against the bound.
  EXPECT_NE(html.find("[-5.16235, 4.87015] deg, against the bound +-5 deg"), std::string::npos)
      << html.substr(html.find("not-certified"), 800);
  EXPECT_NE(html.find("31 periods of 16 ms, to t = 0.496 s"), std::string::npos);
  EXPECT_NE(html.find("Not asked for"), std::string::npos);
  EXPECT_NE(html.find("20 trajectories, 123456 checks, 2 outside, the first at t = 0.3 s."),
            std::string::npos);
}

TEST(VerificationPage, SaysEachFailureKindInWordsWithItsUnit) {
  VerificationReportInput in = report_input(false);
  in.certificate.failure =
      verification::Failure{verification::FailureKind::duty_limit, 0.2, Interval(-0.52, 0.31), 0.5};
  std::string html = render_verification_html(in);
  EXPECT_NE(html.find("duty_limit at t = 0.2 s"), std::string::npos);
  EXPECT_NE(html.find("the duty the law sends may reach its limit"), std::string::npos);
  EXPECT_NE(html.find("[-0.52, 0.31], against the limit +-0.5."), std::string::npos);
  in.certificate.failure =
      verification::Failure{verification::FailureKind::arm_limit, 0.25, Interval(1.4, 1.6), 1.5};
  html = render_verification_html(in);
  EXPECT_NE(html.find("the arm&#39;s angle q1 may reach its limit"), std::string::npos);
  EXPECT_NE(html.find("against the limit +-85.9437 deg"), std::string::npos);
  in.certificate.failure->kind = verification::FailureKind::law_mode;
  EXPECT_NE(render_verification_html(in).find("the law&#39;s balance region"), std::string::npos);
  in.certificate.failure->kind = verification::FailureKind::no_enclosure;
  EXPECT_NE(render_verification_html(in).find("did not close"), std::string::npos);
}

TEST(VerificationFiles, TheThreeFilesOrAnError) {
  const VerificationReportInput in = report_input(true);
  TempDir dir;
  const fs::path out = dir.path() / "new" / "verification";
  write_verification_report(out, in);
  for (const char* name : {"report.html", "verification.json", "verification.svg"}) {
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
    EXPECT_GT(fs::file_size(out / name), 0u) << name;
  }
  EXPECT_EQ(read_text(out / "verification.svg"), svg_verification(in));
  EXPECT_EQ(read_text(out / "report.html"), render_verification_html(in));
  // A directory where a file is: nothing can be written there.
  std::ofstream(dir.path() / "file") << "x";
  EXPECT_THROW(write_verification_report(dir.path() / "file" / "sub", in), std::runtime_error);
}

}  // namespace
}  // namespace furuta::report::verification_page_test

namespace furuta::report::verification_page_test {
namespace {

// The start box not certified, the sampled check run against the largest certified start's tube:
// the figure draws that tube (to its horizon, no failure marked) and the page says so.
TEST(VerificationFigure, DrawsTheStartRegionsTubeWhenTheCheckRanAgainstIt) {
  VerificationReportInput in = report_input(false);
  const VerificationReportInput region = report_input(true);
  verification::StartRegion r;
  r.scale = 0.5;
  r.start = region.start;
  r.certificate = region.certificate;
  r.verifications = 7;
  in.start_region = r;
  in.sampled.on_start_region = true;
  const std::string svg = svg_verification(in);
  EXPECT_EQ(count(svg, "class=\"failure\""), 0u);
  EXPECT_NE(svg.find("certified to 0.8 s"), std::string::npos);
  EXPECT_NE(
      render_verification_html(in).find("the figure below, are for the largest certified start"),
      std::string::npos);
}

}  // namespace
}  // namespace furuta::report::verification_page_test
