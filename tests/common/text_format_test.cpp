// The text helpers behind every hand-written JSON, SVG and HTML output: numbers read back exactly,
// strings escaped for JSON, XML text left inert.
#include "furuta/common/text_format.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace furuta::text {
namespace {

TEST(TextFormat, JsonNumbersReadBackExactlyAndNonFiniteIsNull) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> exponent(-300, 300), mantissa(-1, 1);
  for (int k = 0; k < 20000; ++k) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    EXPECT_EQ(std::stod(json_number(v)), v) << json_number(v);
  }
  EXPECT_EQ(json_number(0.1), "0.10000000000000001");
  EXPECT_EQ(json_number(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(json_number(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(json_number(-std::numeric_limits<double>::infinity()), "null");
}

TEST(TextFormat, JsonStringsEscapeQuotesBackslashesAndControlCharacters) {
  EXPECT_EQ(json_string("plain"), "\"plain\"");
  EXPECT_EQ(json_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(json_string("line\nnext\ttab"), "\"line\\nnext\\ttab\"");
  EXPECT_EQ(json_escape(std::string("\x01\x1f", 2)), "\\u0001\\u001f");
  EXPECT_EQ(json_escape("d\xc3\xa9j\xc3\xa0"), "d\xc3\xa9j\xc3\xa0");  // UTF-8 passes through
}

TEST(TextFormat, XmlEscapeLeavesNoMarkup) {
  EXPECT_EQ(xml_escape("<svg onload=\"x\">&'"), "&lt;svg onload=&quot;x&quot;&gt;&amp;&#39;");
  EXPECT_EQ(xml_escape("mu1 [kg m^2]"), "mu1 [kg m^2]");
  const std::string escaped = xml_escape("a<b>c&d\"e'f");
  EXPECT_EQ(escaped.find_first_of("<>\"'"), std::string::npos);
}

}  // namespace
}  // namespace furuta::text
