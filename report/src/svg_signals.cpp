// Fig. 2/3 (an experiment's signals with their bands), Fig. 5 (the held-out torque) and the
// held-out free runs.
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <utility>

#include "furuta/common/text_format.hpp"
#include "furuta/report/axis.hpp"
#include "furuta/report/svg.hpp"

namespace furuta::report {

namespace {

// A small line plot of one or more series over time, each band (lower, upper) filled under them.
struct Trace {
  const std::vector<double>* y;
  const char* colour;
  const char* label;
};

struct Band {
  std::vector<double> lo, hi;
  const char* colour;
};

// A panel's value range: every finite value of its traces and bands.
std::pair<double, double> value_range(const std::vector<Trace>& traces,
                                      const std::vector<Band>& bands) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto take = [&](const std::vector<double>& values) {
    for (const double v : values) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  };
  for (const Trace& tr : traces) take(*tr.y);
  for (const Band& band : bands) {
    take(band.lo);
    take(band.hi);
  }
  return {lo, hi};
}

// One panel: its title above, a time axis "t [s]" and a value axis named `y_name` (with the
// unit), each scaled to its own data; a legend when it holds more than one trace.
std::string svg_panel(const PlotArea& area, const std::string& title, const std::string& y_name,
                      const std::vector<double>& t, const std::vector<Trace>& traces,
                      const std::vector<Band>& bands = {}) {
  const Ticks time = nice_ticks(t.empty() ? 0.0 : t.front(), t.size() > 1 ? t.back() : 1.0, 5);
  const auto [lo, hi] = value_range(traces, bands);
  const Ticks value = nice_ticks(lo, hi, 4, true);
  const auto X = [&](double tt) {
    return area.x + (tt - time.lo) / (time.hi - time.lo) * area.width;
  };
  const auto Y = [&](double v) {
    return area.y + area.height - (v - value.lo) / (value.hi - value.lo) * area.height;
  };
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<g class=\"panel\">\n<text x=\"" << area.x << "\" y=\"" << area.y - 7
    << "\" font-size=\"12\">" << text::xml_escape(title) << "</text>\n";
  s << svg_axes(area, time, value, "t [s]", y_name);
  for (const Band& band : bands) {
    const std::size_t n = std::min({t.size(), band.lo.size(), band.hi.size()});
    if (n == 0) continue;
    s << "<polygon class=\"band\" fill=\"" << band.colour
      << "\" fill-opacity=\"0.3\" stroke=\"none\" points=\"";
    for (std::size_t i = 0; i < n; ++i) {
      if (std::isfinite(band.hi[i])) s << X(t[i]) << "," << Y(band.hi[i]) << " ";
    }
    for (std::size_t i = n; i-- > 0;) {
      if (std::isfinite(band.lo[i])) s << X(t[i]) << "," << Y(band.lo[i]) << " ";
    }
    s << "\"/>\n";
  }
  double legend_x = area.x + area.width - 80.0 * static_cast<double>(traces.size());
  for (const Trace& tr : traces) {
    s << "<polyline class=\"trace\" fill=\"none\" stroke=\"" << tr.colour
      << "\" stroke-width=\"1\" points=\"";
    for (std::size_t i = 0; i < t.size() && i < tr.y->size(); ++i) {
      if (std::isfinite((*tr.y)[i])) s << X(t[i]) << "," << Y((*tr.y)[i]) << " ";
    }
    s << "\"/>\n";
    if (traces.size() > 1) {
      s << "<text x=\"" << legend_x << "\" y=\"" << area.y - 7 << "\" font-size=\"11\" fill=\""
        << tr.colour << "\">" << text::xml_escape(tr.label) << "</text>\n";
      legend_x += 80;
    }
  }
  s << "</g>\n";
  return s.str();
}

// value +- (absolute + relative |value|): the interval SIVIA gives each sample.
Band bound_band(const std::vector<double>& value, const identification::ChannelErrorBound& bound,
                const char* colour) {
  Band band{value, value, colour};
  for (std::size_t i = 0; i < value.size(); ++i) {
    const double half_width = bound.absolute + bound.relative * std::abs(value[i]);
    band.lo[i] -= half_width;
    band.hi[i] += half_width;
  }
  return band;
}

std::string svg_document(double width, double height, const std::string& body) {
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << body << "</svg>\n";
  return s.str();
}

}  // namespace

std::string svg_signals(const identification::RawExperiment& raw,
                        const identification::JointSeries& p, double angle_resolution_rad,
                        const identification::DataErrorBounds* bounds) {
  const char* arm = "#1f4e9c";
  const char* pendulum = "#b03a2e";
  // The arm's column and the pendulum's, each signal on an axis of its own: a multi-turn arm
  // (hundreds of rad) and a pendulum swinging by one would flatten each other on a shared one.
  const double W = 960, left = 72, gap = 80, right = 20, top = 58, plot_h = 110, row = 172;
  const double column_w = (W - left - gap - right) / 2;
  const auto area = [&](int column, int r) {
    return PlotArea{left + column * (column_w + gap), top + r * row, column_w, plot_h};
  };
  std::optional<identification::ChannelErrorBound> q2_band, dq1_band, dq2_band, ddq1_band,
      ddq2_band, tau_band;
  std::string note;
  if (bounds == nullptr) {
    // The encoders' quantisation on the pendulum angle: all that is known without [sivia].
    q2_band = identification::ChannelErrorBound{angle_resolution_rad, 0};
    note = "band: the pendulum encoder's quantisation";
  } else {
    // The data boxes SIVIA works with: the preprocessed value +- its bound, per channel.
    q2_band = bounds->q2;
    dq1_band = bounds->dq1;
    dq2_band = bounds->dq2;
    ddq1_band = bounds->ddq1;
    ddq2_band = bounds->ddq2;
    tau_band = bounds->tau;
    note = "bands: the data error bounds of [sivia]";
  }
  const auto bands = [](const std::optional<identification::ChannelErrorBound>& bound,
                        const std::vector<double>& value, const char* colour) {
    return bound ? std::vector<Band>{bound_band(value, *bound, colour)} : std::vector<Band>{};
  };
  std::string body = "<text x=\"" + std::to_string(static_cast<int>(left)) +
                     "\" y=\"22\" font-size=\"14\">" +
                     text::xml_escape(p.name + " (" + note + ")") + "</text>\n";
  // The pendulum's angle band is drawn around the raw (quantised) angle without bounds, around
  // the preprocessed one with them, as SIVIA's data boxes are.
  const std::vector<double>& q2_centre = bounds == nullptr ? raw.q2 : p.q2;
  body += svg_panel(area(0, 0), "arm angle q1", "q1 [rad]", p.t_s, {{&raw.q1, arm, "q1"}});
  body += svg_panel(area(1, 0), "pendulum angle q2", "q2 [rad]", p.t_s, {{&raw.q2, pendulum, "q2"}},
                    bands(q2_band, q2_centre, bounds == nullptr ? "#f4c7a1" : pendulum));
  body += svg_panel(area(0, 1), "arm velocity dq1", "dq1 [rad/s]", p.t_s, {{&p.dq1, arm, "dq1"}},
                    bands(dq1_band, p.dq1, arm));
  body += svg_panel(area(1, 1), "pendulum velocity dq2", "dq2 [rad/s]", p.t_s,
                    {{&p.dq2, pendulum, "dq2"}}, bands(dq2_band, p.dq2, pendulum));
  body += svg_panel(area(0, 2), "arm acceleration ddq1", "ddq1 [rad/s^2]", p.t_s,
                    {{&p.ddq1, arm, "ddq1"}}, bands(ddq1_band, p.ddq1, arm));
  body += svg_panel(area(1, 2), "pendulum acceleration ddq2", "ddq2 [rad/s^2]", p.t_s,
                    {{&p.ddq2, pendulum, "ddq2"}}, bands(ddq2_band, p.ddq2, pendulum));
  const PlotArea torque{left, top + 3 * row, W - left - right, plot_h};
  body += svg_panel(torque, "motor torque at the arm tau", "tau [N m]", p.t_s,
                    {{&p.tau, "#222", "tau"}}, bands(tau_band, p.tau, "#222"));
  return svg_document(W, torque.y + plot_h + 42, body);
}

std::string svg_torque_validation(const identification::ValidationResult& v) {
  const double W = 900, H = 340, left = 72, top = 58;
  std::ostringstream title;
  title << "held-out " << v.name << ": measured vs LSMI-predicted torque, RMSE " << std::fixed
        << std::setprecision(2) << v.fit.rmse_percent_of_range << " % of its range";
  const std::string body =
      "<text x=\"" + std::to_string(static_cast<int>(left)) + "\" y=\"22\" font-size=\"14\">" +
      text::xml_escape(title.str()) + "</text>\n" +
      svg_panel(PlotArea{left, top, W - left - 20, H - top - 45}, "motor torque at the arm tau",
                "tau [N m]", v.series.t_s,
                {{&v.series.tau, "#222", "measured"}, {&v.fit.predicted, "#b03a2e", "LSMI"}});
  return svg_document(W, H, body);
}

std::string svg_free_runs(const std::string& name, const identification::FreeRun* lsmi,
                          const identification::FreeRun& refined) {
  const double W = 900, left = 72, top = 58, plot_h = 150, row = 212;
  // The observations interleave the joints; both runs have the held-out recording's, in order.
  struct Joint {
    std::vector<double> t_s, measured, lsmi, refined;
  };
  std::array<Joint, 2> joints;
  for (std::size_t i = 0; i < refined.t_s.size() && i < refined.simulated.size(); ++i) {
    Joint& j = joints.at(static_cast<std::size_t>(refined.joint[i] == 0 ? 0 : 1));
    j.t_s.push_back(refined.t_s[i]);
    j.measured.push_back(refined.measured[i]);
    if (lsmi != nullptr && i < lsmi->simulated.size()) j.lsmi.push_back(lsmi->simulated[i]);
    j.refined.push_back(refined.simulated[i]);
  }
  std::string body =
      "<text x=\"" + std::to_string(static_cast<int>(left)) + "\" y=\"22\" font-size=\"14\">" +
      text::xml_escape("held-out " + name + ": measured angles vs free runs with " +
                       (lsmi != nullptr ? "LSMI and " : "") + "output-error parameters") +
      "</text>\n";
  const char* names[2] = {"arm angle q1", "pendulum angle q2"};
  const char* axes[2] = {"q1 [rad]", "q2 [rad]"};
  for (std::size_t k = 0; k < 2; ++k) {
    std::ostringstream title;
    title << names[k] << ", RMSE " << std::setprecision(3);
    if (lsmi != nullptr) title << "LSMI " << lsmi->rmse_rad[k] << " rad, ";
    title << "output error " << refined.rmse_rad[k] << " rad";
    const Joint& j = joints[k];
    std::vector<Trace> traces = {{&j.measured, "#222", "measured"}};
    if (lsmi != nullptr) traces.push_back({&j.lsmi, "#b03a2e", "LSMI"});
    traces.push_back({&j.refined, "#1f4e9c", "output error"});
    body += svg_panel(PlotArea{left, top + static_cast<double>(k) * row, W - left - 20, plot_h},
                      title.str(), axes[k], j.t_s, traces);
  }
  return svg_document(W, top + row + plot_h + 42, body);
}

}  // namespace furuta::report
