#include "furuta/firmware_bridge/clock.hpp"

#include <gtest/gtest.h>

namespace furuta::bridge {
namespace {

TEST(VirtualClock, MovesOnlyForwardAndOnlyWhenAsked) {
  VirtualClock clock(1000);
  EXPECT_EQ(clock.now_ns(), 1000);
  clock.sleep_until_ns(500);  // a deadline in the past returns at once
  EXPECT_EQ(clock.now_ns(), 1000);
  clock.sleep_until_ns(16'000'000);
  EXPECT_EQ(clock.now_ns(), 16'000'000);
  clock.advance_ns(-5);
  EXPECT_EQ(clock.now_ns(), 16'000'000);
  clock.advance_ns(8);
  EXPECT_EQ(clock.now_ns(), 16'000'008);
}

TEST(MonotonicClock, SleepUntilReturnsNoEarlierThanTheDeadline) {
  MonotonicClock clock;
  const std::int64_t start = clock.now_ns();
  const std::int64_t deadline = start + 2'000'000;
  clock.sleep_until_ns(deadline);
  EXPECT_GE(clock.now_ns(), deadline);
  const std::int64_t before = clock.now_ns();
  clock.sleep_until_ns(before - 1'000'000);  // past: no sleep at all
  EXPECT_LT(clock.now_ns() - before, 1'000'000'000);
}

}  // namespace
}  // namespace furuta::bridge
