// The windowed set against its search box: one row per scaled parameter, in the estimate's sd.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "furuta/identification/physical_inputs.hpp"
#include "furuta/report/axis.hpp"
#include "furuta/report/svg.hpp"

namespace furuta::report {

std::size_t deciding_step(const pipeline::WindowedGuaranteed& w, std::size_t k) {
  const identification::WindowedSet& r = w.result;
  const double final_width = r.set[k].width();
  if (!(final_width < r.search[k].width())) return 0;
  for (std::size_t s = 0; s < r.set_after_step.size(); ++s) {
    if (r.set_after_step[s][k].width() <= 1.01 * final_width) return s + 1;
  }
  return r.set_after_step.size();
}

std::string svg_windowed_set(const pipeline::WindowedGuaranteed& w) {
  const identification::WindowedSet& r = w.result;
  const std::size_t n = model::kParameterCount;
  const double row = 34, W = 640, left = 70, right = 150, top = 40;
  const double pw = W - left - right, ph = row * static_cast<double>(n);
  const double H = top + ph + 60;
  // Offsets from the estimate in its sd; the search box spans +- search_sd.
  const double reach = std::max(1.1 * w.search_sd, 1e-9);
  const Ticks x = nice_ticks(-reach, reach, 4);
  Ticks y;
  y.lo = 0;
  y.hi = static_cast<double>(n);
  const auto X = [&](double v, std::size_t k) {
    const double sd = w.std_dev_scaled[k];
    const double z = sd > 0 ? (v - w.estimate_scaled[k]) / sd : 0.0;
    return left + (std::clamp(z, x.lo, x.hi) - x.lo) / (x.hi - x.lo) * pw;
  };
  std::ostringstream s;
  s << std::setprecision(6);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\">\n";
  s << "<text x=\"" << left << "\" y=\"24\" font-size=\"14\">Windowed set: " << r.windows.size()
    << " windows in " << r.set_after_step.size() << " steps, against the search box</text>\n";
  s << svg_axes(PlotArea{left, top, pw, ph}, x, y, "offset from the output-error estimate [its sd]",
                "");
  for (std::size_t k = 0; k < n; ++k) {
    const double yc = top + row * (static_cast<double>(k) + 0.5);
    const auto bar = [&](const interval::Interval& v, double height, const char* fill,
                         const char* cls) {
      const double x0 = X(v.lo(), k), x1 = X(v.hi(), k);
      s << "<rect class=\"" << cls << "\" data-parameter=\""
        << identification::kScaledParameterNames[k] << "\" x=\"" << x0 << "\" y=\""
        << yc - height / 2 << "\" width=\"" << std::max(x1 - x0, 1.0) << "\" height=\"" << height
        << "\" fill=\"" << fill << "\"/>\n";
    };
    bar(r.search[k], 16, "#d9d9d9", "search");
    bar(r.set[k], 8, "#3d85c6", "set");
    s << "<line x1=\"" << X(w.estimate_scaled[k], k) << "\" x2=\"" << X(w.estimate_scaled[k], k)
      << "\" y1=\"" << yc - 10 << "\" y2=\"" << yc + 10 << "\" stroke=\"#000\"/>\n";
    if (w.truth_scaled) {
      s << "<circle class=\"truth\" cx=\"" << X((*w.truth_scaled)[k], k) << "\" cy=\"" << yc
        << "\" r=\"4\" fill=\"none\" stroke=\"#cc0000\" stroke-width=\"1.5\"/>\n";
    }
    s << "<text x=\"" << left - 6 << "\" y=\"" << yc + 4 << "\" font-size=\"11\" "
      << "text-anchor=\"end\">" << identification::kScaledParameterNames[k] << "</text>\n";
    const std::size_t step = deciding_step(w, k);
    const double sd = w.std_dev_scaled[k];
    const double half_sd = sd > 0 ? 0.5 * r.set[k].width() / sd : 0.0;
    std::ostringstream label;
    label << std::setprecision(3) << "+-" << half_sd << " sd, "
          << (step == 0 ? std::string("not narrowed") : "step " + std::to_string(step));
    s << "<text x=\"" << left + pw + 8 << "\" y=\"" << yc + 4 << "\" font-size=\"11\">"
      << label.str() << "</text>\n";
  }
  s << "<text x=\"" << left << "\" y=\"" << H - 10
    << "\" font-size=\"11\"><tspan fill=\"#888\">search box</tspan>  <tspan "
       "fill=\"#3d85c6\">set</tspan>  | estimate"
    << (w.truth_scaled ? "  <tspan fill=\"#cc0000\">o truth</tspan>" : "")
    << "; right: the set's half-width and the step that narrowed it</text>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace furuta::report
