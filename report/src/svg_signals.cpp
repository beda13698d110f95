// Fig. 2/3 (an experiment's signals with their bands) and Fig. 5 (the held-out torque).
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "furuta/common/text_format.hpp"
#include "furuta/report/svg.hpp"

namespace furuta::report {

namespace {

// A small line plot: each series a polyline, each band (lower, upper) filled under them.
struct Trace {
  const std::vector<double>* y;
  const char* colour;
  const char* label;
};

struct Band {
  std::vector<double> lo, hi;
  const char* colour;
};

std::string svg_panel(double x0, double y0, double width, double height, const std::string& title,
                      const std::vector<double>& t, const std::vector<Trace>& traces,
                      const std::vector<Band>& bands = {}) {
  double lo = 0, hi = 0;
  bool first = true;
  for (const Trace& tr : traces) {
    for (double v : *tr.y) {
      if (!std::isfinite(v)) continue;
      lo = first ? v : std::min(lo, v);
      hi = first ? v : std::max(hi, v);
      first = false;
    }
  }
  for (const Band& band : bands) {
    for (double v : band.lo) lo = std::min(lo, v);
    for (double v : band.hi) hi = std::max(hi, v);
  }
  if (hi <= lo) hi = lo + 1;
  const double t0 = t.empty() ? 0 : t.front();
  const double t1 = t.size() > 1 ? t.back() : t0 + 1;
  auto X = [&](double tt) { return x0 + (tt - t0) / (t1 - t0) * width; };
  auto Y = [&](double v) { return y0 + height - (v - lo) / (hi - lo) * height; };
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << width << "\" height=\"" << height
    << "\" fill=\"none\" stroke=\"#999\"/>\n";
  s << "<text x=\"" << x0 << "\" y=\"" << y0 - 6 << "\" font-size=\"13\">"
    << text::xml_escape(title) << "</text>\n";
  s << "<text x=\"" << x0 - 4 << "\" y=\"" << y0 + 10 << "\" font-size=\"10\" text-anchor=\"end\">"
    << std::setprecision(3) << hi << "</text>\n";
  s << "<text x=\"" << x0 - 4 << "\" y=\"" << y0 + height << "\" font-size=\"10\" "
    << "text-anchor=\"end\">" << lo << "</text>\n"
    << std::setprecision(1);
  for (const Band& band : bands) {
    const std::size_t n = std::min({t.size(), band.lo.size(), band.hi.size()});
    if (n == 0) continue;
    s << "<polygon class=\"band\" fill=\"" << band.colour
      << "\" fill-opacity=\"0.3\" stroke=\"none\" points=\"";
    for (std::size_t i = 0; i < n; ++i) s << X(t[i]) << "," << Y(band.hi[i]) << " ";
    for (std::size_t i = n; i-- > 0;) s << X(t[i]) << "," << Y(band.lo[i]) << " ";
    s << "\"/>\n";
  }
  double legend_x = x0 + width - 160;
  for (const Trace& tr : traces) {
    s << "<polyline fill=\"none\" stroke=\"" << tr.colour << "\" stroke-width=\"1\" points=\"";
    for (std::size_t i = 0; i < t.size() && i < tr.y->size(); ++i) {
      s << X(t[i]) << "," << Y((*tr.y)[i]) << " ";
    }
    s << "\"/>\n";
    s << "<text x=\"" << legend_x << "\" y=\"" << y0 + 14 << "\" font-size=\"11\" fill=\""
      << tr.colour << "\">" << text::xml_escape(tr.label) << "</text>\n";
    legend_x += 80;
  }
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
    << body << "</svg>\n";
  return s.str();
}

}  // namespace

std::string svg_signals(const identification::RawExperiment& raw,
                        const identification::JointSeries& p, double angle_resolution_rad,
                        const identification::DataErrorBounds* bounds) {
  const char* arm = "#1f4e9c";
  const char* pendulum = "#b03a2e";
  const double W = 900, H = 170, left = 70;
  std::string body;
  double y = 30;
  if (bounds == nullptr) {
    // The encoders' quantisation on the pendulum angle: all that is known without [sivia].
    identification::ChannelErrorBound quantisation{angle_resolution_rad, 0};
    body +=
        svg_panel(left, y, W - left - 20, H - 40, p.name + ": angles [rad] (band: quantisation)",
                  p.t_s, {{&raw.q1, arm, "q1"}, {&raw.q2, pendulum, "q2"}},
                  {bound_band(raw.q2, quantisation, "#f4c7a1")});
    y += H;
    body += svg_panel(left, y, W - left - 20, H - 40, "velocities [rad/s]", p.t_s,
                      {{&p.dq1, arm, "dq1"}, {&p.dq2, pendulum, "dq2"}});
    y += H;
    body += svg_panel(left, y, W - left - 20, H - 40, "accelerations [rad/s^2]", p.t_s,
                      {{&p.ddq1, arm, "ddq1"}, {&p.ddq2, pendulum, "ddq2"}});
    y += H;
    body += svg_panel(left, y, W - left - 20, H - 40, "motor torque at the arm [N m]", p.t_s,
                      {{&p.tau, "#222", "tau"}});
  } else {
    // The data boxes SIVIA works with: the preprocessed value +- its bound, per channel.
    const std::string note = " (bands: data error bounds)";
    body += svg_panel(left, y, W - left - 20, H - 40, p.name + ": angles [rad]" + note, p.t_s,
                      {{&raw.q1, arm, "q1"}, {&raw.q2, pendulum, "q2"}},
                      {bound_band(p.q2, bounds->q2, pendulum)});
    y += H;
    body +=
        svg_panel(left, y, W - left - 20, H - 40, "velocities [rad/s]" + note, p.t_s,
                  {{&p.dq1, arm, "dq1"}, {&p.dq2, pendulum, "dq2"}},
                  {bound_band(p.dq1, bounds->dq1, arm), bound_band(p.dq2, bounds->dq2, pendulum)});
    y += H;
    body += svg_panel(
        left, y, W - left - 20, H - 40, "accelerations [rad/s^2]" + note, p.t_s,
        {{&p.ddq1, arm, "ddq1"}, {&p.ddq2, pendulum, "ddq2"}},
        {bound_band(p.ddq1, bounds->ddq1, arm), bound_band(p.ddq2, bounds->ddq2, pendulum)});
    y += H;
    body += svg_panel(left, y, W - left - 20, H - 40, "motor torque at the arm [N m]" + note, p.t_s,
                      {{&p.tau, "#222", "tau"}}, {bound_band(p.tau, bounds->tau, "#222")});
  }
  return svg_document(W, y + H - 20, body);
}

std::string svg_torque_validation(const identification::ValidationResult& v) {
  const double W = 900, H = 320, left = 70;
  std::ostringstream title;
  title << "held-out " << v.name << ": measured vs LSMI-predicted torque [N m], RMSE " << std::fixed
        << std::setprecision(2) << v.fit.rmse_percent_of_range << " %";
  const std::string body =
      svg_panel(left, 30, W - left - 20, H - 60, title.str(), v.series.t_s,
                {{&v.series.tau, "#222", "measured"}, {&v.fit.predicted, "#b03a2e", "LSMI"}});
  return svg_document(W, H, body);
}

}  // namespace furuta::report
