#pragma once
// Text for the project's hand-written JSON and SVG/HTML outputs: numbers that read back exactly,
// strings escaped for JSON, text escaped for XML. One definition for every module that writes them.

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <string>
#include <string_view>

namespace furuta::text {

// The shortest-safe decimal text of v (17 significant digits: reads back as the same double);
// null for NaN and infinities, which JSON cannot hold.
inline std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

// text escaped for the inside of a JSON string (quotes, backslashes, control characters).
inline std::string json_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char code[8];
          std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned char>(c));
          out += code;
        } else {
          out += c;
        }
    }
  }
  return out;
}

// A JSON string literal.
inline std::string json_string(std::string_view text) {
  return "\"" + json_escape(text) + "\"";
}

// text escaped for XML/HTML element content and attribute values.
inline std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace furuta::text
