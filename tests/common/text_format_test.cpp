// The text helper behind the hand-written SVG and HTML: XML text left inert. (The JSON tests are
// in tests/report/json_text_test.cpp, with the writer that replaced json_number and json_string.)
#include "furuta/common/text_format.hpp"

#include <gtest/gtest.h>

#include <string>

namespace furuta::text {
namespace {

TEST(TextFormat, XmlEscapeLeavesNoMarkup) {
  EXPECT_EQ(xml_escape("<svg onload=\"x\">&'"), "&lt;svg onload=&quot;x&quot;&gt;&amp;&#39;");
  EXPECT_EQ(xml_escape("mu1 [kg m^2]"), "mu1 [kg m^2]");
  const std::string escaped = xml_escape("a<b>c&d\"e'f");
  EXPECT_EQ(escaped.find_first_of("<>\"'"), std::string::npos);
}

}  // namespace
}  // namespace furuta::text
