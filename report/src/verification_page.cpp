// The balance controller's verification on a page: report.html, verification.json and the
// writer (the figure is svg_verification.cpp's).
#include "furuta/report/verification_page.hpp"

#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "format.hpp"
#include "furuta/model/parameters.hpp"
#include "furuta/report/outputs.hpp"
#include "html_page.hpp"
#include "verification_words.hpp"

namespace furuta::report {

namespace {

// verification.json's layout: the document's members, and the members of those holding
// containers, a line each (a step, the parameter box, the start), everything below on its line.
constexpr int kVerificationJsonLevels = 2;

// The state's components in verification's order, with what the page shows each in: the angles
// in degrees, the rates in degrees per second.
constexpr std::array<const char*, 4> kStateNames = {"q1", "q2 - pi", "dq1", "dq2"};
constexpr std::array<const char*, 4> kStateUnits = {"deg", "deg", "deg/s", "deg/s"};

Json state_box_json(const verification::StateBox& box) {
  Json j = Json::array();
  for (const interval::Interval& x : box) j.push_back(interval_json(x));
  return j;
}

// An enclosure for a person, each bound times `scale`, with its unit: "[-1.2, 3.4] deg".
std::string enclosure_text(const interval::Interval& x, double scale, const std::string& unit) {
  if (x.is_empty()) return "empty";
  return interval_text(x.lo() * scale, x.hi() * scale) + (unit.empty() ? "" : " " + unit);
}

// A time as the page writes it: "0.512 s".
std::string seconds_text(double t_s) {
  return short_number(t_s, 6) + " s";
}

// The loop's period, from its steps (every step is one period); 0 without a step.
double verified_period_s(const verification::BalanceCertificate& c) {
  return c.steps.empty() ? 0.0 : c.steps.front().t1_s - c.steps.front().t0_s;
}

// How far the steps reach: "625 periods of 16 ms, to t = 10 s".
std::string steps_reach_text(const verification::BalanceCertificate& c) {
  if (c.steps.empty()) return "no period";
  return std::to_string(c.steps.size()) + " periods of " +
         short_number(verified_period_s(c) * 1e3) +
         " ms, to t = " + seconds_text(c.steps.back().t1_s);
}

// The failure in words: which bound, when, the enclosure against the bound, with units.
std::string failure_sentence(const verification::Failure& f) {
  const bool angle = failure_is_angle(f.kind);
  const double scale = angle ? kDegPerRad : 1.0;
  const std::string unit = angle ? "deg" : "";
  const std::string enclosure = enclosure_text(f.value, scale, unit);
  const std::string limit = "+-" + short_number(f.limit * scale, 6) + (angle ? " deg" : "");
  const std::string when = "At t = " + seconds_text(f.t_s) + " ";
  switch (f.kind) {
    case verification::FailureKind::pendulum_limit:
      return when +
             "the pendulum's angle from upright, q2 - pi, may reach its bound: its "
             "enclosure over the period is " +
             enclosure + ", against the bound " + limit + ".";
    case verification::FailureKind::arm_limit:
      return when + "the arm's angle q1 may reach its limit: its enclosure over the period is " +
             enclosure + ", against the limit " + limit + ".";
    case verification::FailureKind::duty_limit:
      return when +
             "the duty the law sends may reach its limit (the enclosure assumes it never "
             "does): its enclosure is " +
             enclosure + ", against the limit " + limit + ".";
    case verification::FailureKind::law_mode:
      return when +
             "a pendulum reading may leave the law's balance region (its release or fall "
             "angle), so the law may not run as the enclosure assumes: the reading's "
             "enclosure is " +
             enclosure + ", against the region's edge " + limit + ".";
    case verification::FailureKind::no_enclosure:
      return when +
             "the enclosure of the period's motion did not close: the nonlinear and "
             "parametric remainder grew the tube faster than the loop contracts it. The "
             "pendulum's enclosure (q2 - pi) was " +
             enclosure + ", against the bound " + limit + ".";
  }
  return when + "the proof stopped.";
}

// The rows of a start box and its estimate error, in degrees and degrees per second.
std::vector<std::vector<std::string>> start_rows(const verification::LoopStart& start) {
  std::vector<std::vector<std::string>> rows;
  for (std::size_t i = 0; i < 4; ++i) {
    rows.push_back({kStateNames[i], enclosure_text(start.state[i], kDegPerRad, kStateUnits[i]),
                    enclosure_text(start.estimate_error[i], kDegPerRad, kStateUnits[i])});
  }
  return rows;
}

// An encoder's count: "0.00157 rad (0.09 deg, 4000 per turn)".
std::string count_text(double count_rad) {
  if (!(count_rad > 0)) return short_number(count_rad) + " rad";
  return short_number(count_rad) + " rad (" + short_number(count_rad * kDegPerRad, 4) + " deg, " +
         short_number(2 * std::numbers::pi / count_rad, 6) + " per turn)";
}

void verification_page_head(Html& h, const VerificationReportInput& in) {
  const std::string title = "Balance verification";
  h.document_start(
      title, in.software_version +
                 ": a validated simulation of the balancing loop of a rotary inverted (Furuta) "
                 "pendulum, for every start, parameter, lag and reading in the boxes below: "
                 "whether the controller keeps the pendulum upright. The numbers are also in "
                 "verification.json.");
  h.raw("<p class=\"meta\">Controller ");
  h.element("code", in.controller);
  h.raw(", parameters from ");
  h.text(in.parameters_source);
  h.raw(".</p>\n</header>\n<nav>\n<ol>\n");
  const std::array<std::pair<const char*, const char*>, 6> sections = {{
      {"proven", "What was proven"},
      {"assumptions", "Assumptions"},
      {"pieces", "Pieces and time"},
      {"start-region", "Start region"},
      {"sampled", "Sampled check"},
      {"tube", "The tube over time"},
  }};
  for (const auto& [id, name] : sections) {
    h.raw(std::string("<li><a href=\"#") + id + "\">");
    h.text(name);
    h.raw("</a></li>\n");
  }
  h.raw("</ol>\n</nav>\n");
}

void section_proven(Html& h, const VerificationReportInput& in) {
  const verification::BalanceCertificate& c = in.certificate;
  h.raw("<section id=\"proven\">\n");
  h.element("h2", "What was proven");
  h.raw("\n");
  if (c.certified()) {
    h.paragraph("Certified to " + seconds_text(c.horizon_s) +
                    ": from every start in the start box, with the filter's estimate off by "
                    "anything in the estimate error, for every parameter in the box and every "
                    "lag, reading and rounding below, the pendulum stays within " +
                    short_number(in.limits.upright_rad * kDegPerRad, 6) +
                    " deg of upright and the arm within " +
                    short_number(in.limits.arm_rad * kDegPerRad, 6) +
                    " deg at every instant, and the law's duty within its limit, so that the law "
                    "runs as the enclosure assumes (" +
                    steps_reach_text(c) + ").",
                "certified");
  } else {
    const verification::Failure& f = *c.failure;
    h.raw("<div class=\"not-certified\">\n");
    h.paragraph("Not certified (" + failure_kind_code(f.kind) + " at t = " + seconds_text(f.t_s) +
                " of the " + seconds_text(c.horizon_s) + " asked).");
    h.paragraph(failure_sentence(f));
    h.paragraph("Proven before it: " + steps_reach_text(c) +
                ", every period's boxes within the bounds.");
    h.raw("</div>\n");
  }
  h.raw("</section>\n");
}

void section_assumptions(Html& h, const VerificationReportInput& in) {
  const verification::LoopModel& loop = in.loop;
  h.raw("<section id=\"assumptions\">\n");
  h.element("h2", "Assumptions");
  h.raw("\n");
  h.paragraph("What the proof takes as given: every value in each interval, each at its worst.");
  std::vector<std::vector<std::string>> parameters;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    parameters.push_back({model::kParameterNames[k], enclosure_text(loop.parameters[k], 1.0, ""),
                          pretty_unit(model::kParameterUnits[k])});
  }
  h.table("verification-parameters", "The plant's parameter box (" + in.parameters_source + ")",
          {"parameter", "box", "unit"}, parameters);
  const std::vector<std::vector<std::string>> loop_rows = {
      {"duty torque (eq. 4, kd)", enclosure_text(loop.duty_torque_nm, 1.0, "N m per unit duty")},
      {"back-EMF (eq. 4, kw)", enclosure_text(loop.back_emf_nm_s, 1.0, "N m s")},
      {"lag until the board takes a duty", enclosure_text(loop.lag_s, 1e3, "ms")},
      {"ramp to a new duty", loop.ramp_duty_per_s > 0
                                 ? short_number(loop.ramp_duty_per_s) + " duty/s"
                                 : "none: the board applies each duty at once"},
      {"reading age", short_number(loop.reading_age_s * 1e3) + " ms before each sample"},
      {"arm encoder count", count_text(loop.arm_count_rad)},
      {"pendulum encoder count", count_text(loop.pendulum_count_rad)},
      {"upright bound", "|q2 - pi| < " + short_number(in.limits.upright_rad * kDegPerRad) + " deg"},
      {"arm limit", "|q1| < " + short_number(in.limits.arm_rad * kDegPerRad) + " deg"},
      {"horizon", seconds_text(in.options.horizon_s)},
      {"noise symbols, at most", std::to_string(in.options.max_symbols)},
      {"pieces of the start and parameter boxes, at most", std::to_string(in.split.max_pieces)},
  };
  h.table("verification-loop", "The drive, the board, the readings and the bounds", {"", "value"},
          loop_rows);
  h.table("verification-start",
          "The start: the plant's state and the filter's estimate error at t = 0",
          {"component", "state", "estimate error"}, start_rows(in.start));
  h.raw("</section>\n");
}

void section_pieces(Html& h, const VerificationReportInput& in) {
  const verification::BalanceCertificate& c = in.certificate;
  h.raw("<section id=\"pieces\">\n");
  h.element("h2", "Pieces and time");
  h.raw("\n");
  const std::string handover =
      c.handover_s > 0 ? " to " + seconds_text(c.handover_s) +
                             ", then one run from the hull of their states to the horizon,"
                       : "";
  h.paragraph(std::to_string(c.pieces) + (c.pieces == 1 ? " piece" : " pieces") +
              " of the start and parameter boxes (split to at most " +
              std::to_string(in.split.max_pieces) + "), each proven on its own" + handover +
              " in " + short_number(c.seconds, 4) + " s; at most " +
              std::to_string(c.largest_symbol_count) + " noise symbols at once (reduced beyond " +
              std::to_string(in.options.max_symbols) + ").");
  h.raw("</section>\n");
}

void section_start_region(Html& h, const VerificationReportInput& in) {
  h.raw("<section id=\"start-region\">\n");
  h.element("h2", "Start region");
  h.raw("\n");
  if (!in.start_region) {
    h.paragraph("Not asked for: only the start box above was verified.", "absent");
    h.raw("</section>\n");
    return;
  }
  const verification::StartRegion& r = *in.start_region;
  if (!(r.scale > 0)) {
    h.paragraph("No scale tried was certified (" + std::to_string(r.verifications) +
                    " verifications by bisection on the scale of the start box about its centre).",
                "absent");
    if (r.certificate.failure)
      h.paragraph("The last failure: " + failure_sentence(*r.certificate.failure));
    h.raw("</section>\n");
    return;
  }
  const bool certified = r.certificate.certified();
  const std::string how = r.verifications == 0 ? "the start box itself, certified above"
                                               : std::to_string(r.verifications) +
                                                     " verifications by bisection on the scale";
  h.paragraph("The largest start certified: the start box scaled by " + short_number(r.scale, 6) +
                  " about its centre (" + how + "), " +
                  (certified ? "certified to " + seconds_text(r.certificate.horizon_s)
                             : std::string("not certified")) +
                  ".",
              certified ? "certified" : "");
  h.table("verification-start-region", "The start at that scale",
          {"component", "state", "estimate error"}, start_rows(r.start));
  h.raw("</section>\n");
}

void section_sampled(Html& h, const VerificationReportInput& in) {
  const VerificationSampled& s = in.sampled;
  h.raw("<section id=\"sampled\">\n");
  h.element("h2", "Sampled check");
  h.raw("\n");
  if (s.trajectories == 0) {
    const bool any_certified =
        in.certificate.certified() || (in.start_region && in.start_region->scale > 0);
    h.paragraph(any_certified ? "Not run: no trajectory was simulated point by point."
                              : "Not run: no tube was certified to check against.",
                "absent");
    h.raw("</section>\n");
    return;
  }
  h.paragraph(
      "The independent check: the loop simulated point by point from points of the boxes "
      "(Runge-Kutta 4, the real law, the readings rounded to whole counts), every sample's "
      "state, duty and filter rates and every state between samples compared with its "
      "period's box.");
  if (s.on_start_region) {
    h.paragraph(
        "The start box was not certified: the check, and the figure below, are for the "
        "largest certified start's tube.");
  }
  std::string counts = std::to_string(s.trajectories) + " trajectories, " +
                       std::to_string(s.checks) + " checks, " + std::to_string(s.outside) +
                       " outside";
  if (s.first_outside_s) counts += ", the first at t = " + seconds_text(*s.first_outside_s);
  h.paragraph(counts + ".", s.outside == 0 ? "none" : "sampled-outside");
  h.raw("</section>\n");
}

}  // namespace

Json verification_json(const VerificationReportInput& input) {
  const verification::BalanceCertificate& c = input.certificate;
  const verification::LoopModel& loop = input.loop;
  Json doc;
  doc["software_version"] = input.software_version;
  doc["controller"] = input.controller;
  doc["parameters_source"] = input.parameters_source;
  doc["certified"] = c.certified();
  doc["horizon_s"] = c.horizon_s;
  doc["seconds"] = c.seconds;
  doc["pieces"] = c.pieces;
  doc["handover_s"] = c.handover_s;
  doc["largest_symbol_count"] = c.largest_symbol_count;
  if (c.failure) {
    const verification::Failure& f = *c.failure;
    doc["failure"] = Json{{"kind", failure_kind_code(f.kind)},
                          {"t_s", f.t_s},
                          {"value", interval_json(f.value)},
                          {"limit", f.limit}};
  } else {
    doc["failure"] = nullptr;
  }

  Json parameters = Json::object();
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    parameters[model::kParameterNames[k]] = interval_json(loop.parameters[k]);
  }
  Json assumptions;
  assumptions["parameters"] = parameters;
  assumptions["duty_torque_nm"] = interval_json(loop.duty_torque_nm);
  assumptions["back_emf_nm_s"] = interval_json(loop.back_emf_nm_s);
  assumptions["lag_s"] = interval_json(loop.lag_s);
  assumptions["ramp_duty_per_s"] = loop.ramp_duty_per_s;
  assumptions["reading_age_s"] = loop.reading_age_s;
  assumptions["arm_count_rad"] = loop.arm_count_rad;
  assumptions["pendulum_count_rad"] = loop.pendulum_count_rad;
  assumptions["start"] = Json{{"state", state_box_json(input.start.state)},
                              {"estimate_error", state_box_json(input.start.estimate_error)}};
  assumptions["limits"] =
      Json{{"upright_rad", input.limits.upright_rad}, {"arm_rad", input.limits.arm_rad}};
  assumptions["max_symbols"] = input.options.max_symbols;
  assumptions["max_pieces"] = input.split.max_pieces;
  doc["assumptions"] = assumptions;

  doc["state_order"] = Json::array({"q1", "q2 - pi", "dq1", "dq2"});
  Json steps = Json::array();
  for (const verification::LoopStepBox& step : c.steps) {
    steps.push_back(Json{{"t0_s", step.t0_s},
                         {"t1_s", step.t1_s},
                         {"over", state_box_json(step.over)},
                         {"at_end", state_box_json(step.at_end)},
                         {"estimate", state_box_json(step.estimate)},
                         {"duty", interval_json(step.duty)}});
  }
  doc["steps"] = steps;

  if (input.start_region) {
    const verification::StartRegion& r = *input.start_region;
    doc["start_region"] = Json{{"scale", r.scale},
                               {"state", state_box_json(r.start.state)},
                               {"estimate_error", state_box_json(r.start.estimate_error)},
                               {"verifications", r.verifications},
                               {"certified", r.scale > 0 && r.certificate.certified()}};
  } else {
    doc["start_region"] = nullptr;
  }

  const VerificationSampled& s = input.sampled;
  doc["sampled"] =
      Json{{"trajectories", s.trajectories},
           {"checks", s.checks},
           {"outside", s.outside},
           {"first_outside_s", s.first_outside_s ? Json(*s.first_outside_s) : Json(nullptr)},
           {"on_start_region", s.on_start_region}};
  return doc;
}

std::string render_verification_html(const VerificationReportInput& input) {
  Html h;
  verification_page_head(h, input);
  section_proven(h, input);
  section_assumptions(h, input);
  section_pieces(h, input);
  section_start_region(h, input);
  section_sampled(h, input);
  h.raw("<section id=\"tube\">\n");
  h.element("h2", "The tube over time");
  h.raw("\n");
  h.figure("fig-verification", svg_verification(input),
           "Over time t [s] from the start: the pendulum's angle from upright q2 - pi [deg], the "
           "arm angle q1 [deg] and the duty the law sends at each sample. Shaded: the tube, the "
           "boxes that hold the loop's state over every period proven (the duty's at each "
           "sample); lines: trajectories simulated point by point, which must stay inside it; "
           "dashed: the stated bound on q2 - pi; a red vertical line: where the proof stopped.");
  h.raw("</section>\n</body>\n</html>\n");
  return h.str();
}

void write_verification_report(const std::filesystem::path& dir,
                               const VerificationReportInput& input) {
  std::filesystem::create_directories(dir);
  write_text_file(dir / "verification.json",
                  json_text(verification_json(input), kVerificationJsonLevels));
  write_text_file(dir / "verification.svg", svg_verification(input));
  write_text_file(dir / "report.html", render_verification_html(input));
}

}  // namespace furuta::report
