// The JSON documents' text (report/src/json_text.cpp): numbers read back exactly, NaN and
// infinities are null, strings escaped, the layout the documents always had.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "furuta/report/json.hpp"

namespace furuta::report {
namespace {

TEST(JsonText, NumbersReadBackExactlyAndNonFiniteIsNull) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> exponent(-300, 300), mantissa(-1, 1);
  for (int k = 0; k < 20000; ++k) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    EXPECT_EQ(std::stod(json_line(v)), v) << json_line(v);
  }
  // The shortest text that reads back (json_number's 17 digits gave "0.10000000000000001").
  EXPECT_EQ(json_line(0.1), "0.1");
  EXPECT_EQ(json_line(0.0), "0");
  EXPECT_EQ(json_line(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(json_line(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(json_line(-std::numeric_limits<double>::infinity()), "null");
}

TEST(JsonText, StringsEscapeQuotesBackslashesAndControlCharacters) {
  EXPECT_EQ(json_line("plain"), "\"plain\"");
  EXPECT_EQ(json_line("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(json_line("line\nnext\ttab"), "\"line\\nnext\\ttab\"");
  EXPECT_EQ(json_line(std::string("\x01\x1f", 2)), "\"\\u0001\\u001f\"");
  EXPECT_EQ(json_line("d\xc3\xa9j\xc3\xa0"), "\"d\xc3\xa9j\xc3\xa0\"");  // UTF-8 passes through
  // A byte that is not UTF-8 (a file name from elsewhere) is replaced, not an exception.
  EXPECT_EQ(json_line(std::string("a\xff", 2)), "\"a\xef\xbf\xbd\"");
}

TEST(JsonText, TopLevelMembersOnALineEachValuesOnOne) {
  Json j;
  j["name"] = "x";
  j["input_lag_s"] = 0.0;
  j["combined"] = Json{{"estimate", Json{{"mu1", 1e-3}}}, {"rank", 7}};
  j["list"] = Json::array({1, 2.5, nullptr, true});
  EXPECT_EQ(json_text(j),
            "{\n  \"name\": \"x\",\n  \"input_lag_s\": 0,\n  \"combined\": {\"estimate\": "
            "{\"mu1\": 0.001}, \"rank\": 7},\n  \"list\": [1, 2.5, null, true]\n}\n");
  EXPECT_EQ(json_text(Json::object()), "{}\n");
  EXPECT_EQ(Json::parse(json_text(j)), j);
}

}  // namespace
}  // namespace furuta::report
