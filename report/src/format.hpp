#pragma once
// Numbers as the tables, figures and the page write them: one definition for all of report/.

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace furuta::report {

// std::scientific with `digits` decimals ("nan" and "inf" as the stream writes them).
inline std::string sci(double v, int digits) {
  std::ostringstream s;
  s << std::scientific << std::setprecision(digits) << v;
  return s.str();
}

// std::fixed with `digits` decimals.
inline std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// A number as a person writes it: at most `significant` digits, no trailing zeros, -0 as 0
// (-100, 0.17, 0).
inline std::string short_number(double v, int significant = 6) {
  std::ostringstream s;
  s << std::setprecision(significant) << (v == 0.0 ? 0.0 : v);
  return s.str();
}

// "12.3 %" of a rate in [0, 1].
inline std::string percent(double rate) {
  return fixed(100.0 * rate, 1) + " %";
}

// The page's cells: "-" where a number is NaN or infinite.
inline std::string or_dash(double v, const std::string& text) {
  return std::isfinite(v) ? text : "-";
}
inline std::string dash_sci(double v, int digits) {
  return or_dash(v, sci(v, digits));
}
inline std::string dash_fixed(double v, int digits) {
  return or_dash(v, fixed(v, digits));
}

}  // namespace furuta::report
