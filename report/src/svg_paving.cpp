// Fig. 4: the SIVIA paving projected on two parameters.
#include <algorithm>
#include <iomanip>
#include <sstream>
#include <string>

#include "furuta/report/axis.hpp"
#include "furuta/report/svg.hpp"

namespace furuta::report {

std::string svg_paving(const identification::GuaranteedResult& r, int xp, int yp,
                       const std::vector<double>* reference) {
  const auto& p = r.paving;
  // The view: the outer hull with a margin (the prior if the set is empty).
  interval::Box view = r.empty ? p.prior : p.outer_hull();
  const double W = 640, H = 480, left = 90, top = 40, pw = W - left - 30, ph = H - top - 70;
  auto range = [&](int k) {
    double lo = view[static_cast<std::size_t>(k)].lo(), hi = view[static_cast<std::size_t>(k)].hi();
    const double margin = std::max(0.15 * (hi - lo), 1e-12);
    return std::pair{lo - margin, hi + margin};
  };
  // Plain variables, not structured bindings: lambdas capturing those need clang 16, and the fuzz
  // build (scripts/fuzz.sh) compiles this with Debian 12's clang 14.
  const std::pair<double, double> x_range = range(xp), y_range = range(yp);
  const double x_lo = x_range.first, x_hi = x_range.second;
  const double y_lo = y_range.first, y_hi = y_range.second;
  auto X = [&](double v) { return left + (v - x_lo) / (x_hi - x_lo) * pw; };
  auto Y = [&](double v) { return top + ph - (v - y_lo) / (y_hi - y_lo) * ph; };
  std::ostringstream s;
  s << std::setprecision(6);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\">\n";
  s << "<text x=\"" << left << "\" y=\"24\" font-size=\"14\">SIVIA paving: " << p.inner.size()
    << " inner, " << p.boundary.size() << " boundary, " << p.outer_count << " outer boxes ("
    << p.boxes_tested << " tested, " << std::setprecision(3) << p.seconds << " s)</text>\n"
    << std::setprecision(6);
  // Axes at nice ticks, named with their units; the grid under the boxes.
  const auto name = [](int k) {
    return std::string(model::kParameterNames[static_cast<std::size_t>(k)]) + " [" +
           model::kParameterUnits[static_cast<std::size_t>(k)] + "]";
  };
  s << svg_axes(PlotArea{left, top, pw, ph}, nice_ticks(x_lo, x_hi, 4), nice_ticks(y_lo, y_hi, 4),
                name(xp), name(yp));
  s << "<clipPath id=\"plot\"><rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << pw
    << "\" height=\"" << ph << "\"/></clipPath>\n<g clip-path=\"url(#plot)\">\n";
  const auto draw = [&](const std::vector<interval::Box>& boxes, const char* fill,
                        const char* cls) {
    for (const interval::Box& b : boxes) {
      const interval::Interval& bx = b[static_cast<std::size_t>(xp)];
      const interval::Interval& by = b[static_cast<std::size_t>(yp)];
      const double x0 = std::max(X(bx.lo()), left - 1), x1 = std::min(X(bx.hi()), left + pw + 1);
      const double y0 = std::max(Y(by.hi()), top - 1), y1 = std::min(Y(by.lo()), top + ph + 1);
      if (x1 < x0 || y1 < y0) continue;
      s << "<rect class=\"" << cls << "\" x=\"" << x0 << "\" y=\"" << y0 << "\" width=\""
        << std::max(x1 - x0, 0.5) << "\" height=\"" << std::max(y1 - y0, 0.5) << "\" fill=\""
        << fill << "\" stroke=\"#333\" stroke-width=\"0.2\"/>\n";
    }
  };
  draw(p.outer, "#6fa8dc", "outer");
  draw(p.boundary, "#ffd966", "boundary");
  draw(p.inner, "#e06666", "inner");
  if (reference && reference->size() == static_cast<std::size_t>(model::kParameterCount)) {
    s << "<circle cx=\"" << X((*reference)[static_cast<std::size_t>(xp)]) << "\" cy=\""
      << Y((*reference)[static_cast<std::size_t>(yp)])
      << "\" r=\"4\" fill=\"none\" stroke=\"black\" stroke-width=\"1.5\"/>\n";
  }
  s << "</g>\n<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << pw << "\" height=\"" << ph
    << "\" fill=\"none\" stroke=\"#000\"/>\n";
  s << "<text x=\"" << left << "\" y=\"" << H - 10
    << "\" font-size=\"11\"><tspan fill=\"#e06666\">inner</tspan>  <tspan "
       "fill=\"#b8860b\">boundary</tspan>  <tspan fill=\"#6fa8dc\">outer</tspan>"
    << (r.empty ? "  (empty: no parameter is consistent)" : "") << "</text>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace furuta::report
