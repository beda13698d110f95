// A parameter box written by hand (config/parameter_box.hpp): read into lo and hi per parameter;
// a missing or misordered bound, a negative inertia, an unknown key or an unreadable file is a
// ConfigError naming the file, the line and the key.
#include "furuta/config/parameter_box.hpp"

#include <gtest/gtest.h>

#include <string>

#include "furuta/config/config_error.hpp"

namespace furuta::config::parameter_box_test {
namespace {

const std::string kBox =
    "[parameters]\n"
    "mu1 = [1.0e-3, 1.1e-3]\n"
    "mu2 = [2.5e-3, 2.6e-3]\n"
    "mu3 = [8.0e-4, 8.4e-4]\n"
    "mu4 = [1.3e-3, 1.35e-3]\n"
    "mug = [0.074, 0.075]\n"
    "fv1 = [0.0, 0.09]\n"
    "fv2 = [6.0e-4, 7.0e-4]\n";

TEST(ParameterBox, ReadsEachParametersBounds) {
  const ParameterBox box = parse_parameter_box(kBox, "box.toml");
  EXPECT_DOUBLE_EQ(box.lo.mu1, 1.0e-3);
  EXPECT_DOUBLE_EQ(box.hi.mu1, 1.1e-3);
  EXPECT_DOUBLE_EQ(box.lo.fv1, 0.0);
  EXPECT_DOUBLE_EQ(box.hi.fv2, 7.0e-4);
  EXPECT_DOUBLE_EQ(box.hi.mug, 0.075);
}

// The error for `text`: its field and line.
ConfigError error_of(const std::string& text) {
  try {
    parse_parameter_box(text, "box.toml");
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return ConfigError("", 0, "", "");
}

TEST(ParameterBox, NamesWhatIsWrongAndWhere) {
  std::string swapped = kBox;
  swapped.replace(swapped.find("[0.074, 0.075]"), 14, "[0.075, 0.074]");
  const ConfigError order = error_of(swapped);
  EXPECT_EQ(order.field(), "parameters.mug");
  EXPECT_EQ(order.line(), 6);
  EXPECT_NE(std::string(order.what()).find("lo <= hi"), std::string::npos) << order.what();

  std::string negative = kBox;
  negative.replace(negative.find("[1.0e-3, 1.1e-3]"), 16, "[-1.0e-3, 1.1e-3]");
  EXPECT_EQ(error_of(negative).field(), "parameters.mu1");

  std::string missing = kBox;
  missing.erase(missing.find("fv2"));
  EXPECT_EQ(error_of(missing).field(), "parameters.fv2");

  EXPECT_EQ(error_of(kBox + "mu5 = [1.0, 2.0]\n").field(), "parameters.mu5");
  EXPECT_EQ(error_of("mu1 = [1.0, 2.0]\n").field(), "parameters");
  EXPECT_THROW(load_parameter_box("/nonexistent/box.toml"), ConfigError);
}

}  // namespace
}  // namespace furuta::config::parameter_box_test
