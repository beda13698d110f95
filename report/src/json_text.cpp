// The text of the JSON documents: one member per line at the top, one line per value below it.
#include <charconv>
#include <cmath>
#include <string>

#include "furuta/report/json.hpp"

namespace furuta::report {

namespace {

void append(std::string& out, const Json& value);

// The shortest decimal text that reads back as the same double; JSON has no NaN or infinity.
void append_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buffer[32];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, v);
  out.append(buffer, error == std::errc() ? end : buffer);
}

void append_string(std::string& out, const std::string& text) {
  out += Json(text).dump(-1, ' ', false, Json::error_handler_t::replace);
}

void append(std::string& out, const Json& value) {
  switch (value.type()) {
    case Json::value_t::object: {
      out += '{';
      bool first = true;
      for (const auto& [key, member] : value.items()) {
        if (!first) out += ", ";
        first = false;
        append_string(out, key);
        out += ": ";
        append(out, member);
      }
      out += '}';
      return;
    }
    case Json::value_t::array: {
      out += '[';
      for (std::size_t i = 0; i < value.size(); ++i) {
        if (i > 0) out += ", ";
        append(out, value[i]);
      }
      out += ']';
      return;
    }
    case Json::value_t::string:
      append_string(out, value.get_ref<const std::string&>());
      return;
    case Json::value_t::number_float:
      append_number(out, value.get<double>());
      return;
    default:  // integers, booleans, null
      out += value.dump();
      return;
  }
}

bool has_structured_member(const Json& value) {
  for (const auto& member : value) {
    if (member.is_structured()) return true;
  }
  return false;
}

// `value` at nesting `level`: expanded (one member per line, indented) while level < expanded and
// it holds containers (below the top: [lo, hi] and a list of names stay on their line).
void append_layout(std::string& out, const Json& value, int level, int expanded) {
  if (level >= expanded || !value.is_structured() || value.empty() ||
      (level > 0 && !has_structured_member(value))) {
    append(out, value);
    return;
  }
  const std::string indent(static_cast<std::size_t>(2 * (level + 1)), ' ');
  const bool object = value.is_object();
  out += object ? '{' : '[';
  bool first = true;
  for (const auto& [key, member] : value.items()) {
    out += (first ? "\n" : ",\n") + indent;
    first = false;
    if (object) {
      append_string(out, key);
      out += ": ";
    }
    append_layout(out, member, level + 1, expanded);
  }
  out += "\n" + std::string(indent.size() - 2, ' ') + (object ? '}' : ']');
}

}  // namespace

std::string json_line(const Json& value) {
  std::string out;
  append(out, value);
  return out;
}

std::string json_text(const Json& document, int expanded_levels) {
  std::string out;
  append_layout(out, document, 0, expanded_levels);
  return out + "\n";
}

}  // namespace furuta::report
