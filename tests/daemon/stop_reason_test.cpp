#include <gtest/gtest.h>

#include <set>
#include <string>

#include "furuta/daemon/safety.hpp"

namespace furuta::daemon {
namespace {

TEST(StopReason, NamesAreDistinctSnakeCaseAndOnlyRequestedEndsAreNotFaults) {
  std::set<std::string> names;
  for (int r = 0; r <= static_cast<int>(StopReason::exception); ++r) {
    const auto reason = static_cast<StopReason>(r);
    const std::string name(to_string(reason));
    EXPECT_NE(name, "unknown");
    EXPECT_EQ(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_"), std::string::npos) << name;
    EXPECT_TRUE(names.insert(name).second) << name;
  }
  EXPECT_FALSE(is_fault(StopReason::duration_reached));
  EXPECT_FALSE(is_fault(StopReason::stop_command));
  EXPECT_TRUE(is_fault(StopReason::estop_command));
  EXPECT_TRUE(is_fault(StopReason::signal));
  EXPECT_TRUE(is_fault(StopReason::usb_error));
}

}  // namespace
}  // namespace furuta::daemon
