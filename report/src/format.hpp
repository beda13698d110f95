#pragma once
// Numbers as the tables, figures and the page write them: one definition for all of report/.

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace furuta::report {

// The figures and tables show the pendulum's angle in degrees.
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

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

// The decimals in a text written elsewhere (an integrator's reason: "enclosure width
// 6.7367745165386133 > max_width 6.2831853071795862 at t = 0.058721594480886791") cut to
// `significant` digits for a person ("enclosure width 6.737 > max_width 6.283 at t = 0.05872");
// shorter numbers and everything else stay as they are. The JSON keeps the full text.
inline std::string readable_numbers(const std::string& text, int significant = 4) {
  static const std::regex decimal(R"(\d+\.\d+([eE][-+]?\d+)?)");
  std::string out;
  std::size_t copied = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), decimal);
       it != std::sregex_iterator(); ++it) {
    const std::string number = it->str();
    const std::string mantissa = number.substr(0, number.find_first_of("eE"));
    const std::size_t first = mantissa.find_first_not_of("0.");
    int digits = 0;
    for (std::size_t i = first; i < mantissa.size(); ++i) digits += mantissa[i] != '.';
    if (first == std::string::npos || digits <= significant) continue;
    // The whole part stays whole: 123456.789 is 123457, not 1.235e+05.
    const std::size_t point = mantissa.find('.');
    const int whole = first < point ? static_cast<int>(point - first) : 0;
    const bool exponent = mantissa.size() != number.size();
    const auto at = static_cast<std::size_t>(it->position());
    out += text.substr(copied, at - copied) +
           short_number(std::stod(number), exponent ? significant : std::max(significant, whole));
    copied = at + number.size();
  }
  return out + text.substr(copied);
}

// An enclosure as a person reads it: "[0.0795123, 0.0805457]", each bound to `significant`
// digits and rounded outward, so the text still holds every value the interval holds.
inline std::string interval_text(double lo, double hi, int significant = 6) {
  // The bound rounded at `significant` digits, then a unit further out should the product's
  // rounding have left the text a hair inside the bound.
  const auto bound = [significant](double v, bool up) {
    if (!std::isfinite(v) || v == 0.0) return short_number(v, significant);
    const double scale = std::pow(10.0, significant - 1 - std::floor(std::log10(std::abs(v))));
    double units = up ? std::ceil(v * scale) : std::floor(v * scale);
    std::string text = short_number(units / scale, significant);
    if (up ? std::stod(text) < v : std::stod(text) > v) {
      units += up ? 1 : -1;
      text = short_number(units / scale, significant + 1);
    }
    return text;
  };
  if (std::isnan(lo) || std::isnan(hi)) return "[empty]";
  return "[" + bound(lo, false) + ", " + bound(hi, true) + "]";
}

// The units as a reader writes them, not as a terminal must.
inline std::string pretty_unit(const std::string& unit) {
  std::string out = unit;
  const auto replace = [&out](const std::string& from, const std::string& to) {
    for (std::size_t at = out.find(from); at != std::string::npos; at = out.find(from, at)) {
      out.replace(at, from.size(), to);
      at += to.size();
    }
  };
  replace("^-2", "\u207b\u00b2");
  replace("^2", "\u00b2");
  return out;
}

// "12.3 %" of a rate in [0, 1].
inline std::string percent(double rate) {
  return fixed(100.0 * rate, 1) + " %";
}

// The column heads of one column per experiment: the names when all are at most `max_chars`
// long, else "E1", "E2", ... with the names in a legend (`legend` true). Names are never cut:
// sessions of one day differ only at their ends, and cutting either end loses what tells them
// apart.
struct ColumnHeads {
  std::vector<std::string> heads;
  bool legend = false;
};
inline ColumnHeads column_heads(const std::vector<std::string>& names, std::size_t max_chars) {
  ColumnHeads out{names, false};
  for (const std::string& name : names) out.legend = out.legend || name.size() > max_chars;
  if (out.legend) {
    for (std::size_t i = 0; i < names.size(); ++i) out.heads[i] = "E" + std::to_string(i + 1);
  }
  return out;
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

// An interval's half-width as a percentage of `centre` ("+-0.12 %"), "-" for a centre of 0.
inline std::string half_width_percent(double rad, double centre) {
  return centre != 0.0 ? "+-" + short_number(100.0 * rad / std::abs(centre), 3) + " %" : "-";
}

}  // namespace furuta::report
