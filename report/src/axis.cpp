// The figures' axes: nice ticks, their labels and their SVG.
#include "furuta/report/axis.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

#include "furuta/common/text_format.hpp"

namespace furuta::report {

namespace {

// Multiples of `step` in [lo, hi], allowing for the rounding of lo / step.
std::pair<double, double> tick_span(double lo, double hi, double step) {
  return {std::ceil(lo / step - 1e-9), std::floor(hi / step + 1e-9)};
}

}  // namespace

Ticks nice_ticks(double lo, double hi, int min_count, bool grow) {
  min_count = std::max(min_count, 2);
  if (!std::isfinite(lo)) lo = std::isfinite(hi) ? hi : 0.0;
  if (!std::isfinite(hi)) hi = lo;
  if (lo > hi) std::swap(lo, hi);
  // A range narrower than the doubles can resolve around it has no ticks of its own: it is drawn
  // as a constant, one per cent either side of its value.
  const double magnitude = std::max(std::abs(lo), std::abs(hi));
  if (!(hi - lo > 1e-12 * magnitude)) {
    const double mid = 0.5 * (lo + hi);
    const double half = mid == 0.0 ? 1.0 : std::max(std::abs(mid) * 0.01, DBL_MIN * 1e3);
    lo = mid - half;
    hi = mid + half;
  }
  const double span = hi - lo;
  // From the largest candidate down: 5, 2, 1 times 10^e.
  double step = 0;
  for (int e = static_cast<int>(std::floor(std::log10(span))); step == 0; --e) {
    for (const double mantissa : {5.0, 2.0, 1.0}) {
      const double candidate = mantissa * std::pow(10.0, e);
      const auto [first, last] = tick_span(lo, hi, candidate);
      if (last - first + 1 >= min_count) {
        step = candidate;
        break;
      }
    }
  }
  Ticks t;
  t.step = step;
  auto [first, last] = tick_span(lo, hi, step);
  if (grow) {
    first = std::min(first, std::floor(lo / step + 1e-9));
    last = std::max(last, std::ceil(hi / step - 1e-9));
  }
  // Grown, the range ends at its outer ticks, but never inside the data (k * step may round in).
  t.lo = grow ? std::min(first * step, lo) : lo;
  t.hi = grow ? std::max(last * step, hi) : hi;
  for (double k = first; k <= last; k += 1) {
    const double v = k * step;
    // k * step of an exact zero is 0, but a tick one rounding away from it would print "-0".
    t.values.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  }
  return t;
}

std::string tick_label(double value, double step) {
  if (!std::isfinite(value)) return "-";
  if (!(step > 0) || std::abs(value) < step * 1e-6) return "0";
  const int step_exponent = static_cast<int>(std::floor(std::log10(step) + 1e-9));
  const int decimals = std::max(0, -step_exponent);
  std::ostringstream s;
  if (decimals <= 6 && std::abs(value) < 1e6) {
    s << std::fixed << std::setprecision(decimals) << value;
  } else {
    const int value_exponent = static_cast<int>(std::floor(std::log10(std::abs(value))));
    s << std::scientific << std::setprecision(std::max(0, value_exponent - step_exponent)) << value;
  }
  return s.str();
}

std::string svg_axes(const PlotArea& a, const Ticks& x, const Ticks& y, const std::string& x_name,
                     const std::string& y_name) {
  const auto X = [&](double v) { return a.x + (v - x.lo) / (x.hi - x.lo) * a.width; };
  const auto Y = [&](double v) { return a.y + a.height - (v - y.lo) / (y.hi - y.lo) * a.height; };
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  s << "<g class=\"grid\" stroke=\"#e2e2e2\" stroke-width=\"0.6\">\n";
  for (const double v : x.values) {
    s << "<line x1=\"" << X(v) << "\" y1=\"" << a.y << "\" x2=\"" << X(v) << "\" y2=\""
      << a.y + a.height << "\"/>\n";
  }
  for (const double v : y.values) {
    s << "<line x1=\"" << a.x << "\" y1=\"" << Y(v) << "\" x2=\"" << a.x + a.width << "\" y2=\""
      << Y(v) << "\"/>\n";
  }
  s << "</g>\n";
  s << "<rect x=\"" << a.x << "\" y=\"" << a.y << "\" width=\"" << a.width << "\" height=\""
    << a.height << "\" fill=\"none\" stroke=\"#777\"/>\n";
  s << "<g class=\"axis x\" data-ticks=\"" << x.values.size()
    << "\" font-size=\"10\" text-anchor=\"middle\">\n";
  for (const double v : x.values) {
    s << "<line x1=\"" << X(v) << "\" y1=\"" << a.y + a.height << "\" x2=\"" << X(v) << "\" y2=\""
      << a.y + a.height + 4 << "\" stroke=\"#777\"/>";
    s << "<text class=\"tick\" x=\"" << X(v) << "\" y=\"" << a.y + a.height + 15 << "\">"
      << tick_label(v, x.step) << "</text>\n";
  }
  s << "<text class=\"axis-label\" x=\"" << a.x + a.width / 2 << "\" y=\"" << a.y + a.height + 29
    << "\" font-size=\"11\">" << text::xml_escape(x_name) << "</text>\n</g>\n";
  if (y.values.empty() && y_name.empty()) return s.str();
  s << "<g class=\"axis y\" data-ticks=\"" << y.values.size()
    << "\" font-size=\"10\" text-anchor=\"end\">\n";
  for (const double v : y.values) {
    s << "<line x1=\"" << a.x - 4 << "\" y1=\"" << Y(v) << "\" x2=\"" << a.x << "\" y2=\"" << Y(v)
      << "\" stroke=\"#777\"/>";
    s << "<text class=\"tick\" x=\"" << a.x - 6 << "\" y=\"" << Y(v) + 3.5 << "\">"
      << tick_label(v, y.step) << "</text>\n";
  }
  const double name_x = a.x - 50, name_y = a.y + a.height / 2;
  s << "<text class=\"axis-label\" x=\"" << name_x << "\" y=\"" << name_y
    << "\" font-size=\"11\" text-anchor=\"middle\" transform=\"rotate(-90 " << name_x << " "
    << name_y << ")\">" << text::xml_escape(y_name) << "</text>\n</g>\n";
  return s.str();
}

}  // namespace furuta::report
