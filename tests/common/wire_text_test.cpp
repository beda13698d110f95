// Text from the wire, bounded and escaped before anything stores, echoes or prints it.
#include "furuta/common/wire_text.hpp"

#include <gtest/gtest.h>

#include <string>

namespace furuta::text {
namespace {

TEST(WireText, PrintableTextThatFitsIsUnchanged) {
  EXPECT_EQ(wire_text("ana@rig-01", 64), "ana@rig-01");
  EXPECT_EQ(wire_quoted("ana@rig", 64), "\"ana@rig\"");
  EXPECT_EQ(wire_text("", 8), "");
}

TEST(WireText, ControlBytesQuotesAndHighBytesAreEscaped) {
  // A terminal escape sequence (clear screen) and a bell must never reach a terminal raw.
  const std::string hostile = "\x1b[2J\a\"\\\xff";
  const std::string safe = wire_text(hostile, 100);
  EXPECT_EQ(safe, "\\x1b[2J\\x07\\x22\\x5c\\xff");
  for (char c : safe) {
    EXPECT_GE(static_cast<unsigned char>(c), 0x20);
    EXPECT_LT(static_cast<unsigned char>(c), 0x7f);
  }
}

TEST(WireText, AMegabyteIsCutToTheBoundWithAMark) {
  const std::string big(1'000'000, 'A');
  for (std::size_t bound : {8u, 40u, 128u, 1000u}) {
    const std::string cut = wire_text(big, bound);
    EXPECT_LE(cut.size(), bound);
    EXPECT_EQ(cut.substr(cut.size() - 3), "...") << bound;
    EXPECT_LE(wire_quoted(big, bound).size(), bound);
  }
  // Escaped bytes count at their escaped length, and an escape is never cut in half.
  const std::string escapes(100, '\x01');
  const std::string cut = wire_text(escapes, 20);
  EXPECT_LE(cut.size(), 20u);
  EXPECT_EQ(cut, "\\x01\\x01\\x01\\x01...");
  // Exactly at the bound: no mark.
  EXPECT_EQ(wire_text("abcd", 4), "abcd");
  EXPECT_EQ(wire_text("abcde", 4), "a...");
}

TEST(WireText, PrintableTextKeepsEarlierEscapesAndQuotes) {
  const std::string reason = "label: " + wire_quoted("a\nb", 20) + " has 0x0a";
  EXPECT_EQ(reason, "label: \"a\\x0ab\" has 0x0a");
  EXPECT_EQ(printable_text(reason, 100), reason);
  EXPECT_EQ(printable_text("bell\a", 100), "bell\\x07");
}

}  // namespace
}  // namespace furuta::text
