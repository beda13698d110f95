#pragma once
// Text that came from the wire (LCM messages anyone on the group may send, or the daemon's answers
// read by a tool), made safe to store, echo into a reply or print to a terminal: bounded, and
// every byte outside printable ASCII, and the quote and backslash, written as \xNN. One helper for
// every such text, so no path echoes a stranger's bytes whole.

#include <cstdio>
#include <string>
#include <string_view>

namespace furuta::text {

namespace detail {

inline std::string bounded_text(std::string_view text, std::size_t max_bytes, bool escape_quoting) {
  constexpr std::string_view kCut = "...";
  std::string out;
  std::size_t fits_with_cut = 0;  // the longest prefix of whole pieces that leaves room for kCut
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    char piece[8] = {ch, 0};
    if (c < 0x20 || c >= 0x7f || (escape_quoting && (c == '"' || c == '\\'))) {
      std::snprintf(piece, sizeof piece, "\\x%02x", c);
    }
    const std::string_view next(piece);
    if (out.size() + next.size() > max_bytes) {
      out.resize(fits_with_cut);
      if (out.size() + kCut.size() <= max_bytes) out += kCut;
      return out;
    }
    out += next;
    if (out.size() + kCut.size() <= max_bytes) fits_with_cut = out.size();
  }
  return out;
}

}  // namespace detail

// `text` escaped and cut so the result is at most `max_bytes` long (at least 8 are needed for any
// escaped byte and the cut mark); a cut ends in "...". Printable text that fits is unchanged.
inline std::string wire_text(std::string_view text, std::size_t max_bytes) {
  return detail::bounded_text(text, max_bytes, true);
}

// The same for a text already built of escaped pieces (a reason quoting wire_text): only bytes
// outside printable ASCII are escaped, so its quotes and escapes read as they were.
inline std::string printable_text(std::string_view text, std::size_t max_bytes) {
  return detail::bounded_text(text, max_bytes, false);
}

// wire_text in double quotes: "...", at most `max_bytes` including the quotes.
inline std::string wire_quoted(std::string_view text, std::size_t max_bytes) {
  return '"' + wire_text(text, max_bytes > 2 ? max_bytes - 2 : 0) + '"';
}

}  // namespace furuta::text
