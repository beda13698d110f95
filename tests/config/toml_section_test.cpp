#include "furuta/config/toml_section.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace furuta::config {
namespace {

enum class Colour { red, green };

// The problem `read` reports for the document `text` (named "t.toml").
template <typename Read>
ConfigError error_of(const std::string& text, Read read) {
  const toml::table root = parse_toml(text, "t.toml");
  Section top(root, "t.toml");
  try {
    read(top);
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << text;
  return ConfigError("", 0, "", "");
}

TEST(TomlSection, ValuesAbsentTakeTheirFallbacks) {
  const toml::table root = parse_toml("[a]\nx = 2\n", "t.toml");
  Section top(root, "t.toml");
  Section a = top.child("a");
  Section b = top.child("b");
  EXPECT_TRUE(a.present());
  EXPECT_FALSE(b.present());
  EXPECT_EQ(a.number("x", 1.0), 2.0);  // an integer reads as a number
  EXPECT_EQ(a.number("y", 1.5), 1.5);
  EXPECT_FALSE(a.optional_number("y").has_value());
  EXPECT_EQ(b.integer("n", 7), 7);
  EXPECT_TRUE(b.boolean("on", true));
  EXPECT_EQ(b.text("s", "d"), "d");
  EXPECT_EQ(b.choice("c", Colour::green, {{"red", Colour::red}, {"green", Colour::green}}),
            Colour::green);
  a.reject_unknown_keys();
  b.reject_unknown_keys();
  top.reject_unknown_keys();
}

TEST(TomlSection, ErrorsNameFileLineAndDottedField) {
  const ConfigError e = error_of("[a.b]\n\nx = -1\n", [](Section& top) {
    top.child("a").child("b").number(
        "x", 1.0, [](double v) { return v > 0; }, "> 0");
  });
  EXPECT_EQ(e.file(), "t.toml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "a.b.x");
  EXPECT_STREQ(e.what(), "t.toml:3: a.b.x: must be > 0");
  EXPECT_STREQ(error_of("x = nan\n", [](Section& top) { top.number("x", 0.0); }).what(),
               "t.toml:1: x: must be finite");
  EXPECT_STREQ(error_of("a = 1\n", [](Section& top) { top.child("a"); }).what(),
               "t.toml:1: a: must be a table ([a])");
}

TEST(TomlSection, ARequiredKeyMissingIsReportedAtItsTable) {
  const ConfigError e = error_of("# first\n[csv]\nother = 1\n", [](Section& top) {
    top.child("csv").required_text("time", "the time column");
  });
  EXPECT_EQ(e.line(), 2);
  EXPECT_STREQ(e.what(), "t.toml:2: csv.time: missing: the time column");
  EXPECT_STREQ(error_of("[m]\nk = 0\n",
                        [](Section& top) {
                          top.child("m").required_number(
                              "k", "a constant", [](double v) { return v > 0; }, "> 0");
                        })
                   .what(),
               "t.toml:2: m.k: must be > 0");
  EXPECT_STREQ(
      error_of("[m]\n", [](Section& top) { top.child("m").required_number("k", "k_t"); }).what(),
      "t.toml:1: m.k: missing: k_t");
  EXPECT_STREQ(
      error_of("s = \"\"\n", [](Section& top) { top.required_text("s", "a name"); }).what(),
      "t.toml:1: s: must not be empty");
}

TEST(TomlSection, ChoicesReadAsTheirValuesAndListTheAllowedSpellings) {
  const toml::table root = parse_toml("c = \"red\"\nu = \"ms\"\n", "t.toml");
  Section top(root, "t.toml");
  EXPECT_EQ(top.choice("c", Colour::green, {{"red", Colour::red}, {"green", Colour::green}}),
            Colour::red);
  EXPECT_EQ(top.required_choice<double>("u", {{"s", 1.0}, {"ms", 1e-3}}), 1e-3);
  top.reject_unknown_keys();

  const auto colour = [](Section& top) {
    top.choice("c", Colour::red, {{"red", Colour::red}, {"green", Colour::green}});
  };
  EXPECT_STREQ(error_of("\nc = \"blue\"\n", colour).what(),
               "t.toml:2: c: 'blue' is not one of: red, green");
  EXPECT_STREQ(error_of("c = 3\n", colour).what(), "t.toml:1: c: must be a string");
  EXPECT_STREQ(error_of("x = 1\n",
                        [](Section& top) {
                          top.required_choice<double>("u", {{"s", 1.0}, {"ms", 1e-3}});
                        })
                   .what(),
               "t.toml: u: missing: one of s, ms");
}

TEST(TomlSection, NumberListsHaveAnyLengthAndABadEntryIsNamedAtItsLine) {
  const toml::table root = parse_toml("a = [1, 2.5, -3]\nb = []\n", "t.toml");
  Section top(root, "t.toml");
  EXPECT_EQ(top.number_list("a", {}), (std::vector<double>{1.0, 2.5, -3.0}));
  EXPECT_TRUE(top.number_list("b", {7.0}).empty());
  EXPECT_EQ(top.number_list("c", {7.0}), std::vector<double>{7.0});
  top.reject_unknown_keys();

  const auto positive = [](Section& top) {
    top.number_list(
        "x", {}, [](double v) { return v > 0; }, "> 0");
  };
  EXPECT_STREQ(error_of("x = [\n  1,\n  -2,\n]\n", positive).what(),
               "t.toml:3: x: entries must be > 0");
  EXPECT_STREQ(error_of("x = [1, nan]\n", positive).what(), "t.toml:1: x: must be finite");
  EXPECT_STREQ(error_of("\nx = [1, \"2\"]\n", positive).what(),
               "t.toml:2: x: must be an array of numbers");
  EXPECT_STREQ(error_of("x = 1\n", positive).what(), "t.toml:1: x: must be an array of numbers");
  EXPECT_STREQ(error_of("x = [[1]]\n", positive).what(),
               "t.toml:1: x: must be an array of numbers");
}

TEST(TomlSection, ARequiredListOfNumbersHasItsLengthAndFiniteEntries) {
  const toml::table root = parse_toml("k = [1, 2.5, -3e-2]\n", "t.toml");
  Section top(root, "t.toml");
  EXPECT_EQ(top.required_numbers("k", "the gain", 2, 4), (std::vector<double>{1.0, 2.5, -0.03}));
  top.reject_unknown_keys();
  const auto read = [](std::size_t min, std::size_t max) {
    return [=](Section& top) { top.required_numbers("k", "the gain", min, max); };
  };
  EXPECT_STREQ(error_of("k = [1, 2]\n", read(3, 5)).what(),
               "t.toml:1: k: must be an array of 3 to 5 numbers");
  EXPECT_STREQ(error_of("k = [1, 2]\n", read(3, 3)).what(),
               "t.toml:1: k: must be an array of 3 numbers");
  EXPECT_STREQ(error_of("k = [1, \"2\"]\n", read(2, 2)).what(),
               "t.toml:1: k: must be an array of numbers");
  EXPECT_STREQ(error_of("k = 1\n", read(1, 1)).what(), "t.toml:1: k: must be an array of numbers");
  // An entry's problem is at its own line.
  EXPECT_STREQ(error_of("k = [\n  1,\n  inf,\n]\n", read(2, 2)).what(),
               "t.toml:3: k: must be finite");
  EXPECT_STREQ(error_of("x = 1\n", read(1, 2)).what(), "t.toml: k: missing: the gain");
}

TEST(TomlSection, KeysNeverReadAreUnknown) {
  const ConfigError e = error_of("[a]\nx = 1\ny = 2\n", [](Section& top) {
    Section a = top.child("a");
    a.number("x", 0.0);
    a.reject_unknown_keys();
  });
  EXPECT_STREQ(e.what(), "t.toml:3: a.y: unknown key");
}

TEST(TomlSection, SyntaxErrorsCarryTheirLine) {
  try {
    parse_toml("a = 1\nb = \n", "t.toml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "t.toml");
    EXPECT_EQ(e.line(), 2);
    EXPECT_TRUE(e.field().empty());
  }
}

}  // namespace
}  // namespace furuta::config
