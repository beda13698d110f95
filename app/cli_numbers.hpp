#pragma once
// Numbers typed on the command line, checked finite and in range where they enter; CLI11 names the
// option in its message. CLI11's own Range and NonNegativeNumber let NaN through (every comparison
// with NaN is false), and an unsigned option reads -1 as its largest value, so every number option
// takes one of these instead.

#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>
#include <string>

namespace furuta::app {

// A finite number in [lo, hi].
inline CLI::Validator finite_in(double lo, double hi) {
  std::ostringstream range;
  range << "[" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi, range = range.str()](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value)) {
          return text + " is not a finite number";
        }
        if (value < lo || value > hi) return text + " is not in " + range;
        return {};
      },
      "NUMBER in " + range.str());
}

// A finite number, whose range another check (the configuration's) decides.
inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value)) {
          return text + " is not a finite number";
        }
        return {};
      },
      "NUMBER");
}

// `check` with the option's name in its message: CLI11 names no hidden option (group "") in its
// errors, and an old name kept as a hidden alias must still say which option was wrong.
inline CLI::Validator named(CLI::Validator check, const std::string& name) {
  return CLI::Validator(
      [check, name](std::string& text) mutable -> std::string {
        const std::string why = check(text);
        return why.empty() ? why : name + " " + why;
      },
      "");
}

// A whole number in [lo, hi], checked before it is read into its (perhaps unsigned) type.
inline CLI::Validator whole_in(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        long long value = 0;
        if (!CLI::detail::lexical_cast(text, value)) return text + " is not a whole number";
        if (value < lo || value > hi) return text + " is not in " + range;
        return {};
      },
      "INTEGER in " + range);
}

}  // namespace furuta::app
