#pragma once
// Text escaped for XML: the SVG figures and the HTML report (report/) write it by hand.

#include <string>
#include <string_view>

namespace furuta::text {

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
