// Fig. 6: a scenario's q2 tube over the measured q2.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "format.hpp"
#include "furuta/common/text_format.hpp"
#include "furuta/report/axis.hpp"
#include "furuta/report/svg.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::report {

std::string svg_scenario(const validated::ScenarioResult& r) {
  const double width = 860, height = 440;
  const double left = 70, right = 20, top = 50, bottom = 120;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const validated::ScenarioMeasurement& m = r.measurement;
  const double t_max = std::max(r.scenario.duration_s, m.t_s.empty() ? 0.0 : m.t_s.back());

  // The view follows the measurement (with a margin): a tube that blew up before its run ended
  // would otherwise flatten everything; it is clipped to the plot instead.
  double y_lo = std::numeric_limits<double>::infinity();
  double y_hi = -y_lo;
  for (const double q : m.q2_rad) {
    y_lo = std::min(y_lo, q * kDegPerRad);
    y_hi = std::max(y_hi, q * kDegPerRad);
  }
  if (!(y_lo <= y_hi)) {
    y_lo = r.scenario.q2_initial_rad * kDegPerRad - 10;
    y_hi = y_lo + 20;
  }
  const double margin = std::max(5.0, 0.1 * (y_hi - y_lo));
  const Ticks time = nice_ticks(0, t_max, 5);
  const Ticks angle = nice_ticks(y_lo - margin, y_hi + margin, 5, true);
  y_lo = angle.lo;
  y_hi = angle.hi;
  const auto px = [&](double t) { return left + plot_w * (t - time.lo) / (time.hi - time.lo); };
  const auto py = [&](double deg) {
    const double clipped = std::clamp(deg, y_lo, y_hi);
    return top + plot_h * (y_hi - clipped) / (y_hi - y_lo);
  };

  std::ostringstream s;
  s << std::fixed << std::setprecision(2);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  s << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << "<text x=\"" << width / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">"
    << text::xml_escape("Scenario " + scenario_label(r.scenario) + ": " +
                        scenario_description(r.scenario) + ", " + r.parameters.name + " parameters")
    << "</text>\n";
  s << svg_axes(PlotArea{left, top, plot_w, plot_h}, time, angle, "t [s]",
                "pendulum angle q2 [deg]");

  // The tube: step boxes, merged within a pixel column (a 4 s run has over a thousand steps).
  s << "<g class=\"tube\" fill=\"#6fa8dc\" fill-opacity=\"0.55\" stroke=\"none\">\n";
  const auto emit = [&](const validated::TubeBand& b) {
    const double x0 = px(b.t0_s);
    const double x1 = std::max(px(b.t1_s), x0 + 0.5);
    const double y0 = py(b.hi_rad * kDegPerRad);
    const double y1 = std::max(py(b.lo_rad * kDegPerRad), y0 + 0.5);
    s << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << x1 - x0 << "\" height=\""
      << y1 - y0 << "\"/>\n";
  };
  bool open = false;
  validated::TubeBand group;
  for (const validated::TubeBand& b : r.q2_tube) {
    if (open && b.t0_s >= group.t0_s && px(b.t1_s) - px(group.t0_s) < 2.0) {
      group.t1_s = std::max(group.t1_s, b.t1_s);
      group.lo_rad = std::min(group.lo_rad, b.lo_rad);
      group.hi_rad = std::max(group.hi_rad, b.hi_rad);
      continue;
    }
    if (open) emit(group);
    group = b;
    open = true;
  }
  if (open) emit(group);
  s << "</g>\n";

  // Where the tube ends before the scenario does.
  if (r.t_reached_s < r.scenario.duration_s) {
    s << "<line class=\"tube-end\" x1=\"" << px(r.t_reached_s) << "\" y1=\"" << top << "\" x2=\""
      << px(r.t_reached_s) << "\" y2=\"" << top + plot_h
      << "\" stroke=\"#cc0000\" stroke-dasharray=\"5,3\"/>\n";
    s << "<text x=\"" << px(r.t_reached_s) + 4 << "\" y=\"" << top + 14
      << "\" fill=\"#cc0000\" font-size=\"11\">tube ends at " << fixed(r.t_reached_s, 3)
      << " s</text>\n";
  }

  // The measurement: a thin line through the samples, the samples the paper's test misses red.
  s << "<polyline class=\"measured\" fill=\"none\" stroke=\"black\" stroke-width=\"0.8\" "
       "points=\"";
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    s << (k ? " " : "") << px(m.t_s[k]) << "," << py(m.q2_rad[k] * kDegPerRad);
  }
  s << "\"/>\n<g class=\"samples\">\n";
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    const bool covered = k < r.q2_covered_step.size() && r.q2_covered_step[k];
    s << "<circle cx=\"" << px(m.t_s[k]) << "\" cy=\"" << py(m.q2_rad[k] * kDegPerRad)
      << "\" r=\"1.8\" fill=\"" << (covered ? "black" : "#cc0000") << "\"/>\n";
  }
  s << "</g>\n";

  // Legend.
  const double ly = top + plot_h + 55;
  s << "<g class=\"legend\">\n";
  s << "<rect x=\"" << left << "\" y=\"" << ly - 10 << "\" width=\"18\" height=\"10\" "
    << "fill=\"#6fa8dc\" fill-opacity=\"0.55\"/>\n";
  s << "<text x=\"" << left + 24 << "\" y=\"" << ly << "\">"
    << text::xml_escape("tube [q2], " + r.parameters.name +
                        " parameters, x0 +- data uncertainty (" + std::to_string(r.steps) +
                        " steps, " + validated::to_string(r.status) + ", reached " +
                        fixed(r.t_reached_s, 3) + " of " + fixed(r.scenario.duration_s, 1) + " s)")
    << "</text>\n";
  s << "<circle cx=\"" << left + 9 << "\" cy=\"" << ly + 13 << "\" r=\"2.5\" fill=\"black\"/>\n";
  s << "<circle cx=\"" << left + 15 << "\" cy=\"" << ly + 13 << "\" r=\"2.5\" fill=\"#cc0000\"/>\n";
  s << "<text x=\"" << left + 24 << "\" y=\"" << ly + 17 << "\">"
    << text::xml_escape("measured q2 (simulated rig, every " +
                        short_number(m.t_s.size() > 1 ? (m.t_s[1] - m.t_s[0]) * 1000 : 0.0) +
                        " ms, quantised); red: outside the paper's test")
    << "</text>\n";
  s << "<text x=\"" << left << "\" y=\"" << ly + 36 << "\">"
    << text::xml_escape("coverage of q2: step (paper) " + percent(r.q2_step.rate()) +
                        " of all samples, " + percent(r.q2_step.rate_in_time()) +
                        " of those reached; interpolated " + percent(r.q2_interpolated.rate()) +
                        " (" + percent(r.q2_interpolated.rate_in_time()) + ")")
    << "</text>\n";
  s << "</g>\n</svg>\n";
  return s.str();
}

}  // namespace furuta::report
