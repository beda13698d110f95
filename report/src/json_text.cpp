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

}  // namespace

std::string json_line(const Json& value) {
  std::string out;
  append(out, value);
  return out;
}

std::string json_text(const Json& document) {
  if (!document.is_object() || document.empty()) return json_line(document) + "\n";
  std::string out = "{";
  bool first = true;
  for (const auto& [key, member] : document.items()) {
    out += first ? "\n  " : ",\n  ";
    first = false;
    append_string(out, key);
    out += ": ";
    append(out, member);
  }
  return out + "\n}\n";
}

}  // namespace furuta::report
