// A balance session's figure: the angle from upright, the arm angle, the duty and the mode over
// time, four panels on one time axis.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "furuta/common/text_format.hpp"
#include "furuta/report/axis.hpp"
#include "furuta/report/balance_page.hpp"
#include "furuta/rig_control_t.hpp"
#include "thinning.hpp"

namespace furuta::report {

namespace {

// The modes in rig_control_t's order, with the colour each is drawn in.
struct ModeStyle {
  std::int8_t mode;
  const char* name;
  const char* colour;
};
constexpr ModeStyle kModes[] = {
    {furuta::rig_control_t::MODE_SWING_UP, "swing-up", "#9aa5b1"},
    {furuta::rig_control_t::MODE_CATCH, "catch", "#e0a526"},
    {furuta::rig_control_t::MODE_BALANCE, "balance", "#3f9b4f"},
    {furuta::rig_control_t::MODE_FALLEN, "fallen", "#c0392b"},
};

const ModeStyle* style_of(std::int8_t mode) {
  for (const ModeStyle& m : kModes) {
    if (m.mode == mode) return &m;
  }
  return nullptr;
}

// One panel of a value over time: its title above, axes, the trace.
std::string value_panel(const PlotArea& area, const char* id, const std::string& title,
                        const std::string& y_name, const Ticks& time, const std::vector<double>& t,
                        const std::vector<double>& y, const char* colour) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : y) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  const Ticks value = nice_ticks(lo, hi, 4, true);
  const auto X = [&](double tt) {
    return area.x + (tt - time.lo) / (time.hi - time.lo) * area.width;
  };
  const auto Y = [&](double v) {
    return area.y + area.height - (v - value.lo) / (value.hi - value.lo) * area.height;
  };
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<g class=\"panel\" id=\"" << id << "\">\n<text x=\"" << area.x << "\" y=\"" << area.y - 7
    << "\" font-size=\"12\">" << text::xml_escape(title) << "</text>\n";
  s << svg_axes(area, time, value, "t [s]", y_name);
  s << "<polyline class=\"trace\" fill=\"none\" stroke=\"" << colour
    << "\" stroke-width=\"1\" points=\"";
  for (const std::size_t i : thinned(t, y, time.lo, time.hi, area.width)) {
    if (std::isfinite(y[i])) s << X(t[i]) << "," << Y(y[i]) << " ";
  }
  s << "\"/>\n</g>\n";
  return s.str();
}

// The mode as bands: each run of cycles in one mode a rectangle from its first cycle's time to the
// next run's, in the mode's colour; the legend above names the colours.
std::string mode_panel(const PlotArea& area, const Ticks& time, const std::vector<double>& t,
                       const std::vector<std::int8_t>& mode) {
  const auto X = [&](double tt) {
    return area.x + std::clamp((tt - time.lo) / (time.hi - time.lo), 0.0, 1.0) * area.width;
  };
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<g class=\"panel\" id=\"mode\">\n<text x=\"" << area.x << "\" y=\"" << area.y - 7
    << "\" font-size=\"12\">controller mode</text>\n";
  double legend_x = area.x + area.width - 90.0 * std::size(kModes);
  for (const ModeStyle& m : kModes) {
    s << "<rect x=\"" << legend_x << "\" y=\"" << area.y - 16 << "\" width=\"10\" height=\"10\" "
      << "fill=\"" << m.colour << "\"/><text x=\"" << legend_x + 14 << "\" y=\"" << area.y - 7
      << "\" font-size=\"11\">" << m.name << "</text>\n";
    legend_x += 90;
  }
  const std::size_t n = std::min(t.size(), mode.size());
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i;
    while (j < n && mode[j] == mode[i]) ++j;
    const double from = X(t[i]);
    // The run lasts until the next run starts; the last one to its own last cycle.
    const double to = X(j < n ? t[j] : t[n - 1]);
    const ModeStyle* m = style_of(mode[i]);
    s << "<rect class=\"mode-band\" data-mode=\"" << (m ? m->name : "unknown") << "\" x=\"" << from
      << "\" y=\"" << area.y << "\" width=\"" << std::max(to - from, 0.5) << "\" height=\""
      << area.height << "\" fill=\"" << (m ? m->colour : "#000000") << "\"/>\n";
    i = j;
  }
  s << svg_axes(area, time, Ticks{0, 1, 1, {}}, "t [s]", "");
  s << "</g>\n";
  return s.str();
}

}  // namespace

std::string svg_balance(const pipeline::BalanceSummary& b) {
  const double W = 960, left = 72, right = 20, top = 40, plot_h = 110, row = 162, mode_h = 26;
  const double width = W - left - right;
  const std::vector<double>& t = b.time_s;
  const Ticks time = nice_ticks(t.empty() ? 0.0 : t.front(), t.size() > 1 ? t.back() : 1.0, 5);
  const auto area = [&](int r, double h) { return PlotArea{left, top + r * row, width, h}; };
  const double H = top + 3 * row + mode_h + 45;
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << value_panel(area(0, plot_h), "upright", "pendulum angle from upright", "angle [deg]", time,
                   t, b.upright_error_deg, "#b03a2e");
  s << value_panel(area(1, plot_h), "arm", "arm angle", "angle [deg]", time, t, b.arm_deg,
                   "#1f4e9c");
  s << value_panel(area(2, plot_h), "duty", "commanded duty", "duty", time, t, b.duty, "#222222");
  s << mode_panel(area(3, mode_h), time, t, b.mode);
  s << "</svg>\n";
  return s.str();
}

}  // namespace furuta::report
