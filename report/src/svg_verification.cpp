// The balance controller's verification as a figure: the tube of every proven period over time
// (the pendulum from upright, the arm, the duty), with trajectories simulated point by point
// inside it, the stated bound and where the proof stopped.
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "format.hpp"
#include "furuta/common/text_format.hpp"
#include "furuta/report/axis.hpp"
#include "furuta/report/verification_page.hpp"
#include "thinning.hpp"
#include "verification_words.hpp"

namespace furuta::report {

namespace {

// A bound further out than this many times the data's extent is named, not drawn.
constexpr double kBoundScale = 4.0;

// The drawn trajectories' colours, by index: a trajectory has the same colour in every panel.
constexpr std::array<const char*, 5> kTrajectoryColours = {"#222222", "#7d3c98", "#d35400",
                                                           "#117a65", "#5d6d7e"};

// Steps are drawn as one piece of the band, their hull, until the piece is this many pixels wide:
// a long run's thousands of periods stay a polygon of a few hundred corners, and the band still
// holds every step's box.
constexpr double kBandColumnPx = 2.0;
// A trajectory keeps per column of this many pixels its first, lowest, highest and last value.
constexpr double kTraceColumnPx = 3.0;

// Where a quantity is over [t0_s, t1_s] (t0_s == t1_s: at one instant).
struct TubeSlice {
  double t0_s = 0;
  double t1_s = 0;
  double lo = 0;
  double hi = 0;
};

// One trajectory's values over time, in time order.
struct TubeTrace {
  std::vector<double> t_s;
  std::vector<double> value;
};

struct TubePanel {
  const char* id;
  std::string title;
  std::string y_name;
  const char* band_colour;
  std::vector<TubeSlice> band;
  std::vector<TubeTrace> traces;  // in the order of VerificationSampled::drawn
  std::optional<double> bound;    // dashed at +-bound, in the panel's unit
  std::string bound_label;
};

// A state component of a trajectory, scaled, at its samples and at every inner step between them
// (the motion within a period), merged in time order.
TubeTrace state_trace(const verification::LoopTrajectory& trajectory, std::size_t component,
                      double scale) {
  TubeTrace out;
  const std::size_t inner = std::min(trajectory.inner_t_s.size(), trajectory.inner_state.size());
  std::size_t i = 0, j = 0;
  while (i < trajectory.samples.size() || j < inner) {
    const bool sample = j >= inner || (i < trajectory.samples.size() &&
                                       trajectory.samples[i].t_s <= trajectory.inner_t_s[j]);
    if (sample) {
      out.t_s.push_back(trajectory.samples[i].t_s);
      out.value.push_back(trajectory.samples[i].state[component] * scale);
      ++i;
    } else {
      out.t_s.push_back(trajectory.inner_t_s[j]);
      out.value.push_back(trajectory.inner_state[j][component] * scale);
      ++j;
    }
  }
  return out;
}

// The duty a trajectory's law sent at each sample from `from_s` on: the samples whose duty a
// step's box bounds (sample k closes step k - 1; the start's is before any).
TubeTrace duty_trace(const verification::LoopTrajectory& trajectory, double from_s) {
  TubeTrace out;
  for (const verification::LoopSample& s : trajectory.samples) {
    if (s.t_s < from_s) continue;
    out.t_s.push_back(s.t_s);
    out.value.push_back(s.duty);
  }
  return out;
}

// One panel: its title, axes, the band, the bound, the trajectories, the failure's time.
std::string tube_panel(const PlotArea& area, const Ticks& time, const TubePanel& panel,
                       const std::optional<double>& failure_t_s, const std::string& failure_label) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto take = [&](double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  };
  for (const TubeSlice& s : panel.band) {
    take(s.lo);
    take(s.hi);
  }
  for (const TubeTrace& trace : panel.traces) {
    for (const double v : trace.value) take(v);
  }
  // The bound is drawn where it does not squeeze the tube into a line: within a few times the
  // data's extent; beyond that its label says so.
  const double extent = std::max(std::fabs(lo), std::fabs(hi));
  const bool bound_drawn = panel.bound && !(*panel.bound > kBoundScale * extent);
  if (bound_drawn) {
    take(*panel.bound);
    take(-*panel.bound);
  }
  const Ticks value = nice_ticks(lo, hi, 4, true);
  const auto X = [&](double t) {
    return area.x + std::clamp((t - time.lo) / (time.hi - time.lo), 0.0, 1.0) * area.width;
  };
  // An unbounded enclosure is drawn to the plot's edge.
  const auto Y = [&](double v) {
    return area.y + area.height -
           std::clamp((v - value.lo) / (value.hi - value.lo), 0.0, 1.0) * area.height;
  };

  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<g class=\"panel\" id=\"" << panel.id << "\">\n<text x=\"" << area.x << "\" y=\""
    << area.y - 7 << "\" font-size=\"12\">" << text::xml_escape(panel.title) << "</text>\n";
  s << svg_axes(area, time, value, "t [s]", panel.y_name);

  // The band: the steps within a column hulled, the upper edge forwards, the lower back.
  std::vector<TubeSlice> columns;
  for (const TubeSlice& slice : panel.band) {
    if (!(slice.lo <= slice.hi)) continue;  // an empty enclosure has nothing to draw
    if (!columns.empty() && X(columns.back().t1_s) - X(columns.back().t0_s) < kBandColumnPx) {
      TubeSlice& c = columns.back();
      c.t1_s = std::max(c.t1_s, slice.t1_s);
      c.lo = std::min(c.lo, slice.lo);
      c.hi = std::max(c.hi, slice.hi);
      continue;
    }
    columns.push_back(slice);
  }
  if (!columns.empty()) {
    s << "<polygon class=\"tube-band\" fill=\"" << panel.band_colour
      << "\" fill-opacity=\"0.35\" stroke=\"" << panel.band_colour
      << "\" stroke-width=\"0.5\" points=\"";
    for (const TubeSlice& c : columns) {
      s << X(c.t0_s) << "," << Y(c.hi) << " " << X(c.t1_s) << "," << Y(c.hi) << " ";
    }
    for (auto c = columns.rbegin(); c != columns.rend(); ++c) {
      s << X(c->t1_s) << "," << Y(c->lo) << " " << X(c->t0_s) << "," << Y(c->lo) << " ";
    }
    s << "\"/>\n";
  }

  if (panel.bound && !bound_drawn) {
    s << "<text x=\"" << area.x + area.width - 4 << "\" y=\"" << area.y + 12
      << "\" font-size=\"10\" text-anchor=\"end\" fill=\"#b00020\">"
      << text::xml_escape(panel.bound_label + ", beyond this scale") << "</text>\n";
  }
  if (bound_drawn) {
    for (const double v : {*panel.bound, -*panel.bound}) {
      s << "<line class=\"bound\" x1=\"" << area.x << "\" y1=\"" << Y(v) << "\" x2=\""
        << area.x + area.width << "\" y2=\"" << Y(v)
        << "\" stroke=\"#b00020\" stroke-width=\"1\" stroke-dasharray=\"6,4\"/>\n";
    }
    s << "<text x=\"" << area.x + area.width - 4 << "\" y=\"" << Y(*panel.bound) - 3
      << "\" font-size=\"10\" text-anchor=\"end\" fill=\"#b00020\">"
      << text::xml_escape(panel.bound_label) << "</text>\n";
  }

  const double columns_px = std::max(1.0, area.width / kTraceColumnPx);
  for (std::size_t k = 0; k < panel.traces.size(); ++k) {
    const TubeTrace& trace = panel.traces[k];
    s << "<polyline class=\"trajectory\" data-trajectory=\"" << k + 1
      << "\" fill=\"none\" stroke=\"" << kTrajectoryColours[k % kTrajectoryColours.size()]
      << "\" stroke-width=\"0.8\" points=\"";
    for (const std::size_t i : thinned(trace.t_s, trace.value, time.lo, time.hi, columns_px)) {
      if (std::isfinite(trace.value[i])) s << X(trace.t_s[i]) << "," << Y(trace.value[i]) << " ";
    }
    s << "\"/>\n";
  }

  if (failure_t_s) {
    const double x = X(*failure_t_s);
    s << "<line class=\"failure\" x1=\"" << x << "\" y1=\"" << area.y << "\" x2=\"" << x
      << "\" y2=\"" << area.y + area.height << "\" stroke=\"#c0392b\" stroke-width=\"1.5\"/>\n";
    // Above the plot, at its right end: inside it the label would cross the bound's line.
    if (!failure_label.empty()) {
      s << "<text class=\"failure-label\" x=\"" << area.x + area.width << "\" y=\"" << area.y - 7
        << "\" font-size=\"11\" text-anchor=\"end\" fill=\"#c0392b\">"
        << text::xml_escape(failure_label) << "</text>\n";
    }
  }
  s << "</g>\n";
  return s.str();
}

}  // namespace

std::string svg_verification(const VerificationReportInput& input) {
  // The tube the sampled check ran against: the start region's when the start box was not
  // certified and a region was.
  const verification::BalanceCertificate& c = input.sampled.on_start_region && input.start_region
                                                  ? input.start_region->certificate
                                                  : input.certificate;
  const std::vector<verification::LoopStepBox>& steps = c.steps;
  const std::vector<verification::LoopTrajectory>& drawn = input.sampled.drawn;

  // The time axis: the horizon asked, or as far as the steps went should they go further.
  double t_end = std::max(input.options.horizon_s, c.horizon_s);
  if (!steps.empty()) t_end = std::max(t_end, steps.back().t1_s);
  if (c.failure) t_end = std::max(t_end, c.failure->t_s);
  const Ticks time = nice_ticks(0.0, t_end > 0 ? t_end : 1.0, 5);

  TubePanel upright{"upright",
                    "pendulum angle from upright, q2 - pi",
                    "angle [deg]",
                    "#b03a2e",
                    {},
                    {},
                    input.limits.upright_rad * kDegPerRad,
                    "bound +-" + short_number(input.limits.upright_rad * kDegPerRad, 4) + " deg"};
  TubePanel arm{"arm", "arm angle, q1", "angle [deg]", "#1f4e9c", {}, {}, std::nullopt, ""};
  TubePanel duty{
      "duty", "duty the law sends at each sample", "duty", "#5b5b5b", {}, {}, std::nullopt, ""};
  for (const verification::LoopStepBox& step : steps) {
    const auto& q2 = step.over[1];
    const auto& q1 = step.over[0];
    upright.band.push_back({step.t0_s, step.t1_s, q2.lo() * kDegPerRad, q2.hi() * kDegPerRad});
    arm.band.push_back({step.t0_s, step.t1_s, q1.lo() * kDegPerRad, q1.hi() * kDegPerRad});
    duty.band.push_back({step.t1_s, step.t1_s, step.duty.lo(), step.duty.hi()});
  }
  // Sample k's duty is bounded by step k - 1's box, from the first step's end on; a hair early
  // so that a sample's time rounded differently from the step's still counts.
  const double duty_from_s =
      steps.empty() ? 0.0 : steps.front().t1_s - 1e-6 * (steps.front().t1_s - steps.front().t0_s);
  for (const verification::LoopTrajectory& trajectory : drawn) {
    upright.traces.push_back(state_trace(trajectory, 1, kDegPerRad));
    arm.traces.push_back(state_trace(trajectory, 0, kDegPerRad));
    duty.traces.push_back(duty_trace(trajectory, duty_from_s));
  }

  std::optional<double> failure_t_s;
  std::string failure_label;
  if (c.failure) {
    failure_t_s = c.failure->t_s;
    failure_label = "not certified: " + failure_kind_label(c.failure->kind) +
                    " at t = " + short_number(c.failure->t_s, 4) + " s";
  }

  const double W = 960, left = 72, right = 20, top = 58, plot_h = 120, row = 172;
  const double width = W - left - right;
  const double H = top + 2 * row + plot_h + 45;
  const auto area = [&](int r) { return PlotArea{left, top + r * row, width, plot_h}; };
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  const std::string verdict =
      c.certified() ? "certified to " + short_number(c.horizon_s, 4) + " s"
                    : "not certified: proven to " +
                          short_number(steps.empty() ? 0.0 : steps.back().t1_s, 4) + " s";
  s << "<text class=\"legend\" x=\"" << left << "\" y=\"20\" font-size=\"12\">"
    << text::xml_escape("Shaded: the tube, every state the loop can be in over each period (" +
                        verdict + "); lines: " + std::to_string(drawn.size()) +
                        " trajectories simulated point by point")
    << "</text>\n";
  s << tube_panel(area(0), time, upright, failure_t_s, failure_label);
  s << tube_panel(area(1), time, arm, failure_t_s, "");
  s << tube_panel(area(2), time, duty, failure_t_s, "");
  s << "</svg>\n";
  return s.str();
}

}  // namespace furuta::report
